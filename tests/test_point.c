/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_point.c - face_point.h, the face flux and cell update the CPU and the
 * GPU share (doc/gpu.md#the-same-bits), checked on the CPU:
 *
 *   flux             ss_point_flux gives the bits of ss_face_fluxes on the
 *                    generic path, every closure form, random gradients from
 *                    far below to far above the critical slope, NaN and
 *                    huge ones
 *   cfl entry        ss_point_cfl_entry on ss_cfl_bound_thresholds picks the
 *                    entry ss_cfl_bound_lookup picks (atan), at random slopes
 *                    and next to every threshold
 *   device loop      the GPU's forward-Euler loop (src/cuda/euler.cu: halo
 *                    by ss_point_ghost, the largest slope by a maximum of
 *                    ss_point_cell_slope2, ss_point_step_size, each cell's
 *                    update from its four faces into a second buffer),
 *                    written here on the host with the same functions, gives
 *                    the reference sweep's bits at every step (euler_cases.h:
 *                    every closure, walls, open cells, every kind of side)
 *
 * What this cannot see: the thread mapping and nvcc's code, which
 * tests/gpu/ checks on a GPU (the same cases) and tests/gpu/check_ptx.sh in
 * the PTX (no fused multiply-add).  About 1 s.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "euler_cases.h"
#include "core/face_point.h"
#include "sandslide/cpu.h"
#include "sandslide/parallel.h"

static uint64_t seed = 20261205;

/* ---- flux ----------------------------------------------------------------- */

static void test_flux(void)
{
	struct rng r = {seed};
	int faces = 0;
	for (int c = 0; c < EULER_CLOSURES; c++) {
		struct ss_closure closure;
		struct ss_face_rule rule;
		const double angle = 20.0 + 25.0 * rng_uniform(&r);
		CHECK(ss_closure_init(&closure, euler_closures[c].kind, angle, euler_closures[c].gamma,
		                      0.01 + rng_uniform(&r)) == 0, "%s refused", euler_closures[c].name);
		ss_face_rule_init(&rule, &closure);
		const struct ss_point_rule p = ss_face_point_rule(&rule);
		enum { N = 4000 };
		static double gn[N], gt[N], row[N];
		for (int k = 0; k < N; k++) {
			/* |g| from 1e-3 to 1e3 tan a_cr, either sign; a few exact and odd ones */
			const double scale = closure.tan_cr * pow(10.0, -3.0 + 6.0 * rng_uniform(&r));
			gn[k] = scale * (2.0 * rng_uniform(&r) - 1.0);
			gt[k] = scale * (2.0 * rng_uniform(&r) - 1.0);
		}
		gn[0] = closure.tan_cr, gt[0] = 0.0;          /* at the threshold */
		gn[1] = NAN, gt[1] = 0.1;
		gn[2] = 1e200, gt[2] = -1e200;
		gn[3] = 0.0, gt[3] = 0.0;
		ss_face_fluxes(&rule, N, gn, gt, row);
		int bad = 0;
		for (int k = 0; k < N; k++) {
			const double one = ss_point_flux(&p, gn[k], gt[k]);
			if (!same_bits(one, row[k]) && bad++ < 3)
				CHECK(0, "%s: g_n %.17g g_t %.17g: ss_point_flux %.17g, the generic "
				      "path's ss_face_fluxes %.17g", euler_closures[c].name, gn[k], gt[k],
				      one, row[k]);
		}
		CHECK(bad == 0, "%s: %d of %d faces differ from the generic path",
		      euler_closures[c].name, bad, N);
		faces += N;
	}
	printf("  flux: %d faces of %d closures, the generic path's bits\n", faces, EULER_CLOSURES);
}

/* ---- cfl entry ------------------------------------------------------------ */

static void test_cfl_entry(void)
{
	struct rng r = {seed + 1};
	static double bound[SS_CFL_TABLE_SIZE];
	struct ss_closure closure;
	struct ss_cfl_bound table;
	CHECK(ss_closure_init(&closure, SS_CLOSURE_COULOMB, 30.0, 1.0, 1.0) == 0, "closure refused");
	ss_cfl_bound_init(&table, &closure);
	/* entries made distinct, so that a wrong entry shows as a wrong value */
	for (int k = 0; k <= SS_CFL_TABLE_SIZE; k++)
		table.lambda_max[k] = k;
	table.tan_cr = 0.0;
	ss_cfl_bound_thresholds(bound);
	int checked = 0, bad = 0;
	for (int k = 1; k < SS_CFL_TABLE_SIZE; k++)
		CHECK(bound[k] > bound[k - 1], "thresholds %d and %d: %.17g, %.17g not increasing",
		      k - 1, k, bound[k - 1], bound[k]);
	for (int n = 0; n < 200000; n++) {
		double s;
		if (n < 6 * SS_CFL_TABLE_SIZE) {
			/* each threshold, its neighbours below and above */
			const double b = bound[n / 6 % SS_CFL_TABLE_SIZE];
			const int w = n % 6;
			s = w == 0 ? b : w == 1 ? nextafter(b, 0.0) : w == 2 ? nextafter(b, INFINITY)
			  : w == 3 ? nextafter(nextafter(b, INFINITY), INFINITY) : b * (1 + 1e-12);
		} else {
			s = pow(10.0, -6.0 + 12.0 * rng_uniform(&r));
		}
		if (!(s > 0.0))
			continue;
		const double want = ss_cfl_bound_lookup(&table, s);
		const double got = table.lambda_max[ss_point_cfl_entry(bound, SS_CFL_TABLE_SIZE, s)];
		checked++;
		if (want != got && bad++ < 3)
			CHECK(0, "slope %.17g: atan's entry %g, the thresholds' %g", s, want, got);
	}
	const double inf_entry = table.lambda_max[ss_point_cfl_entry(bound, SS_CFL_TABLE_SIZE,
	                                                             INFINITY)];
	CHECK(inf_entry == ss_cfl_bound_lookup(&table, INFINITY),
	      "an infinite slope: atan's entry %g, the thresholds' %g",
	      ss_cfl_bound_lookup(&table, INFINITY), inf_entry);
	CHECK(bad == 0, "%d of %d slopes got another entry than atan's", bad, checked);
	printf("  cfl entry: %d slopes, atan's entry every time\n", checked);
}

