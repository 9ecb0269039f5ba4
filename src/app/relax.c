/*
 * relax.c - `sandslide relax` (see relax.h): DEM -> stepper -> the shared
 * time loop (drive.h) -> the steady surface, in the input's format or as a
 * series.
 */
#include "sandslide/relax.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/drive.h"
#include "io/output.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

void ss_relax_options_init(struct ss_relax_options *o)
{
	*o = (struct ss_relax_options){
		.closure = SS_CLOSURE_COULOMB, .angle_deg = 35.0, .gamma = 1.0, .nu = 1.0,
		.tol = 1e-9, .slope_tol = 1e-6, .integrator = SS_INTEGRATOR_AUTO,
		.rkl2_max_stages = SS_RKL2_MAX_STAGES_DEFAULT,
		.rkl2_tol = SS_RKL2_TOL_DEFAULT, .max_time = INFINITY, .cfl = 0.9, .sides = SS_SIDE_WALL,
		.nodata_type = SS_CELL_WALL, .open_level = NAN, .output_every = NAN,
	};
	ss_dem_read_options_init(&o->read);
}

/* "dir/name.asc" -> "out/name-relaxed.asc"; "FILE.h5:/dataset" -> .h5; a
 * raster relax reads but does not write (.img, .vrt, .xyz: other GDAL
 * formats) -> .tif, which keeps its georeferencing */
static void default_output(const char *dem, char *out, size_t size)
{
	const char *base = strrchr(dem, '/') ? strrchr(dem, '/') + 1 : dem;
	const char *colon = strstr(base, ".h5:");
	const int len = colon ? (int)(colon - base) + 3 : (int)strlen(base);
	const char *dot = NULL;
	for (const char *p = base; p < base + len; p++)
		if (*p == '.')
			dot = p;
	const int stem = dot && dot != base ? (int)(dot - base) : len;
	snprintf(out, size, "out/%.*s-relaxed%.*s", stem, base, len - stem, base + stem);
	if (ss_dem_format_of(out) == SS_DEM_AUTO && ss_dem_gdal_available())
		snprintf(out, size, "out/%.*s-relaxed.tif", stem, base);
}

int ss_relax_sides_parse(const char *word, enum ss_side_kind *sides)
{
	enum ss_side_kind kind;
	if (ss_side_kind_parse(word, &kind) || kind == SS_SIDE_PERIODIC)
		return -1;
	*sides = kind;
	return 0;
}

int ss_relax_nodata_parse(const char *word, enum ss_cell_type *type)
{
	if (strcmp(word, "wall") && strcmp(word, "open"))
		return -1;
	*type = !strcmp(word, "wall") ? SS_CELL_WALL : SS_CELL_OPEN;
	return 0;
}

/* The steepest face of the sand (ss_stepper_max_sand_slope), in degrees:
 * what run's /max_slope_deg holds too. */
static double steepest_sand_face_deg(struct ss_stepper *st)
{
	return atan(ss_stepper_max_sand_slope(st)) * (180.0 / M_PI);
}

/* The stepper for raster r: grid, closure, cell types (nodata), heights,
 * bedrock, the poured source; prepared. */
