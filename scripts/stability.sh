#!/usr/bin/env bash
# Regenerates docs/stability.md (and docs/stability.csv, .svg, .png): the
# full BSDF stability sweep on both backends (GPU: the default Vulkan
# device, lavapipe where there is no GPU).
#   bash scripts/stability.sh [extra glint stability options, e.g. --cpu-only]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
cargo run --release --quiet -- stability -o docs "$@"
