/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sweeper.c - the kernel a stepper drives: the fast or the reference sweep
 * behind one call per pass, its timers and tile counts (see sweeper.h).
 */
#include "core/sweeper.h"

#include <math.h>
#include <string.h>

#include "core/ledger.h"
#include "core/stages.h"
#include "core/sources.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

int ss_sweeper_create(struct ss_sweeper **out, const struct ss_stepper *st,
                      const struct ss_tiling *tiling, double tiles_all)
{
	struct ss_sweeper *w = ss_alloc(1, sizeof *w, "sweeper");
	*out = w;
	if (!w)
		return SS_ERR_FAIL;
	memset(w, 0, sizeof *w);
	w->tiling = *tiling;
	w->tiles_all = tiles_all;
	ss_boundary_neighbours(&st->grid, &st->boundary, &w->rank_south, &w->rank_north);
	ss_cfl_bound_init(&w->cfl_bound, &st->closure);
	ss_face_rule_init(&w->face_rule, &st->closure);
	w->edges_in = ss_alloc(2 * (size_t)w->tiling.tiles_x, 1, "tile flags");
	return w->edges_in ? SS_OK : SS_ERR_FAIL;
}

void ss_sweeper_destroy(struct ss_sweeper *w)
{
	if (!w)
		return;
	ss_sweep_fast_release(&w->fast);
	ss_free(w->edges_in);
	ss_free(w->flux_y);
	ss_free(w->flux_x);
	ss_free(w->cell_type_bytes);
	ss_face_table_release(&w->materials);
	ss_free(w);
}

int ss_sweeper_rules(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	ss_cfl_bound_init(&w->cfl_bound, &st->closure);
	ss_face_rule_init(&w->face_rule, &st->closure);
	if (!st->material)
		return SS_OK;
	for (int m = 0; m < st->material_count; m++)
		ss_cfl_bound_widen(&w->cfl_bound, &st->materials[m], st->closure.nu);
	int err = ss_face_table_create(&w->materials, st->materials, st->material_count);
	w->face_rule.table = &w->materials;
	w->face_rule.material = st->material;
	return err;
}

int ss_sweeper_change_rules(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	struct ss_face_table old = w->materials;
	const struct ss_face_rule rule = w->face_rule;
	const struct ss_cfl_bound bound = w->cfl_bound;
	memset(&w->materials, 0, sizeof w->materials);
	const int err = ss_sweeper_rules(st);
	if (err) {   /* the new table goes, the old one stays */
		ss_face_table_release(&w->materials);
		w->materials = old;
		w->face_rule = rule;
		w->cfl_bound = bound;
	} else {
		ss_face_table_release(&old);
	}
	return err;
}

int ss_sweeper_prepare(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	if (st->kernel == SS_KERNEL_REFERENCE) {
		/* the reference sweep reads one type byte per cell */
		const size_t n = ss_grid_storage_cells(g);
		w->flux_x = ss_alloc(n, sizeof(double), "x-face fluxes");
		w->flux_y = ss_alloc(n, sizeof(double), "y-face fluxes");
		w->cell_type_bytes = ss_alloc(n, 1, "cell types");
		if (!w->flux_x || !w->flux_y || !w->cell_type_bytes)
			return SS_ERR_FAIL;
		ss_cell_types_unpack(st->cell_types, 0, n, w->cell_type_bytes);
		return SS_OK;
	}
	/* periodic y across ranks is the ranks' business (comm.h) */
	return ss_sweep_fast_init(&w->fast, g, &w->tiling, ss_parallel_max_threads(),
	                          st->boundary.side[SS_WEST] == SS_SIDE_PERIODIC,
	                          st->boundary.side[SS_SOUTH] == SS_SIDE_PERIODIC &&
	                          ss_grid_is_whole(g),
	                          st->cell_types, st->ledger->open_faces,
	                          st->ledger->open_face_count);
}

void ss_sweeper_wake_all(struct ss_stepper *st)
{
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_wake_all(&st->sweeper->fast, &st->grid, st->height, st->cell_types);
}

