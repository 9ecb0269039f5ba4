/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * parallel.c - thin wrapper over the OpenMP runtime (see parallel.h).
 */
#define _GNU_SOURCE   /* sched_getaffinity, CPU_COUNT */
#include "sandslide/parallel.h"

#include <sched.h>
#include <stdlib.h>
#include <strings.h>
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

/* Whether the calling thread's count was asked for (set_threads) rather
 * than taken by default (use_default_threads), and that default: per
 * thread, as OpenMP's own count is, so that Python calls in different
 * threads keep theirs.  A thread that set neither (a BMI model's) counts
 * as defaulted. */
static _Thread_local int threads_asked;
static _Thread_local int threads_default;

static void set_count(int n)
{
#ifdef _OPENMP
	omp_set_num_threads(n > 0 ? n : 1);
#else
	(void)n;
#endif
}

void ss_parallel_set_threads(int n)
{
	threads_asked = 1;
	set_count(n);
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

void ss_parallel_use_default_threads(int share)
{
	threads_asked = 0;
	threads_default = ss_parallel_default_threads(share);
	set_count(threads_default);
}

int ss_parallel_threads_for(double cells, long long tile_rows)
{
	if (threads_asked || omp_num_threads_env() > 0)
		return ss_parallel_max_threads();
	int n = threads_default > 0 ? threads_default : ss_parallel_default_threads(1);
	const double by_cells = cells / SS_PARALLEL_CELLS_PER_THREAD;
	if (by_cells < n)
		n = by_cells >= 1.0 ? (int)by_cells : 1;
	if (tile_rows < n)
		n = tile_rows >= 1 ? (int)tile_rows : 1;
	set_count(n);
	return n;
}

const char *ss_parallel_wait_policy(void)
{
#ifdef _OPENMP
	/* what the runtime read when it started: OMP_WAIT_POLICY, else
	 * libgomp's GOMP_SPINCOUNT (which the policy overrides only when
	 * unset), else the runtime's own choice (libgomp: spin about 3 ms) */
	const char *policy = getenv("OMP_WAIT_POLICY");
	if (policy && !strcasecmp(policy, "passive"))
		return "passive";
	if (policy && !strcasecmp(policy, "active"))
		return "active";
	if (getenv("GOMP_SPINCOUNT"))
		return "GOMP_SPINCOUNT";
	return "runtime default";
#else
	return "none (no OpenMP)";
#endif
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
