/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * setup.c - from a case or a raster to a ready stepper (see setup.h).  Both
 * go through start() (grid, integrator, memory, closure, stepper) and
 * add_source() (a region's rates, and the check that it covers a cell), so
 * that run and relax build their steppers one way.
 */
#include "model/setup.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/strings.h"
#include "model/materials.h"
#include "sandslide/comm.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"
#include "sandslide/shape.h"

static const char *const role_names[] = {"wall", "open", "source"};

/* What start() needs beyond the model, and how the messages name things. */
struct start {
	const struct ss_model_options *m;
	int nx, ny;
	double dx, dy, x0, y0;                /* m */
	const struct ss_boundary *boundary;
	int has_bedrock;
	int steady;                           /* the run goes on until steady */
	int relaxing;                         /* a raster relaxed (relax) */
	int tile_nx, tile_ny;
	enum ss_kernel kernel;
	const char *integrator_what;          /* "--integrator rkl2" */
	const char *bedrock_what;             /* "--bedrock" */
	const char *static_what;              /* "--static-angle" */
	const char *angle_what;               /* "--angle FILE" */
	const char *grid_what;                /* "dem.asc: 60 x 40 cells need" */
	const char *memory_advice;            /* " (reduce nx and ny)", or "" */
};

enum ss_rest_mode ss_setup_rest_mode(const struct ss_model_options *m, int steady,
                                     int has_bedrock)
{
	return steady && !has_bedrock ? m->rest : SS_REST_OFF;
}

double ss_setup_node_bytes(const struct ss_grid *g, enum ss_integrator integrator,
                           enum ss_rest_mode rest)
{
	return ss_stepper_memory_bytes(g, integrator, rest) / ss_comm_size() *
	       ss_comm_node_ranks();
}

/* Each cell's material number (2 B, stepper.h) when the model gives the
 * angles per cell or has hysteresis, this node's share as
 * ss_setup_node_bytes counts. */
static double material_node_bytes(const struct ss_model_options *m, const struct ss_grid *g)
{
	const int per_cell = m->angle_file || m->materials_file || !isnan(m->static_angle_deg);
	return per_cell ? (double)ss_grid_storage_cells(g) * sizeof(uint16_t) / ss_comm_size() *
	                  ss_comm_node_ranks()
	                : 0.0;
}

int ss_setup_check_raster_memory(const char *name, int nx, int ny, int rasters,
                                 const struct ss_model_options *m, int has_bedrock)
{
	struct ss_grid g;
	int err = ss_grid_init(&g, nx, ny, 1.0, 1.0, 0.0, 0.0);
	if (err)
		return err;
	const double cells = (double)nx * (double)ny;
	/* a raster: values (8 B) and nodata flags (1 B) a cell, split over the
	 * ranks as the stepper is */
	const double raster = rasters * cells * (sizeof(double) + 1.0) / ss_comm_size() *
	                      ss_comm_node_ranks();
	/* auto as a run (fit) or a relax resolves it, whichever needs more */
	const enum ss_rest_mode rest = ss_setup_rest_mode(m, 1, has_bedrock);   /* at most */
	const double run = ss_setup_node_bytes(&g, ss_integrator_resolve(m->integrator, has_bedrock,
	                                                                0), rest);
	const double relax = ss_setup_node_bytes(&g, ss_integrator_resolve(m->integrator,
	                                                                  has_bedrock, 1), rest);
	const double need = raster + fmax(run, relax) + material_node_bytes(m, &g);
	const double have = ss_memory_available_bytes();
	if (have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("%s: %d x %d cells need %s of memory; this machine has %s "
		                      "available", name, nx, ny, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb));
	}
	return SS_OK;
}

/* The grid, the integrator auto resolves to, the memory check, the closure
 * and the stepper (its grid then this rank's slab): what every set-up
 * starts with.  On error st is released. */
