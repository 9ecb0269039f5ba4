/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * euler_cases.h - the states the GPU's forward-Euler loop is held to, and
 * the CPU's reference steps it must give the bits of (tests/test_point.c
 * on the CPU, tests/gpu/test_cuda.c on a GPU).
 *
 * A case: a grid with scattered walls and open cells, sides of every kind
 * (periodic, wall, open), one closure, random heights from below to far
 * above the critical slope.  The reference step is the stepper's reference
 * sweep (sweep.h: ss_sweep_fluxes, ss_sweep_update) with bench's step rule
 * (bench.c): dt = cfl / (2 Lambda (1/dx^2 + 1/dy^2)), Lambda = nu
 * table(S_max), or the idle rate when nothing slides.  The caller runs it
 * on the generic path (cpu.h), whose bits the device's are.
 */
#ifndef SANDSLIDE_TESTS_EULER_CASES_H
#define SANDSLIDE_TESTS_EULER_CASES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "core/face.h"
#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/cpu.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

#define EULER_CASES_CFL 0.9

static int same_bits(double a, double b)
{
	return memcmp(&a, &b, sizeof a) == 0;
}

/* What both programs' main() does first: the seed (SANDSLIDE_TEST_SEED
 * overrides *seed), 2 threads, and the generic path, whose bits the
 * device's are (face.h); nonzero if that path is refused. */
static int euler_cases_start(uint64_t *seed)
{
	const char *env = getenv("SANDSLIDE_TEST_SEED");
	if (env && *env)
		*seed = strtoull(env, NULL, 10);
	ss_parallel_set_threads(2);
	return ss_cpu_select("generic");
}

struct euler_case {
	char name[128];
	struct ss_stepper st;        /* reference kernel: byte types, fluxes */
	double lambda_idle;          /* m^2/s */
	double bound[SS_CFL_TABLE_SIZE];
};

static const struct {
	enum ss_closure_kind kind;
	double gamma;
	const char *name;
} euler_closures[] = {
	{SS_CLOSURE_COULOMB, 1.0, "coulomb"},
	{SS_CLOSURE_BINGHAM, 1.0, "bingham"},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 0.5, "herschel-bulkley 0.5"},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 2.0, "herschel-bulkley 2"},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 0.3, "herschel-bulkley 0.3 (pow)"},
	{SS_CLOSURE_CASSON, 1.0, "casson"},
};
#define EULER_CLOSURES ((int)(sizeof euler_closures / sizeof *euler_closures))

/* Case number `number` (any int; its sides, sizes and closure follow from
 * it and the seed) set up, its halo filled; nonzero if refused. */
static int euler_case_init(struct euler_case *c, int number, uint64_t seed)
{
	struct rng r = {seed + (uint64_t)number * 7919u};
	static const enum ss_side_kind kinds[3] = {SS_SIDE_WALL, SS_SIDE_OPEN, SS_SIDE_PERIODIC};
	const int nx = 5 + rng_int(&r, 90), ny = 3 + rng_int(&r, 70);
	const int cl = number % EULER_CLOSURES;
	const enum ss_side_kind kx = kinds[number / EULER_CLOSURES % 3];
	const enum ss_side_kind ky = kinds[rng_int(&r, 3)];
	struct ss_boundary b = {{kx, kx == SS_SIDE_PERIODIC ? kx : kinds[rng_int(&r, 2)], ky,
	                         ky == SS_SIDE_PERIODIC ? ky : kinds[rng_int(&r, 2)]},
	                        0.01 * (rng_uniform(&r) - 0.5)};
	const double dx = 0.005 + 0.02 * rng_uniform(&r), dy = 0.005 + 0.02 * rng_uniform(&r);
	struct ss_grid g;
	struct ss_closure closure;
	memset(c, 0, sizeof *c);
	snprintf(c->name, sizeof c->name, "case %d: %d x %d, %s, sides %s %s %s %s", number, nx,
	         ny, euler_closures[cl].name, ss_side_kind_name(b.side[0]),
	         ss_side_kind_name(b.side[1]), ss_side_kind_name(b.side[2]),
	         ss_side_kind_name(b.side[3]));
	if (ss_grid_init(&g, nx, ny, dx, dy, 0.0, 0.0) ||
	    ss_closure_init(&closure, euler_closures[cl].kind, 35.0, euler_closures[cl].gamma,
	                    0.05) ||
	    ss_stepper_init(&c->st, &g, &closure, &b, EULER_CASES_CFL, 0, 0))
		return -1;
	c->st.kernel = SS_KERNEL_REFERENCE;
	/* amplitude: from well below to well above tan 35 deg per cell */
	const double amp = dx * pow(10.0, -1.0 + 2.0 * rng_uniform(&r));
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const ptrdiff_t k = ss_grid_index(&c->st.grid, i, j);
			const double u = rng_uniform(&r);
			const enum ss_cell_type t = u < 0.06 ? SS_CELL_WALL
			                          : u < 0.09 ? SS_CELL_OPEN : SS_CELL_FLOW;
			ss_cell_type_set(c->st.cell_types, k, t);
			/* a ramp and noise: faces slide at first, then settle */
			c->st.height[k] = t == SS_CELL_FLOW ? amp * (0.5 * i + rng_uniform(&r))
			                : t == SS_CELL_OPEN ? b.open_level : 0.0;
		}
	}
	if (ss_stepper_prepare(&c->st)) {
		ss_stepper_release(&c->st);
		return -1;
	}
	c->lambda_idle = closure.nu * ss_cfl_bound_lookup(&c->st.sweeper->cfl_bound,
	                                                  2.0 * closure.tan_cr);
	ss_cfl_bound_thresholds(c->bound);
	ss_boundary_fill_heights(&c->st.grid, &c->st.boundary, c->st.height);
	return 0;
}

static void euler_case_release(struct euler_case *c)
{
	ss_stepper_release(&c->st);
}

/* One reference step of c's stepper, in place; returns dt. */
static double euler_case_step(struct euler_case *c)
{
	struct ss_stepper *st = &c->st;
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double s_max = ss_sweep_fluxes(g, &w->tiling, &w->face_rule, st->height,
	                                     w->cell_type_bytes, w->flux_x, w->flux_y);
	double lambda = st->closure.nu * ss_cfl_bound_lookup(&w->cfl_bound, s_max);
	lambda = lambda > 0.0 ? lambda : c->lambda_idle;
	const double dt = st->cfl / (2.0 * lambda * inv_d2);
	ss_sweep_update(g, &w->tiling, dt, w->flux_x, w->flux_y, NULL, w->cell_type_bytes,
	                st->height);
	return dt;
}

#endif
