/*
 * parallel.c - thin wrapper over the OpenMP runtime (see parallel.h).
 */
#define _GNU_SOURCE   /* sched_getaffinity, CPU_COUNT */
#include "sandslide/parallel.h"

#include <sched.h>
#include <stdlib.h>
#include <time.h>

#ifdef _OPENMP
#include <omp.h>
#endif

int ss_parallel_max_threads(void)
{
#ifdef _OPENMP
	return omp_get_max_threads();
#else
	return 1;
#endif
}

void ss_parallel_set_threads(int n)
{
#ifdef _OPENMP
	omp_set_num_threads(n > 0 ? n : 1);
#else
	(void)n;
#endif
}

/* The CPUs this process may run on (taskset, a batch system's cpuset),
 * not every processor of the machine. */
int ss_parallel_processors(void)
{
	cpu_set_t set;
	if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
		return CPU_COUNT(&set);
#ifdef _OPENMP
	return omp_get_num_procs();
#else
	return 1;
#endif
}

/* OMP_NUM_THREADS as OpenMP reads it: its first entry (a list gives the
 * counts of nested levels), a positive integer; 0 when unset or not one. */
static int omp_num_threads_env(void)
{
	const char *v = getenv("OMP_NUM_THREADS");
	if (!v)
		return 0;
	char *end;
	const long n = strtol(v, &end, 10);
	while (*end == ' ' || *end == '\t')
		end++;
	return end != v && (*end == '\0' || *end == ',') && n >= 1 && n <= 4096 ? (int)n : 0;
}

int ss_parallel_default_threads(int share)
{
	const int env = omp_num_threads_env();
	if (env > 0)
		return env;   /* a batch system's grant is per process already */
	const int n = ss_parallel_processors() / (share > 1 ? share : 1);
	return n > 0 ? n : 1;
}

int ss_parallel_thread_id(void)
{
#ifdef _OPENMP
	return omp_get_thread_num();
#else
	return 0;
#endif
}

double ss_parallel_wall_seconds(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