static int start(const struct start *s, struct ss_stepper *st)
{
	const struct ss_model_options *m = s->m;
	struct ss_grid g;
	struct ss_closure closure;
	memset(st, 0, sizeof *st);
	int err = ss_grid_init(&g, s->nx, s->ny, s->dx, s->dy, s->x0, s->y0);
	if (err)
		return err;
	const enum ss_integrator integrator =
		ss_integrator_resolve(m->integrator, s->has_bedrock, s->relaxing);
	if (integrator == SS_INTEGRATOR_RKL2 && s->has_bedrock)
		return ss_error_input("%s cannot be used with %s: its stages cannot keep the sand "
		                      "above the rock (use euler or auto)", s->integrator_what,
		                      s->bedrock_what);
	const enum ss_rest_mode rest = ss_setup_rest_mode(m, s->steady, s->has_bedrock);
	/* the memory of one rank's slab, times the ranks on this node */
	const double need = ss_setup_node_bytes(&g, integrator, rest) + material_node_bytes(m, &g);
	const double have = ss_memory_available_bytes();
	if (have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("%s %s of memory; this machine has %s available%s",
		                      s->grid_what, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb), s->memory_advice);
	}
	err = ss_model_closure(m, &closure);
	const double a_s = m->static_angle_deg;
	if (!err && !isnan(a_s) && (m->angle_file || m->materials_file))
		err = ss_error_input("%s %g with %s: one static angle is for one repose angle; "
		                     "give each [material NAME] of a material table its "
		                     "static_angle (doc/model.md#hysteresis)", s->static_what, a_s,
		                     s->angle_what);
	if (!err && !isnan(a_s) && a_s < m->angle_deg)
		err = ss_error_input("%s %g is below the repose angle %g: sand at rest starts to "
		                     "slide at an angle at least the one where moving sand stops "
		                     "(doc/model.md#hysteresis)", s->static_what, a_s, m->angle_deg);
	if (!err)
		err = ss_stepper_init(st, &g, &closure, s->boundary, m->cfl, s->tile_nx, s->tile_ny);
	if (!err && !isnan(a_s))
		err = ss_stepper_set_hysteresis(st, a_s);
	if ((err = ss_comm_agree(err))) {
		ss_stepper_release(st);   /* another rank's failure: ours is whole */
		return err;
	}
	st->kernel = s->kernel;
	st->integrator = integrator;
	st->rest = rest;
	st->rkl2_max_stages = m->rkl2_max_stages;
	st->rkl2_tol = m->rkl2_tol;
	st->rkl2_pouring_tol = m->rkl2_pouring_tol;
	return SS_OK;
}

/* The cells of shape in mask (this rank's rows, cleared first); a shape
 * that covers no cell centre of the whole grid is refused, naming what. */
static int rasterize(const struct ss_shape *shape, const struct ss_grid *g, uint8_t *mask,
                     const char *what)
{
	long long covered = 0;
	memset(mask, 0, (size_t)g->nx * (size_t)g->ny);
	int err = ss_shape_rasterize(shape, g, mask, &covered);
	double covered_all = (double)covered, none = 0.0;
	ss_comm_reduce(&none, 0, &covered_all, 1);
	if (!err && covered_all == 0)
		err = ss_error_input("%s covers no cell centre of the grid (x %g .. %g m, y %g .. %g m, "
		                     "dx = %g m, dy = %g m): enlarge it or refine the grid", what,
		                     g->origin_x, g->origin_x + (double)g->global_nx * g->dx,
		                     g->origin_y, g->origin_y + (double)g->global_ny * g->dy,
		                     g->dx, g->dy);
	return err;
}

/* ---- from a case ------------------------------------------------------ */

/* SS_ERR_INPUT unless r (what, read from path) is the grid's size. */
static int check_grid_size(const char *path, const char *where, const char *what,
                           const struct ss_grid *g, const struct ss_raster *r)
{
	if (r->nx == g->global_nx && r->ny == g->global_ny)
		return SS_OK;
	return ss_error_input("%s: %s '%s' is %d x %d cells: expected the grid's %lld x %lld "
	                      "(nx x ny)", where, what, path, r->nx, r->ny, g->global_nx,
	                      g->global_ny);
}

