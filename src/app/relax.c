/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
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
#include "app/relax_inputs.h"
#include "model/setup.h"
#include "io/output.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

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

/* The steepest face of the sand (ss_stepper_max_sand_slope), in degrees:
 * what run's /max_slope_deg holds too. */
static double steepest_sand_face_deg(struct ss_stepper *st)
{
	return atan(ss_stepper_max_sand_slope(st)) * (180.0 / M_PI);
}

static double flow_volume(struct ss_stepper *st)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	return d.volume;
}

/* The report (ss_relax_report_json, the one formatter) to path, whole or
 * not at all. */
static int write_report(const char *path, const struct ss_relax_report *r)
{
	/* the numbers, and both paths with every byte escaped (\u00XX) */
	const size_t size = 2048 + 6 * (strlen(r->input) + strlen(r->output));
	char *json = ss_alloc(size, 1, "the report");
	if (!json)
		return SS_ERR_FAIL;
	int err = ss_relax_report_json(r, json, size);
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

/* The relaxed heights into r's values (this rank's rows: r holds them,
 * dem.h's window); nodata cells keep theirs. */
static void heights_to_raster(const struct ss_stepper *st, struct ss_raster *r)
{
	const struct ss_grid *g = &st->grid;
	double *rows = r->values + (size_t)(g->offset_j - r->row_first) * g->nx;
	const uint8_t *nodata = r->nodata ? r->nodata + (size_t)(g->offset_j - r->row_first) * g->nx
	                                  : NULL;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			if (!nodata || !nodata[(size_t)j * g->nx + i])
				rows[(size_t)j * g->nx + i] = st->height[ss_grid_index(g, i, j)];
}

/* The rows of an nx x ny raster that rank `rank`'s slab holds, as the
 * stepper splits the grid with relax's tiles (stepper.h). */
static int slab_rows(int nx, int ny, const struct ss_relax_options *o, int rank, int *first,
                     int *rows)
{
	struct ss_grid whole;
	const int err = ss_grid_init(&whole, nx, ny, 1.0, 1.0, 0.0, 0.0);
	if (!err)
		ss_stepper_slab_rows(&whole, o->job.tile[0], o->job.tile[1], rank, first, rows);
	return err;
}

/* Rows per block of a streamed write: about 4 MiB of heights and flags,
 * what rank 0 holds of the other ranks' rows at a time. */
static int block_rows(int nx)
{
	const long long rows = (4LL << 20) / (9LL * nx);
	return rows < 1 ? 1 : rows > 1 << 20 ? 1 << 20 : (int)rows;
}

/*
 * The raster r (each rank's rows, its window) written to path by rank 0,
 * north row first: rank 0 writes its own rows and receives the others' in
 * blocks (ss_comm_relay), so that no rank holds the whole raster.  The
 * writer needs the summary of all the data first (the PNG's range, a
 * nodata value no height takes): a reduction.  After a failed write rank
 * 0 goes on receiving (the senders cannot know), then all agree.
 */
static int write_streamed(const char *path, enum ss_dem_format format, const struct ss_raster *r,
                          const struct ss_relax_options *o)
{
	struct ss_dem_summary s;
	ss_dem_summarize(r, &s);
	ss_comm_reduce(s.max, 3, s.count, SS_DEM_NODATA_CANDIDATES);
	const int me = ss_comm_rank(), nx = r->nx, block = block_rows(nx);
	struct ss_dem_writer *w = NULL;
	int err = me == 0 ? ss_dem_writer_open(&w, path, format, r, &s) : SS_OK;
	if ((err = ss_comm_agree(err)))
		return err;
	double *values = ss_alloc((size_t)block * nx, sizeof *values, "a block of rows");
	uint8_t *flags = ss_alloc((size_t)block * nx, 1, "a block of nodata flags");
	err = ss_comm_agree(values && flags ? SS_OK : SS_ERR_FAIL);
	for (int q = ss_comm_size() - 1; q >= 0 && !err; q--) {   /* north first */
		int first = 0, rows = 0;
		err = slab_rows(nx, r->ny, o, q, &first, &rows);   /* the grid's: it cannot fail */
		if (err || (me != 0 && me != q))
			continue;
		for (int top = first + rows; top > first;) {   /* rows top - n .. top - 1 */
			const int n = top - first < block ? top - first : block;
			if (me == q) {   /* north row first */
				for (int k = 0; k < n; k++) {
					const size_t from = (size_t)(top - 1 - k - r->row_first) * nx;
					memcpy(values + (size_t)k * nx, r->values + from, nx * sizeof *values);
					if (r->nodata)
						memcpy(flags + (size_t)k * nx, r->nodata + from, (size_t)nx);
					else
						memset(flags + (size_t)k * nx, 0, (size_t)nx);
				}
			}
			ss_comm_relay(values, (size_t)n * nx * sizeof *values, q, 0);
			ss_comm_relay(flags, (size_t)n * nx, q, 0);
			if (me == 0)
				ss_dem_writer_put(w, values, flags, n);   /* its failure: at close */
			top -= n;
		}
	}
	if (me == 0)
		err = ss_dem_writer_close(&w, !err);
	ss_free(values);
	ss_free(flags);
	return ss_comm_agree(err);
}

/* Everything one relaxation holds, released by ss_relax_run. */
struct relax {
	const struct ss_relax_options *o;
	struct ss_relax_inputs in;        /* in.dem: the initial heights, then
	                                   * the output raster's */
	enum ss_dem_format format;        /* of the output */
	struct ss_stepper st;
	struct ss_drive drive;
	struct ss_pour_cover cover;       /* where --add-sand's sand lands */
};

/* The driver's rebuild: the DEM's stepper at t = 0. */
static int rebuild(void *context, struct ss_stepper *st)
{
	struct relax *x = context;
	return ss_relax_setup_stepper(x->o, &x->in, 1, st, &x->cover);
}

/* The output's name and format, checked before any work: every rank
 * checks the same, so they agree. */
static int check_output(struct relax *x, struct ss_relax_report *rep)
{
	const struct ss_relax_options *o = x->o;
	if (o->output_raster) {
		snprintf(rep->output, sizeof rep->output, "(array)");
		if (o->output_raster->nx != x->in.dem.nx || o->output_raster->ny != x->in.dem.ny)
			return ss_error_input("the output raster is %d x %d cells: expected the DEM's "
			                      "%d x %d", o->output_raster->nx, o->output_raster->ny,
			                      x->in.dem.nx, x->in.dem.ny);
		return SS_OK;
	}
	if (o->job.output)
		snprintf(rep->output, sizeof rep->output, "%s", o->job.output);
	else
		default_output(o->dem, rep->output, sizeof rep->output);
	int err = ss_dem_format_from_path(rep->output, "-o", &x->format);
	if (!err && x->format == SS_DEM_GDAL && !ss_dem_gdal_available())
		err = ss_error_input("-o %s: GeoTIFF output needs a build with GDAL (libgdal-dev); "
		                     "write .asc, .png or .h5", rep->output);
	if (!err)
		err = ss_output_check_folder(rep->output, o->job.output == NULL);
	/* refused now, not after the relaxation whose result it would be */
	if (!err)
		err = ss_dem_check_not_source(rep->output, &x->in.dem);
	return err;
}

/* The initial state's measures.  What moved is counted against the DEM's
 * rows (x->in.dem, until write_raster overwrites them), which hold the
 * initial height of every flow cell: no copy of the heights. */
static int measure_before(struct relax *x, struct ss_relax_report *rep)
{
	const struct ss_grid *g = &x->st.grid;
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
	d->end = ss_model_time_limit(&o->model);
	d->steady_tol = o->model.steady_tol;
	d->steady_slope_tol = o->model.steady_slope_tol;
	d->output_every = !isnan(o->output_every) ? o->output_every
	                : series && isfinite(d->end) ? d->end / 20.0 : INFINITY;
	d->job = &o->job;
	d->samples = 1;   /* the steps do not depend on when snapshots are taken */
	d->rebuild = rebuild;
	d->rebuild_context = x;
	if (o->output_raster)
		return SS_OK;   /* nothing to claim: the caller's memory */
	int err = ss_drive_claim(d, rep->output, o->job.output == NULL, o->job.force, 0, NULL);
	if (err || !series)
		return err;
	const struct ss_snapshot_meta meta = {
		.title = o->dem, .history = o->job.history ? o->job.history : "",
		.case_text = "", .model = &o->model,
		.integrator = ss_integrator_name(x->st.integrator),
		.bedrock = x->st.bedrock, .crs_wkt = x->in.dem.crs_wkt, .boundary = &x->st.boundary,
		.nodata = x->in.dem.nodata, .moving = x->st.hysteresis,
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
	rep->end = rep->steady ? "steady" : rep->interrupted ? "interrupted" : "max time";
	rep->steps = st->steps;
	rep->evaluations = st->evaluations;
	ss_stepper_rest_counts(st, &rep->rest_steps, &rep->rest_evaluations);
	rep->integrator = ss_integrator_name(st->integrator);
	rep->time = st->time;
	rep->inflow = ss_stepper_inflow(st);
	rep->outflow = ss_stepper_outflow(st);
	rep->volume_after = flow_volume(st);
	rep->max_slope_after_deg = steepest_sand_face_deg(st);
	/* with hysteresis each material is two states (stepper.h) */
	rep->materials = st->material ? st->material_count >> st->hysteresis : 1;
	ss_stepper_repose_range(st, &rep->repose_min_deg, &rep->repose_max_deg);
	rep->model.angle_deg = rep->repose_min_deg;   /* an angle raster's smallest */
	/* in row order, carried from rank to rank (comm.h) */
	double moved = 0.0, cells_moved = 0.0, none = 0.0;
	const double *h0 = x->in.dem.values + (size_t)(g->offset_j - x->in.dem.row_first) * g->nx;
	ss_comm_fold_start(&moved, 1);
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const double before = h0[(size_t)j * g->nx + i];
			if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW || st->height[k] == before)
				continue;
			cells_moved++;
			moved += fabs(st->height[k] - before);
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
	heights_to_raster(&x->st, &x->in.dem);
	if (x->o->output_raster) {   /* one rank, whole (raster_copy) */
		memcpy(x->o->output_raster->values, x->in.dem.values,
		       (size_t)x->in.dem.nx * x->in.dem.ny * sizeof *x->in.dem.values);
		return SS_OK;
	}
	return write_streamed(path, x->format, &x->in.dem, x->o);
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
	if (ss_drive_check_device(&o->job.device, NULL, "relax"))
		return SS_ERR_INPUT;
	const double started = ss_parallel_wall_seconds();
	struct relax x;
	memset(&x, 0, sizeof x);
	memset(rep, 0, sizeof *rep);
	rep->input = o->dem;
	rep->model = o->model;
	x.o = o;
	ss_drive_init(&x.drive, &x.st, started);
	ss_drive_set_threads(o->job.threads);

	enum ss_drive_end end = SS_DRIVE_END;
	int err = ss_relax_inputs_read(o, &x.in);
	if (!err)
		err = ss_comm_agree(check_output(&x, rep));
	rep->read_seconds = ss_parallel_wall_seconds() - started;
	if (!err)
		err = rebuild(&x, &x.st);
	if (!err && o->sand_shape.kind != SS_SHAPE_NONE) {
		rep->pour_cells = x.cover.cells;
		rep->pour_cells_nodata = x.cover.nodata;
		rep->pour_extent[0] = x.cover.x_min;
		rep->pour_extent[1] = x.cover.x_max;
		rep->pour_extent[2] = x.cover.y_min;
		rep->pour_extent[3] = x.cover.y_max;
	}
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
		const double t0 = ss_parallel_wall_seconds();
		err = write_raster(&x, rep->output);
		rep->write_seconds = ss_parallel_wall_seconds() - t0;
	}
	rep->wall_seconds = ss_parallel_wall_seconds() - started;
	if (!err) {   /* the output is written: the peak is the run's */
		const struct ss_grid *g = &x.st.grid;
		rep->ranks = ss_comm_size();
		rep->bytes_per_cell = ss_stepper_bytes(&x.st) / fmax((double)g->nx * g->ny, 1.0);
		/* the largest rank's: the job waits for it */
		double most[3] = {ss_memory_peak_bytes(), rep->read_seconds, rep->write_seconds};
		ss_comm_reduce(most, 3, NULL, 0);
		rep->memory_peak_bytes = most[0];
		rep->read_seconds = most[1];
		rep->write_seconds = most[2];
	}
	if (!err && o->report)
		err = ss_comm_agree(ss_comm_rank() == 0 ? write_report(o->report, rep) : SS_OK);
	err = ss_drive_finish(&x.drive, err);
	ss_stepper_release(&x.st);
	ss_relax_inputs_release(&x.in);
	return err;
}
