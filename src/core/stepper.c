/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * stepper.c - the stepper's life (init, prepare, restore, release) and its
 * advance loop: adaptive forward-Euler substeps or RKL2 super-steps,
 * events, the steady rule, diagnostics (see stepper.h for the rules).  The
 * kernel it drives is sweeper.c, the sources sources.c, the volume ledger
 * ledger.c, RKL2's super-steps rkl2.c.
 */
#include "sandslide/stepper.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "core/hysteresis.h"
#include "core/ledger.h"
#include "core/rest.h"
#include "core/rkl2.h"
#include "core/stages.h"
#include "core/sources.h"
#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/comm.h"
#include "sandslide/cpu.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

double ss_stepper_memory_bytes(const struct ss_grid *g, enum ss_integrator integrator,
                               enum ss_rest_mode rest)
{
	/* the heights and the sources' rates (doubles) and the packed types,
	 * and the stages' Y_0, D_{j-1}, D_{j-2} and M(Y_0) (RKL2's, also the
	 * approach to rest's); the fast sweep's ring rows and buffers are
	 * below 2 % of that */
	const int stages = integrator == SS_INTEGRATOR_RKL2 || rest == SS_REST_CHEBYSHEV;
	const double doubles = stages ? 6.0 : 2.0;
	return (double)ss_grid_storage_cells(g) * (doubles * sizeof(double) + 0.25);
}

double ss_stepper_bytes(const struct ss_stepper *st)
{
	const double materials = st->material
		? (double)ss_grid_storage_cells(&st->grid) * sizeof *st->material : 0.0;
	return ss_stepper_memory_bytes(&st->grid, st->integrator, st->rest) + materials;
}

void ss_stepper_repose_range(const struct ss_stepper *st, double *min_deg, double *max_deg)
{
	*min_deg = *max_deg = st->closure.repose_angle_deg;
	/* with hysteresis the odd numbers are the moving states, at a_d */
	for (int m = st->hysteresis; m < st->material_count; m += 1 + st->hysteresis) {
		*min_deg = fmin(*min_deg, st->materials[m].repose_angle_deg);
		*max_deg = fmax(*max_deg, st->materials[m].repose_angle_deg);
	}
}

void ss_stepper_slab_rows(const struct ss_grid *g, int tile_nx, int tile_ny, int rank,
                          int *first_row, int *rows)
{
	struct ss_tiling t;
	ss_tiling_init(&t, g, tile_nx, tile_ny);
	long long first = 0, count = t.tiles_y;
	if (ss_comm_size() > 1)
		ss_comm_split_of(t.tiles_y, rank, &first, &count);
	const long long j0 = first * t.tile_ny, j1 = (first + count) * t.tile_ny;
	*first_row = (int)(j0 < g->ny ? j0 : g->ny);
	*rows = (int)((j1 < g->ny ? j1 : g->ny) - *first_row);
}

void ss_stepper_tile_size(const struct ss_stepper *st, int *tile_nx, int *tile_ny)
{
	*tile_nx = st->sweeper->tiling.tile_nx;
	*tile_ny = st->sweeper->tiling.tile_ny;
}