int ss_setup_read_window(const char *spec, const char *context,
                         struct ss_dem_read_options opt, int tile_nx, int tile_ny,
                         struct ss_raster *r)
{
	if (ss_comm_size() > 1) {   /* the header, then this rank's rows */
		opt.rows = 0;
		int err = ss_dem_read(spec, context, &opt, r);
		struct ss_grid whole;
		if (!err)
			err = ss_grid_init(&whole, r->nx, r->ny, 1.0, 1.0, 0.0, 0.0);
		if (!err)
			ss_stepper_slab_rows(&whole, tile_nx, tile_ny, ss_comm_rank(), &opt.row_first,
			                     &opt.rows);
		ss_raster_release(r);
		if (err)
			return err;
	}
	return ss_dem_read(spec, context, &opt, r);
}

/* This rank's rows of the raster `path`, which must be the grid's size
 * and, where the file says, have its cells (square: one cellsize is
 * compared with both dx and dy); `what` ("initial file", "bedrock") names
 * it. */
static int read_slab(const char *path, const char *where, const char *what,
                     const struct ss_stepper *st, struct ss_raster *r)
{
	const struct ss_grid *g = &st->grid;
	struct ss_dem_read_options o;
	ss_dem_read_options_init(&o);
	int tile_nx, tile_ny;
	ss_stepper_tile_size(st, &tile_nx, &tile_ny);
	int err = ss_setup_read_window(path, where, o, tile_nx, tile_ny, r);
	if (!err)
		err = check_grid_size(path, where, what, g, r);
	if (!err && !isnan(r->cellsize) &&
	    (fabs(r->cellsize - g->dx) > 1e-9 * g->dx || fabs(r->cellsize - g->dy) > 1e-9 * g->dy))
		err = ss_error_input("%s: %s '%s' has cellsize %g m: expected the grid's dx = %g m, "
		                     "dy = %g m", where, what, path, r->cellsize, g->dx, g->dy);
	if (err)
		ss_raster_release(r);
	return err;
}

