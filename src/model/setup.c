/*
 * setup.c - from a case to a ready stepper (see setup.h).
 */
#include "model/setup.h"

#include <math.h>
#include <string.h>

#include "sandslide/comm.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"
#include "sandslide/shape.h"

static const char *const role_names[] = {"wall", "open", "source"};

static int initial_heights(const struct ss_case *c, struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (c->initial == SS_INITIAL_FILE) {
		struct ss_raster r;
		int err = ss_dem_read(c->initial_file, c->initial_where, NULL, &r);
		if (!err && (r.nx != g->global_nx || r.ny != g->global_ny))
			err = ss_error_input("%s: initial file '%s' is %d x %d cells: expected the "
			                     "grid's %lld x %lld (nx x ny)", c->initial_where,
			                     c->initial_file, r.nx, r.ny, g->global_nx, g->global_ny);
		if (!err && !isnan(r.cellsize) &&
		    (fabs(r.cellsize - g->dx) > 1e-9 * g->dx || fabs(r.cellsize - g->dy) > 1e-9 * g->dy))
			err = ss_error_input("%s: initial file '%s' has cellsize %g m: expected the "
			                     "grid's dx = %g m, dy = %g m", c->initial_where,
			                     c->initial_file, r.cellsize, g->dx, g->dy);
		if (err) {
			ss_raster_release(&r);
			return err;
		}
		/* every rank reads the file and keeps its rows */
		for (int j = 0; j < g->ny; j++) {
			for (int i = 0; i < g->nx; i++) {
				const size_t m = (size_t)(g->offset_j + j) * g->nx + i;
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
	const struct ss_grid *g = &st->grid;
	struct ss_raster r;
	int err = ss_dem_read(c->bedrock_file, c->bedrock_where, NULL, &r);
	if (!err && (r.nx != g->global_nx || r.ny != g->global_ny))
		err = ss_error_input("%s: bedrock '%s' is %d x %d cells: expected the grid's "
		                     "%lld x %lld (nx x ny)", c->bedrock_where, c->bedrock_file,
		                     r.nx, r.ny, g->global_nx, g->global_ny);
	for (size_t m = 0; !err && r.nodata && m < (size_t)r.nx * r.ny; m++)
		if (r.nodata[m])
			err = ss_error_input("%s: bedrock '%s' has no data at cell (%d, %d): the "
			                     "bedrock needs a value in every cell", c->bedrock_where,
			                     c->bedrock_file, (int)(m % (size_t)r.nx),
			                     (int)(m / (size_t)r.nx));
	if (!err)   /* this rank's rows */
		err = ss_stepper_set_bedrock(st, r.values + (size_t)g->offset_j * g->nx);
	ss_raster_release(&r);
	return err;
}

int ss_setup_stepper(const struct ss_case *c, int tile_nx, int tile_ny,
                     enum ss_kernel kernel, struct ss_stepper *st)
{
	struct ss_grid g;
	struct ss_closure closure;
	memset(st, 0, sizeof *st);
	int err = ss_grid_init(&g, c->nx, c->ny, c->dx, c->dy, c->origin_x, c->origin_y);
	const enum ss_integrator integrator =
		ss_integrator_resolve(c->integrator, c->bedrock_file != NULL);
	if (integrator == SS_INTEGRATOR_RKL2 && c->bedrock_file)
		return ss_error_input("%s: [time] integrator = rkl2 cannot be used with a "
		                      "bedrock: its stages cannot keep the sand above the rock "
		                      "(use euler or auto)", c->bedrock_where);
	/* the memory of one rank's slab, times the ranks on this node */
	const double need = ss_stepper_memory_bytes(&g, integrator) / ss_comm_size() *
	                    ss_comm_node_ranks();
	const double have = ss_memory_available_bytes();
	if (!err && have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("%s: [grid] nx = %d, ny = %d needs %s of memory; this "
		                      "machine has %s available (reduce nx and ny)", c->grid_where,
		                      c->nx, c->ny, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb));
	}
	if (!err)
		err = ss_closure_init(&closure, c->closure, c->repose_angle_deg, c->gamma, c->nu);
	if (!err)
		err = ss_stepper_init(st, &g, &closure, &c->boundary, c->cfl, tile_nx, tile_ny);
	if ((err = ss_comm_agree(err))) {
		ss_stepper_release(st);   /* another rank's failure: ours is whole */
		return err;
	}
	st->kernel = kernel;
	/* from here on the grid is this rank's slab (stepper.h) */
	g = st->grid;
	st->integrator = integrator;
	st->rkl2_max_stages = c->rkl2_max_stages;
	st->rkl2_tol = c->rkl2_tol;

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
			long long covered = 0;
			memset(mask, 0, (size_t)g.nx * (size_t)g.ny);
			err = ss_shape_rasterize(&r->shape, &g, mask, &covered);
			double covered_all = (double)covered, none = 0.0;
			ss_comm_reduce(&none, 0, &covered_all, 1);
			if (!err && covered_all == 0)
				err = ss_error_input("%s: [%s %s] covers no cell centre: enlarge it or "
				                     "refine the grid (dx = %g m, dy = %g m)",
				                     r->shape.where, role_names[r->role], r->name,
				                     g.dx, g.dy);
			if (err)
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
	if (!err)
		err = ss_stepper_prepare(st);
	if (err)
		ss_stepper_release(st);
	return err;
}