int ss_stepper_init(struct ss_stepper *st, const struct ss_grid *g,
                    const struct ss_closure *c, const struct ss_boundary *b,
                    double cfl, int tile_nx, int tile_ny)
{
	memset(st, 0, sizeof *st);
	if (!(cfl > 0.0 && cfl <= 1.0))
		return ss_error_input("cfl %g is outside (0, 1]", cfl);
	/* the kernel path SANDSLIDE_CPU names (cpu.h), for a program of one
	 * process that did not check it first as the command line does (in a
	 * distributed run ss_cpu_init is collective: the program calls it) */
	int err = ss_comm_size() == 1 ? ss_cpu_init() : SS_OK;
	if (err)
		return err;
	err = ss_boundary_check(b);
	if (err)
		return err;

	/* the tiling of the whole grid, then this rank's run of tile rows */
	struct ss_tiling tiling;
	ss_tiling_init(&tiling, g, tile_nx, tile_ny);
	const long long tile_rows = tiling.tiles_y;
	if (ss_comm_size() > tile_rows)
		return ss_error_input("%d ranks for a grid of %lld tile rows (ny = %lld cells, "
		                      "tiles of %d rows): use at most %lld ranks", ss_comm_size(),
		                      tile_rows, g->global_ny, tiling.tile_ny, tile_rows);
	const double tiles_all = (double)tiling.tiles_x * (double)tile_rows;
	st->grid = *g;
	if (ss_comm_size() > 1) {
		int first_row, rows;
		ss_stepper_slab_rows(g, tile_nx, tile_ny, ss_comm_rank(), &first_row, &rows);
		ss_grid_take_rows(&st->grid, first_row, rows);
		tiling.tiles_y = (rows + tiling.tile_ny - 1) / tiling.tile_ny;
	}
	g = &st->grid;
	/* a default thread count follows this rank's work: on a small grid the
	 * threads of every parallel loop would cost more at its barriers than
	 * they share out (parallel.h); a count asked for stays */
	ss_parallel_threads_for((double)g->nx * (double)g->ny, tiling.tiles_y);
	st->closure = *c;
	st->boundary = *b;
	st->cfl = cfl;

	const size_t n = ss_grid_storage_cells(g);
	st->height = ss_alloc(n, sizeof(double), "heights");
	st->cell_types = ss_alloc(ss_cell_types_bytes(n), 1, "cell types");
	if (!st->height || !st->cell_types ||
	    ss_sweeper_create(&st->sweeper, st, &tiling, tiles_all) ||
	    ss_sources_create(&st->sources) || ss_ledger_create(&st->ledger, g->ny)) {
		ss_stepper_release(st);
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

void ss_stepper_release(struct ss_stepper *st)
{
	ss_rest_destroy(st->rest_state);
	ss_rkl2_destroy(st->rkl2);
	ss_ledger_destroy(st->ledger);
	ss_sources_destroy(st->sources);
	ss_sweeper_destroy(st->sweeper);
	ss_free(st->bedrock);
	ss_free(st->material);
	ss_free(st->materials);
	ss_free(st->cell_types);
	ss_free(st->height);
	memset(st, 0, sizeof *st);
}

int ss_stepper_add_source(struct ss_stepper *st, const uint8_t *mask,
                          double rate, double start, double stop)
{
	return ss_sources_add(st->sources, &st->grid, st->cell_types, mask, rate, start, stop);
}

int ss_stepper_set_bedrock(struct ss_stepper *st, const double *bedrock)
{
	const struct ss_grid *g = &st->grid;
	if (!st->bedrock) {
		st->bedrock = ss_alloc(ss_grid_storage_cells(g), sizeof(double), "bedrock");
		if (!st->bedrock)
			return SS_ERR_FAIL;
	}
	for (size_t k = 0; k < ss_grid_storage_cells(g); k++)
		st->bedrock[k] = -INFINITY;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const double b = bedrock[(size_t)j * g->nx + i];
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (!isfinite(b))
				return ss_error_input("bedrock of %s is %g: it must be finite",
				                      SS_GRID_CELL(g, i, j), b);
			if (ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				st->bedrock[k] = b;
		}
	}
	return SS_OK;
}

/* A material while they are numbered: its closure, its static angle
 * (hysteresis; 0 without) and its number given. */
struct material_entry {
	const struct ss_closure *c;
	double static_deg;
	int given;
};

/* By angle, then kind, gamma, nu and static angle (equal materials side
 * by side), then as given: the order of the materials' numbers. */
static int compare_materials(const void *pa, const void *pb)
{
	const struct material_entry *a = pa, *b = pb;
	const double ka[5] = {a->c->tan_cr, a->c->kind, a->c->gamma, a->c->nu, a->static_deg};
	const double kb[5] = {b->c->tan_cr, b->c->kind, b->c->gamma, b->c->nu, b->static_deg};
	for (int k = 0; k < 5; k++)
		if (ka[k] != kb[k])
			return ka[k] < kb[k] ? -1 : 1;
	return (a->given > b->given) - (a->given < b->given);
}

static int same_closure(const struct ss_closure *a, const struct ss_closure *b)
{
	return a->kind == b->kind && a->tan_cr == b->tan_cr && a->gamma == b->gamma &&
	       a->nu == b->nu;
}

static int same_material(const struct material_entry *a, const struct material_entry *b)
{
	return same_closure(a->c, b->c) && a->static_deg == b->static_deg;
}

/* The materials of set_materials into *out_materials, *out_count and
 * *out_material (NULL and 0 when they are one material, whose closure goes
 * to *smallest); st is not changed.  static_deg: each given material's
 * static angle, part of what makes materials distinct, and the distinct
 * ones' into *out_static (owned; both NULL: none).  Collective. */
static int build_materials(const struct ss_stepper *st, const struct ss_closure *closures,
                           const double *static_deg, int count,
                           const uint16_t *material_of_cell,
                           struct ss_closure **out_materials, int *out_count,
                           uint16_t **out_material, struct ss_closure *smallest,
                           double **out_static)
{
	const struct ss_grid *g = &st->grid;
	*out_materials = NULL;
	*out_material = NULL;
	*out_count = 0;
	/* the given materials by angle; each given number's place among the
	 * distinct closures; those in use (on any rank: all decide alike) */
	struct material_entry *order = ss_alloc((size_t)count, sizeof *order, "materials");
	uint16_t *number = ss_alloc((size_t)count, sizeof *number, "materials");
	double *used = ss_alloc((size_t)count, sizeof *used, "materials");
	int err = order && number && used ? SS_OK : SS_ERR_FAIL;
	for (int m = 0; !err && m < count; m++)
		order[m] = (struct material_entry){&closures[m], static_deg ? static_deg[m] : 0.0, m};
	if (!err)
		qsort(order, (size_t)count, sizeof *order, compare_materials);
	int places = 0;
	for (int k = 0; !err && k < count; k++) {
		if (k > 0 && !same_material(&order[k - 1], &order[k]))
			places++;
		number[order[k].given] = (uint16_t)places;
		used[k] = 0.0;
	}
	for (int j = 0; !err && j < g->ny; j++)
		for (int i = 0; !err && i < g->nx; i++) {
			const int m = material_of_cell[(size_t)j * g->nx + i];
			if (m >= count)
				err = ss_error_input("material %d of %s: the materials are numbered 0 "
				                     "to %d", m, SS_GRID_CELL(g, i, j), count - 1);
			else
				used[number[m]] = 1.0;
		}
	if (!(err = ss_comm_agree(err)))
		ss_comm_reduce(used, count, NULL, 0);
	/* the places in use, renumbered from 0: a face takes the larger
	 * number of its two cells (face.h) */
	int distinct = 0;
	for (int k = 0; !err && k < count; k++)
		used[k] = used[k] != 0.0 ? (double)distinct++ : -1.0;
	struct ss_closure *materials = NULL;
	uint16_t *material = NULL;
	double *statics = NULL;
	int allocated = 1;
	if (!err && distinct > 1) {
		materials = ss_alloc((size_t)distinct, sizeof *materials, "materials");
		material = ss_alloc(ss_grid_storage_cells(g), sizeof *material, "materials");
		allocated = materials && material;
	}
	if (!err && out_static)
		allocated &= (statics = ss_alloc((size_t)distinct, sizeof *statics,
		                                 "static angles")) != NULL;
	if (!err)
		err = ss_comm_agree(allocated ? SS_OK : SS_ERR_FAIL);
	if (!err) {
		for (int k = 0; k < count; k++) {
			const int n = (int)used[number[order[k].given]];
			if (n >= 0 && distinct > 1)
				materials[n] = *order[k].c;
			if (n >= 0 && statics)
				statics[n] = order[k].static_deg;
			if (n == 0)   /* the smallest angle: the rules' scale */
				*smallest = *order[k].c;
		}
	}
	if (!err && distinct > 1) {
		memset(material, 0, ss_grid_storage_cells(g) * sizeof *material);
		for (int j = 0; j < g->ny; j++)
			for (int i = 0; i < g->nx; i++)
				material[ss_grid_index(g, i, j)] = (uint16_t)
					used[number[material_of_cell[(size_t)j * g->nx + i]]];
		*out_materials = materials;
		*out_material = material;
		*out_count = distinct;
	} else {
		ss_free(material);
		ss_free(materials);
	}
	if (!err && out_static)
		*out_static = statics;
	else
		ss_free(statics);
	ss_free(used);
	ss_free(number);
	ss_free(order);
	return err;
}

/* Whether the materials built are st's own: a change that changes nothing. */
static int same_materials(const struct ss_stepper *st, const struct ss_closure *materials,
                          int count, const uint16_t *material, const struct ss_closure *smallest)
{
	if (count != st->material_count || !same_closure(smallest, &st->closure) ||
	    smallest->repose_angle_deg != st->closure.repose_angle_deg)
		return 0;
	for (int m = 0; m < count; m++)
		if (!same_closure(&materials[m], &st->materials[m]))
			return 0;
	const struct ss_grid *g = &st->grid;
	int same = 1;
	for (int j = 0; same && j < g->ny; j++)
		for (int i = 0; same && i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			same = !count || material[k] == st->material[k];
		}
	double differs = !same;
	ss_comm_reduce(&differs, 1, NULL, 0);   /* any rank's */
	return differs == 0.0;
}

static int check_count(const struct ss_stepper *st, int count)
{
	if (count < 1 || count > UINT16_MAX)
		return ss_error_input("%d materials: between 1 and %d are accepted", count,
		                      UINT16_MAX);
	if (st->hysteresis)
		return ss_error_input("materials with a static angle are not supported: hysteresis "
		                      "takes one repose angle");
	return SS_OK;
}

/* check_count, then build_materials without static angles. */
static int checked_materials(const struct ss_stepper *st, const struct ss_closure *closures,
                             int count, const uint16_t *material_of_cell,
                             struct ss_closure **materials, int *distinct,
                             uint16_t **material, struct ss_closure *smallest)
{
	const int err = check_count(st, count);
	return err ? err : build_materials(st, closures, NULL, count, material_of_cell, materials,
	                                   distinct, material, smallest, NULL);
}

/* st's materials become these (st takes them), its old ones freed. */
static void install_materials(struct ss_stepper *st, struct ss_closure *materials,
                              uint16_t *material, int count, const struct ss_closure *smallest)
{
	ss_free(st->material);
	ss_free(st->materials);
	st->materials = materials;
	st->material = material;
	st->material_count = count;
	st->closure = *smallest;
}

int ss_stepper_set_materials(struct ss_stepper *st, const struct ss_closure *closures,
                             int count, const uint16_t *material_of_cell)
{
	struct ss_closure *materials, smallest = st->closure;
	uint16_t *material;
	int distinct;
	const int err = checked_materials(st, closures, count, material_of_cell, &materials,
	                                  &distinct, &material, &smallest);
	if (err)
		return err;
	install_materials(st, materials, material, distinct, &smallest);
	return SS_OK;
}

int ss_stepper_set_hysteresis_materials(struct ss_stepper *st,
                                        const struct ss_closure *closures,
                                        const double *static_deg, int count,
                                        const uint16_t *material_of_cell)
{
	int err = check_count(st, count);
	for (int m = 0; !err && m < count; m++)
		if (!(static_deg[m] >= closures[m].repose_angle_deg && static_deg[m] < 90.0))
			err = ss_error_input("material %d: static angle %g deg: expected degrees from its "
			                     "repose angle, %g, to 90 (sand at rest starts to slide at an "
			                     "angle at least the one where moving sand stops)", m,
			                     static_deg[m], closures[m].repose_angle_deg);
	if (err)
		return err;
	struct ss_closure *materials, smallest = st->closure;
	uint16_t *material;
	double *statics;
	int distinct;
	if ((err = build_materials(st, closures, static_deg, count, material_of_cell, &materials,
	                           &distinct, &material, &smallest, &statics)))
		return err;
	int any = 0;
	for (int n = 0; n < distinct; n++)
		any |= statics[n] != (material ? materials[n] : smallest).repose_angle_deg;
	if (!any || !material) {   /* one material, or none with hysteresis */
		const double a_s = statics[0];
		ss_free(statics);
		install_materials(st, materials, material, distinct, &smallest);
		return material ? SS_OK : ss_stepper_set_hysteresis(st, a_s);
	}
	/* material n at rest is 2n (its static angle), moving 2n + 1 (its
	 * repose angle): a face takes the larger material of its two cells,
	 * and of one material the moving state (face.h, hysteresis.c) */
	struct ss_closure *states = distinct <= UINT16_MAX / 2
		? ss_alloc(2 * (size_t)distinct, sizeof *states, "hysteresis") : NULL;
	if (!states)
		err = distinct > UINT16_MAX / 2
			? ss_error_input("%d materials with hysteresis: at most %d are accepted",
			                 distinct, UINT16_MAX / 2) : SS_ERR_FAIL;
	for (int n = 0; !err && n < distinct; n++) {
		const struct ss_closure *c = &materials[n];
		states[2 * n + 1] = *c;
		err = ss_closure_init(&states[2 * n], c->kind, statics[n], c->gamma, c->nu);
	}
	if (!err) {
		for (size_t k = 0; k < ss_grid_storage_cells(&st->grid); k++)
			material[k] = (uint16_t)(2 * material[k]);
		install_materials(st, states, material, 2 * distinct, &smallest);
		st->hysteresis = 1;
	} else {
		ss_free(states);
		ss_free(material);
	}
	ss_free(materials);
	ss_free(statics);
	return ss_comm_agree(err);
}

int ss_stepper_change_materials(struct ss_stepper *st, const struct ss_closure *closures,
                                int count, const uint16_t *material_of_cell)
{
	struct ss_closure *materials, smallest = st->closure;
	uint16_t *material;
	int distinct;
	int err = checked_materials(st, closures, count, material_of_cell, &materials, &distinct,
	                            &material, &smallest);
	if (err)
		return err;
	if (same_materials(st, materials, distinct, material, &smallest)) {
		ss_free(material);
		ss_free(materials);
		return SS_OK;
	}
	/* the kernel's rules are built before the old materials go: a
	 * failure leaves st as it was */
	struct ss_stepper next = *st;
	next.materials = materials;
	next.material = material;
	next.material_count = distinct;
	next.closure = smallest;
	if ((err = ss_comm_agree(ss_sweeper_change_rules(&next)))) {
		ss_free(material);
		ss_free(materials);
		return err;
	}
	install_materials(st, materials, material, distinct, &smallest);
	if (st->material)
		ss_boundary_fill_materials(&st->grid, &st->boundary, st->material);
	/* what the CFL table sizes starts over: RKL2's super-steps and the
	 * approach to rest (rkl2.h, rest.h); every tile may slide now */
	if (st->rkl2)
		ss_rkl2_scale(st->rkl2, st);
	if (st->rest_state)
		ss_rest_scale(st->rest_state, st);
	ss_sweeper_wake_all(st);
	return SS_OK;
}

/* The checks of ss_stepper_prepare on this rank's cells (the messages name
 * a cell by its index in the whole grid). */
static int check_cells(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const enum ss_cell_type type = ss_cell_type_get(st->cell_types, k);
			if (type == SS_CELL_OPEN)
				st->height[k] = st->boundary.open_level;
			else if (type == SS_CELL_WALL)
				st->height[k] = 0.0;
			else if (st->height[k] == 0.0)
				st->height[k] = 0.0;   /* no -0: h + 0 then keeps every bit */
			if (!isfinite(st->height[k]))
				return ss_error_input("initial height of %s is %g: heights must be finite",
				                      SS_GRID_CELL(g, i, j), st->height[k]);
			if (st->bedrock && type == SS_CELL_FLOW && st->bedrock[k] > st->height[k])
				return ss_error_input("bedrock of %s is %.17g m, above the surface %.17g m: "
				                      "the surface must be at or above the bedrock",
				                      SS_GRID_CELL(g, i, j), st->bedrock[k], st->height[k]);
		}
	}
	return SS_OK;
}

