#!/usr/bin/env bash
# Several glint binaries' CPU speed in one run, renders in turn (B1, B2, ...,
# B1, B2, ...) so that the machine's load falls on all alike: per scene the
# median samples/s of the first over ROUNDS renders (the render's own --stats,
# one thread unless RAYON_NUM_THREADS says otherwise) and each other's median
# over it. scripts/speed_ab.sh for two; a second copy of the first binary in
# the list measures the run's own noise (a control). RENDER_ARGS (environment)
# adds arguments to every render.
# Usage: scripts/speed_many.sh ROUNDS SPP WIDTH "BIN1 BIN2 ..." SCENE...
set -euo pipefail
[ $# -ge 5 ] || { sed -n 2,9p "$0" >&2; exit 2; }
rounds=$1 spp=$2 width=$3
read -ra bins <<< "$4"
shift 4
export RAYON_NUM_THREADS=${RAYON_NUM_THREADS:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '| scene | %s M samples/s |' "$(basename "${bins[0]}")"
for b in "${bins[@]:1}"; do printf ' %s / first |' "$(basename "$b")"; done
printf '\n|---|---:|'
for _ in "${bins[@]:1}"; do printf -- '---:|'; done
echo
for scene in "$@"; do
  for _ in $(seq "$rounds"); do
    for k in "${!bins[@]}"; do
      "${bins[$k]}" render "$scene" -o "$tmp/img.png" --backend cpu --width "$width" --spp "$spp" \
        --stats "$tmp/stats.json" --quiet ${RENDER_ARGS:-} 2>"$tmp/err" || { cat "$tmp/err" >&2; exit 1; }
      python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['samples_per_second'])" \
        "$tmp/stats.json" >> "$tmp/$k"
    done
  done
  python3 - "$scene" "$tmp" "${#bins[@]}" <<'PY'
import os, statistics, sys
scene, tmp, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
m = [statistics.median(float(x) for x in open(f"{tmp}/{k}")) for k in range(n)]
print(f"| {os.path.basename(scene)} | {m[0] / 1e6:.3f} | " + " | ".join(f"{x / m[0]:.3f}" for x in m[1:]) + " |")
PY
  rm -f "$tmp"/[0-9]*
done
