#!/bin/bash
# Submits the shard array, then the merge to run once every array task has succeeded.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
array=$(sbatch --parsable "$here/render.sbatch")
sbatch --dependency=afterok:"${array%%;*}" "$here/merge.sbatch"
