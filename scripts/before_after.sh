#!/usr/bin/env bash
# Before/after in one run: the release binary of an earlier commit against this
# tree's, on the same machine in the same session, renders alternating, so the
# machine's load falls on both alike. For every bundled scene both commits have:
#   - a CPU reference from this tree at REF_SPP (cached under the output folder
#     by the after binary's digest),
#   - ROUNDS rounds of: before GPU, after GPU, before CPU, after CPU, each at SPP
#     with the round's seed, timed by the render's own --stats (render seconds,
#     set-up and pipeline compilation excluded),
#   - relMSE of every image against the reference (this tree's `glint diff`, so
#     both are measured alike),
# then prints a markdown table: per scene and backend the median render seconds,
# samples/s ratio, median relMSE and the efficiency ratio at equal error,
#   (relMSE_before * s_before) / (relMSE_after * s_after),
# i.e. how many times faster the after binary reaches the same error. The
# reference's own noise adds to both relMSEs alike, which understates the gain of
# the side with the smaller error.
#
# Usage: scripts/before_after.sh BEFORE_REV [SPP] [WIDTH] [ROUNDS] [REF_SPP]
#   defaults: 64 spp, 64 px wide, 3 rounds, reference 4096 spp; BACKENDS="cpu"
#   (environment) times one backend only (default "gpu cpu"); AFTER_BIN
#   (environment) times that binary as the after side, as it is (say
#   scripts/build.sh's PGO build of this tree), in place of a plain release build.
# Output: target/before-after/ (images, stats, table.md). The earlier commit is
# built in a git worktree under target/before-after/src with its own target dir.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
rev=${1:?usage: scripts/before_after.sh BEFORE_REV [SPP] [WIDTH] [ROUNDS] [REF_SPP]}
spp=${2:-64}; width=${3:-64}; rounds=${4:-3}; ref_spp=${5:-4096}
out=target/before-after
mkdir -p "$out"

if [ -n "${AFTER_BIN:-}" ]; then
  after=$(realpath "$AFTER_BIN")
else
  cargo build --release --locked
  after="$root/target/release/glint"
fi
src="$out/src"
if [ ! -d "$src" ] || [ "$(git -C "$src" rev-parse HEAD 2>/dev/null)" != "$(git rev-parse "$rev^{commit}")" ]; then
  git worktree remove --force "$src" 2>/dev/null || rm -rf "$src"
  git worktree prune
  git worktree add --detach "$src" "$rev"
fi
# The worktree has no target/shaderc of its own (scripts/setup.sh makes it here).
(cd "$src" && SHADERC_LIB_DIR="$root/target/shaderc" CARGO_TARGET_DIR="$root/$out/target" cargo build --release --locked)
before="$root/$out/target/release/glint"

table="$out/table.md"
summary="$out/summary.tsv"
: > "$summary"
header="\`${AFTER_BIN:+AFTER_BIN=$AFTER_BIN }scripts/before_after.sh $rev $spp $width $rounds $ref_spp\`: before = $(git rev-parse --short "$rev"), after = $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo ' with uncommitted changes'), $(date -u +%Y-%m-%d), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg) at the start."

after_digest=$(sha256sum "$after" | cut -c1-12)
for scene in assets/*.gltf assets/*.glb; do
  [ -e "$src/$scene" ] || continue
  name=$(basename "${scene%.*}")
  # Named by the after binary's digest: a reference another build made (say,
  # before a change of a material's colour) would be stale.
  ref="$out/$name-ref-$width-$ref_spp-$after_digest.exr"
  if [ ! -e "$ref" ]; then
    "$after" render "$scene" --width "$width" --spp "$ref_spp" --backend cpu --seed 1000 -o "$ref" 2> /dev/null
  fi
  for r in $(seq 1 "$rounds"); do
    for backend in ${BACKENDS:-gpu cpu}; do
      for side in before after; do
        bin=$before; [ "$side" = after ] && bin=$after
        base="$out/$name-$backend-$side-$r"
        "$bin" render "$scene" --width "$width" --spp "$spp" --backend "$backend" --seed "$r" \
          -o "$base.exr" --stats "$base.json" 2> /dev/null
        "$after" diff "$base.exr" "$ref" --json "$base.diff.json" > /dev/null 2>&1 || true
        python3 - "$base" "$name" "$backend" "$side" >> "$summary" <<'PY'
import json, sys
base, name, backend, side = sys.argv[1:]
s, d = json.load(open(base + ".json")), json.load(open(base + ".diff.json"))
print(name, backend, side, s["render_seconds"], d["relmse"], d["relmse_trim"], sep="\t")
PY
      done
    done
  done
done

python3 - "$summary" "$header" "$rounds" "$ref_spp" > "$table" <<'PY'
import statistics, sys
from collections import defaultdict
summary, header, rounds, ref_spp = sys.argv[1:]
runs = defaultdict(list)
scenes = []
for line in open(summary):
    name, backend, side, s, e, et = line.split("\t")
    if name not in scenes:
        scenes.append(name)
    runs[name, backend, side].append((float(s), float(e), float(et)))
med = lambda k, i: statistics.median(r[i] for r in runs[k])
print(header)
print(f"Medians over {rounds} rounds of each; relMSE against a {ref_spp} spp CPU reference. Efficiency = 1 / (relMSE x render s); "
      "\"after / before\" is how many times sooner the after binary reaches the same error (trimmed: the 0.1% worst pixels dropped).")
print()
print("| scene | backend | render s, before | after | samples/s after / before | relMSE before | after | efficiency after / before | trimmed |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
eff = {}
backends = [b for b in ("gpu", "cpu") if any(k[1] == b for k in runs)]
for name in scenes:
    for backend in backends:
        b, a = (name, backend, "before"), (name, backend, "after")
        sb, sa, eb, ea = med(b, 0), med(a, 0), med(b, 1), med(a, 1)
        tb, ta = med(b, 2), med(a, 2)
        eff[name, backend] = 1 / (ea * sa)
        print(f"| {name} | {backend} | {sb:.3f} | {sa:.3f} | {sb / sa:.2f} | {eb:.3g} | {ea:.3g} | "
              f"{eb * sb / (ea * sa):.2f} | {tb * sb / (ta * sa):.2f} |")
if len(backends) == 2:
    print()
    print("GPU / CPU efficiency of the after binary (above 1: the GPU backend reaches the error sooner):", ", ".join(
        f"{n} {eff[n, 'gpu'] / eff[n, 'cpu']:.2f}" for n in scenes) + ".")
PY
cat "$table"
