/*
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
/* Seconds on a monotonic clock (as omp_get_wtime, also without OpenMP):
 * differences time the phases of a run and the benchmarks. */
double ss_parallel_wall_seconds(void);

#endif
