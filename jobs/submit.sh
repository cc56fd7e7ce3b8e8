#!/usr/bin/env bash
# Submit the build step, then the sweeps after it (Slurm --dependency=afterok): no task
# compiles, so a first submission has no compile race.
#
#   bash jobs/submit.sh          the job array (jobs/sweep_array.slurm)
#   bash jobs/submit.sh mpi      the MPI sweep (jobs/sweep_mpi.slurm), built with mpifort
set -euo pipefail
cd "$(dirname "$0")/.."
what=${1:-array}
case "$what" in
    array) build=$(sbatch --parsable jobs/build.slurm)
           sbatch --dependency=afterok:"$build" jobs/sweep_array.slurm ;;
    mpi)   build=$(sbatch --parsable --export=ALL,CONMECH_MPI=1 jobs/build.slurm)
           sbatch --dependency=afterok:"$build" jobs/sweep_mpi.slurm ;;
    *) echo "usage: bash jobs/submit.sh [array|mpi]" >&2; exit 2 ;;
esac