static int build_stepper(const struct ss_relax_options *o, const struct ss_raster *r,
                         const struct ss_raster *bedrock, struct ss_stepper *st)
{
	const double dx = isnan(o->read.cellsize) ? r->cellsize : o->read.cellsize;
	const double dy = isnan(r->cellsize_y) || !isnan(o->read.cellsize) ? dx : r->cellsize_y;
	if (isnan(dx))
		return ss_error_input("%s: the file gives no cell size: give it with --dx M",
		                      o->dem);
	struct ss_grid g;
	int err = ss_grid_init(&g, r->nx, r->ny, dx, dy, isnan(r->x0) ? 0.0 : r->x0,
	                       isnan(r->y0) ? 0.0 : r->y0);
	if (err)
		return err;
	/* auto is Euler for relax: a DEM comes to rest, where RKL2 damps the
	 * stiff remainder only by ~1/2 a super-step; measured (README,
	 * Performance): the 4096^2 terrain took 2579 RKL2 evaluations against
	 * 1389 Euler steps, a 1024^2 one 3068 against 14487 */
	const enum ss_integrator integrator = o->integrator == SS_INTEGRATOR_AUTO
		? SS_INTEGRATOR_EULER : o->integrator;
	if (integrator == SS_INTEGRATOR_RKL2 && bedrock)
		return ss_error_input("--integrator rkl2 cannot be used with --bedrock: its stages "
		                      "cannot keep the sand above the rock (use euler or auto)");
	/* the memory of one rank's slab, times the ranks on this node */
	const double need = ss_stepper_memory_bytes(&g, integrator) / ss_comm_size() *
	                    ss_comm_node_ranks();
	const double have = ss_memory_available_bytes();
	if (have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("%s: %d x %d cells need %s of memory; this machine has %s "
		                      "available", o->dem, r->nx, r->ny, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb));
	}

	double level = o->open_level;
	if (isnan(level)) {
		/* sand that reaches an open side, or a nodata cell with
		 * --nodata open, leaves at the lowest ground of the DEM */
		level = INFINITY;
		for (size_t m = 0; m < (size_t)r->nx * r->ny; m++)
			if (!r->nodata || !r->nodata[m])
				level = fmin(level, r->values[m]);
		if (isinf(level))
			return ss_error_input("%s: every cell is nodata: nothing to relax", o->dem);
	}
	struct ss_closure closure;
	const struct ss_boundary sides = {{o->sides, o->sides, o->sides, o->sides}, level};
	if ((err = ss_closure_init(&closure, o->closure, o->angle_deg, o->gamma, o->nu)))
		return err;
	if ((err = ss_stepper_init(st, &g, &closure, &sides, o->cfl, 0, 0)))
		return err;
	st->integrator = integrator;
	st->rkl2_max_stages = o->rkl2_max_stages;
	st->rkl2_tol = o->rkl2_tol;
	/* every rank read the DEM; from here on g is this rank's slab */
	g = st->grid;
	const size_t first = (size_t)g.offset_j * g.nx;
	for (int j = 0; j < g.ny; j++) {
		for (int i = 0; i < g.nx; i++) {
			const size_t m = first + (size_t)j * g.nx + i;
			const ptrdiff_t k = ss_grid_index(&g, i, j);
			st->height[k] = r->values[m];
			if (r->nodata && r->nodata[m])
				ss_cell_type_set(st->cell_types, k, o->nodata_type);
		}
	}
	/* agreed: the collective calls of prepare follow */
	if ((err = ss_comm_agree(bedrock ? ss_stepper_set_bedrock(st, bedrock->values + first)
	                                 : SS_OK)))
		return err;
	if (o->add_sand) {
		uint8_t *mask = ss_alloc((size_t)g.nx * g.ny, 1, "sand source mask");
		long long covered = 0;
		if (!mask)
			return SS_ERR_FAIL;
		err = ss_shape_rasterize(&o->sand_shape, &g, mask, &covered);
		double covered_all = (double)covered, none = 0.0;
		ss_comm_reduce(&none, 0, &covered_all, 1);
		if (!err && covered_all == 0)
			err = ss_error_input("--add-sand covers no cell centre of the DEM (x %g .. %g "
			                     "m, y %g .. %g m)", g.origin_x, g.origin_x + r->nx * dx,
			                     g.origin_y, g.origin_y + r->ny * dy);
		if (!err)
			err = ss_stepper_add_source(st, mask, o->sand_rate, 0.0, o->sand_duration);
		ss_free(mask);
		if ((err = ss_comm_agree(err)))
			return err;
	}
	return ss_stepper_prepare(st);
}

static double flow_volume(struct ss_stepper *st)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	return d.volume;
}