static int initial_heights(const struct ss_case *c, struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (c->initial == SS_INITIAL_FILE) {
		struct ss_raster r;
		const int err = read_slab(c->initial_file, c->initial_where, "initial file", st, &r);
		if (err)
			return err;
		/* the window: this rank's rows */
		for (int j = 0; j < g->ny; j++) {
			for (int i = 0; i < g->nx; i++) {
				const size_t m = (size_t)j * g->nx + i;
				const ptrdiff_t k = ss_grid_index(g, i, j);
				st->height[k] = r.values[m];
				if (r.nodata && r.nodata[m] &&
				    ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
					ss_cell_type_set(st->cell_types, k, SS_CELL_OPEN);  /* nodata: sand leaves */
			}
		}
		ss_raster_release(&r);
		return SS_OK;
	}

	const double slope = c->initial == SS_INITIAL_CONE
	                     ? tan(c->cone_angle_deg * M_PI / 180.0) : 0.0;
	#pragma omp parallel for schedule(static)
	for (int j = 0; j < g->ny; j++) {
		const double y = ss_grid_y(g, j);
		for (int i = 0; i < g->nx; i++) {
			double h = c->initial_height;
			if (c->initial == SS_INITIAL_CONE) {
				const double x = ss_grid_x(g, i);
				const double r = hypot(x - c->cone_x, y - c->cone_y);
				h += slope * fmax(c->cone_radius - r, 0.0);
			}
			st->height[ss_grid_index(g, i, j)] = h;
		}
	}
	return SS_OK;
}

/* [initial] bedrock = FILE: the fixed base, the grid's size, data in every
 * cell. */
static int load_bedrock(const struct ss_case *c, struct ss_stepper *st)
{
	struct ss_raster r;
	int err = read_slab(c->bedrock_file, c->bedrock_where, "bedrock", st, &r);
	for (size_t m = 0; !err && r.nodata && m < (size_t)r.nx * r.rows; m++)
		if (r.nodata[m])
			err = ss_error_input("%s: bedrock '%s' has no data at %s: the bedrock needs a "
			                     "value in every cell", c->bedrock_where, c->bedrock_file,
			                     SS_GRID_CELL(&st->grid, (int)(m % (size_t)r.nx),
			                                  (int)(m / (size_t)r.nx + r.row_first -
			                                        st->grid.offset_j)));
	if (!err)   /* the window: this rank's rows */
		err = ss_stepper_set_bedrock(st, r.values);
	ss_raster_release(&r);
	return err;
}

/* [model] repose_angle = FILE: each cell's angle, the grid's size
 * (collective). */
static int load_angles(const struct ss_case *c, struct ss_stepper *st)
{
	struct ss_raster r;
	memset(&r, 0, sizeof r);
	char what[SS_CASE_WHERE_SIZE + 4200], where[SS_CASE_WHERE_SIZE + 32];
	snprintf(what, sizeof what, "%s: repose_angle '%s'", c->angle_where, c->angle_file);
	snprintf(where, sizeof where, "%s: [model] repose_angle", c->angle_where);
	int err = ss_comm_agree(read_slab(c->angle_file, where, "repose angle raster", st, &r));
	if (!err)
		err = ss_materials_from_angles(st, &c->model, &r, what);
	ss_raster_release(&r);
	return err;
}

/* [model] materials = FILE: each cell's class, the law of its [material
 * NAME] (collective). */
static int load_classes(const struct ss_case *c, struct ss_stepper *st)
{
	struct ss_raster r;
	memset(&r, 0, sizeof r);
	char what[SS_CASE_WHERE_SIZE + 4200], where[SS_CASE_WHERE_SIZE + 32];
	snprintf(what, sizeof what, "%s: materials '%s'", c->materials_where,
	         c->model.materials_file);
	snprintf(where, sizeof where, "%s: [model] materials", c->materials_where);
	int err = ss_comm_agree(read_slab(c->model.materials_file, where, "class raster", st,
	                                  &r));
	if (!err)
		err = ss_materials_from_classes(st, &c->model, c->material_table, &r, what);
	ss_raster_release(&r);
	return err;
}

int ss_setup_stepper(const struct ss_case *c, int tile_nx, int tile_ny,
                     enum ss_kernel kernel, struct ss_stepper *st)
{
	char integrator_what[SS_CASE_WHERE_SIZE + 64], grid_what[SS_CASE_WHERE_SIZE + 64];
	snprintf(integrator_what, sizeof integrator_what,
	         "%s: [time] integrator = rkl2", c->bedrock_where);
	snprintf(grid_what, sizeof grid_what, "%s: [grid] nx = %d, ny = %d needs", c->grid_where,
	         c->nx, c->ny);
	const struct start s = {
		.m = &c->model, .nx = c->nx, .ny = c->ny, .dx = c->dx, .dy = c->dy,
		.x0 = c->origin_x, .y0 = c->origin_y, .boundary = &c->boundary,
		.has_bedrock = c->bedrock_file != NULL, .steady = c->steady, .tile_nx = tile_nx,
		.tile_ny = tile_ny, .kernel = kernel, .integrator_what = integrator_what,
		.bedrock_what = "a bedrock", .grid_what = grid_what,
		.static_what = "[model] static_angle =", .angle_what = "repose_angle = FILE",
		.memory_advice = " (reduce nx and ny)",
	};
	int err = start(&s, st);
	if (err)
		return err;
	const struct ss_grid g = st->grid;   /* this rank's slab (stepper.h) */

	/* a grid-sized mask only when there are regions to rasterise */
	uint8_t *mask = c->region_count == 0 ? NULL
	              : ss_alloc((size_t)g.nx * (size_t)g.ny, 1, "region mask");
	if (c->region_count > 0 && !mask) {
		ss_stepper_release(st);
		return SS_ERR_FAIL;
	}
	/* walls and open cells first, so that sources see the final types */
	for (int pass = 0; pass < 2 && !err; pass++) {
		for (int k = 0; k < c->region_count && !err; k++) {
			const struct ss_region *r = &c->regions[k];
			if ((r->role == SS_REGION_SOURCE) != (pass == 1))
				continue;
			char what[SS_CASE_WHERE_SIZE + 96];
			snprintf(what, sizeof what, "%s: [%s %s]", r->shape.where, role_names[r->role],
			         r->name);
			if ((err = rasterize(&r->shape, &g, mask, what)))
				break;
			if (r->role == SS_REGION_SOURCE) {
				err = ss_stepper_add_source(st, mask, r->rate, r->start, r->stop);
				continue;
			}
			const enum ss_cell_type type = r->role == SS_REGION_WALL ? SS_CELL_WALL
			                                                         : SS_CELL_OPEN;
			for (int j = 0; j < g.ny; j++)
				for (int i = 0; i < g.nx; i++)
					if (mask[(size_t)j * g.nx + i])
						ss_cell_type_set(st->cell_types, ss_grid_index(&g, i, j),
						                 type);
		}
		if (pass == 0 && !err)
			err = initial_heights(c, st);
		if (pass == 0 && !err && c->bedrock_file)
			err = load_bedrock(c, st);
	}
	ss_free(mask);
	/* failures of one rank (a file, an allocation) before the collective
	 * calls of prepare */
	err = ss_comm_agree(err);
	if (!err && c->angle_file)
		err = load_angles(c, st);
	if (!err && c->model.materials_file)
		err = load_classes(c, st);
	if (!err)
		err = ss_stepper_prepare(st);
	if (err)
		ss_stepper_release(st);
	return err;
}

/* ---- from a raster ---------------------------------------------------- */

/* The lowest height of the raster's cells with data: where sand leaves.
 * The minimum of the ranks' rows (exact in any order). */
static int lowest_height(const struct ss_raster_setup *s, double *level)
{
	const struct ss_raster *r = s->heights;
	double minus_lowest = -INFINITY;
	for (size_t m = 0; m < (size_t)r->nx * r->rows; m++)
		if (!r->nodata || !r->nodata[m])
			minus_lowest = fmax(minus_lowest, -r->values[m]);
	ss_comm_reduce(&minus_lowest, 1, NULL, 0);
	*level = -minus_lowest;
	if (isinf(*level))
		return ss_error_input("%s: every cell is nodata: nothing to relax", s->name);
	return SS_OK;
}

/* Where the pour of mask lands (all ranks' cells); SS_ERR_INPUT when every
 * cell it covers is without data: the sources pour on flow cells only, so
 * such a pour would pour nothing and report "poured 0 m^3" as a success. */
static int pour_cover(const struct ss_stepper *st, const uint8_t *mask,
                      struct ss_pour_cover *out)
{
	const struct ss_grid *g = &st->grid;
	/* the extent as maxima: -x_min, x_max, -y_min, y_max */
	double most[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY}, count[2] = {0.0, 0.0};
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			if (!mask[(size_t)j * g->nx + i])
				continue;
			count[0]++;
			if (ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j)) != SS_CELL_FLOW) {
				count[1]++;
				continue;
			}
			const double x = ss_grid_x(g, i), y = ss_grid_y(g, j);
			most[0] = fmax(most[0], -x);
			most[1] = fmax(most[1], x);
			most[2] = fmax(most[2], -y);
			most[3] = fmax(most[3], y);
		}
	}
	ss_comm_reduce(most, 4, count, 2);
	if (count[1] == count[0])
		return ss_error_input("--add-sand covers %.0f cell%s, all without data: nothing would "
		                      "be poured (give a region on cells with data)", count[0],
		                      count[0] == 1 ? "" : "s");
	if (out) {
		*out = (struct ss_pour_cover){
			.cells = (long long)count[0], .nodata = (long long)count[1],
			.x_min = -most[0], .x_max = most[1], .y_min = -most[2], .y_max = most[3],
		};
	}
	return SS_OK;
}

