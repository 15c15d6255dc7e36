#!/usr/bin/env bash
# Render SCENE over a Slurm cluster in N shards and merge them:
#   scripts/slurm/submit.sh SCENE OUT.exr N [render options...]
# e.g. scripts/slurm/submit.sh assets/cornell.gltf cornell.exr 16 --spp 4096 --width 1024
# Submits an array job (one task per shard, shard.sbatch) and a merge job
# (merge.sbatch) that runs once every shard succeeded; prints the merge
# job's id. GLINT (default: glint on PATH) must be reachable on every node,
# and OUT's folder (holding OUT.shards/) shared between them.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE OUT.exr N [render options...]" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$1"); out=$(realpath -m "$2"); n=$3; shift 3
case $n in ''|*[!0-9]*|0) echo "$0: N must be a positive integer, not '$n'" >&2; exit 2;; esac
glint=$(command -v "${GLINT:-glint}") || { echo "$0: no glint binary (set GLINT)" >&2; exit 2; }
shard_dir="$out.shards"
mkdir -p "$shard_dir"
export GLINT="$glint" SCENE="$scene" SHARD_DIR="$shard_dir" SHARDS="$n" OUTPUT="$out" GLINT_ARGS="$*"
array=$(sbatch --parsable --export=ALL --array="0-$((n - 1))" \
  --output="$shard_dir/shard-%a.log" "$here/shard.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --export=ALL --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$shard_dir/merge.log" "$here/merge.sbatch")
echo "${merge%%;*}"
