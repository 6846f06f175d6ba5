#!/usr/bin/env bash
# A real single-node Slurm cluster runs a sharded campaign through deploy/slurm/, and the merged
# result equals a local run.
#
#   bash tests/slurm/run.sh [path/to/paracosm-fuzz]
#
# Installs Debian's slurmctld, slurmd, slurm-client and munge when missing, writes a
# configuration into a temporary folder (no cgroups, no accounting: what works in a container
# without systemd), starts munged, slurmctld and slurmd in the foreground (-D) under this shell,
# submits the job array of deploy/slurm/paracosm-array.sbatch for the pedestrian study and the
# merge step that depends on it, waits, and compares the merged results.jsonl with a local run
# (sorted, without wall_ms). Then submits one task again while it still runs (an overlapping
# requeue): the second must be refused by the campaign's lock and the first must finish intact.
# Stops the daemons and deletes the folder at the end. Needs root.
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
fuzz=$(realpath "${1:-target/release/paracosm-fuzz}")
[ -x "$fuzz" ] || { echo "no paracosm-fuzz at $fuzz (build it first)" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || { echo "tests/slurm/run.sh needs root (it starts Slurm's daemons)" >&2; exit 1; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  echo "== installing slurm-wlm and munge"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    slurmctld slurmd slurm-client munge >/dev/null
fi

work=$(mktemp -d /tmp/paracosm-slurm.XXXXXX)
chmod 755 "$work"
pids=()
started_munge=no
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  if [ "$started_munge" = yes ]; then pkill -x munged || true; fi
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

host=$(hostname)
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool" "$work/log" "$work/out"
cat > "$work/slurm.conf" <<CONF
ClusterName=paracosm-test
SlurmctldHost=$host
SlurmUser=root
SlurmctldPort=6917
SlurmdPort=6918
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
MailProg=/bin/true
ReturnToService=2
NodeName=$host CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"

echo "== starting munged, slurmctld, slurmd"
install -d -o munge -g munge /run/munge
if ! pgrep -x munged >/dev/null; then
  runuser -u munge -- /usr/sbin/munged
  started_munge=yes
fi
slurmctld -D -f "$SLURM_CONF" >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$work/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 1 100); do
  state=$(sinfo -h -o %T 2>/dev/null | head -1 || true)
  [ "$state" = "idle" ] && break
  sleep 0.2
done
if [ "$state" != "idle" ]; then
  echo "Slurm did not come up (node state '$state')" >&2
  tail -n 20 "$work"/log/* >&2 || true
  exit 1
fi
echo "node $host is idle"

budget=120
shards=4
args=(--strategy halton --budget "$budget" --seed 3)
out="$work/out"
echo "== submitting a $shards-task array and the merge step"
export PARACOSM_FUZZ="$fuzz"
array=$(sbatch --parsable --wait --array="0-$((shards - 1))" --chdir="$out" \
  --export=ALL "$repo/deploy/slurm/paracosm-array.sbatch" pedestrian-crossing "$out" "${args[@]}")
echo "array job $array finished"
sbatch --parsable --wait --dependency="afterok:${array%%;*}" --chdir="$out" --export=ALL \
  "$repo/deploy/slurm/paracosm-merge.sbatch" "$out" >/dev/null
echo "merge job finished"
cat "$out"/paracosm-merge-*.out

echo "== comparing with a local run"
"$fuzz" pedestrian-crossing "${args[@]}" --out "$work/local" >/dev/null || [ $? -eq 1 ]
strip() { sed 's/,"wall_ms":[^}]*}$//' "$1" | sort; }
if ! diff <(strip "$work/local/results.jsonl") <(strip "$out/merged/results.jsonl") >/dev/null; then
  echo "the merged Slurm campaign differs from the local run" >&2
  exit 1
fi
lines=$(wc -l < "$out/merged/results.jsonl")
[ "$lines" -eq "$budget" ] || { echo "merged $lines results, expected $budget" >&2; exit 1; }
for k in $(seq 0 $((shards - 1))); do
  [ -f "$out/shard-$k/campaign.json" ] || { echo "shard $k missing" >&2; exit 1; }
done
echo "ok: $shards Slurm array tasks + merge = the local run ($lines tests)"

echo "== a requeued task that overlaps its predecessor is refused (one writer per campaign)"
# Task 0 of a one-task array runs a long campaign; while it runs, the same task is submitted
# again (what a requeue that overlaps its predecessor does). The second must exit 2 at once
# with the lock's message, and the first must finish a campaign equal to a local run.
ov="$work/overlap"
mkdir -p "$ov"
long=(--strategy halton --budget 3000 --seed 5)
# One core each (the script asks for two), so that both fit the node at once.
sbatch --parsable --wait --array=0-0 --cpus-per-task=1 --chdir="$ov" --export=ALL \
  "$repo/deploy/slurm/paracosm-array.sbatch" pedestrian-crossing "$ov" "${long[@]}" \
  >"$work/first.id" &
first=$!
for _ in $(seq 1 300); do
  [ -s "$ov/shard-0/results.jsonl" ] && break
  sleep 0.1
done
[ -s "$ov/shard-0/results.jsonl" ] || { echo "the first task never started writing" >&2; exit 1; }
code=0
second=$(sbatch --parsable --wait --array=0-0 --cpus-per-task=1 --chdir="$ov" --export=ALL \
  "$repo/deploy/slurm/paracosm-array.sbatch" pedestrian-crossing "$ov" "${long[@]}") || code=$?
if [ "$code" -eq 0 ]; then
  echo "the overlapping task was accepted (exit $code); jobs:" >&2
  scontrol show job 2>&1 | grep -E "JobId=|StartTime|ExitCode" >&2 || true
  ls "$ov" >&2; tail -n 3 "$ov"/paracosm-*.out >&2 || true
  exit 1
fi
if ! grep -q "is being written by process" "$ov"/paracosm-"${second%%;*}"_0.out; then
  echo "the overlapping task did not name the lock:" >&2
  cat "$ov"/paracosm-"${second%%;*}"_0.out >&2 || true
  exit 1
fi
wait "$first"
"$fuzz" pedestrian-crossing "${long[@]}" --out "$work/local-long" >/dev/null || [ $? -eq 1 ]
if ! diff <(strip "$work/local-long/results.jsonl") <(strip "$ov/shard-0/results.jsonl") >/dev/null; then
  echo "the campaign written beside the refused task differs from a local run" >&2
  exit 1
fi
echo "ok: the overlapping task exited with the lock's message; the first finished intact ($(wc -l < "$ov/shard-0/results.jsonl") tests)"