/* The raster's heights and nodata cells into st (this rank's rows), the
 * bedrock, the poured sand. */
static int fill_from_raster(const struct ss_raster_setup *s, struct ss_stepper *st)
{
	const struct ss_raster *r = s->heights;
	const struct ss_grid g = st->grid;
	if (g.offset_j < r->row_first || g.offset_j + g.ny > r->row_first + r->rows)
		SS_BUG("the raster holds rows %d + %d: not the slab's %lld + %d", r->row_first,
		       r->rows, (long long)g.offset_j, g.ny);
	/* the raster holds the slab's rows (a window) or more */
	const size_t first = (size_t)(g.offset_j - r->row_first) * g.nx;
	for (int j = 0; j < g.ny; j++) {
		for (int i = 0; i < g.nx; i++) {
			const size_t m = first + (size_t)j * g.nx + i;
			const ptrdiff_t k = ss_grid_index(&g, i, j);
			st->height[k] = r->values[m];
			if (r->nodata && r->nodata[m])
				ss_cell_type_set(st->cell_types, k, s->nodata_type);
		}
	}
	/* agreed: the collective calls of prepare follow */
	const struct ss_raster *rock = s->bedrock;
	if (rock && (g.offset_j < rock->row_first || g.offset_j + g.ny > rock->row_first + rock->rows))
		SS_BUG("the bedrock holds rows %d + %d: not the slab's", rock->row_first, rock->rows);
	int err = ss_comm_agree(rock ? ss_stepper_set_bedrock(st, rock->values + (size_t)(g.offset_j -
	                                                      rock->row_first) * g.nx)
	                             : SS_OK);
	if (!err && s->angles)
		err = s->classes
			? ss_materials_from_classes(st, s->model, s->classes, s->angles, s->angles_what)
			: ss_materials_from_angles(st, s->model, s->angles, s->angles_what);
	if (err || !s->pour)
		return err;
	uint8_t *mask = ss_alloc((size_t)g.nx * g.ny, 1, "sand source mask");
	if (!mask)
		return ss_comm_agree(SS_ERR_FAIL);
	err = rasterize(s->pour, &g, mask, "--add-sand");
	if (!err)
		err = pour_cover(st, mask, s->pour_cover);
	if (!err)
		err = ss_stepper_add_source(st, mask, s->pour_rate, 0.0, s->pour_duration);
	ss_free(mask);
	return ss_comm_agree(err);
}

