#!/usr/bin/env bash
# The release binary, built with profile-guided optimisation (PGO): the same
# source and the same floating-point operations as `cargo build --release`
# (PGO changes code layout, inlining and branch order, never arithmetic, so
# the images are the same bits), 5-12% more samples per second on the CPU
# backend (docs/benchmarks.md, "Profile-guided optimisation").
#
# It is built for this machine's CPU (`-C target-cpu=native`: its AVX2, FMA
# or AVX-512 in all the code, not only in the kernels that detect them at run
# time), another 4-16% on the CPU backend on a Zen 4 with AVX-512, with the
# same images bit for bit:
# Rust never fuses or reorders floating-point operations, whatever the
# instruction set (docs/benchmarks.md, "Built for the machine's CPU"). The
# binary refuses, in one line, to run on a CPU that lacks what it was built
# for. GLINT_TARGET_CPU (environment) names another LLVM CPU: x86-64 for a
# binary that runs on any x86-64, x86-64-v3 for any with AVX2.
#
#  1. an instrumented build (target/pgo-train);
#  2. it renders every bundled scene small on the CPU backend, recording
#     which branches and calls the renderer takes; skipped when the
#     instrumented binary is the one the profile was recorded with;
#  3. the optimised build from that profile: target/pgo/release/glint.
#
# The profile is made here from the checkout's own source, never committed,
# so it is never stale and always matches the toolchain. It needs
# llvm-profdata of the toolchain's LLVM (rustup's llvm-tools component, which
# this script adds where rustup can); without it, a plain release build goes
# to the same path, with a warning. GLINT_PGO=off (environment) asks for that
# plain build.
# Usage: scripts/build.sh        (prints the binary's path last)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
out=target/pgo
train=target/pgo-train
bin=$out/release/glint
# The target CPU, the caller's RUSTFLAGS (a target-cpu there wins: rustc
# takes the last) and one flag of ours, as cargo's unit-separated list (so
# that a checkout path with spaces stays one argument).
flags_with() {
  local words=() out="" w
  read -ra words <<< "${RUSTFLAGS:-}"
  for w in "-Ctarget-cpu=${GLINT_TARGET_CPU:-native}" "${words[@]}" "$@"; do out+="${out:+$'\x1f'}$w"; done
  printf '%s' "$out"
}

host=$(rustc -vV | sed -n 's/^host: //p')
profdata="$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-profdata"
pgo=${GLINT_PGO:-on}
if [ "$pgo" != off ] && [ ! -x "$profdata" ] && command -v rustup >/dev/null 2>&1; then
  # (The component's name before Rust 1.72: llvm-tools-preview.)
  rustup component add llvm-tools >&2 || rustup component add llvm-tools-preview >&2 || true
fi
if [ "$pgo" != off ] && [ ! -x "$profdata" ]; then
  echo "glint: warning: llvm-profdata not found (rustup component llvm-tools): building without PGO" >&2
  pgo=off
fi
if [ "$pgo" = off ]; then
  CARGO_ENCODED_RUSTFLAGS=$(flags_with) CARGO_TARGET_DIR=$out cargo build --release --bin glint >&2
  echo "$bin"
  exit 0
fi

echo "build.sh: instrumented build ($train)" >&2
CARGO_ENCODED_RUSTFLAGS=$(flags_with "-Cprofile-generate=$root/$train/raw") CARGO_TARGET_DIR=$train \
  cargo build --release --bin glint >&2

sum=$(sha256sum "$train/release/glint" | cut -c1-16)
profile=$out/glint-$sum.profdata
if [ ! -f "$profile" ]; then
  echo "build.sh: recording the profile (bundled scenes, CPU backend)" >&2
  rm -rf "$train/raw"
  mkdir -p "$train/raw" "$out"
  for scene in assets/*.gltf assets/bunny.glb; do
    LLVM_PROFILE_FILE="$root/$train/raw/%p-%m.profraw" "$train/release/glint" render "$scene" \
      -o "$train/img.exr" --backend cpu --width 96 --spp 32 --quiet >&2
  done
  rm -f "$out"/glint-*.profdata
  "$profdata" merge -o "$profile.tmp" "$train"/raw/*.profraw
  mv "$profile.tmp" "$profile"
fi

# The profile's digest is in its path, so a new profile is a new flag and
# cargo rebuilds what it optimises.
echo "build.sh: optimised build ($bin)" >&2
CARGO_ENCODED_RUSTFLAGS=$(flags_with "-Cprofile-use=$root/$profile") CARGO_TARGET_DIR=$out \
  cargo build --release --bin glint >&2
echo "$bin"