/* The parts of prepare that allocate (each rank's own failure; the caller
 * agrees on it before the next collective call): the sources' field, the
 * ledger's open faces, RKL2's state, the kernel's arrays. */
static int prepare_parts(struct ss_stepper *st)
{
	int err = ss_sweeper_rules(st);
	if (!err)
		err = ss_sources_prepare(st->sources, &st->grid);
	if (!err)
		err = ss_ledger_list_open_faces(st->ledger, &st->grid, st->cell_types);
	if (!err && st->integrator == SS_INTEGRATOR_RKL2)
		err = ss_rkl2_create(&st->rkl2, st);
	/* the approach to rest's stages have negative weights, as RKL2's:
	 * with a bedrock the integrator's own steps go on to the end */
	if (!err && st->rest == SS_REST_CHEBYSHEV && !st->bedrock)
		err = ss_rest_create(&st->rest_state, st);
	return err ? err : ss_sweeper_prepare(st);
}

int ss_stepper_prepare(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_types(g, &st->boundary, st->cell_types);
	int err = ss_comm_agree(check_cells(st));
	if (err)
		return err;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	if (st->bedrock)
		/* bedrock ghosts: a periodic side copies the cell it wraps to;
		 * elsewhere no sand lies outside the grid (-infinity: no limit) */
		ss_boundary_fill_field(g, &st->boundary, st->bedrock, -INFINITY, -INFINITY);
	if (st->hysteresis)
		ss_hysteresis_start(st);   /* every flow cell at rest */
	else if (st->material)
		ss_boundary_fill_materials(g, &st->boundary, st->material);
	if ((err = ss_comm_agree(prepare_parts(st))))
		return err;
	if ((err = ss_comm_agree(ss_ledger_prepare_batch(st->ledger))))
		return err;
	ss_ledger_agree_batch(st->ledger);
	ss_sweeper_wake_all(st);
	if (st->hysteresis)
		ss_hysteresis_update(st, 1e-6);   /* what is steeper than tan a_s moves */
	return SS_OK;
}

