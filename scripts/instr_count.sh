#!/usr/bin/env bash
# Instructions per sample of the CPU backend, counted by valgrind's callgrind:
# a deterministic measure of the sampling work, for changes too small for
# wall-clock timing to see (scripts/speed_ab.sh's run-to-run noise is 2-5%).
# On this project's machines the CPU path runs at about 3 instructions per
# cycle, so its time follows its instruction count, though not one for one:
# the instructions the eighth session removed (mostly moves and predictable
# branches) saved about half as much time (docs/benchmarks.md, "Instructions
# per sample"). speed_ab.sh confirms the larger changes.
#
# Only what runs inside `trace_wave` is counted (camera rays, traversal,
# shading, light and BSDF sampling, the Sobol numbers: every sample's work);
# set-up, BVH build, film accumulation and image output are not. One thread,
# the same seed and sample count for every binary, so two binaries that make
# the same image count the same paths.
#
# Usage: scripts/instr_count.sh BIN_A [BIN_B] -- SCENE...
#   WIDTH (default 16) and SPP (default 64) set the render (64 spp: the
#   per-pixel work, such as the Sobol keys, shares out as in a real render;
#   at 16 px a pixel's camera rays are far less alike than at the 128 px
#   that speed_ab.sh and before_after.sh time, so camera packets count up
#   to three times their share there: WIDTH=128 SPP=8 counts them as timed);
#   prints a markdown table of instructions per sample and B / A. PARTS=1
#   (environment) adds, per scene, where a sample's instructions go
#   (scripts/instr_parts.py: traversal by query, light sampling, the Sobol
#   numbers, the BSDFs kept out of line, the shading frame, textures, and
#   the rest of trace_wave).
set -euo pipefail
shopt -s inherit_errexit
command -v valgrind > /dev/null || { echo "instr_count.sh: valgrind is not installed (apt-get install valgrind)" >&2; exit 1; }
bins=() names=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do bins+=("$(realpath "$1")"); names+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
[ ${#bins[@]} -ge 1 ] && [ $# -ge 1 ] || { echo "usage: scripts/instr_count.sh BIN_A [BIN_B] -- SCENE..." >&2; exit 2; }
width=${WIDTH:-16}; spp=${SPP:-64}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
profile() { echo "$tmp/cg${1//\//_}-$(basename "$2").out"; }

count() { # binary scene -> instructions per sample (the profile kept for PARTS)
  local out stats
  out=$(profile "$1" "$2") stats="$tmp/stats-$(basename "$2").json"
  RAYON_NUM_THREADS=1 valgrind --tool=callgrind --toggle-collect='*trace_wave*' \
    --callgrind-out-file="$out" "$1" render "$2" -o "$tmp/img.exr" --backend cpu \
    --width "$width" --spp "$spp" --quiet --stats "$stats" 2> "$tmp/err" \
    || { echo "instr_count.sh: $1 did not render $2: $(grep -v '^==' "$tmp/err" | tail -1)" >&2; return 1; }
  python3 - "$out" "$stats" << 'EOF'
import json, sys
ir = next(int(l.split()[1]) for l in open(sys.argv[1]) if l.startswith(("summary:", "totals:")))
print(f"{ir / json.load(open(sys.argv[2]))['samples']:.0f}")
EOF
}

echo "\`WIDTH=$width SPP=$spp scripts/instr_count.sh ${names[*]} -- $*\` (instructions per sample inside trace_wave, one thread)"
echo
if [ ${#bins[@]} -eq 2 ]; then
  echo "| scene | A | B | B / A |"; echo "|---|---:|---:|---:|"
else
  echo "| scene | instructions per sample |"; echo "|---|---:|"
fi
for scene in "$@"; do
  name=$(basename "${scene%.*}")
  a=$(count "${bins[0]}" "$scene")
  if [ ${#bins[@]} -eq 2 ]; then
    b=$(count "${bins[1]}" "$scene")
    echo "| $name | $a | $b | $(python3 -c "print(f'{$b / $a:.3f}')") |"
  else
    echo "| $name | $a |"
  fi
done

if [ "${PARTS:-0}" = 1 ]; then
  here=$(dirname "$0")
  for scene in "$@"; do
    stats="$tmp/stats-$(basename "$scene").json"
    printf '\n%s, instructions per sample by part:\n\n' "$(basename "${scene%.*}")"
    if [ ${#bins[@]} -eq 2 ]; then
      echo "| part | A | B |"; echo "|---|---:|---:|"
      paste <(python3 "$here/instr_parts.py" "$(profile "${bins[0]}" "$scene")" "$stats") \
        <(python3 "$here/instr_parts.py" "$(profile "${bins[1]}" "$scene")" "$stats" | cut -f2) \
        | awk -F'\t' '{print "| " $1 " | " $2 " | " $3 " |"}'
    else
      echo "| part | instructions per sample |"; echo "|---|---:|"
      python3 "$here/instr_parts.py" "$(profile "${bins[0]}" "$scene")" "$stats" \
        | awk -F'\t' '{print "| " $1 " | " $2 " |"}'
    fi
  done
fi
