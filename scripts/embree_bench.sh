#!/usr/bin/env bash
# glint's CPU traversal against Embree 3 on the same rays, one thread
# (bench/embree, a crate of its own so the default build needs no Embree).
# Installs Debian's libembree-dev where it is missing (apt, the machine's own
# sources), then prints a markdown table (docs/benchmarks.md keeps one run).
# Usage: scripts/embree_bench.sh
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -e /usr/include/embree3/rtcore.h ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "embree_bench: installing libembree-dev" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq libembree-dev >/dev/null
fi
cd bench/embree
cargo run --release --quiet
