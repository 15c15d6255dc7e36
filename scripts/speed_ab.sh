#!/usr/bin/env bash
# Two glint binaries' CPU speed in one run, renders alternating (A, B, A, B,
# ...) so that the machine's load falls on both alike: per scene the median
# samples/s of each over ROUNDS renders (the render's own --stats, one thread
# unless RAYON_NUM_THREADS says otherwise) and the ratio B/A. For changes that
# keep the image (check that with `cmp` on the EXRs); scripts/before_after.sh
# also measures the error. RENDER_ARGS (environment) adds arguments to every
# render (say "--sampler independent").
# Usage: scripts/speed_ab.sh ROUNDS SPP WIDTH BIN_A BIN_B SCENE...
set -euo pipefail
[ $# -ge 6 ] || { sed -n 2,10p "$0" >&2; exit 2; }
rounds=$1 spp=$2 width=$3 a=$4 b=$5
shift 5
export RAYON_NUM_THREADS=${RAYON_NUM_THREADS:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| scene | A M samples/s | B M samples/s | B/A |"
echo "|---|---:|---:|---:|"
for scene in "$@"; do
  for i in $(seq "$rounds"); do
    for side in a b; do
      bin=$a
      [ "$side" = b ] && bin=$b
      "$bin" render "$scene" -o "$tmp/img.png" --backend cpu --width "$width" --spp "$spp" \
        --stats "$tmp/stats.json" --quiet ${RENDER_ARGS:-} 2>"$tmp/err" || { cat "$tmp/err" >&2; exit 1; }
      python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['samples_per_second'])" \
        "$tmp/stats.json" >> "$tmp/$side"
    done
  done
  python3 - "$scene" "$tmp/a" "$tmp/b" <<'PY'
import statistics, sys, os
a = [float(x) for x in open(sys.argv[2])]
b = [float(x) for x in open(sys.argv[3])]
ma, mb = statistics.median(a), statistics.median(b)
print(f"| {os.path.basename(sys.argv[1])} | {ma / 1e6:.3f} | {mb / 1e6:.3f} | {mb / ma:.3f} |")
PY
  rm -f "$tmp/a" "$tmp/b"
done