void ss_stepper_heights_changed(struct ss_stepper *st)
{
	ss_boundary_fill_heights(&st->grid, &st->boundary, st->height);
	ss_sweeper_wake_all(st);
	if (st->rest_state)   /* what moves now is the caller's: start over */
		st->rest_state->stages = 0;
}

double ss_stepper_next_source_event(const struct ss_stepper *st, double t)
{
	return ss_sources_next_event(st->sources, t);
}

int ss_stepper_set_rate_field(struct ss_stepper *st, const double *rate)
{
	return ss_sources_set_field(st->sources, &st->grid, st->cell_types, st->bedrock != NULL,
	                            rate);
}

void ss_stepper_book_external(struct ss_stepper *st, double volume_m3)
{
	ss_ledger_add_external(st->ledger, volume_m3);
}

double ss_stepper_inflow(const struct ss_stepper *st)
{
	return ss_volume_sum_total(&st->ledger->inflow);
}

double ss_stepper_outflow(const struct ss_stepper *st)
{
	return ss_volume_sum_total(&st->ledger->outflow);
}

void ss_stepper_rest_counts(const struct ss_stepper *st, long long *steps,
                            long long *evaluations)
{
	*steps = st->rest_state ? st->rest_state->steps : 0;
	*evaluations = st->rest_state ? st->rest_state->evaluations : 0;
}

