/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * comm.c - the ranks of a distributed run (see comm.h).  The only file
 * that calls MPI; built with MPI when SS_HAVE_MPI is defined (make MPI=1),
 * else every function is the one-rank case.
 */
#include "sandslide/comm.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/parallel.h"

/* Seconds spent in MPI calls (waiting for other ranks included). */
static double comm_seconds;

double ss_comm_seconds(void)
{
	return comm_seconds;
}

#ifdef SS_HAVE_MPI
#include <mpi.h>

#include "base/comm_mpi.h"

static int comm_rank, comm_size = 1, node_ranks = 1, started;
static char library[MPI_MAX_LIBRARY_VERSION_STRING];
static MPI_Op reduce_op;
static MPI_Datatype reduce_type;

/* The reduction's operand: maxima, then integer-valued sums. */
struct reduce_block {
	double max[SS_COMM_REDUCE_MAX];
	double sum[SS_COMM_REDUCE_MAX];
};

static void reduce_blocks(void *in, void *inout, int *len, MPI_Datatype *type)
{
	(void)type;
	const struct reduce_block *a = in;
	struct reduce_block *b = inout;
	for (int n = 0; n < *len; n++) {
		for (int k = 0; k < SS_COMM_REDUCE_MAX; k++) {
			/* NaN was made +infinity before: a plain max is exact */
			b[n].max[k] = a[n].max[k] > b[n].max[k] ? a[n].max[k] : b[n].max[k];
			b[n].sum[k] += a[n].sum[k];
		}
	}
}

MPI_Comm ss_comm_mpi(void)
{
	return MPI_COMM_WORLD;
}

/* Whether a launcher (mpirun, srun) started this process: Open MPI's
 * mpirun sets OMPI_COMM_WORLD_SIZE, PMIx launchers PMIX_RANK, PMI-1/2 ones
 * (MPICH's hydra, Slurm's srun --mpi=pmi2) PMI_RANK. */
static int launched(void)
{
	static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"};
	for (size_t k = 0; k < sizeof vars / sizeof *vars; k++)
		if (getenv(vars[k]))
			return 1;
	return 0;
}

void ss_comm_init(int *argc, char ***argv)
{
	int len = 0;
	MPI_Get_library_version(library, &len);   /* allowed before MPI_Init */
	library[strcspn(library, "\n,")] = '\0';
	/* Started without a launcher: one rank, and no MPI_Init, which as a
	 * singleton would start Open MPI's orted from PATH and write its
	 * shared-memory files (failing under a small ulimit -f); the
	 * one-rank paths never call MPI. */
	if (!launched())
		return;
	int provided;
	MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
	started = 1;
	MPI_Comm_rank(MPI_COMM_WORLD, &comm_rank);
	MPI_Comm_size(MPI_COMM_WORLD, &comm_size);
	MPI_Comm node;
	MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, comm_rank, MPI_INFO_NULL,
	                    &node);
	MPI_Comm_size(node, &node_ranks);
	MPI_Comm_free(&node);
	MPI_Type_contiguous(2 * SS_COMM_REDUCE_MAX, MPI_DOUBLE, &reduce_type);
	MPI_Type_commit(&reduce_type);
	MPI_Op_create(reduce_blocks, 1, &reduce_op);
}

void ss_comm_finalize(void)
{
	if (!started)
		return;
	MPI_Op_free(&reduce_op);
	MPI_Type_free(&reduce_type);
	MPI_Finalize();
	started = 0;
}

_Noreturn void ss_comm_abort(int status)
{
	if (started && comm_size > 1)
		MPI_Abort(MPI_COMM_WORLD, status);
	exit(status);
}

int ss_comm_rank(void)
{
	return comm_rank;
}

int ss_comm_size(void)
{
	return comm_size;
}

int ss_comm_node_ranks(void)
{
	return node_ranks;
}

const char *ss_comm_library(void)
{
	return library[0] ? library : "MPI";
}

static void exchange(int south, int north, const void *send_south, void *recv_south,
                     const void *send_north, void *recv_north, size_t bytes)
{
	if (comm_size == 1)
		return;
	/* rows of up to a few MB: one message each (a count is an int) */
	if (bytes > (size_t)INT32_MAX)
		SS_BUG("a halo row of %zu bytes", bytes);
	const int n = (int)bytes;
	MPI_Request req[4];
	int r = 0;
	/* tags: 1 travels north, 2 travels south */
	if (south >= 0) {
		MPI_Irecv(recv_south, n, MPI_BYTE, south, 1, MPI_COMM_WORLD, &req[r++]);
		MPI_Isend(send_south, n, MPI_BYTE, south, 2, MPI_COMM_WORLD, &req[r++]);
	}
	if (north >= 0) {
		MPI_Irecv(recv_north, n, MPI_BYTE, north, 2, MPI_COMM_WORLD, &req[r++]);
		MPI_Isend(send_north, n, MPI_BYTE, north, 1, MPI_COMM_WORLD, &req[r++]);
	}
	MPI_Waitall(r, req, MPI_STATUSES_IGNORE);
}