void ss_sweeper_count_superstep(struct ss_sweeper *w, double awake, int evaluations)
{
	w->tile_sweeps += awake / evaluations;
	w->tiles_evaluated += awake;
	w->tile_evaluation_slots += evaluations * w->tiles_all;
}

int ss_stages_arrays_create(const struct ss_stepper *st, const char *const names[4],
                            double **y0, double **d1, double **d2, double **m0)
{
	double **arrays[4] = {y0, d1, d2, m0};
	const size_t n = ss_grid_storage_cells(&st->grid);
	for (int k = 0; k < 4; k++) {
		if (!(*arrays[k] = ss_alloc(n, sizeof(double), names[k])))
			return SS_ERR_FAIL;
		if (k == 0)
			memcpy(*y0, st->height, n * sizeof(double));
		else
			memset(*arrays[k], 0, n * sizeof(double));
	}
	return SS_OK;
}

void ss_stages_take_back(struct ss_stepper *st, const double *y0)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	if (st->kernel == SS_KERNEL_FAST) {
		/* the tiles swept so far in the super-step: the others did not
		 * change (a tile is left out of a stage only when it cannot) */
		struct ss_sweep_fast *f = &w->fast;
		for (int k = 0; k < f->tiles; k++) {
			if (!f->superstep_swept[k])
				continue;
			const struct ss_tile_span sp = ss_tiling_span(&w->tiling, g,
			                                              k % w->tiling.tiles_x,
			                                              k / w->tiling.tiles_x);
			for (int j = sp.j0; j < sp.j1; j++) {
				const ptrdiff_t k0 = ss_grid_index(g, sp.i0, j);
				memcpy(st->height + k0, y0 + k0, (size_t)(sp.i1 - sp.i0) * sizeof(double));
			}
		}
		memset(f->superstep_swept, 0, (size_t)f->tiles);
		memset(f->moving_superstep, 0, (size_t)f->tiles);
		memset(f->edges_superstep, 0, (size_t)f->tiles);
	} else {   /* every cell, every stage */
		for (int j = 0; j < g->ny; j++) {
			const ptrdiff_t k0 = ss_grid_index(g, 0, j);
			memcpy(st->height + k0, y0 + k0, (size_t)g->nx * sizeof(double));
		}
	}
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	ss_sweeper_wake_all(st);
}

void ss_sweeper_mark_sources(struct ss_stepper *st)
{
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_mark_sources(&st->sweeper->fast, &st->grid,
		                           ss_sources_rate(st->sources));
}

/* The tiles the coming pass sweeps on this rank (the reference sweep:
 * all). */
static double tiles_to_sweep(const struct ss_stepper *st)
{
	const struct ss_sweeper *w = st->sweeper;
	return st->kernel == SS_KERNEL_FAST
		? ss_sweep_fast_awake(&w->fast) : (double)w->tiling.tiles_x * w->tiling.tiles_y;
}

double ss_sweeper_measure(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double t0 = ss_parallel_wall_seconds();
	double s_max = st->kernel == SS_KERNEL_FAST
		? ss_sweep_fast_begin(&w->fast, g, st->height, st->cell_types)
		: ss_sweep_fluxes(g, &w->tiling, &w->face_rule, st->height,
		                  w->cell_type_bytes, w->flux_x, w->flux_y);
	w->seconds_measure += ss_parallel_wall_seconds() - t0;
	w->tiles_awake = w->tiles_awake_here = tiles_to_sweep(st);
	ss_comm_reduce(&s_max, 1, &w->tiles_awake, 1);
	return isinf(s_max) ? NAN : s_max;
}

/* The start of an RKL2 stage after the first: the halo and what the sweep
 * reads besides the heights (the fast sweep's ring rows, the reference
 * sweep's fluxes), but no slope and nothing summed over the ranks: the
 * super-step's length is fixed, and a NaN shows in the stage's change.
 * Returns the tiles this rank sweeps. */
