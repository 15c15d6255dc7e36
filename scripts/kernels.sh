#!/usr/bin/env bash
# Issue 8's figures, one run on one machine: for every bundled scene,
#   - the kernel features and the bytes per triangle (`glint info`);
#   - one `glint converge` with the specialised and the generic GPU kernel
#     (same seed, so the same paths and relMSE: only the time differs) and
#     the CPU backend beside them: samples/s and efficiency 1/(relMSE s);
#   - GPU set-up seconds cold (empty glint and Mesa caches) and warm (the
#     same caches again), from `render --stats`.
# Prints a markdown table (docs/benchmarks.md, section "Kernels").
# Usage: [SCENES="a.gltf b.glb"] scripts/kernels.sh [GLINT] [WIDTH] [SPP]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
glint=${1:-target/release/glint}
width=${2:-64}
spp=${3:-64}
[ -x "$glint" ] || { echo "kernels.sh: no $glint (cargo build --release)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

json() { # FILE KEY: a number from a flat JSON object
  sed -n "s/.*\"$2\": *\([0-9.eE+-]*\).*/\1/p" "$1" | head -1
}

echo "| scene | features (specialised kernel) | bytes/triangle now (one record each before) | GPU samples/s spec / generic | generic / spec time | efficiency spec / generic / CPU | CPU samples/s | set-up s cold / warm |"
echo "|---|---|---|---:|---:|---:|---:|---:|"
for scene in ${SCENES:-assets/*.gltf assets/*.glb}; do
  name=$(basename "${scene%.*}")
  info=$("$glint" info "$scene")
  features=$(sed -n 's/^kernel features: //p' <<<"$info")
  bpt=$(sed -n 's/^bytes per triangle: \([0-9.]*\) .*; \([0-9.]*\) with a shading record.*/\1 (\2)/p' <<<"$info")
  dir="$work/$name"
  "$glint" converge "$scene" -o "$dir" --width "$width" --spp "$spp" --reference-spp $((4 * spp)) \
    --variant 'spec=--backend gpu --kernel specialized' \
    --variant 'generic=--backend gpu --kernel generic' \
    --variant 'cpu=--backend cpu' >/dev/null 2>&1
  # converge.csv: variant,backend,spp,seconds,relmse,...
  row() { awk -F, -v v="$1" '$1 == v { print $4, $5 }' "$dir/converge.csv" | tail -1; }
  read -r s_spec e_spec <<<"$(row spec)"
  read -r s_gen e_gen <<<"$(row generic)"
  read -r s_cpu e_cpu <<<"$(row cpu)"
  ran_spp=$(awk -F, 'NR > 1 { print $3; exit }' "$dir/converge.csv")
  h=$("$glint" render "$scene" -o "$work/h.png" --width "$width" --spp 1 --quiet --stats "$work/h.json" --backend cpu && json "$work/h.json" height)
  px=$((width * h))
  cache="$work/cache-$name"
  mkdir -p "$cache"
  setup() {
    XDG_CACHE_HOME="$cache" MESA_SHADER_CACHE_DIR="$cache/mesa" \
      "$glint" render "$scene" -o "$work/s.png" --width "$width" --spp 1 --quiet --stats "$work/s.json" --backend gpu
    json "$work/s.json" setup_seconds
  }
  cold=$(setup)
  warm=$(setup)
  awk -v n="$name" -v f="$features" -v b="$bpt" -v ss="$s_spec" -v sg="$s_gen" -v sc="$s_cpu" \
      -v es="$e_spec" -v eg="$e_gen" -v ec="$e_cpu" -v spp="$ran_spp" -v px="$px" -v c="$cold" -v w="$warm" \
    'BEGIN { printf "| %s | %s | %s | %.3g / %.3g | %.2f | %.3g / %.3g / %.3g | %.3g | %.2f / %.2f |\n",
      n, f, b, spp * px / ss, spp * px / sg, sg / ss, 1 / (es * ss), 1 / (eg * sg), 1 / (ec * sc), spp * px / sc, c, w }'
done
