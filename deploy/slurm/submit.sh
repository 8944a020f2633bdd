#!/bin/bash
# Submits the shard array, then the merge to run once every array task has succeeded.
# Arguments are sbatch options for both jobs, and beat their #SBATCH lines: e.g. --partition=P
# or --account=A, or --gres=none --cpus-per-task=1 on a node without a GPU (tests/slurm.rs).
# Prints the ids of the array and of the merge.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
array=$(sbatch --parsable "$@" "$here/render.sbatch")
merge=$(sbatch --parsable "$@" --dependency=afterok:"${array%%;*}" "$here/merge.sbatch")
echo "array ${array%%;*} merge ${merge%%;*}"