static double measure_stage(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double t0 = ss_parallel_wall_seconds();
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_save_rings(&w->fast, g, st->height);
	else
		ss_sweep_fluxes(g, &w->tiling, &w->face_rule, st->height, w->cell_type_bytes,
		                w->flux_x, w->flux_y);
	w->seconds_measure += ss_parallel_wall_seconds() - t0;
	return tiles_to_sweep(st);
}

/* After a pass of the fast sweep that planned the next: the tiles here
 * that changed edges of the ranks beside wake (sweep.h). */
static void wake_across(struct ss_stepper *st)
{
	struct ss_sweeper *w = st->sweeper;
	if (st->kernel != SS_KERNEL_FAST || ss_grid_is_whole(&st->grid))
		return;
	const size_t n = (size_t)w->tiling.tiles_x;
	uint8_t *from_south = w->edges_in, *from_north = w->edges_in + n;
	ss_comm_exchange(w->rank_south, w->rank_north, w->fast.edges_out_south, from_south,
	                 w->fast.edges_out_north, from_north, n);
	ss_sweep_fast_wake_across(&w->fast, w->rank_south >= 0 ? from_south : NULL,
	                          w->rank_north >= 0 ? from_north : NULL);
}

/* The reference sweep's fluxes of the open faces, as the fast sweep writes
 * them itself. */
static void copy_open_fluxes(struct ss_stepper *st)
{
	const struct ss_sweeper *w = st->sweeper;
	struct ss_ledger *l = st->ledger;
	for (size_t m = 0; m < l->open_face_count; m++) {
		const struct ss_open_face *f = &l->open_faces[m];
		l->open_flux[m] = f->axis == 0 ? w->flux_x[f->index] : w->flux_y[f->index];
	}
}

double ss_sweeper_euler(struct ss_stepper *st, double dt)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	const double *src = ss_sources_rate(st->sources);
	const double t0 = ss_parallel_wall_seconds();
	double rate_max;
	w->tile_sweeps += w->tiles_awake;
	w->tiles_evaluated += w->tiles_awake;
	w->tile_evaluation_slots += w->tiles_all;
	if (st->kernel == SS_KERNEL_FAST) {
		rate_max = ss_sweep_fast_step(&w->fast, g, &w->face_rule, dt, src, st->bedrock,
		                              st->cell_types, st->height, st->ledger->open_flux);
	} else {
		if (st->bedrock)
			ss_sweep_limit(g, &w->tiling, dt, st->height, st->bedrock, w->flux_x,
			               w->flux_y);
		rate_max = ss_sweep_update(g, &w->tiling, dt, w->flux_x, w->flux_y, src,
		                           w->cell_type_bytes, st->height);
	}
	w->seconds_sweep += ss_parallel_wall_seconds() - t0;
	if (st->kernel == SS_KERNEL_REFERENCE)
		copy_open_fluxes(st);
	wake_across(st);
	return rate_max;
}

double ss_sweeper_stage(struct ss_stepper *st, const struct ss_sweep_stage *stage, int last,
                        int measured, double *awake)
{
	struct ss_sweeper *w = st->sweeper;
	const struct ss_grid *g = &st->grid;
	const double *src = ss_sources_rate(st->sources);
	*awake += measured ? w->tiles_awake_here : measure_stage(st);
	const double t1 = ss_parallel_wall_seconds();
	double change;
	if (st->kernel == SS_KERNEL_FAST) {
		change = ss_sweep_fast_stage(&w->fast, g, &w->face_rule, stage, last, src,
		                             st->cell_types, st->height, st->ledger->open_flux);
	} else {
		change = ss_sweep_stage_update(g, &w->tiling, stage, w->flux_x, w->flux_y, src,
		                               w->cell_type_bytes, st->height);
	}
	w->seconds_sweep += ss_parallel_wall_seconds() - t1;
	if (!stage->estimate_only) {
		if (st->kernel == SS_KERNEL_REFERENCE)
			copy_open_fluxes(st);
		wake_across(st);
	}
	return change;
}