/* ---- device loop ---------------------------------------------------------- */

/* euler.cu's kernels, one after the other on the host. */
struct host_device {
	double *h[2];
	int current;
};

static void host_fill_sides(const struct euler_case *c, double *h)
{
	const struct ss_grid *g = &c->st.grid;
	const int nx = g->nx, ny = g->ny;
	const enum ss_side_kind *side = c->st.boundary.side;
	const double open = c->st.boundary.open_level;
	for (int j = 0; j < ny; j++) {
		h[ss_grid_index(g, -1, j)] = ss_point_ghost(side[SS_WEST], h[ss_grid_index(g, nx - 1, j)],
		                                            open);
		h[ss_grid_index(g, nx, j)] = ss_point_ghost(side[SS_EAST], h[ss_grid_index(g, 0, j)], open);
	}
	for (int i = -1; i <= nx; i++) {
		h[ss_grid_index(g, i, -1)] = ss_point_ghost(side[SS_SOUTH],
		                                            h[ss_grid_index(g, i, ny - 1)], open);
		h[ss_grid_index(g, i, ny)] = ss_point_ghost(side[SS_NORTH], h[ss_grid_index(g, i, 0)],
		                                            open);
	}
}

static double host_step(const struct euler_case *c, const struct ss_point_rule *rule,
                        struct host_device *d, int *nonfinite)
{
	const struct ss_grid *g = &c->st.grid;
	const uint8_t *type = c->st.sweeper->cell_type_bytes;
	const ptrdiff_t stride = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	double *h = d->h[d->current], *next = d->h[1 - d->current];
	host_fill_sides(c, h);
	double s2 = 0.0;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			s2 = fmax(s2, ss_point_cell_slope2(h, type, ss_grid_index(g, i, j), stride,
			                                   i == g->nx - 1, j == g->ny - 1, inv_dx, inv_dy,
			                                   inv_2dx, inv_2dy));
	const double dt = ss_point_step_size(s2, c->st.sweeper->cfl_bound.lambda_max, c->bound,
	                                     SS_CFL_TABLE_SIZE, rule->tan_cr, rule->nu,
	                                     c->lambda_idle, c->st.cfl, inv_d2);
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const int flows = type[k] == SS_POINT_FLOW;
			const double r = ss_point_cell_rate(rule, h, type, k, stride, inv_dx, inv_dy,
			                                    inv_2dx, inv_2dy);
			next[k] = ss_point_euler(h[k], dt, r, flows);
			*nonfinite |= flows && !isfinite(r);
		}
	}
	d->current = 1 - d->current;
	return dt;
}

static void test_device_loop(void)
{
	int cases = 0, steps_total = 0;
	for (int n = 0; n < 3 * EULER_CLOSURES; n++) {
		struct euler_case c;
		if (euler_case_init(&c, n, seed)) {
			CHECK(0, "case %d refused", n);
			continue;
		}
		const struct ss_grid *g = &c.st.grid;
		const size_t cells = ss_grid_storage_cells(g);
		struct host_device d = {{malloc(cells * sizeof(double)), malloc(cells * sizeof(double))}, 0};
		if (!d.h[0] || !d.h[1]) {
			CHECK(0, "out of memory");
			break;
		}
		memcpy(d.h[0], c.st.height, cells * sizeof(double));
		memcpy(d.h[1], c.st.height, cells * sizeof(double));
		const struct ss_point_rule rule = ss_face_point_rule(&c.st.sweeper->face_rule);
		int nonfinite = 0, first_bad = -1;
		for (int step = 0; step < 40 && first_bad < 0; step++) {
			const double dt_ref = euler_case_step(&c);
			const double dt = host_step(&c, &rule, &d, &nonfinite);
			if (!same_bits(dt, dt_ref)) {
				CHECK(0, "%s, step %d: dt %.17g, the reference's %.17g", c.name, step, dt,
				      dt_ref);
				first_bad = step;
			}
			for (int j = 0; j < g->ny && first_bad < 0; j++) {
				for (int i = 0; i < g->nx; i++) {
					const ptrdiff_t k = ss_grid_index(g, i, j);
					if (!same_bits(d.h[d.current][k], c.st.height[k])) {
						CHECK(0, "%s, step %d, cell (%d, %d): %.17g, the reference "
						      "sweep's %.17g", c.name, step, i, j, d.h[d.current][k],
						      c.st.height[k]);
						first_bad = step;
						break;
					}
				}
			}
			steps_total++;
		}
		CHECK(first_bad < 0, "%s: the device's loop left the reference's bits", c.name);
		CHECK(!nonfinite, "%s: a rate was not finite", c.name);
		free(d.h[0]);
		free(d.h[1]);
		euler_case_release(&c);
		cases++;
	}
	printf("  device loop: %d cases, %d steps, the reference sweep's bits\n", cases, steps_total);
}

int main(void)
{
	if (euler_cases_start(&seed)) {
		printf("test_point: the generic path refused\n");
		return 1;
	}
	printf("test_point: seed %llu, generic path\n", (unsigned long long)seed);
	RUN(test_flux);
	RUN(test_cfl_entry);
	RUN(test_device_loop);
	return check_report();
}
