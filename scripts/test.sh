#!/usr/bin/env bash
# The test command (README.md and .ci/run): set up what is missing, then run
# the whole suite with the Vulkan validation layer on (where installed); any
# error it reports fails the GPU tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export GLINT_VALIDATION=1
cargo test --workspace --locked "$@"
