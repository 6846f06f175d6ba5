#!/usr/bin/env bash
# Submits a sharded paracosm campaign to Slurm: an array of SHARDS tasks, then a merge step
# that starts when every task succeeded. Prints the two job ids.
#
#   deploy/slurm/submit.sh SHARDS SCENARIO OUT [paracosm-fuzz options]
#   deploy/slurm/submit.sh 8 pedestrian-crossing /shared/runs/ped --strategy halton --budget 20000
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
shards=${1:?usage: submit.sh SHARDS SCENARIO OUT [options]}
scenario=${2:?usage: submit.sh SHARDS SCENARIO OUT [options]}
out=${3:?usage: submit.sh SHARDS SCENARIO OUT [options]}
shift 3
mkdir -p "$out"
array=$(sbatch --parsable --array="0-$((shards - 1))" --chdir="$out" \
  "$here/paracosm-array.sbatch" "$scenario" "$out" "$@")
merge=$(sbatch --parsable --dependency="afterok:${array%%;*}" --chdir="$out" \
  "$here/paracosm-merge.sbatch" "$out")
echo "array job $array, merge job $merge"
