/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * comm_mpi.h - the communicator itself, for the parallel HDF5 file access
 * of the snapshot writer and reader (make MPI=1 only).
 */
#ifndef SANDSLIDE_BASE_COMM_MPI_H
#define SANDSLIDE_BASE_COMM_MPI_H

#ifdef SS_HAVE_MPI
#include <mpi.h>

/* The communicator of every rank of the run (comm.h). */
MPI_Comm ss_comm_mpi(void);
#endif

#endif