int ss_setup_stepper_from_raster(const struct ss_raster_setup *s, struct ss_stepper *st)
{
	const struct ss_raster *r = s->heights;
	memset(st, 0, sizeof *st);
	const double dx = isnan(s->dx) ? r->cellsize : s->dx;
	const double dy = isnan(r->cellsize_y) || !isnan(s->dx) ? dx : r->cellsize_y;
	if (isnan(dx))
		return ss_error_input("%s: the file gives no cell size: give it with --dx M", s->name);
	double level = s->open_level;
	int err = isnan(level) ? lowest_height(s, &level) : SS_OK;
	if (err)
		return err;
	char grid_what[4200];
	snprintf(grid_what, sizeof grid_what, "%s: %d x %d cells need", s->name, r->nx, r->ny);
	const struct ss_boundary sides = {{s->sides, s->sides, s->sides, s->sides}, level};
	const struct start start_with = {
		.m = s->model, .nx = r->nx, .ny = r->ny, .dx = dx, .dy = dy,
		.x0 = isnan(r->x0) ? 0.0 : r->x0, .y0 = isnan(r->y0) ? 0.0 : r->y0,
		.boundary = &sides, .has_bedrock = s->bedrock != NULL, .steady = s->steady,
		.relaxing = 1,
		.tile_nx = s->tile_nx, .tile_ny = s->tile_ny,
		.kernel = SS_KERNEL_FAST, .integrator_what = "--integrator rkl2",
		.bedrock_what = "--bedrock", .grid_what = grid_what, .memory_advice = "",
		.static_what = "--static-angle", .angle_what = "--angle FILE",
	};
	if ((err = start(&start_with, st)))
		return err;
	err = fill_from_raster(s, st);
	if (!err)
		err = ss_stepper_prepare(st);
	if (err)
		ss_stepper_release(st);
	return err;
}
