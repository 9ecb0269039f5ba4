/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * parallel.h - the only place that calls omp_* (so the code builds with
 * OPENMP=0, where these report one thread), and the clock that times runs.
 */
#ifndef SANDSLIDE_PARALLEL_H
#define SANDSLIDE_PARALLEL_H

/* Threads the next parallel region will use. */
int ss_parallel_max_threads(void);
/* Use n threads (n >= 1) from now on, in the parallel regions the calling
 * thread starts: OpenMP keeps the count per thread (its nthreads-var ICV
 * is the calling task's), so calls in different threads each use their
 * own; run, relax and fit set it at the start of every call. */
void ss_parallel_set_threads(int n);
/* Number of the calling thread in its parallel region (0 outside). */
int ss_parallel_thread_id(void);
/* Processors this process may run on (its CPU affinity). */
int ss_parallel_processors(void);
/* Threads to use when none are asked for: OMP_NUM_THREADS when set (what a
 * batch system grants), else the processors this process may run on
 * divided by share (the processes sharing them, >= 1), at least 1. */
int ss_parallel_default_threads(int share);
/* Use ss_parallel_default_threads(share) threads, as a default that
 * ss_parallel_threads_for may lower for a small grid (unlike a count given
 * to ss_parallel_set_threads, which is kept). */
void ss_parallel_use_default_threads(int share);

/* Cells each thread needs before another thread is worth its start and its
 * barriers.  Measured with `sandslide bench --surface supercritical` on a
 * loaded 2-core machine, passive wait (doc/running.md#threads): 2 threads
 * made 0.58 to 0.63 of one thread's rate on 64^2 cells, 0.94 to 0.97 on
 * 512^2. */
#define SS_PARALLEL_CELLS_PER_THREAD 65536.0

/* The threads for a sweep of `cells` cells in `tile_rows` rows of tiles
 * (the unit the sweep shares out), set for the calling thread and
 * returned: when the count is a default (ss_parallel_use_default_threads,
 * or never set, and OMP_NUM_THREADS unset), that default lowered to one
 * thread per SS_PARALLEL_CELLS_PER_THREAD cells and per tile row, at least
 * 1; a count asked for is kept. */
int ss_parallel_threads_for(double cells, long long tile_rows);

/* How the OpenMP runtime's idle threads wait, as the environment it read at
 * start-up says: "passive" (they sleep), "active" (they spin), "GOMP_SPINCOUNT"
 * (libgomp spins that long), "runtime default" (libgomp spins about 3 ms),
 * or "none (no OpenMP)".  The command line and the Python module set
 * OMP_WAIT_POLICY=passive when neither variable is set (doc/running.md). */
const char *ss_parallel_wait_policy(void);
/* Seconds on a monotonic clock (as omp_get_wtime, also without OpenMP):
 * differences time the phases of a run and the benchmarks. */
double ss_parallel_wall_seconds(void);

#endif