double ss_stepper_swept_fraction(const struct ss_stepper *st)
{
	const struct ss_sweeper *w = st->sweeper;
	return w->tile_evaluation_slots > 0.0 ? w->tiles_evaluated / w->tile_evaluation_slots
	                                      : 0.0;
}

void ss_stepper_kernel_seconds(const struct ss_stepper *st, double *measure, double *sweep)
{
	*measure = st->sweeper->seconds_measure;
	*sweep = st->sweeper->seconds_sweep;
}

/* What every step starts from: the sources of this time, the next event,
 * and the measure. */
struct step_start {
	double next_event;      /* the next target or source switch, s */
	int may_be_steady;      /* a steady stop is asked for, no source to come */
	double s_max;           /* NaN if a height is not finite */
};

static struct step_start step_begin(struct ss_stepper *st, double t_target,
                                    const struct ss_advance_options *o)
{
	struct step_start b;
	if (ss_sources_update(st->sources, &st->grid, st->time))
		ss_sweeper_mark_sources(st);
	const double next_switch = ss_sources_next_event(st->sources, st->time);
	/* a state is steady only if no source will switch on later */
	b.may_be_steady = o->steady_tol > 0.0 && isinf(next_switch);
	/* a target the caller samples at is no event: steps pass it */
	b.next_event = o->samples ? next_switch : fmin(next_switch, t_target);
	b.s_max = ss_sweeper_measure(st);
	return b;
}

