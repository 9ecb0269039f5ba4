/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * comm.h - the ranks of a distributed run, and the only calls to MPI
 * (src/base/comm.c; with MPI=0 every function is the one-rank case).
 *
 * sandslide decomposes a grid into slabs of whole tile rows, one per rank,
 * in rank order from the south (stepper.h).  What crosses a rank edge:
 *   - halo rows, exchanged after the x sides are filled, so that corner
 *     ghosts come along (a corner takes the y side's rule, boundary.h);
 *   - the wake flags of the edge tile rows (sweep.h);
 *   - maxima (NaN counted as +infinity, so a NaN on any rank wins on every
 *     rank) and sums of integer-valued doubles, which are exact in any
 *     order, in one reduction per stencil evaluation;
 *   - ordered folds: a floating-point sum is carried from rank to rank in
 *     rank order and continued with the very additions the one-rank code
 *     makes, so the total has the same bits for any rank count.
 * Every rank takes every decision (a steady state, a NaN, a stop signal)
 * from reduced values, at the same substep.
 *
 * Errors: a rank that fails keeps its message (error.c prints on rank 0
 * only); ss_comm_agree, called by every rank before the next collective
 * call, tells every rank the first failure and has rank 0 print its
 * message.  None of these functions fails: an MPI error aborts the job
 * (MPI's default handler).
 */
#ifndef SANDSLIDE_COMM_H
#define SANDSLIDE_COMM_H

#include <stddef.h>

/* Start MPI (threads funnelled to the main thread) or nothing; call once,
 * first thing in main.  Started without a launcher (mpirun, srun) an MPI
 * build runs as one rank and does not initialise MPI at all. */
void ss_comm_init(int *argc, char ***argv);
/* Leave MPI (after every HDF5 file is closed). */
void ss_comm_finalize(void);
/* End every rank of the job now with this exit status (a signal handler
 * or a failure that cannot be agreed). */
_Noreturn void ss_comm_abort(int status);

int ss_comm_rank(void);
int ss_comm_size(void);
/* Ranks on this node (1 without MPI): --threads defaults to the node's
 * processors divided by it. */
int ss_comm_node_ranks(void);
/* "Open MPI v4.1.4, ..." (the first line of MPI_Get_library_version), or
 * NULL in a build without MPI. */
const char *ss_comm_library(void);

/* This rank's part of `items` (tile rows) split into ss_comm_size() parts:
 * [*first, *first + *count), the first ranks taking one more when the
 * split is uneven.  A rank may get none when items < ranks. */
void ss_comm_split(long long items, long long *first, long long *count);

/* Ranks holding the slab south and north of this one, or -1 for none:
 * with periodic, rank 0 and the last rank are each other's neighbours
 * (with one rank, none: the halo fill copies within the block). */
void ss_comm_neighbours(int periodic, int *south, int *north);

/*
 * Halo exchange of one row each way: send_south (bytes) to the south
 * neighbour while receiving its row into recv_south, and likewise north.
 * A neighbour of -1 is skipped (its buffers are not touched).
 */
void ss_comm_exchange(int south, int north, const void *send_south, void *recv_south,
                      const void *send_north, void *recv_north, size_t bytes);

/*
 * One reduction over every rank: max[0 .. n_max - 1] become their maxima
 * (a NaN anywhere becomes +infinity everywhere) and sum[0 .. n_sum - 1]
 * their sums, which must be integer-valued (below 2^53) so that any order
 * gives the same bits.  n_max, n_sum <= SS_COMM_REDUCE_MAX.
 */
#define SS_COMM_REDUCE_MAX 4
void ss_comm_reduce(double *max, int n_max, double *sum, int n_sum);

/*
 * An ordered fold of n running sums over the ranks: ss_comm_fold_start
 * gives this rank the values the ranks south of it reached (rank 0: it
 * leaves `running` as the caller set it, the start), the caller continues
 * them over its own part in order, and ss_comm_fold_finish passes them on
 * and gives every rank the totals of the last rank.  Every rank calls both.
 */
void ss_comm_fold_start(double *running, int n);
void ss_comm_fold_finish(double *running, int n);

/* Gather the rows of the ranks into `all` on rank 0, in rank order:
 * `bytes` from each rank (which may differ); `all` may be NULL elsewhere. */
void ss_comm_gather_rows(const void *mine, size_t bytes, void *all);

/* Seconds this rank has spent in the calls above (waiting for the other
 * ranks included): the communication share of a run. */
double ss_comm_seconds(void);

/* bytes of buf from rank `from` to rank `to` (the two call it; a rank
 * that is neither returns at once, and from == to does nothing): rows
 * streamed to the rank that writes a file. */
void ss_comm_relay(void *buf, size_t bytes, int from, int to);

/* The part of `items` that ss_comm_split gives rank `rank`. */
void ss_comm_split_of(long long items, int rank, long long *first, long long *count);

/* bytes of buf from rank `root` to every rank. */
void ss_comm_broadcast(void *buf, size_t bytes, int root);
void ss_comm_barrier(void);

/* The first failure of any rank (in rank order), agreed by all: status
 * SS_OK everywhere, or the status of the first rank that failed, whose
 * message rank 0 prints if it did not fail itself.  Collective. */
int ss_comm_agree(int status);

#endif
