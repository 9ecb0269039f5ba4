/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * euler.cu - forward Euler on one block, every step on the GPU (cuda.h).
 *
 * A step is four kernels on one stream, none waiting for the host:
 *
 *   fill_sides     the halo of the heights: a wall's ghost 0 (the sweep
 *                  mirrors across walls by the type byte), an open side's the
 *                  open level, a periodic side's the far column or row; west
 *                  and east first, then south and north over i = -1 .. nx,
 *                  corners included (boundary.c's order)
 *   slope_max      s^2 of every face that carries flux, its maximum by a
 *                  block reduction and one atomicMax on the bits (s^2 >= 0,
 *                  so its bits order as it does; NaN counts as +inf): a
 *                  maximum is exact, so the order does not matter
 *   step_size      one thread: S = sqrt(max s^2), Lambda = nu table[entry(S)]
 *                  (ss_point_cfl_entry, no atan), the idle rate when nothing
 *                  slides, dt = cfl / (2 Lambda (1/dx^2 + 1/dy^2)); resets
 *                  the maximum for the next step
 *   update         each cell its four faces and h + dt rate (face_point.h,
 *                  ss_point_cell_rate): two buffers, so no cell waits for
 *                  another
 *
 * The expressions are face_point.h's, compiled with -fmad=false and IEEE
 * division and square root (Makefile, tests/gpu/check_ptx.sh): the bits of
 * the CPU's generic path for every step of every cell (doc/gpu.md).
 *
 * Small grids are bound by the launches (a few microseconds each against
 * microseconds of work): the steps go out as a CUDA graph of GRAPH_STEPS
 * steps, captured once (SANDSLIDE_CUDA_GRAPH=0 queues them one by one).
 */
#include <cuda_runtime.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cuda/cuda.h"

extern "C" {
int ss_error_input(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
int ss_error_fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
}
/* error.h's codes (its _Noreturn is C's, not C++'s) */
enum { OK = 0, ERR_FAIL = -1, ERR_INPUT = -2 };

enum { BLOCK_X = 32, BLOCK_Y = 8, SIDE_BLOCK = 256, GRAPH_STEPS = 16 };

#define CHECK(call, what)                                                              \
	do {                                                                            \
		const cudaError_t err_ = (call);                                        \
		if (err_ != cudaSuccess)                                                \
			return ss_error_fail("cuda: %s: %s", (what), cudaGetErrorString(err_)); \
	} while (0)

struct ss_cuda_euler {
	int device;
	int nx, ny;
	ptrdiff_t stride;
	size_t storage;                 /* cells, halo included */
	int side[4];
	double open_level;
	struct ss_point_rule rule;
	double inv_dx, inv_dy, inv_2dx, inv_2dy, inv_d2;
	double cfl, lambda_idle;
	int table_size;
	cudaStream_t stream;
	double *height[2];              /* device: the current and the next */
	int current;
	uint8_t *type;                  /* device */
	double *lambda, *bound;         /* device: the CFL table and thresholds */
	unsigned long long *s2_bits;    /* device: max s^2, as bits */
	double *dt;                     /* device: this step's size */
	int *nonfinite;                 /* device: a rate was NaN or infinite */
	cudaGraphExec_t graph;          /* GRAPH_STEPS steps from height[0] */
	int graph_ready, use_graph;
};

/* ss_grid_index (grid.h) on the device: one ghost cell each side */
static __device__ ptrdiff_t cell(ptrdiff_t stride, int i, int j)
{
	return (ptrdiff_t)(j + 1) * stride + (i + 1);
}

/* The ghost columns of rows 0 .. ny - 1 (ss_point_ghost). */
__global__ void fill_west_east(double *__restrict__ h, int nx, int ny, ptrdiff_t stride,
                               int west, int east, double open_level)
{
	const int j = blockIdx.x * blockDim.x + threadIdx.x;
	if (j >= ny)
		return;
	h[cell(stride, -1, j)] = ss_point_ghost(west, h[cell(stride, nx - 1, j)], open_level);
	h[cell(stride, nx, j)] = ss_point_ghost(east, h[cell(stride, 0, j)], open_level);
}

/* The ghost rows, columns -1 .. nx: the corners after the columns. */
__global__ void fill_south_north(double *__restrict__ h, int nx, int ny, ptrdiff_t stride,
                                 int south, int north, double open_level)
{
	const int i = (int)(blockIdx.x * blockDim.x + threadIdx.x) - 1;
	if (i > nx)
		return;
	h[cell(stride, i, -1)] = ss_point_ghost(south, h[cell(stride, i, ny - 1)], open_level);
	h[cell(stride, i, ny)] = ss_point_ghost(north, h[cell(stride, i, 0)], open_level);
}

/* The largest s^2 of the faces each cell owns (ss_point_cell_slope2),
 * reduced over the block and then the grid. */
__global__ void slope_max(const double *__restrict__ h, const uint8_t *__restrict__ type,
                          int nx, int ny, ptrdiff_t stride, double inv_dx, double inv_dy,
                          double inv_2dx, double inv_2dy, unsigned long long *s2_bits)
{
	const int i = blockIdx.x * blockDim.x + threadIdx.x;
	const int j = blockIdx.y * blockDim.y + threadIdx.y;
	double s2 = 0.0;
	if (i < nx && j < ny)
		s2 = ss_point_cell_slope2(h, type, cell(stride, i, j), stride, i == nx - 1,
		                          j == ny - 1, inv_dx, inv_dy, inv_2dx, inv_2dy);
	/* the block's maximum: the warps', then the first warp's */
	__shared__ double warp_max[BLOCK_X * BLOCK_Y / 32];
	const int lane = (threadIdx.y * blockDim.x + threadIdx.x) % 32;
	const int warp = (threadIdx.y * blockDim.x + threadIdx.x) / 32;
	for (int o = 16; o > 0; o /= 2)
		s2 = fmax(s2, __shfl_down_sync(0xffffffffu, s2, o));
	if (lane == 0)
		warp_max[warp] = s2;
	__syncthreads();
	if (warp == 0) {
		s2 = lane < BLOCK_X * BLOCK_Y / 32 ? warp_max[lane] : 0.0;
		for (int o = 16; o > 0; o /= 2)
			s2 = fmax(s2, __shfl_down_sync(0xffffffffu, s2, o));
		if (lane == 0 && s2 > 0.0)
			atomicMax(s2_bits, (unsigned long long)__double_as_longlong(s2));
	}
}

/* One thread: the step size from the largest slope (ss_point_step_size,
 * the CFL bound of doc/model.md#the-cfl-bound); the maximum cleared for the
 * next step. */
__global__ void step_size(unsigned long long *s2_bits, const double *__restrict__ lambda,
                          const double *__restrict__ bound, int table_size, double tan_cr,
                          double nu, double lambda_idle, double cfl, double inv_d2, double *dt)
{
	const double s2_max = __longlong_as_double((long long)*s2_bits);
	*s2_bits = 0;
	*dt = ss_point_step_size(s2_max, lambda, bound, table_size, tan_cr, nu, lambda_idle, cfl,
	                         inv_d2);
}

__global__ void update(struct ss_point_rule rule, const double *__restrict__ h,
                       const uint8_t *__restrict__ type, int nx, int ny, ptrdiff_t stride,
                       double inv_dx, double inv_dy, double inv_2dx, double inv_2dy,
                       const double *__restrict__ dt, double *__restrict__ next,
                       int *__restrict__ nonfinite)
{
	const int i = blockIdx.x * blockDim.x + threadIdx.x;
	const int j = blockIdx.y * blockDim.y + threadIdx.y;
	if (i >= nx || j >= ny)
		return;
	const ptrdiff_t k = cell(stride, i, j);
	const int flows = type[k] == SS_POINT_FLOW;
	const double rate = ss_point_cell_rate(&rule, h, type, k, stride, inv_dx, inv_dy, inv_2dx,
	                                       inv_2dy);
	next[k] = ss_point_euler(h[k], *dt, rate, flows);
	if (flows && !isfinite(rate))
		*nonfinite = 1;
}

/* One step queued from height[from] to height[1 - from]. */
static int queue_step(struct ss_cuda_euler *e, int from)
{
	double *h = e->height[from], *next = e->height[1 - from];
	const dim3 block(BLOCK_X, BLOCK_Y);
	const dim3 grid((unsigned)((e->nx + BLOCK_X - 1) / BLOCK_X),
	                (unsigned)((e->ny + BLOCK_Y - 1) / BLOCK_Y));
	fill_west_east<<<(e->ny + SIDE_BLOCK - 1) / SIDE_BLOCK, SIDE_BLOCK, 0, e->stream>>>(
		h, e->nx, e->ny, e->stride, e->side[0], e->side[1], e->open_level);
	fill_south_north<<<(e->nx + 2 + SIDE_BLOCK - 1) / SIDE_BLOCK, SIDE_BLOCK, 0, e->stream>>>(
		h, e->nx, e->ny, e->stride, e->side[2], e->side[3], e->open_level);
	slope_max<<<grid, block, 0, e->stream>>>(h, e->type, e->nx, e->ny, e->stride, e->inv_dx,
	                                         e->inv_dy, e->inv_2dx, e->inv_2dy, e->s2_bits);
	step_size<<<1, 1, 0, e->stream>>>(e->s2_bits, e->lambda, e->bound, e->table_size,
	                                  e->rule.tan_cr, e->rule.nu, e->lambda_idle, e->cfl,
	                                  e->inv_d2, e->dt);
	update<<<grid, block, 0, e->stream>>>(e->rule, h, e->type, e->nx, e->ny, e->stride,
	                                      e->inv_dx, e->inv_dy, e->inv_2dx, e->inv_2dy, e->dt,
	                                      next, e->nonfinite);
	CHECK(cudaGetLastError(), "a kernel launch");
	return OK;
}

/* GRAPH_STEPS steps from height[0] back to height[0] (an even count). */
static int capture_graph(struct ss_cuda_euler *e)
{
	cudaGraph_t graph;
	CHECK(cudaStreamBeginCapture(e->stream, cudaStreamCaptureModeThreadLocal),
	      "capturing the steps");
	int err = OK;
	for (int s = 0; s < GRAPH_STEPS && !err; s++)
		err = queue_step(e, s % 2);
	const cudaError_t end = cudaStreamEndCapture(e->stream, &graph);
	if (err)
		return err;
	CHECK(end, "capturing the steps");
	const cudaError_t inst = cudaGraphInstantiate(&e->graph, graph, 0);
	cudaGraphDestroy(graph);
	CHECK(inst, "instantiating the steps' graph");
	e->graph_ready = 1;
	return OK;
}

extern "C" int ss_cuda_device_count(int *count, char *why, size_t why_size)
{
	*count = 0;
	const cudaError_t err = cudaGetDeviceCount(count);
	if (err == cudaErrorNoDevice)
		return 0;
	if (err == cudaErrorInsufficientDriver) {
		snprintf(why, why_size, "no NVIDIA driver, or one older than this build's CUDA "
		         "%d.%d runtime", CUDART_VERSION / 1000, CUDART_VERSION % 1000 / 10);
		*count = 0;
		return -1;
	}
	if (err != cudaSuccess) {
		snprintf(why, why_size, "%s", cudaGetErrorString(err));
		*count = 0;
		return -1;
	}
	return 0;
}

extern "C" int ss_cuda_device_describe(int index, char *buf, size_t size)
{
	cudaDeviceProp p;
	CHECK(cudaGetDeviceProperties(&p, index), "reading the device's properties");
	snprintf(buf, size, "%s, %.1f GiB, sm_%d%d, %d SMs", p.name,
	         (double)p.totalGlobalMem / (1024.0 * 1024.0 * 1024.0), p.major, p.minor,
	         p.multiProcessorCount);
	return OK;
}

extern "C" int ss_cuda_device_memory(int index, size_t *free_bytes, size_t *total_bytes)
{
	CHECK(cudaSetDevice(index), "choosing the device");
	CHECK(cudaMemGetInfo(free_bytes, total_bytes), "reading the device's memory");
	return OK;
}

extern "C" int ss_cuda_copy_bandwidth(int index, size_t bytes, double *bytes_per_s)
{
	enum { COPIES = 20 };
	void *a = NULL, *b = NULL;
	cudaEvent_t start, stop;
	float ms = 0.0f;
	*bytes_per_s = 0.0;
	CHECK(cudaSetDevice(index), "choosing the device");
	CHECK(cudaMalloc(&a, bytes), "allocating the bandwidth probe");
	if (cudaMalloc(&b, bytes) != cudaSuccess) {
		cudaFree(a);
		return ss_error_fail("cuda: allocating the bandwidth probe: out of memory");
	}
	cudaMemset(a, 0, bytes);
	cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice);   /* warm-up */
	cudaEventCreate(&start);
	cudaEventCreate(&stop);
	cudaEventRecord(start);
	for (int c = 0; c < COPIES; c++)
		cudaMemcpyAsync(c % 2 ? a : b, c % 2 ? b : a, bytes, cudaMemcpyDeviceToDevice);
	cudaEventRecord(stop);
	const cudaError_t err = cudaEventSynchronize(stop);
	cudaEventElapsedTime(&ms, start, stop);
	cudaEventDestroy(start);
	cudaEventDestroy(stop);
	cudaFree(a);
	cudaFree(b);
	CHECK(err, "the bandwidth probe");
	*bytes_per_s = 2.0 * (double)bytes * COPIES / (ms * 1e-3);
	return OK;
}

extern "C" void ss_cuda_euler_destroy(struct ss_cuda_euler *e)
{
	if (!e)
		return;
	cudaSetDevice(e->device);
	if (e->graph_ready)
		cudaGraphExecDestroy(e->graph);
	if (e->stream)
		cudaStreamDestroy(e->stream);
	cudaFree(e->height[0]);
	cudaFree(e->height[1]);
	cudaFree(e->type);
	cudaFree(e->lambda);
	cudaFree(e->bound);
	cudaFree(e->s2_bits);
	cudaFree(e->dt);
	cudaFree(e->nonfinite);
	free(e);
}

static int create(struct ss_cuda_euler *e, const struct ss_cuda_euler_setup *s)
{
	const size_t storage = e->storage;
	const size_t need = storage * ss_cuda_euler_bytes_per_cell();
	size_t free_bytes, total_bytes;
	CHECK(cudaSetDevice(s->device), "choosing the device");
	CHECK(cudaMemGetInfo(&free_bytes, &total_bytes), "reading the device's memory");
	if (need + ((size_t)64 << 20) > free_bytes) {
		/* the largest square grid that would fit, halo and padding aside */
		const double side = floor(sqrt((double)(free_bytes > ((size_t)64 << 20)
		                                        ? free_bytes - ((size_t)64 << 20) : 0) /
		                               (double)ss_cuda_euler_bytes_per_cell()));
		return ss_error_input("%d x %d cells need %.2f GB on cuda:%d (%zu B per cell); "
		                      "%.2f GB of its %.2f GB are free: at most about %.0f x %.0f "
		                      "cells fit", s->nx, s->ny, (double)need * 1e-9, s->device,
		                      ss_cuda_euler_bytes_per_cell(), (double)free_bytes * 1e-9,
		                      (double)total_bytes * 1e-9, side, side);
	}
	CHECK(cudaStreamCreateWithFlags(&e->stream, cudaStreamNonBlocking), "creating a stream");
	CHECK(cudaMalloc(&e->height[0], storage * sizeof(double)), "allocating the heights");
	CHECK(cudaMalloc(&e->height[1], storage * sizeof(double)), "allocating the heights");
	CHECK(cudaMalloc(&e->type, storage), "allocating the cell types");
	CHECK(cudaMalloc(&e->lambda, (size_t)(s->table_size + 1) * sizeof(double)),
	      "allocating the CFL table");
	CHECK(cudaMalloc(&e->bound, (size_t)s->table_size * sizeof(double)),
	      "allocating the CFL table");
	CHECK(cudaMalloc(&e->s2_bits, sizeof *e->s2_bits), "allocating the reductions");
	CHECK(cudaMalloc(&e->dt, sizeof *e->dt), "allocating the reductions");
	CHECK(cudaMalloc(&e->nonfinite, sizeof *e->nonfinite), "allocating the reductions");
	CHECK(cudaMemcpy(e->height[0], s->height, storage * sizeof(double),
	                 cudaMemcpyHostToDevice), "copying the heights");
	/* the second buffer's halo and padding as the first's: every cell of
	 * it is defined before a step reads it */
	CHECK(cudaMemcpy(e->height[1], s->height, storage * sizeof(double),
	                 cudaMemcpyHostToDevice), "copying the heights");
	CHECK(cudaMemcpy(e->type, s->type, storage, cudaMemcpyHostToDevice),
	      "copying the cell types");
	CHECK(cudaMemcpy(e->lambda, s->lambda, (size_t)(s->table_size + 1) * sizeof(double),
	                 cudaMemcpyHostToDevice), "copying the CFL table");
	CHECK(cudaMemcpy(e->bound, s->bound, (size_t)s->table_size * sizeof(double),
	                 cudaMemcpyHostToDevice), "copying the CFL table");
	CHECK(cudaMemset(e->s2_bits, 0, sizeof *e->s2_bits), "clearing the reductions");
	CHECK(cudaMemset(e->dt, 0, sizeof *e->dt), "clearing the reductions");
	CHECK(cudaMemset(e->nonfinite, 0, sizeof *e->nonfinite), "clearing the reductions");
	return OK;
}

extern "C" int ss_cuda_euler_create(struct ss_cuda_euler **out,
                                    const struct ss_cuda_euler_setup *s)
{
	*out = NULL;
	int count = 0;
	char why[160] = "";
	if (ss_cuda_device_count(&count, why, sizeof why) || s->device >= count)
		return ss_error_input("cuda:%d: no such GPU%s%s", s->device, *why ? ": " : "", why);
	struct ss_cuda_euler *e = (struct ss_cuda_euler *)calloc(1, sizeof *e);
	if (!e)
		return ss_error_fail("cannot allocate the GPU loop's state");
	e->device = s->device;
	e->nx = s->nx;
	e->ny = s->ny;
	e->stride = s->stride;
	e->storage = (size_t)s->stride * (size_t)(s->ny + 2);
	memcpy(e->side, s->side, sizeof e->side);
	e->open_level = s->open_level;
	e->rule = s->rule;
	/* the reference sweep's constants, computed as it computes them */
	e->inv_dx = 1.0 / s->dx;
	e->inv_dy = 1.0 / s->dy;
	e->inv_2dx = 0.5 / s->dx;
	e->inv_2dy = 0.5 / s->dy;
	e->inv_d2 = 1.0 / (s->dx * s->dx) + 1.0 / (s->dy * s->dy);
	e->cfl = s->cfl;
	e->lambda_idle = s->lambda_idle;
	e->table_size = s->table_size;
	const char *graph = getenv("SANDSLIDE_CUDA_GRAPH");
	e->use_graph = !(graph && strcmp(graph, "0") == 0);
	const int err = create(e, s);
	if (err) {
		ss_cuda_euler_destroy(e);
		return err;
	}
	*out = e;
	return OK;
}

extern "C" int ss_cuda_euler_steps(struct ss_cuda_euler *e, long long steps)
{
	CHECK(cudaSetDevice(e->device), "choosing the device");
	if (e->use_graph && !e->graph_ready && steps >= GRAPH_STEPS) {
		const int err = capture_graph(e);
		if (err)
			return err;
	}
	while (steps > 0) {
		if (e->graph_ready && e->current == 0 && steps >= GRAPH_STEPS) {
			CHECK(cudaGraphLaunch(e->graph, e->stream), "launching the steps' graph");
			steps -= GRAPH_STEPS;
			continue;
		}
		const int err = queue_step(e, e->current);
		if (err)
			return err;
		e->current = 1 - e->current;
		steps--;
	}
	return OK;
}

extern "C" int ss_cuda_euler_finish(struct ss_cuda_euler *e, int *nonfinite)
{
	*nonfinite = 0;
	CHECK(cudaSetDevice(e->device), "choosing the device");
	CHECK(cudaStreamSynchronize(e->stream), "running the steps");
	CHECK(cudaMemcpy(nonfinite, e->nonfinite, sizeof *nonfinite, cudaMemcpyDeviceToHost),
	      "reading the NaN flag");
	return OK;
}

extern "C" int ss_cuda_euler_heights(struct ss_cuda_euler *e, double *height)
{
	CHECK(cudaSetDevice(e->device), "choosing the device");
	CHECK(cudaStreamSynchronize(e->stream), "running the steps");
	CHECK(cudaMemcpy(height, e->height[e->current], e->storage * sizeof(double),
	                 cudaMemcpyDeviceToHost), "copying the heights back");
	return OK;
}

extern "C" int ss_cuda_euler_last_dt(struct ss_cuda_euler *e, double *dt)
{
	CHECK(cudaSetDevice(e->device), "choosing the device");
	CHECK(cudaStreamSynchronize(e->stream), "running the steps");
	CHECK(cudaMemcpy(dt, e->dt, sizeof *dt, cudaMemcpyDeviceToHost), "reading the step");
	return OK;
}
