/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * device.c - whether a device can run here (device.h): the CPU always, a
 * GPU when this build has CUDA and the machine has that GPU.  In a build
 * without CUDA it also stands in for cuda.h's functions, each of which
 * says so.
 */
#include "sandslide/device.h"

#include <stdio.h>

#include "cuda/cuda.h"
#include "sandslide/cpu.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

#define NO_CUDA "this build has no CUDA: make CUDA=1 builds one (doc/gpu.md)"

int ss_device_cuda_built(void)
{
#ifdef SS_HAVE_CUDA
	return 1;
#else
	return 0;
#endif
}

int ss_device_check(const struct ss_device *d, const char *what)
{
	if (d->kind == SS_DEVICE_CPU)
		return SS_OK;
#ifdef SS_HAVE_CUDA
	int count;
	char why[160];
	if (ss_cuda_device_count(&count, why, sizeof why))
		return ss_error_input("%s: no GPU: %s", what, why);
	if (count == 0)
		return ss_error_input("%s: the CUDA driver sees no GPU on this machine", what);
	if (d->index >= count && count == 1)
		return ss_error_input("%s: this machine has one GPU, cuda:0", what);
	if (d->index >= count)
		return ss_error_input("%s: this machine has %d GPUs, cuda:0 to cuda:%d", what, count,
		                      count - 1);
	return SS_OK;
#else
	return ss_error_input("%s: %s", what, NO_CUDA);
#endif
}

int ss_device_list(char *buf, size_t size)
{
	const enum ss_cpu_path path = ss_cpu_path();
	int n = snprintf(buf, size, "cpu: %s, %d threads\n", ss_cpu_path_name(path),
	                 ss_parallel_max_threads());
#define MORE(...) n += snprintf(buf + (n < (int)size ? n : (int)size), \
                                 n < (int)size ? size - (size_t)n : 0, __VA_ARGS__)
#ifdef SS_HAVE_CUDA
	int count = 0;
	char why[160];
	const int err = ss_cuda_device_count(&count, why, sizeof why);
	if (err)
		MORE("cuda: none (%s)\n", why);
	else if (count == 0)
		MORE("cuda: none (the CUDA driver sees no GPU)\n");
	for (int k = 0; !err && k < count; k++) {
		char what[160];
		if (ss_cuda_device_describe(k, what, sizeof what))
			snprintf(what, sizeof what, "?");
		MORE("cuda:%d: %s\n", k, what);
	}
#else
	MORE("cuda: none (%s)\n", NO_CUDA);
#endif
#undef MORE
	return n;
}

#ifndef SS_HAVE_CUDA
/* cuda.h without CUDA: every answer is that there is none. */
int ss_cuda_device_count(int *count, char *why, size_t why_size)
{
	*count = 0;
	snprintf(why, why_size, "%s", NO_CUDA);
	return -1;
}

int ss_cuda_device_describe(int index, char *buf, size_t size)
{
	(void)index;
	(void)buf;
	(void)size;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_device_memory(int index, size_t *free_bytes, size_t *total_bytes)
{
	(void)index;
	*free_bytes = *total_bytes = 0;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_copy_bandwidth(int index, size_t bytes, double *bytes_per_s)
{
	(void)index;
	(void)bytes;
	*bytes_per_s = 0.0;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_euler_create(struct ss_cuda_euler **e, const struct ss_cuda_euler_setup *s)
{
	(void)s;
	*e = NULL;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_euler_steps(struct ss_cuda_euler *e, long long steps)
{
	(void)e;
	(void)steps;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_euler_finish(struct ss_cuda_euler *e, int *nonfinite)
{
	(void)e;
	*nonfinite = 0;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_euler_heights(struct ss_cuda_euler *e, double *height)
{
	(void)e;
	(void)height;
	return ss_error_input("%s", NO_CUDA);
}

int ss_cuda_euler_last_dt(struct ss_cuda_euler *e, double *dt)
{
	(void)e;
	*dt = 0.0;
	return ss_error_input("%s", NO_CUDA);
}

void ss_cuda_euler_destroy(struct ss_cuda_euler *e)
{
	(void)e;
}
#endif
