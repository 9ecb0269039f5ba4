/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_cuda.c - the GPU's forward-Euler loop (src/cuda/cuda.h) on a GPU,
 * against the CPU's generic path (doc/gpu.md#the-same-bits):
 *
 *   bits         every case of euler_cases.h (every closure, walls, open
 *                cells, every kind of side) stepped on the device gives the
 *                reference sweep's heights and step size bit for bit after
 *                1, 2, 17 and 40 steps (single launches and the 16-step
 *                graph), but Herschel-Bulkley by pow(), whose pow() is
 *                CUDA's: there the largest relative difference is printed
 *                and held under 1e-12
 *   again        the same case twice on the device: the same bits
 *   nan          a NaN height raises the device's NaN flag
 *   too big      a grid larger than the device's memory is refused up front
 *                (SS_ERR_INPUT) with what would fit
 *
 * Skipped, with the reason, in a build without CUDA or on a machine
 * without a GPU, where it checks that the device and its loop are refused
 * as bad input: `make CUDA=1 test-cuda` runs it everywhere (CI), and
 * tools/gpu_check.sh on the GPU machine.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "euler_cases.h"
#include "cuda/cuda.h"
#include "sandslide/cpu.h"
#include "sandslide/device.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

static uint64_t seed = 20261205;

static int create(struct euler_case *c, struct ss_cuda_euler **e)
{
	const struct ss_grid *g = &c->st.grid;
	struct ss_cuda_euler_setup s = {
		.device = 0, .nx = g->nx, .ny = g->ny, .stride = g->stride, .dx = g->dx,
		.dy = g->dy, .open_level = c->st.boundary.open_level,
		.rule = ss_face_point_rule(&c->st.sweeper->face_rule), .cfl = c->st.cfl,
		.lambda_idle = c->lambda_idle, .lambda = c->st.sweeper->cfl_bound.lambda_max,
		.bound = c->bound, .table_size = SS_CFL_TABLE_SIZE, .height = c->st.height,
		.type = c->st.sweeper->cell_type_bytes,
	};
	for (int k = 0; k < 4; k++)
		s.side[k] = (int)c->st.boundary.side[k];
	return ss_cuda_euler_create(e, &s);
}

static void test_bits(void)
{
	static const int stops[] = {1, 2, 17, 40};
	int cases = 0, exact = 0;
	double worst_pow = 0.0;
	for (int n = 0; n < 3 * EULER_CLOSURES; n++) {
		struct euler_case c;
		if (euler_case_init(&c, n, seed)) {
			CHECK(0, "case %d refused", n);
			continue;
		}
		const int by_pow = c.st.sweeper->face_rule.form == SS_FACE_HB_POW;
		const struct ss_grid *g = &c.st.grid;
		const size_t cells = ss_grid_storage_cells(g);
		double *h = malloc(cells * sizeof *h);
		struct ss_cuda_euler *e = NULL;
		if (!h || create(&c, &e)) {
			CHECK(0, "%s: the device's loop refused", c.name);
			free(h);
			euler_case_release(&c);
			continue;
		}
		int done = 0, same = 1, nonfinite = 0;
		double dt_ref = 0.0, dt = 0.0, worst = 0.0;
		for (int s = 0; s < (int)(sizeof stops / sizeof *stops); s++) {
			for (; done < stops[s]; done++)
				dt_ref = euler_case_step(&c);
			CHECK(ss_cuda_euler_steps(e, stops[s] - (s ? stops[s - 1] : 0)) == SS_OK &&
			      ss_cuda_euler_finish(e, &nonfinite) == SS_OK &&
			      ss_cuda_euler_heights(e, h) == SS_OK && ss_cuda_euler_last_dt(e, &dt) == SS_OK,
			      "%s: the device's steps failed", c.name);
			for (int j = 0; j < g->ny; j++) {
				for (int i = 0; i < g->nx; i++) {
					const ptrdiff_t k = ss_grid_index(g, i, j);
					if (!same_bits(h[k], c.st.height[k])) {
						same = 0;
						worst = fmax(worst, fabs(h[k] - c.st.height[k]) /
						                    fmax(fabs(c.st.height[k]), 1e-300));
						if (!by_pow && worst > 0.0)
							CHECK(0, "%s, after %d steps, cell (%d, %d): device %.17g, "
							      "CPU %.17g", c.name, stops[s], i, j, h[k],
							      c.st.height[k]);
					}
				}
			}
			if (!by_pow)
				CHECK(same_bits(dt, dt_ref), "%s, after %d steps: dt %.17g on the device, "
				      "%.17g on the CPU", c.name, stops[s], dt, dt_ref);
		}
		CHECK(!nonfinite, "%s: the device raised its NaN flag", c.name);
		if (by_pow) {
			worst_pow = fmax(worst_pow, worst);
			CHECK(worst < 1e-12, "%s (CUDA's pow): relative difference %.3g", c.name, worst);
		} else {
			CHECK(same, "%s: the device left the CPU's bits", c.name);
		}
		exact += same;
		cases++;
		ss_cuda_euler_destroy(e);
		free(h);
		euler_case_release(&c);
	}
	printf("  bits: %d cases, %d bit for bit; Herschel-Bulkley by pow(): largest relative "
	       "difference %.3g\n", cases, exact, worst_pow);
}

