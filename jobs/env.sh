# The environment of conmech's job scripts (sourced by jobs/*.slurm): adapt it to your
# cluster once.
#
# 1. Modules: the compiler (and MPI) the programs are built and run with. Set
#    CONMECH_MODULES, or replace the line below, e.g.
#        module load GCC/12.3.0 OpenMPI/4.1.5        (EasyBuild names)
#        module load gcc/12 openmpi/4                 (other sites)
#    A module that cannot be loaded stops the job (better than a build with the wrong
#    compiler).
if [ -n "${CONMECH_MODULES:-}" ]; then
    module load ${CONMECH_MODULES}
fi
# 2. fpm, for the build step, comes from the project's virtual environment (made by
#    `bash scripts/setup.sh`, or any environment with `pip install fpm`).
if [ -f .venv/bin/activate ]; then
    # shellcheck disable=SC1091
    source .venv/bin/activate
fi
