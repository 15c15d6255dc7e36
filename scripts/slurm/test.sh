#!/usr/bin/env bash
# End-to-end test of scripts/slurm on a real single-node Slurm cluster
# started here (Debian's slurm-wlm and munge; slurmctld and slurmd run as
# root with state in a temp folder) and stopped on exit:
#   1. render the Cornell box once on this machine (the reference);
#   2. submit.sh: the same render as a 4-task array job + a dependent merge;
#   3. wait for the merge, then check the merged image against the single
#      render: glint diff must agree and every pixel match to 1e-6 relative.
# Installs slurm-wlm and munge when missing (needs root or sudo). GLINT
# names the binary (default target/debug/glint, built if missing).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
t0=$(date +%s)
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
say() { echo "slurm-test: $*" >&2; }

missing=()
for p in slurm-wlm munge; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  say "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

glint=${GLINT:-$root/target/debug/glint}
if [ ! -x "$glint" ]; then
  (cd "$root" && cargo build --locked --bin glint)
fi

tmp=$(mktemp -d /tmp/glint-slurm.XXXXXX)
chmod 755 "$tmp"
host=$(hostname -s)
conf=$tmp/slurm.conf
started_munge=""
cleanup() {
  for d in slurmd slurmctld; do
    [ -f "$tmp/$d.pid" ] && $sudo kill "$(cat "$tmp/$d.pid")" 2>/dev/null || true
  done
  if [ -n "$started_munge" ] && [ -f /run/munge/munged.pid ]; then
    $sudo kill "$(cat /run/munge/munged.pid)" 2>/dev/null || true
  fi
  sleep 1
  $sudo rm -rf "$tmp"
}
trap cleanup EXIT

mkdir -p "$tmp/state" "$tmp/spool"
cat >"$conf" <<CONF
ClusterName=glinttest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=glint Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$conf

if ! pgrep -x munged >/dev/null; then
  $sudo mkdir -p /run/munge
  $sudo chown munge:munge /run/munge
  $sudo runuser -u munge -- /usr/sbin/munged
  started_munge=1
fi
$sudo env SLURM_CONF="$conf" slurmctld -f "$conf"
$sudo env SLURM_CONF="$conf" slurmd -f "$conf"
for _ in $(seq 60); do
  state=$(sinfo -h -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || { say "the node never became idle ($state)"; cat "$tmp"/*.log >&2; exit 1; }
say "cluster up after $(($(date +%s) - t0)) s"

opts=(--backend cpu --width 32 --spp 64 --seed 5)
"$glint" render "$root/assets/cornell.gltf" -o "$tmp/single.exr" --variance --quiet "${opts[@]}"
merge=$(GLINT="$glint" "$root/scripts/slurm/submit.sh" "$root/assets/cornell.gltf" "$tmp/merged.exr" 4 "${opts[@]}")
say "submitted; merge job $merge"
for _ in $(seq 300); do
  [ -z "$(squeue -h 2>/dev/null)" ] && break
  sleep 1
done
if [ ! -f "$tmp/merged.exr" ]; then
  say "no merged image"
  cat "$tmp"/merged.exr.shards/*.log "$tmp/slurmctld.log" >&2 || true
  exit 1
fi
"$glint" diff "$tmp/merged.exr" "$tmp/single.exr" --json "$tmp/diff.json"
worst=$(sed -n 's/.*"max_relative_difference": \([^,]*\),*/\1/p' "$tmp/diff.json")
say "merged vs single: max relative difference per pixel $worst"
awk -v w="$worst" 'BEGIN { exit !(w != "" && w <= 1e-6) }' || { say "FAIL: above 1e-6"; exit 1; }
say "ok in $(($(date +%s) - t0)) s"
