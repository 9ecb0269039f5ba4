#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# The Slurm job of doc/cluster.md#slurm as CI runs it on one node
# (tests/slurm/run.sh submits it with sbatch --wait, twice: 2 tasks of 1
# CPU, and 1 task of 2 CPUs, the options on sbatch's command line
# overriding these).  One rank per task, the task's CPUs as threads.
# SANDSLIDE_MPI is the MPI build, exported to the job by sbatch; dem.asc
# is in the job's folder.  --max-time keeps it to a second: the DEM is
# not relaxed by then, and the bits of every snapshot are still compared.
#SBATCH --nodes=1 --ntasks=2 --cpus-per-task=1 --time=00:05:00
set -eu
export OMP_NUM_THREADS=$SLURM_CPUS_PER_TASK
srun --mpi=pmix "$SANDSLIDE_MPI" relax dem.asc -o relaxed.h5 --threads "$SLURM_CPUS_PER_TASK" \
	--max-time 2000
