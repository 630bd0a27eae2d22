#!/usr/bin/env bash
# Tests splitray on a real Slurm cluster: starts a one-node cluster on localhost
# (munged, slurmctld, slurmd), submits tools/slurm/render-array.sbatch (a 4-task array of
# a small render and the merge job that depends on it), waits for both, checks the merged
# image against a single-process render of the same samples, and stops what it started.
#
#   tools/slurm/test-local-cluster.sh [SPLITRAY_BINARY]     (as root; `make slurm-test`)
#
# Debian 12's Slurm 22.05 runs here without systemd or cgroups: process tracking by
# /proc (proctrack/linuxproc), no task plugin, no accounting. munged runs as the munge
# user with its socket in /run/munge (created here when missing); every client command
# reads the cluster's configuration from SLURM_CONF. The daemons are started in the
# foreground as background jobs of this script, so it knows their PIDs and stops only
# them; a munged already running is used and left alone. Everything else lives in a
# temporary folder, removed at the end.
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)
splitray=$(realpath "${1:-$repo/target/ci/splitray}")
[ -x "$splitray" ] || { echo "slurm-test: no splitray binary at $splitray" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || { echo "slurm-test: run as root (it starts daemons)" >&2; exit 1; }
start=$(date +%s%N)
elapsed() {
  local ms=$(( ($(date +%s%N) - start) / 1000000 ))
  printf '%d.%d' $((ms / 1000)) $((ms % 1000 / 100))
}

bash "$repo/tools/slurm/install.sh"
echo "slurm-test: packages ready after $(elapsed) s"

work=$(mktemp -d /tmp/splitray-slurm.XXXXXX)
chmod 755 "$work"
started=()
stop_cluster() {
  local status=$?
  for pid in "${started[@]}"; do
    kill -TERM "$pid" 2>/dev/null || true
  done
  for pid in "${started[@]}"; do
    # Daemons end within seconds of SIGTERM; wait for each so none outlives the test.
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
  if [ $status -ne 0 ]; then
    for log in "$work"/*.log "$work"/out/*.log; do
      [ -f "$log" ] && { echo "--- $log"; tail -n 20 "$log"; }
    done
  fi
  rm -rf "$work"
  exit $status
}
trap stop_cluster EXIT

# munge: the key comes with the package; the socket folder lives in /run (a tmpfs that
# nothing created when the machine has no systemd).
if ! pgrep -x munged >/dev/null; then
  install -d -o munge -g munge -m 0755 /run/munge
  setpriv --reuid=munge --regid=munge --init-groups /usr/sbin/munged --foreground \
    >"$work/munged.log" 2>&1 &
  started+=($!)
  for _ in $(seq 50); do [ -S /run/munge/munge.socket.2 ] && break; sleep 0.1; done
fi
munge -n | unmunge >/dev/null

host=$(hostname -s)
mkdir -p "$work/state" "$work/spool" "$work/out"
cat >"$work/slurm.conf" <<CONF
ClusterName=splitray-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
/usr/sbin/slurmctld -D -f "$SLURM_CONF" >>"$work/slurmctld.log" 2>&1 &
started+=($!)
/usr/sbin/slurmd -D -f "$SLURM_CONF" >>"$work/slurmd.log" 2>&1 &
started+=($!)
for _ in $(seq 150); do
  sinfo -h -N -o '%T' 2>/dev/null | grep -qx idle && break
  sleep 0.2
done
sinfo -h -N -o '%T' | grep -qx idle || { echo "slurm-test: the node never became idle" >&2; exit 1; }
echo "slurm-test: cluster up after $(elapsed) s ($(sinfo -V), node $host, $(nproc) CPUs)"

film=(--integrator pt --width 32 --height 24 --spp 8)
render=("${film[@]}" --seed 3)
cd "$work"
read -r array merge < <(SHARDS=4 SPLITRAY=$splitray \
  bash "$repo/tools/slurm/render-array.sbatch" submit out cornell-box "${render[@]}")
echo "slurm-test: submitted array job $array (4 tasks) and merge job $merge"
deadline=$(( $(date +%s) + 180 ))
while squeue -h -j "$array,$merge" 2>/dev/null | grep -q .; do
  [ "$(date +%s)" -lt "$deadline" ] || { scancel "$array" "$merge"; echo "slurm-test: jobs still queued after 180 s" >&2; exit 1; }
  sleep 0.5
done
for job in "$array" "$merge"; do
  state=$(scontrol show job "$job" | grep -o 'JobState=[A-Z_]*' | sort -u | tr '\n' ' ')
  echo "slurm-test: job $job: $state"
  [ "$state" = "JobState=COMPLETED " ] || { echo "slurm-test: job $job did not complete" >&2; exit 1; }
done
cat out/merge-*.log

# The merged image holds the samples of one 8-pass render: a single-process render of
# them, with the merged image as its reference, differs only by the rounding of f32
# film sums (relative MSE ≲ (2·8·2⁻²⁴)² ≈ 1e-12).
"$splitray" render cornell-box "${render[@]}" -o single.exr --reference out/merged.exr \
  --stats single.json >/dev/null
mse=$(grep -o '"relative_mse": [^,]*' single.json | cut -d' ' -f2)
echo "slurm-test: relative MSE of a single-process render against the merged image: $mse"
awk -v m="$mse" 'BEGIN { exit !(m < 1e-10) }' || { echo "slurm-test: merged image differs" >&2; exit 1; }
# The check can fail: another seed's samples differ by the noise (relative MSE ~1e-2).
"$splitray" render cornell-box "${film[@]}" --seed 4 -o other.exr \
  --reference out/merged.exr --stats other.json >/dev/null
other=$(grep -o '"relative_mse": [^,]*' other.json | cut -d' ' -f2)
echo "slurm-test: and of a render of another seed: $other"
awk -v m="$other" 'BEGIN { exit !(m > 1e-4) }' || { echo "slurm-test: the check cannot tell images apart" >&2; exit 1; }
grep -q 'merged 4 parts: 32x24 8 spp (passes 0..8)' out/merge-*.log
echo "slurm-test: passed in $(elapsed) s"