/* The report (ss_relax_report_json, the one formatter) to path, whole or
 * not at all. */
static int write_report(const char *path, const struct ss_relax_options *o,
                        const struct ss_relax_report *r)
{
	/* the numbers, and both paths with every byte escaped (\u00XX) */
	const size_t size = 2048 + 6 * (strlen(o->dem) + strlen(r->output));
	char *json = ss_alloc(size, 1, "the report");
	if (!json)
		return SS_ERR_FAIL;
	int err = ss_relax_report_json(o, r, json, size);
	char tmp[4200];
	snprintf(tmp, sizeof tmp, "%s.partial", path);
	FILE *f = err ? NULL : fopen(tmp, "w");
	if (!err && !f)
		err = ss_error_input("--report: cannot write '%s': %s", path, strerror(errno));
	if (f) {
		fputs(json, f);
		const int bad = ferror(f) | (fclose(f) != 0);
		if (bad || rename(tmp, path) != 0) {
			remove(tmp);
			err = ss_error_fail("--report: writing '%s' failed", path);
		}
	}
	ss_free(json);
	return err;
}

/* The relaxed heights into r's values (nodata cells keep theirs): each
 * rank's rows, gathered on rank 0. */
static void heights_to_raster(const struct ss_stepper *st, struct ss_raster *r)
{
	const struct ss_grid *g = &st->grid;
	double *rows = r->values + (size_t)g->offset_j * g->nx;
	const uint8_t *nodata = r->nodata ? r->nodata + (size_t)g->offset_j * g->nx : NULL;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			if (!nodata || !nodata[(size_t)j * g->nx + i])
				rows[(size_t)j * g->nx + i] = st->height[ss_grid_index(g, i, j)];
	if (!ss_grid_is_whole(g))
		ss_comm_gather_rows(rows, (size_t)g->ny * g->nx * sizeof *rows, r->values);
}

/* Everything one relaxation holds, released by ss_relax_run. */
struct relax {
	const struct ss_relax_options *o;
	struct ss_raster dem, bedrock;
	enum ss_dem_format format;        /* of the output */
	struct ss_stepper st;
	struct ss_drive drive;
	double *h0;                       /* the initial heights, halo layout */
};

/* The driver's rebuild: the DEM's stepper at t = 0. */
static int rebuild(void *context, struct ss_stepper *st)
{
	const struct relax *x = context;
	return build_stepper(x->o, &x->dem, x->o->bedrock ? &x->bedrock : NULL, st);
}

/* A copy of a caller's raster (values, nodata and geometry: the writers'
 * metadata is not needed in memory) into r. */
static int raster_copy(const struct ss_raster *from, struct ss_raster *r)
{
	const size_t cells = (size_t)from->nx * (size_t)from->ny;
	int err = ss_raster_init(r, from->nx, from->ny);
	if (!err && from->nodata && !(r->nodata = ss_alloc(cells, 1, "nodata flags")))
		err = SS_ERR_FAIL;
	if (err)
		return err;
	memcpy(r->values, from->values, cells * sizeof *r->values);
	if (from->nodata)
		memcpy(r->nodata, from->nodata, cells);
	r->cellsize = from->cellsize;
	r->cellsize_y = from->cellsize_y;
	r->x0 = from->x0;
	r->y0 = from->y0;
	return SS_OK;
}