static void reduce(double *max, int n_max, double *sum, int n_sum)
{
	if (n_max > SS_COMM_REDUCE_MAX || n_sum > SS_COMM_REDUCE_MAX)
		SS_BUG("ss_comm_reduce of %d maxima and %d sums", n_max, n_sum);
	for (int k = 0; k < n_max; k++)
		if (isnan(max[k]))
			max[k] = INFINITY;
	if (comm_size == 1)
		return;
	struct reduce_block b;
	for (int k = 0; k < SS_COMM_REDUCE_MAX; k++) {
		b.max[k] = k < n_max ? max[k] : -INFINITY;
		b.sum[k] = k < n_sum ? sum[k] : 0.0;
	}
	MPI_Allreduce(MPI_IN_PLACE, &b, 1, reduce_type, reduce_op, MPI_COMM_WORLD);
	/* max or sum may be NULL with a count of 0, which memcpy may not get */
	if (n_max > 0)
		memcpy(max, b.max, (size_t)n_max * sizeof *max);
	if (n_sum > 0)
		memcpy(sum, b.sum, (size_t)n_sum * sizeof *sum);
}

static void fold_start(double *running, int n)
{
	if (comm_size > 1 && comm_rank > 0)
		MPI_Recv(running, n, MPI_DOUBLE, comm_rank - 1, 3, MPI_COMM_WORLD,
		         MPI_STATUS_IGNORE);
}

static void fold_finish(double *running, int n)
{
	if (comm_size == 1)
		return;
	if (comm_rank + 1 < comm_size)
		MPI_Send(running, n, MPI_DOUBLE, comm_rank + 1, 3, MPI_COMM_WORLD);
	MPI_Bcast(running, n, MPI_DOUBLE, comm_size - 1, MPI_COMM_WORLD);
}