/*
 * The slope part of the steady test (stepper.h): the steepest face in sand
 * carries no more sliding flux than a Coulomb face steeper than the repose
 * angle by slope_tol.  s_max is the state's largest face slope (exact above
 * the critical slope); with a bedrock, bare rock may stay steep for ever,
 * so the faces in sand are measured again.
 */
static int slopes_settled(struct ss_stepper *st, double s_max, double slope_tol)
{
	const struct ss_closure *c = &st->closure;
	const double t = c->tan_cr + slope_tol;
	const double flux_tol = slope_tol / sqrt(1.0 + t * t);   /* f_coulomb(t) */
	const struct ss_grid *g = &st->grid;
	/* a film of sand thinner than round-off of the heights is rock */
	const double bare = 1e-9 * fmax(g->dx, g->dy);
	if (st->hysteresis && st->flowing_cells > 0)
		return 0;   /* sand still moving is not at rest */
	if (st->material) {
		/* each face against its own material's rule */
		double excess = ss_sweep_material_excess(g, st->height, st->cell_types, st->material,
		                                         st->materials, st->bedrock, bare, slope_tol);
		ss_comm_reduce(&excess, 1, NULL, 0);
		return excess <= 1.0;
	}
	if (st->bedrock) {
		s_max = ss_sweep_max_sand_slope(g, st->height, st->cell_types, st->bedrock, bare);
		ss_comm_reduce(&s_max, 1, NULL, 0);
	}
	return !(s_max > c->tan_cr) || ss_closure_eval(c, s_max) <= flux_tol;
}

/* After a step: the counters, progress, and why to stop (or -1 to go
 * on).  *steady_candidate: the rate is below steady_tol, so the next
 * step's start checks the slopes. */
static int step_end(struct ss_stepper *st, const struct ss_advance_options *o,
                    const struct step_start *b, int *steady_candidate)
{
	st->sweeper->tile_slots += st->sweeper->tiles_all;
	/* every rank decides on the same values: a signal reaches the ranks
	 * at different times; and the outflow batch's room on every rank
	 * (a minimum, as the maximum of the negatives) */
	const int batched = st->ledger->batch != NULL;
	double agree[3] = {st->rate_max, o->stop && *o->stop ? 1.0 : 0.0,
	                   batched ? -ss_ledger_room_here(st->ledger) : 0.0};
	ss_comm_reduce(agree, batched ? 3 : 2, NULL, 0);
	st->rate_max = agree[0];
	if (batched)
		ss_ledger_room_agreed(st->ledger, -agree[2]);
	if (o->progress)
		o->progress(o->context, st);
	if (!isfinite(st->rate_max))
		return SS_ADVANCE_NONFINITE;
	*steady_candidate = b->may_be_steady && st->rate_max < o->steady_tol;
	if (agree[1] != 0.0)
		return SS_ADVANCE_INTERRUPTED;
	return -1;
}

/* One forward-Euler substep of dt seconds from the state step_begin
 * measured. */
static void euler_step(struct ss_stepper *st, double dt)
{
	st->rate_max = ss_sweeper_euler(st, dt);
	const struct ss_ledger_entry e = {.kind = SS_LEDGER_EULER, .tau_mu = dt};
	ss_ledger_add_outflow(st->ledger, &st->grid, &e);
	ss_ledger_add_inflow(st->ledger, dt * st->sources->volume_rate);
	st->evaluations++;
}

