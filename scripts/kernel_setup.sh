#!/usr/bin/env bash
# Issue 25 item 5's figure, one run on one machine: what a fresh machine
# (empty glint and Mesa caches) pays in GPU set-up to render every bundled
# scene once, with the specialised kernel (a pipeline per feature set) and
# with the generic one (one pipeline for every scene), per traversal; each
# render's set-up seconds from `render --stats`, then the sum.
# Prints a markdown table (docs/benchmarks.md, section "Kernels").
# Usage: [SCENES="a.gltf b.glb"] [TRAVERSALS="software hardware"] scripts/kernel_setup.sh [GLINT] [WIDTH]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
glint=${1:-target/release/glint}
width=${2:-32}
[ -x "$glint" ] || { echo "kernel_setup.sh: no $glint (cargo build --release)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

json() { # FILE KEY: a number from a flat JSON object
  sed -n "s/.*\"$2\": *\([0-9.eE+-]*\).*/\1/p" "$1" | head -1
}

scenes=(${SCENES:-assets/*.gltf assets/*.glb})
header="| traversal | kernel |"
rule="|---|---|"
for scene in "${scenes[@]}"; do
  header="$header $(basename "${scene%.*}") |"
  rule="$rule---:|"
done
echo "$header total s |"
echo "$rule---:|"
for traversal in ${TRAVERSALS:-software hardware}; do
  for kernel in specialized generic; do
    cache="$work/cache-$traversal-$kernel"
    mkdir -p "$cache"
    line="| $traversal | $kernel |"
    total=0
    for scene in "${scenes[@]}"; do
      XDG_CACHE_HOME="$cache" MESA_SHADER_CACHE_DIR="$cache/mesa" \
        "$glint" render "$scene" -o "$work/s.png" --width "$width" --spp 1 --quiet \
        --stats "$work/s.json" --backend gpu --kernel "$kernel" --traversal "$traversal"
      s=$(json "$work/s.json" setup_seconds)
      line="$line $(printf '%.1f' "$s") |"
      total=$(awk -v a="$total" -v b="$s" 'BEGIN { print a + b }')
    done
    echo "$line $(printf '%.1f' "$total") |"
  done
done
