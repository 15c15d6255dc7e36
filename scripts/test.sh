#!/usr/bin/env bash
# The test command (README.md and .ci/run): set up what is missing, then run
# the whole suite with the Vulkan validation layer on (where installed); any
# error it reports fails the GPU tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# The report test of `glint test` loads its HTML in headless Chromium
# (Debian's chromium package; the render command's set-up does not need it).
# Installed here when missing; then the test requires it
# (GLINT_REQUIRE_BROWSER). Without root and sudo it cannot be installed: the
# test is skipped with a note.
if ! command -v chromium >/dev/null 2>&1; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  if [ -z "$sudo" ] || sudo -n true 2>/dev/null; then
    echo "test: installing chromium" >&2
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq chromium >/dev/null
  else
    echo "test: chromium missing and not root: the browser test will be skipped" >&2
  fi
fi
command -v chromium >/dev/null 2>&1 && export GLINT_REQUIRE_BROWSER=1
export GLINT_VALIDATION=1
cargo test --workspace --locked "$@"
# The lanes once more as scripts/build.sh compiles them, for this machine's
# CPU: there F32x8's operations are AVX2 instructions (cpu/src/lanes.rs,
# `ymm_or!`) rather than loops, and the wave shades its Lambertian vertices
# in lanes by default. Every lane and every bundled scene must still give
# the scalar code's bits (cpu/tests/lanes.rs). Its own target folder, so the
# suite's build above is not rebuilt with other flags.
if grep -qw avx2 /proc/cpuinfo 2>/dev/null; then
  native=(env RUSTFLAGS="${RUSTFLAGS:-} -C target-cpu=native" CARGO_TARGET_DIR=target/native-test)
  "${native[@]}" cargo test -p glint-cpu --locked --test lanes "$@"
  "${native[@]}" cargo test -p glint-cpu --locked --lib lanes:: "$@"
fi