int ss_stages_stop(struct ss_stepper *st, const struct ss_advance_options *o)
{
	if (o->progress)
		o->progress(o->context, st);
	/* every rank decides on the same value: a signal reaches the ranks at
	 * different times */
	double asked = o->stop && *o->stop ? 1.0 : 0.0;
	if (ss_comm_size() > 1)
		ss_comm_reduce(&asked, 1, NULL, 0);
	return asked != 0.0;
}

static enum ss_advance_end advance(struct ss_stepper *st, double t_target,
                                   const struct ss_advance_options *o)
{
	const struct ss_grid *g = &st->grid;
	const struct ss_closure *c = &st->closure;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	const double source_rise = st->cfl * c->tan_cr * fmin(g->dx, g->dy);
	const double slope_tol = o->steady_slope_tol > 0.0 ? o->steady_slope_tol : 1e-6;
	const struct ss_sources *src = st->sources;
	const int rkl2 = st->integrator == SS_INTEGRATOR_RKL2;
	struct ss_rest *rest = st->rest_state;

	long long steps_left = o->max_steps > 0 ? o->max_steps : -1;
	int steady_candidate = 0;
	while (st->time < t_target) {
		if (steps_left == 0)
			return SS_ADVANCE_STEPS;
		const struct step_start b = step_begin(st, t_target, o);
		if (!isfinite(b.s_max)) {
			st->rate_max = NAN;
			return SS_ADVANCE_NONFINITE;
		}
		if (steady_candidate && slopes_settled(st, b.s_max, slope_tol))
			return SS_ADVANCE_STEADY;

		const double lambda = c->nu * ss_cfl_bound_lookup(&st->sweeper->cfl_bound, b.s_max);
		double dt = lambda > 0.0 ? st->cfl / (2.0 * lambda * inv_d2) : INFINITY;
		/* RKL2: stable for every state its stages can reach, also when
		 * a source is about to raise a flat state past the onset */
		if (rkl2 && (lambda > 0.0 || src->rate_on))
			dt = ss_rkl2_longest(st->rkl2);
		if (src->rate_on && source_rise / src->rate_max < dt)
			dt = source_rise / src->rate_max;

		if (isinf(dt)) {
			/* nothing slides and nothing is poured: the state is
			 * stationary until the next event */
			st->rate_max = 0.0;
			if (b.may_be_steady)
				return SS_ADVANCE_STEADY;
			st->time = b.next_event;
			continue;
		}

		/* the approach to rest, unless a super-step would pass a target
		 * the caller needs it to end on (the step below lands there) */
		const int resting = rest && rest->stages > 0 && b.may_be_steady && !src->rate_on &&
		                    st->time + ss_rest_length(rest) <= b.next_event;
		/* a stop between the stages of a super-step takes it back: time,
		 * steps and all as they were (stages.h) */
		int stopped = 0;
		if (resting) {
			double tau;
			const double change = ss_rest_superstep(st, &tau, o, &stopped);
			if (stopped)
				return SS_ADVANCE_INTERRUPTED;
			st->rate_max = change / tau;
			st->time += tau;
		} else {
			const int lands = st->time + dt >= b.next_event;
			if (lands)
				dt = b.next_event - st->time;
			else if (st->time + dt == st->time)
				return SS_ADVANCE_STALLED;
			if (rkl2) {
				const double change = ss_rkl2_superstep(st, dt, o, &stopped);
				if (stopped)
					return SS_ADVANCE_INTERRUPTED;
				st->rate_max = change / dt;
			} else {
				euler_step(st, dt);
			}
			st->time = lands ? b.next_event : st->time + dt;
		}
		st->steps++;
		steps_left--;
		if (st->hysteresis)
			ss_hysteresis_update(st, slope_tol);   /* between steps: hysteresis.c */
		const int end = step_end(st, o, &b, &steady_candidate);
		if (end >= 0)
			return (enum ss_advance_end)end;
		/* near rest (rest.h): the approach begins with the rate the
		 * ranks agreed on */
		if (rest && !resting && b.may_be_steady && !src->rate_on)
			ss_rest_begins(rest, st->rate_max);
	}
	/* on a target: the slopes are measured here, not by the next step */
	if (steady_candidate) {
		ss_boundary_fill_heights(g, &st->boundary, st->height);
		double s_max = ss_sweep_max_slope(g, st->height, st->cell_types);
		ss_comm_reduce(&s_max, 1, NULL, 0);
		if (slopes_settled(st, s_max, slope_tol))
			return SS_ADVANCE_STEADY;
	}
	return SS_ADVANCE_REACHED;
}

enum ss_advance_end ss_stepper_advance(struct ss_stepper *st, double t_target,
                                       const struct ss_advance_options *o)
{
	const enum ss_advance_end end = advance(st, t_target, o);
	/* every rank returns after the same substep: the outflow batch is
	 * folded here, so that the ledger is current between calls */
	ss_ledger_flush(st->ledger, &st->grid);
	return end;
}

