/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * cuda.h - what the library asks of a GPU (make CUDA=1; doc/gpu.md): the
 * devices there are, and forward Euler on one block kept on the device.
 *
 * Implemented by the CUDA files of this folder (*.cu, nvcc) in a build
 * with CUDA; in a build without, by device.c, whose answers say so
 * (SS_ERR_INPUT).  Plain C types only: nvcc's C++ reads this header too.
 *
 * The loop on the device (euler.cu) is the two-buffer scheme of
 * face_point.h: per step, the halo (walls, open and periodic sides, as
 * boundary.c fills it), the largest face slope by a max-reduction (exact,
 * so in no particular order), the step size from the CFL table on the
 * device (ss_point_cfl_entry: no host round trip), and every cell's
 * forward-Euler update from its four faces.  The steps are queued on one
 * stream, and as CUDA graphs of a few steps where that is faster (small
 * grids are bound by the launches).  The heights come back only when asked.
 */
#ifndef SANDSLIDE_CUDA_CUDA_H
#define SANDSLIDE_CUDA_CUDA_H

#include <stddef.h>
#include <stdint.h>

#include "core/face_point.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The GPUs the CUDA runtime sees: 0 and *count (0 or more), or -1 and
 * the runtime's reason in why (no driver, a driver older than the
 * runtime); prints nothing. */
int ss_cuda_device_count(int *count, char *why, size_t why_size);

/* "NVIDIA H200, 139.8 GiB, sm_90" for device index into buf. */
int ss_cuda_device_describe(int index, char *buf, size_t size);

/* The device's free and total memory, bytes. */
int ss_cuda_device_memory(int index, size_t *free_bytes, size_t *total_bytes);

/* Bytes per second of a device-to-device copy of `bytes` bytes, counting
 * the bytes read and those written (the roofline's bandwidth). */
int ss_cuda_copy_bandwidth(int index, size_t bytes, double *bytes_per_s);

/* One block stepped by forward Euler on a GPU. */
struct ss_cuda_euler;

struct ss_cuda_euler_setup {
	int device;                 /* cuda:N */
	int nx, ny;                 /* cells, halo not included */
	ptrdiff_t stride;           /* elements between rows (grid.h) */
	double dx, dy;              /* m */
	int side[4];                /* west, east, south, north: SS_POINT_SIDE_*
	                             * (boundary.h's kinds) */
	double open_level;          /* m: the open sides' ghost heights */
	struct ss_point_rule rule;  /* one closure everywhere */
	double cfl;                 /* the step: cfl / (2 Lambda (1/dx^2 + 1/dy^2)) */
	double lambda_idle;         /* m^2/s: Lambda when no face slides */
	const double *lambda;       /* Lambda(S)/nu, SS_CFL_TABLE_SIZE + 1 entries
	                             * (closure.h), and its thresholds: */
	const double *bound;        /* SS_CFL_TABLE_SIZE (ss_cfl_bound_thresholds) */
	int table_size;             /* SS_CFL_TABLE_SIZE */
	const double *height;       /* m, (ny + 2) * stride, halo included */
	const uint8_t *type;        /* a byte per cell (grid.h), halo filled */
};

/* Bytes of device memory per cell of storage (halo included) the loop
 * holds: two height buffers and the type byte. */
static inline size_t ss_cuda_euler_bytes_per_cell(void)
{
	return 2 * sizeof(double) + 1;
}

/* Bytes of memory each step moves per cell: the slope pass reads the
 * heights and types (9 B), the update reads them and writes the heights
 * (17 B). */
static inline double ss_cuda_euler_bytes_per_update(void)
{
	return (double)(sizeof(double) + 1) + (double)(2 * sizeof(double) + 1);
}

/* Copy the setup's arrays to device memory.  SS_ERR_INPUT when the grid
 * does not fit in the device's free memory (the message says what would),
 * SS_ERR_FAIL on a CUDA error. */
int ss_cuda_euler_create(struct ss_cuda_euler **e, const struct ss_cuda_euler_setup *s);

/* Queue `steps` steps (returns before they are done). */
int ss_cuda_euler_steps(struct ss_cuda_euler *e, long long steps);

/* Wait for the queued steps; *nonfinite: whether some flow cell's rate was
 * NaN or infinite in any step so far. */
int ss_cuda_euler_finish(struct ss_cuda_euler *e, int *nonfinite);

/* The heights now, halo included, into height ((ny + 2) * stride). */
int ss_cuda_euler_heights(struct ss_cuda_euler *e, double *height);

/* The last step's size, s. */
int ss_cuda_euler_last_dt(struct ss_cuda_euler *e, double *dt);

void ss_cuda_euler_destroy(struct ss_cuda_euler *e);

#ifdef __cplusplus
}
#endif

#endif