static void gather_rows(const void *mine, size_t bytes, void *all)
{
	/* in pieces of at most 1 GiB: an MPI count is an int */
	const size_t piece = (size_t)1 << 30;
	if (comm_rank != 0) {
		for (size_t at = 0; at < bytes; at += piece) {
			const size_t n = bytes - at < piece ? bytes - at : piece;
			MPI_Send((const char *)mine + at, (int)n, MPI_BYTE, 0, 4, MPI_COMM_WORLD);
		}
		unsigned long long b = bytes;
		MPI_Send(&b, 1, MPI_UNSIGNED_LONG_LONG, 0, 5, MPI_COMM_WORLD);
		return;
	}
	char *out = all;
	if (out != mine)
		memmove(out, mine, bytes);
	out += bytes;
	for (int r = 1; r < comm_size; r++) {
		/* the sender's size first is not known: probe each piece */
		for (;;) {
			MPI_Status st;
			MPI_Probe(r, MPI_ANY_TAG, MPI_COMM_WORLD, &st);
			if (st.MPI_TAG == 5) {
				unsigned long long b;
				MPI_Recv(&b, 1, MPI_UNSIGNED_LONG_LONG, r, 5, MPI_COMM_WORLD,
				         MPI_STATUS_IGNORE);
				break;
			}
			int n;
			MPI_Get_count(&st, MPI_BYTE, &n);
			MPI_Recv(out, n, MPI_BYTE, r, 4, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
			out += n;
		}
	}
}

static void broadcast(void *buf, size_t bytes, int root)
{
	if (comm_size == 1)
		return;
	const size_t piece = (size_t)1 << 30;
	for (size_t at = 0; at < bytes; at += piece) {
		const size_t n = bytes - at < piece ? bytes - at : piece;
		MPI_Bcast((char *)buf + at, (int)n, MPI_BYTE, root, MPI_COMM_WORLD);
	}
}

void ss_comm_barrier(void)
{
	if (comm_size > 1)
		MPI_Barrier(MPI_COMM_WORLD);
}

static void relay(void *buf, size_t bytes, int from, int to)
{
	if (from == to || (comm_rank != from && comm_rank != to))
		return;
	const size_t piece = (size_t)1 << 30;   /* an MPI count is an int */
	for (size_t at = 0; at < bytes; at += piece) {
		const int n = (int)(bytes - at < piece ? bytes - at : piece);
		if (comm_rank == from)
			MPI_Send((char *)buf + at, n, MPI_BYTE, to, 7, MPI_COMM_WORLD);
		else
			MPI_Recv((char *)buf + at, n, MPI_BYTE, from, 7, MPI_COMM_WORLD,
			         MPI_STATUS_IGNORE);
	}
}

static int agree(int status)
{
	if (comm_size == 1)
		return status;
	/* the first failing rank, and its status and message */
	int mine = status != SS_OK ? comm_rank : comm_size, first;
	MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
	if (first == comm_size)
		return SS_OK;
	int agreed = status;
	MPI_Bcast(&agreed, 1, MPI_INT, first, MPI_COMM_WORLD);
	if (first != 0) {
		char message[SS_ERROR_MESSAGE_MAX];
		if (comm_rank == first) {
			snprintf(message, sizeof message, "%s", ss_error_last_message());
			MPI_Send(message, (int)sizeof message, MPI_CHAR, 0, 6, MPI_COMM_WORLD);
		} else if (comm_rank == 0) {
			MPI_Recv(message, (int)sizeof message, MPI_CHAR, first, 6, MPI_COMM_WORLD,
			         MPI_STATUS_IGNORE);
			if (message[0])
				ss_error_print(message);
		}
	}
	return agreed;
}

/* The calls above, timed (ss_comm_seconds). */
#define TIMED(call)                                                   \
	do {                                                          \
		const double t0_ = ss_parallel_wall_seconds();        \
		call;                                                 \
		comm_seconds += ss_parallel_wall_seconds() - t0_;     \
	} while (0)

void ss_comm_exchange(int south, int north, const void *send_south, void *recv_south,
                      const void *send_north, void *recv_north, size_t bytes)
{
	TIMED(exchange(south, north, send_south, recv_south, send_north, recv_north, bytes));
}

void ss_comm_reduce(double *max, int n_max, double *sum, int n_sum)
{
	TIMED(reduce(max, n_max, sum, n_sum));
}

void ss_comm_fold_start(double *running, int n)
{
	TIMED(fold_start(running, n));
}

void ss_comm_fold_finish(double *running, int n)
{
	TIMED(fold_finish(running, n));
}

void ss_comm_gather_rows(const void *mine, size_t bytes, void *all)
{
	TIMED(gather_rows(mine, bytes, all));
}

void ss_comm_broadcast(void *buf, size_t bytes, int root)
{
	TIMED(broadcast(buf, bytes, root));
}

void ss_comm_relay(void *buf, size_t bytes, int from, int to)
{
	TIMED(relay(buf, bytes, from, to));
}

int ss_comm_agree(int status)
{
	int agreed;
	TIMED(agreed = agree(status));
	return agreed;
}

#else /* one rank */

void ss_comm_init(int *argc, char ***argv)
{
	(void)argc;
	(void)argv;
}

void ss_comm_finalize(void)
{
}

_Noreturn void ss_comm_abort(int status)
{
	exit(status);
}

int ss_comm_rank(void)
{
	return 0;
}

int ss_comm_size(void)
{
	return 1;
}

int ss_comm_node_ranks(void)
{
	return 1;
}

const char *ss_comm_library(void)
{
	return NULL;
}

void ss_comm_exchange(int south, int north, const void *send_south, void *recv_south,
                      const void *send_north, void *recv_north, size_t bytes)
{
	(void)south, (void)north, (void)send_south, (void)recv_south;
	(void)send_north, (void)recv_north, (void)bytes;
}

void ss_comm_reduce(double *max, int n_max, double *sum, int n_sum)
{
	(void)sum, (void)n_sum;
	for (int k = 0; k < n_max; k++)
		if (isnan(max[k]))
			max[k] = INFINITY;
}

void ss_comm_fold_start(double *running, int n)
{
	(void)running, (void)n;
}

void ss_comm_fold_finish(double *running, int n)
{
	(void)running, (void)n;
}

void ss_comm_gather_rows(const void *mine, size_t bytes, void *all)
{
	if (all != mine)
		memmove(all, mine, bytes);
}

void ss_comm_broadcast(void *buf, size_t bytes, int root)
{
	(void)buf, (void)bytes, (void)root;
}

void ss_comm_relay(void *buf, size_t bytes, int from, int to)
{
	(void)buf, (void)bytes, (void)from, (void)to;   /* one rank: from == to */
}

void ss_comm_barrier(void)
{
}

int ss_comm_agree(int status)
{
	return status;
}

#endif

void ss_comm_split_of(long long items, int rank, long long *first, long long *count)
{
	const long long p = ss_comm_size(), r = rank;
	const long long base = items / p, extra = items % p;
	*count = base + (r < extra ? 1 : 0);
	*first = r * base + (r < extra ? r : extra);
}

void ss_comm_split(long long items, long long *first, long long *count)
{
	ss_comm_split_of(items, ss_comm_rank(), first, count);
}

void ss_comm_neighbours(int periodic, int *south, int *north)
{
	const int p = ss_comm_size(), r = ss_comm_rank();
	*south = r > 0 ? r - 1 : periodic && p > 1 ? p - 1 : -1;
	*north = r + 1 < p ? r + 1 : periodic && p > 1 ? 0 : -1;
}
