/*
 * parallel.h - the only place that calls omp_* (so the code builds with
 * OPENMP=0, where these report one thread), and the clock that times runs.
 */
#ifndef SANDSLIDE_PARALLEL_H
#define SANDSLIDE_PARALLEL_H

/* Threads the next parallel region will use. */
int ss_parallel_max_threads(void);
/* Use n threads (n >= 1) from now on. */
void ss_parallel_set_threads(int n);
/* Number of the calling thread in its parallel region (0 outside). */
int ss_parallel_thread_id(void);
/* Processors available to this process. */
int ss_parallel_processors(void);
/* Seconds on a monotonic clock (as omp_get_wtime, also without OpenMP):
 * differences time the phases of a run and the benchmarks. */
double ss_parallel_wall_seconds(void);

#endif