static void test_again(void)
{
	double *h[2] = {NULL, NULL};
	size_t cells = 0;
	for (int run = 0; run < 2; run++) {
		struct euler_case c;
		struct ss_cuda_euler *e = NULL;
		int nonfinite;
		if (euler_case_init(&c, 3, seed) || create(&c, &e)) {
			CHECK(0, "case 3 refused");
			return;
		}
		cells = ss_grid_storage_cells(&c.st.grid);
		h[run] = calloc(cells, sizeof(double));
		CHECK(h[run] && ss_cuda_euler_steps(e, 100) == SS_OK &&
		      ss_cuda_euler_finish(e, &nonfinite) == SS_OK &&
		      ss_cuda_euler_heights(e, h[run]) == SS_OK, "run %d failed", run);
		ss_cuda_euler_destroy(e);
		euler_case_release(&c);
	}
	CHECK(h[0] && h[1] && memcmp(h[0], h[1], cells * sizeof(double)) == 0,
	      "the same case twice on the device: other bits");
	free(h[0]);
	free(h[1]);
}

static void test_nan(void)
{
	struct euler_case c;
	struct ss_cuda_euler *e = NULL;
	int nonfinite = 0;
	if (euler_case_init(&c, 0, seed))
		return;
	const struct ss_grid *g = &c.st.grid;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			if (c.st.sweeper->cell_type_bytes[ss_grid_index(g, i, j)] == SS_CELL_FLOW)
				c.st.height[ss_grid_index(g, i, j)] = NAN, i = g->nx, j = g->ny;
	CHECK(create(&c, &e) == SS_OK && ss_cuda_euler_steps(e, 3) == SS_OK &&
	      ss_cuda_euler_finish(e, &nonfinite) == SS_OK, "the NaN case failed to run");
	CHECK(nonfinite, "a NaN height: the device's NaN flag is not raised");
	ss_cuda_euler_destroy(e);
	euler_case_release(&c);
}

static void test_too_big(void)
{
	size_t free_bytes = 0, total_bytes = 0;
	CHECK(ss_cuda_device_memory(0, &free_bytes, &total_bytes) == SS_OK, "no memory figures");
	/* a grid of twice the free memory, never allocated on the host: the
	 * refusal comes before any copy */
	const double side = ceil(sqrt(2.0 * (double)free_bytes /
	                              (double)ss_cuda_euler_bytes_per_cell()));
	static const double lambda[SS_CFL_TABLE_SIZE + 1], bound[SS_CFL_TABLE_SIZE];
	struct ss_cuda_euler_setup s = {
		.nx = (int)side, .ny = (int)side, .stride = (ptrdiff_t)side + 8, .dx = 1.0,
		.dy = 1.0, .cfl = 0.9, .lambda_idle = 1.0, .lambda = lambda, .bound = bound,
		.table_size = SS_CFL_TABLE_SIZE,
	};
	struct ss_cuda_euler *e = NULL;
	ss_error_set_quiet(1);
	const int err = ss_cuda_euler_create(&e, &s);
	ss_error_set_quiet(0);
	CHECK(err == SS_ERR_INPUT && e == NULL, "%.0f^2 cells on a device with %.1f GB free: "
	      "status %d, not refused as input", side, free_bytes * 1e-9, err);
	CHECK(strstr(ss_error_last_message(), "fit") != NULL,
	      "the refusal does not say what fits: %s", ss_error_last_message());
	printf("  too big: %s\n", ss_error_last_message());
}

int main(void)
{
	if (euler_cases_start(&seed)) {
		printf("test_cuda: the generic path refused\n");
		return 1;
	}
	const struct ss_device gpu = {SS_DEVICE_CUDA, 0};
	ss_error_set_quiet(1);
	const int missing = ss_device_check(&gpu, "cuda:0");
	ss_error_set_quiet(0);
	if (missing) {
		/* what a machine without a GPU checks: the refusals, as bad input */
		char why[512];
		snprintf(why, sizeof why, "%s", ss_error_last_message());
		CHECK(missing == SS_ERR_INPUT, "no GPU: ss_device_check status %d, not bad input",
		      missing);
		struct euler_case c;
		struct ss_cuda_euler *e = NULL;
		if (euler_case_init(&c, 0, seed) == 0) {
			ss_error_set_quiet(1);
			const int err = create(&c, &e);
			ss_error_set_quiet(0);
			CHECK(err == SS_ERR_INPUT && e == NULL,
			      "no GPU: the device's loop was not refused as bad input (status %d)", err);
			euler_case_release(&c);
		}
		CHECK_SKIP("the GPU tests: %s", why);
		return check_report();
	}
	char what[256];
	ss_cuda_device_describe(0, what, sizeof what);
	printf("test_cuda: seed %llu, cuda:0 (%s), against the generic path\n",
	       (unsigned long long)seed, what);
	RUN(test_bits);
	RUN(test_again);
	RUN(test_nan);
	RUN(test_too_big);
	return check_report();
}
