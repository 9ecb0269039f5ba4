/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * hysteresis.c - sand at rest and moving sand (doc/model.md#hysteresis,
 * stepper.h): each flow cell's state, kept in its material number (2n: at
 * rest, material n's static angle a_s; 2n + 1: moving, its repose angle
 * a_d).  A face takes the larger number of its two cells (face.h), so a
 * face beside moving sand of the same material slides at a_d.
 *
 * The states change between steps, from the heights the step left:
 *
 *   at rest -> moving   where a face of the cell is steeper than tan a_s
 *   moving  -> at rest  where no face of the cell carries more sliding
 *                       flux at a_d, f_d(s) |g_n| / s, than a Coulomb
 *                       face steeper than a_d by the steady rule's
 *                       slope tolerance
 *
 * (the faces that carry flux, s and g_n of doc/model.md#face-flux).  A
 * face at a_d comes down to tan a_d only in the limit, and one steep
 * along itself (g_t) but level across it carries nothing: both would keep
 * a cell moving for ever by its slope alone.  A cell's new
 * state depends on its heights' stencil and its own old state only, so it
 * is the same for any thread count, tile size and rank count.  Cells that
 * do not flow are "at rest" (0): a face between a flow cell and an open
 * cell takes the flow cell's state.
 */
#include "core/hysteresis.h"

#include <math.h>
#include <string.h>

#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/boundary.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

/* the state bit of a number: a face takes the larger number of its two
 * cells (face.h), so a face beside moving sand slides at a_d, as the
 * avalanche takes the sand at its edge */
enum { AT_REST = 0, MOVING = 1 };

int ss_stepper_set_hysteresis(struct ss_stepper *st, double static_deg)
{
	const struct ss_closure *c = &st->closure;
	if (!(static_deg > 0.0 && static_deg < 90.0))
		return ss_error_input("static angle %g: expected degrees in (0, 90)", static_deg);
	if (static_deg < c->repose_angle_deg)
		return ss_error_input("static angle %g deg is below the repose angle %g deg: sand at "
		                      "rest starts to slide at an angle at least the one where moving "
		                      "sand stops", static_deg, c->repose_angle_deg);
	if (st->material)
		return ss_error_input("a static angle with a field of materials is not supported: "
		                      "give one repose angle");
	if (static_deg == c->repose_angle_deg)
		return SS_OK;   /* no hysteresis: the model of one angle */
	st->materials = ss_alloc(2, sizeof *st->materials, "hysteresis");
	st->material = ss_alloc(ss_grid_storage_cells(&st->grid), sizeof *st->material,
	                        "hysteresis");
	if (!st->materials || !st->material)
		return SS_ERR_FAIL;
	st->materials[MOVING] = *c;   /* `closure` stays a_d's: the rules' scale */
	int err = ss_closure_init(&st->materials[AT_REST], c->kind, static_deg, c->gamma, c->nu);
	if (err)
		return err;
	st->material_count = 2;
	st->hysteresis = 1;
	memset(st->material, 0, ss_grid_storage_cells(&st->grid) * sizeof *st->material);
	return SS_OK;
}

/* Of the faces of cell k that carry flux (the kernel's expressions: g_n
 * across, g_t the mean of the central differences along, a wall neighbour
 * mirrored): the largest s^2 into *s2_max, and the largest sliding flux
 * over nu at a_d, f_d(s) |g_n| / s, returned. */
static double cell_faces(const struct ss_grid *g, const double *h, const uint8_t *t,
                         ptrdiff_t k, const struct ss_closure *moving, double *s2_max)
{
	const ptrdiff_t s = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	/* the four faces: (a, normal, along, 1/spacing, 1/(2 spacing along)) */
	const ptrdiff_t a[4] = {k - 1, k, k - s, k};
	const ptrdiff_t normal[4] = {1, 1, s, s}, along[4] = {s, s, 1, 1};
	const double inv_n[4] = {inv_dx, inv_dx, inv_dy, inv_dy};
	const double inv_2a[4] = {inv_2dy, inv_2dy, inv_2dx, inv_2dx};
	double q_max = 0.0, flux_max = 0.0;
	for (int f = 0; f < 4; f++) {
		double s2;
		const double flux = ss_sweep_face_sliding(h, t, a[f], normal[f], along[f], inv_n[f],
		                                          inv_2a[f], moving, &s2);
		q_max = s2 > q_max || s2 != s2 ? s2 : q_max;
		flux_max = flux > flux_max || flux != flux ? flux : flux_max;
	}
	*s2_max = q_max;
	return flux_max;
}

long long ss_hysteresis_update(struct ss_stepper *st, double slope_tol)
{
	const struct ss_grid *g = &st->grid;
	const struct ss_face_table *rules = &st->sweeper->materials;
	const double e = slope_tol;
	const uint8_t *t = st->cell_types;
	const double *h = st->height;
	uint16_t *state = st->material;
	long long changed = 0, moving_cells = 0;

	ss_boundary_fill_heights(g, &st->boundary, st->height);
	#pragma omp parallel for schedule(static) reduction(+:changed, moving_cells)
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(t, k) != SS_CELL_FLOW)
				continue;
			const uint16_t old = state[k], rest = old & ~MOVING, moving = old | MOVING;
			const struct ss_closure *moving_law = &st->materials[moving];
			double s2;
			const double flux = cell_faces(g, h, t, k, moving_law, &s2);
			/* the steady rule's tolerance (stepper.h): the flux of a
			 * Coulomb face steeper than a_d by slope_tol */
			const double te = moving_law->tan_cr + e;
			const double flux_tol = e / sqrt(1.0 + te * te);
			/* a NaN slope leaves the state: the guard stops the run */
			const uint16_t now = old == rest ? (s2 > rules->tan_cr2[rest] ? moving : rest)
			                                 : (flux > flux_tol ? moving : rest);
			state[k] = now;
			changed += now != old;
			moving_cells += now == moving;
		}
	}
	double sums[2] = {(double)changed, (double)moving_cells};
	ss_comm_reduce(NULL, 0, sums, 2);
	st->flowing_cells = (long long)sums[1];
	if (sums[0] > 0.0) {
		/* the states of the halo, and every tile swept and measured
		 * again: a lower angle may set a resting tile sliding */
		ss_boundary_fill_materials(g, &st->boundary, st->material);
		ss_sweeper_wake_all(st);
	}
	return (long long)sums[0];
}

void ss_hysteresis_start(struct ss_stepper *st)
{
	const size_t n = ss_grid_storage_cells(&st->grid);
	for (size_t k = 0; k < n; k++)
		st->material[k] &= (uint16_t)~MOVING;
	ss_boundary_fill_materials(&st->grid, &st->boundary, st->material);
}

void ss_hysteresis_restore(struct ss_stepper *st, const uint8_t *moving)
{
	const struct ss_grid *g = &st->grid;
	double count = 0.0;
	ss_hysteresis_start(st);
	for (int j = 0; j < g->ny && moving; j++)
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const int flows = ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW;
			const int now = flows && moving[(size_t)j * g->nx + i];
			st->material[k] = (uint16_t)(st->material[k] | (now ? MOVING : AT_REST));
			count += now;
		}
	ss_comm_reduce(NULL, 0, &count, 1);
	st->flowing_cells = (long long)count;
	ss_boundary_fill_materials(g, &st->boundary, st->material);
}