/* The inputs and the output's name and format, all checked. */
static int read_inputs(struct relax *x, struct ss_relax_report *rep)
{
	const struct ss_relax_options *o = x->o;
	if ((o->input_raster && !o->dem) || (o->bedrock_raster && !o->bedrock))
		SS_BUG("ss_relax_run: an input raster without its name (dem, bedrock)");
	if (o->output_raster)
		snprintf(rep->output, sizeof rep->output, "(array)");
	else if (o->output)
		snprintf(rep->output, sizeof rep->output, "%s", o->output);
	else
		default_output(o->dem, rep->output, sizeof rep->output);
	int err = o->input_raster ? raster_copy(o->input_raster, &x->dem)
	                          : ss_dem_read(o->dem, NULL, &o->read, &x->dem);
	if (!err && o->output_raster && (o->output_raster->nx != x->dem.nx ||
	                                 o->output_raster->ny != x->dem.ny))
		err = ss_error_input("the output raster is %d x %d cells: expected the DEM's "
		                     "%d x %d", o->output_raster->nx, o->output_raster->ny,
		                     x->dem.nx, x->dem.ny);
	if (!err && !o->output_raster)
		err = ss_dem_format_from_path(rep->output, "-o", &x->format);
	if (!err && x->format == SS_DEM_GDAL && !ss_dem_gdal_available())
		err = ss_error_input("-o %s: GeoTIFF output needs a build with GDAL (libgdal-dev); "
		                     "write .asc, .png or .h5", rep->output);
	if (!err && !o->output_raster)
		err = ss_output_check_folder(rep->output, o->output == NULL);
	if (err || !o->bedrock)
		return err;
	struct ss_dem_read_options bo = o->read;
	if ((err = o->bedrock_raster ? raster_copy(o->bedrock_raster, &x->bedrock)
	                             : ss_dem_read(o->bedrock, "--bedrock", &bo, &x->bedrock)))
		return err;
	if (x->bedrock.nx != x->dem.nx || x->bedrock.ny != x->dem.ny)
		return ss_error_input("--bedrock %s is %d x %d cells: expected the DEM's %d x %d",
		                      o->bedrock, x->bedrock.nx, x->bedrock.ny, x->dem.nx, x->dem.ny);
	return SS_OK;
}

/* The initial state's measures, and a copy of it to count what moved. */
static int measure_before(struct relax *x, struct ss_relax_report *rep)
{
	const struct ss_grid *g = &x->st.grid;
	const size_t cells = ss_grid_storage_cells(g);
	if (!(x->h0 = ss_alloc(cells, sizeof *x->h0, "initial heights")))
		return SS_ERR_FAIL;
	memcpy(x->h0, x->st.height, cells * sizeof *x->h0);
	rep->nx = (int)g->global_nx;
	rep->ny = (int)g->global_ny;
	rep->dx = g->dx;
	rep->dy = g->dy;
	rep->volume_before = flow_volume(&x->st);
	rep->max_slope_before_deg = steepest_sand_face_deg(&x->st);
	return SS_OK;
}

/* The loop's settings, the claim of the output and, for .h5, the series. */
static int open_output(struct relax *x, const struct ss_relax_report *rep)
{
	const struct ss_relax_options *o = x->o;
	struct ss_drive *d = &x->drive;
	const int series = x->format == SS_DEM_H5;
	d->end = o->max_time;
	d->steady_tol = o->tol;
	d->steady_slope_tol = o->slope_tol;
	d->output_every = !isnan(o->output_every) ? o->output_every
	                : series && isfinite(o->max_time) ? o->max_time / 20.0 : INFINITY;
	d->stop_signal = o->stop_signal;
	d->progress = o->progress;
	d->progress_context = o->progress_context;
	d->rebuild = rebuild;
	d->rebuild_context = x;
	if (o->output_raster)
		return SS_OK;   /* nothing to claim: the caller's memory */
	int err = ss_drive_claim(d, rep->output, o->output == NULL, o->force, 0, NULL);
	if (err || !series)
		return err;
	const struct ss_snapshot_meta meta = {
		.title = o->dem, .history = o->history ? o->history : "",
		.case_text = "", .closure = ss_closure_name(o->closure),
		.integrator = ss_integrator_name(x->st.integrator),
		.repose_angle_deg = o->angle_deg, .nu = o->nu, .gamma = o->gamma,
		.bedrock = x->st.bedrock, .crs_wkt = x->dem.crs_wkt, .boundary = &x->st.boundary,
		.nodata = x->dem.nodata,
	};
	return ss_drive_create(d, &meta);
}