/* ss_stepper_max_sand_slope on this rank's faces (the halo filled). */
static double max_sand_slope_here(const struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (!st->bedrock)
		return ss_sweep_max_slope(g, st->height, st->cell_types);
	return ss_sweep_max_sand_slope(g, st->height, st->cell_types, st->bedrock,
	                               1e-6 * fmin(g->dx, g->dy));
}

double ss_stepper_max_sand_slope(struct ss_stepper *st)
{
	ss_boundary_fill_heights(&st->grid, &st->boundary, st->height);
	double s = max_sand_slope_here(st);
	ss_comm_reduce(&s, 1, NULL, 0);
	return s;
}

void ss_stepper_diagnostics(struct ss_stepper *st, struct ss_diagnostics *d)
{
	const struct ss_grid *g = &st->grid;
	double *row_volume = st->ledger->row_volume, max_height = -INFINITY;
	ss_ledger_flush(st->ledger, g);   /* empty after ss_stepper_advance; collective */

	/* rows summed in parallel, then the row sums in order: the same bits
	 * for any thread count */
	#pragma omp parallel for schedule(static) reduction(max:max_height)
	for (int j = 0; j < g->ny; j++) {
		double row = 0.0, top = -INFINITY;
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW)
				continue;
			const double h = st->height[k];
			row += h;
			top = h > top || h != h ? (h != h ? INFINITY : h) : top;
		}
		row_volume[j] = row;
		if (top > max_height)
			max_height = top;
	}
	/* the row sums in row order, carried from rank to rank */
	double volume = 0.0;
	ss_comm_fold_start(&volume, 1);
	for (int j = 0; j < g->ny; j++)
		volume += row_volume[j];
	ss_comm_fold_finish(&volume, 1);

	ss_boundary_fill_heights(g, &st->boundary, st->height);
	double max[2] = {max_sand_slope_here(st), max_height};
	ss_comm_reduce(max, 2, NULL, 0);
	const double s_max = max[0];
	max_height = max[1];
	d->volume = volume * g->dx * g->dy;
	d->inflow = ss_volume_sum_total(&st->ledger->inflow);
	d->outflow = ss_volume_sum_total(&st->ledger->outflow);
	d->external = ss_volume_sum_total(&st->ledger->external);
	d->max_height = max_height;
	d->max_slope_deg = atan(s_max) * (180.0 / M_PI);
	d->steps = (double)st->steps;
	d->evaluations = (double)st->evaluations;
	struct ss_sweeper *w = st->sweeper;
	d->active_fraction = w->tile_slots > 0.0 ? w->tile_sweeps / w->tile_slots : 0.0;
	w->tile_sweeps = w->tile_slots = 0.0;
}

void ss_stepper_restart_state(const struct ss_stepper *st, struct ss_restart_state *s)
{
	s->steps = st->steps;
	s->evaluations = st->evaluations;
	s->rkl2_tau = st->rkl2 ? st->rkl2->tau_limit : INFINITY;
	s->rest_stages = st->rest_state ? st->rest_state->stages : 0;
	s->inflow = st->ledger->inflow;
	s->outflow = st->ledger->outflow;
}

void ss_stepper_restore(struct ss_stepper *st, double t, const double *height,
                        const uint8_t *moving, const struct ss_restart_state *s)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++)
		memcpy(st->height + ss_grid_index(g, 0, j), height + (size_t)j * g->nx,
		       (size_t)g->nx * sizeof(double));
	if (st->hysteresis)
		ss_hysteresis_restore(st, moving);
	st->time = t;
	st->steps = s->steps;
	st->evaluations = s->evaluations;
	if (st->rkl2)
		st->rkl2->tau_limit = s->rkl2_tau;
	st->ledger->inflow = s->inflow;
	st->ledger->outflow = s->outflow;
	ss_stepper_heights_changed(st);   /* (it starts the approach over) */
	if (st->rest_state) {
		st->rest_state->stages = s->rest_stages;
	}
}

int ss_stepper_first_nonfinite(const struct ss_stepper *st, int *i, int *j)
{
	const struct ss_grid *g = &st->grid;
	/* the first in global row order: the largest of minus its index */
	double first = -INFINITY;
	for (int jj = 0; jj < g->ny && first == -INFINITY; jj++)
		for (int ii = 0; ii < g->nx; ii++)
			if (!isfinite(st->height[ss_grid_index(g, ii, jj)])) {
				first = -((double)(g->offset_j + jj) * (double)g->global_nx +
				          (double)(g->offset_i + ii));
				break;
			}
	ss_comm_reduce(&first, 1, NULL, 0);
	if (first == -INFINITY)
		return 0;
	*j = (int)(-first / (double)g->global_nx);
	*i = (int)(-first - (double)*j * (double)g->global_nx);
	return 1;
}