/* The end state's measures; cells moved and half the volume moved. */
static void measure_after(struct relax *x, enum ss_drive_end end, struct ss_relax_report *rep)
{
	struct ss_stepper *st = &x->st;
	const struct ss_grid *g = &st->grid;
	rep->steady = end == SS_DRIVE_STEADY;
	rep->interrupted = end == SS_DRIVE_INTERRUPTED;
	rep->steps = st->steps;
	rep->evaluations = st->evaluations;
	rep->integrator = ss_integrator_name(st->integrator);
	rep->time = st->time;
	rep->inflow = st->inflow;
	rep->outflow = st->outflow;
	rep->volume_after = flow_volume(st);
	rep->max_slope_after_deg = steepest_sand_face_deg(st);
	/* in row order, carried from rank to rank (comm.h) */
	double moved = 0.0, cells_moved = 0.0, none = 0.0;
	ss_comm_fold_start(&moved, 1);
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW ||
			    st->height[k] == x->h0[k])
				continue;
			cells_moved++;
			moved += fabs(st->height[k] - x->h0[k]);
		}
	}
	ss_comm_fold_finish(&moved, 1);
	ss_comm_reduce(&none, 0, &cells_moved, 1);
	rep->cells_moved = (long long)cells_moved;
	rep->volume_moved = 0.5 * moved * g->dx * g->dy;
}

/* The relaxed surface as a raster in the input's format (a series is
 * written as it goes). */
static int write_raster(struct relax *x, const char *path)
{
	if (x->format == SS_DEM_H5)
		return SS_OK;
	heights_to_raster(&x->st, &x->dem);
	if (x->o->output_raster) {
		memcpy(x->o->output_raster->values, x->dem.values,
		       (size_t)x->dem.nx * x->dem.ny * sizeof *x->dem.values);
		return SS_OK;
	}
	return ss_comm_agree(ss_comm_rank() == 0 ? ss_dem_write(path, x->format, &x->dem)
	                                         : SS_OK);
}

/* The guard fired: the last good state goes to a raster output too. */
static int nonfinite(struct relax *x, const char *path)
{
	const int kept = x->drive.trouble.good_step >= 0;
	int err = kept ? write_raster(x, path) : SS_OK;
	if (err)
		return err;
	return ss_drive_nonfinite_error(&x->drive, kept && x->format != SS_DEM_H5 ? path : NULL);
}

int ss_relax_run(const struct ss_relax_options *o, struct ss_relax_report *rep)
{
	const double started = ss_parallel_wall_seconds();
	struct relax x;
	memset(&x, 0, sizeof x);
	memset(rep, 0, sizeof *rep);
	x.o = o;
	ss_drive_init(&x.drive, &x.st, started);
	ss_drive_set_threads(o->threads);

	enum ss_drive_end end = SS_DRIVE_END;
	int err = read_inputs(&x, rep);
	if (!err)
		err = rebuild(&x, &x.st);
	if (!err)
		err = measure_before(&x, rep);
	if (!err)
		err = open_output(&x, rep);
	if (!err)
		err = ss_drive_run(&x.drive, &end);
	if (!err && end == SS_DRIVE_NONFINITE)
		err = nonfinite(&x, rep->output);
	if (!err) {
		measure_after(&x, end, rep);
		err = write_raster(&x, rep->output);
	}
	rep->wall_seconds = ss_parallel_wall_seconds() - started;
	if (!err && o->report)
		err = ss_comm_agree(ss_comm_rank() == 0 ? write_report(o->report, o, rep) : SS_OK);
	err = ss_drive_finish(&x.drive, err);
	ss_free(x.h0);
	ss_stepper_release(&x.st);
	ss_raster_release(&x.bedrock);
	ss_raster_release(&x.dem);
	return err;
}
