/*
 * relax.c - the `sandslide relax` driver: DEM -> stepper -> steady surface
 * (see relax.h).
 */
#include "sandslide/relax.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sandslide/error.h"
#include "io/output.h"
#include "sandslide/parallel.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

void ss_relax_options_init(struct ss_relax_options *o)
{
	memset(o, 0, sizeof *o);
	ss_dem_read_options_init(&o->read);
	o->closure = SS_CLOSURE_COULOMB;
	o->angle_deg = 35.0;
	o->gamma = 1.0;
	o->nu = 1.0;
	o->tol = 1e-9;
	o->max_time = INFINITY;
	o->cfl = 0.9;
	o->sides = SS_SIDE_WALL;
	o->nodata_type = SS_CELL_OPEN;
	o->open_level = NAN;
	o->output_every = NAN;
}

/* "dir/name.asc" -> "out/name-relaxed.asc"; "FILE.h5:/dataset" -> .h5 */
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
}

/* An existing output is replaced only with force. */
static int check_not_existing(const char *path, int force)
{
	struct stat sb;
	if (!force && stat(path, &sb) == 0)
		return ss_error_input("'%s' exists: give --force to replace it", path);
	return SS_OK;
}

/*
 * The steepest face of the sand, as an angle: faces that can carry flux
 * (SPEC section 2) whose stencil (both cells and their neighbours along the
 * face) lies in sand at least 1e-6 min(dx, dy) thick.  Bare rock may be
 * steeper than the repose angle for ever, and so may the slope measured
 * next to a rock cliff, whose step enters the tangential difference; a cell
 * at the top of a cliff drains geometrically (a quarter of its sand per
 * face and step, face.h), so it never quite reaches 0.  Without bedrock
 * this is ss_sweep_max_slope.
 */
static double steepest_sand_face_deg(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	if (!st->bedrock)
		return atan(ss_sweep_max_slope(g, st->height, st->cell_types)) * (180.0 / M_PI);
	const double *h = st->height, *b = st->bedrock;
	const double bare = 1e-6 * fmin(g->dx, g->dy);   /* m */
	const uint8_t *t = st->cell_types;
	double s2_max = 0.0;
	for (int axis = 0; axis < 2; axis++) {
		const ptrdiff_t normal = axis == 0 ? 1 : g->stride, along = axis == 0 ? g->stride : 1;
		const double dn = axis == 0 ? g->dx : g->dy, da = axis == 0 ? g->dy : g->dx;
		#pragma omp parallel for schedule(static) reduction(max:s2_max)
		for (int j = 0; j <= g->ny; j++) {
			for (int i = 0; i <= g->nx; i++) {
				if ((axis == 0 && j == g->ny) || (axis == 1 && i == g->nx))
					continue;
				const ptrdiff_t kb = ss_grid_index(g, i, j), ka = kb - normal;
				const enum ss_cell_type ta = ss_cell_type_get(t, ka);
				const enum ss_cell_type tb = ss_cell_type_get(t, kb);
				if (ta == SS_CELL_WALL || tb == SS_CELL_WALL ||
				    (ta != SS_CELL_FLOW && tb != SS_CELL_FLOW))
					continue;
				const ptrdiff_t stencil[6] = {ka, kb, ka + along, ka - along,
				                              kb + along, kb - along};
				int in_sand = 1;
				for (int m = 0; m < 6; m++)
					in_sand &= ss_cell_type_get(t, stencil[m]) != SS_CELL_FLOW ||
					           h[stencil[m]] - b[stencil[m]] > bare;
				if (!in_sand)
					continue;
				double gt = 0.0;
				const ptrdiff_t cells[2] = {ka, kb};
				for (int m = 0; m < 2; m++) {
					const ptrdiff_t k = cells[m];
					const double up = ss_cell_type_get(t, k + along) == SS_CELL_WALL
					                  ? h[k] : h[k + along];
					const double down = ss_cell_type_get(t, k - along) == SS_CELL_WALL
					                    ? h[k] : h[k - along];
					gt += 0.5 * (up - down) / (2.0 * da);
				}
				const double gn = (h[kb] - h[ka]) / dn, s2 = gn * gn + gt * gt;
				s2_max = s2 > s2_max ? s2 : s2_max;
			}
		}
	}
	return atan(sqrt(s2_max)) * (180.0 / M_PI);
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
	const double need = ss_stepper_memory_bytes(&g), have = ss_memory_available_bytes();
	if (have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("%s: %d x %d cells need %s of memory; this machine has %s "
		                      "available", o->dem, r->nx, r->ny, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb));
	}

	double level = o->open_level;
	if (isnan(level)) {
		/* sand that reaches a nodata cell or an open side leaves at the
		 * lowest ground of the DEM */
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
	for (int j = 0; j < g.ny; j++) {
		for (int i = 0; i < g.nx; i++) {
			const size_t m = (size_t)j * g.nx + i;
			const ptrdiff_t k = ss_grid_index(&g, i, j);
			st->height[k] = r->values[m];
			if (r->nodata && r->nodata[m])
				ss_cell_type_set(st->cell_types, k, o->nodata_type);
		}
	}
	if (bedrock && (err = ss_stepper_set_bedrock(st, bedrock->values)))
		return err;
	if (o->add_sand) {
		uint8_t *mask = ss_alloc((size_t)g.nx * g.ny, 1, "sand source mask");
		long long covered = 0;
		if (!mask)
			return SS_ERR_FAIL;
		err = ss_shape_rasterize(&o->sand_shape, &g, mask, &covered);
		if (!err && covered == 0)
			err = ss_error_input("--add-sand covers no cell centre of the DEM (x %g .. %g "
			                     "m, y %g .. %g m)", g.origin_x, g.origin_x + g.nx * dx,
			                     g.origin_y, g.origin_y + g.ny * dy);
		if (!err)
			err = ss_stepper_add_source(st, mask, o->sand_rate, 0.0, o->sand_duration);
		ss_free(mask);
		if (err)
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

static void progress_print(void *context, const struct ss_stepper *st)
{
	double *last = context;
	const double now = ss_parallel_wall_seconds();
	if (now - *last < 0.5)
		return;
	*last = now;
	fprintf(stderr, "\r  t = %.6g s  steps %lld  max|dh/dt| %.2e m/s   ", st->time,
	        st->steps, st->rate_max);
	fflush(stderr);
}

static int write_report(const char *path, const struct ss_relax_options *o,
                        const struct ss_relax_report *r)
{
	char tmp[4200];
	snprintf(tmp, sizeof tmp, "%s.partial", path);
	FILE *f = fopen(tmp, "w");
	if (!f)
		return ss_error_input("--report: cannot write '%s': %s", path, strerror(errno));
	fprintf(f, "{\n  \"input\": \"%s\",\n  \"output\": \"%s\",\n", o->dem, r->output);
	fprintf(f, "  \"nx\": %d, \"ny\": %d, \"dx\": %.17g, \"dy\": %.17g,\n", r->nx, r->ny,
	        r->dx, r->dy);
	fprintf(f, "  \"closure\": \"%s\", \"repose_angle_deg\": %.17g, \"nu\": %.17g,\n",
	        ss_closure_name(o->closure), o->angle_deg, o->nu);
	fprintf(f, "  \"steady\": %s, \"tol\": %.17g,\n", r->steady ? "true" : "false", o->tol);
	fprintf(f, "  \"steps\": %lld, \"time\": %.17g, \"wall_seconds\": %.6g,\n", r->steps,
	        r->time, r->wall_seconds);
	fprintf(f, "  \"cells_moved\": %lld, \"volume_moved\": %.17g,\n", r->cells_moved,
	        r->volume_moved);
	fprintf(f, "  \"volume_before\": %.17g, \"volume_after\": %.17g,\n", r->volume_before,
	        r->volume_after);
	fprintf(f, "  \"inflow\": %.17g, \"outflow\": %.17g,\n", r->inflow, r->outflow);
	fprintf(f, "  \"max_slope_before_deg\": %.17g, \"max_slope_after_deg\": %.17g\n}\n",
	        r->max_slope_before_deg, r->max_slope_after_deg);
	const int bad = ferror(f) | (fclose(f) != 0);
	if (bad || rename(tmp, path) != 0) {
		remove(tmp);
		return ss_error_fail("--report: writing '%s' failed", path);
	}
	return SS_OK;
}

/* The relaxed heights into r's values (nodata cells keep theirs). */
static void heights_to_raster(const struct ss_stepper *st, struct ss_raster *r)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			if (!r->nodata || !r->nodata[(size_t)j * g->nx + i])
				r->values[(size_t)j * g->nx + i] = st->height[ss_grid_index(g, i, j)];
}

static int write_series_snapshot(struct ss_snapshot *snap, struct ss_stepper *st,
                                 double started)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	d.wall_seconds = ss_parallel_wall_seconds() - started;
	return ss_snapshot_append(snap, st->time, st->height, &d, NULL);
}

int ss_relax_run(const struct ss_relax_options *o, struct ss_relax_report *rep)
{
	const double started = ss_parallel_wall_seconds();
	struct ss_raster dem, bedrock;
	struct ss_stepper st;
	struct ss_snapshot *snap = NULL;
	double *h0 = NULL;
	int err;

	memset(rep, 0, sizeof *rep);
	memset(&st, 0, sizeof st);
	memset(&bedrock, 0, sizeof bedrock);
	ss_parallel_set_threads(o->threads > 0 ? o->threads : ss_parallel_processors());
	if (o->output)
		snprintf(rep->output, sizeof rep->output, "%s", o->output);
	else
		default_output(o->dem, rep->output, sizeof rep->output);
	enum ss_dem_format out_format;
	if ((err = ss_dem_read(o->dem, NULL, &o->read, &dem)))
		goto out;
	if ((err = ss_dem_format_from_path(rep->output, "-o", &out_format)))
		goto out;
	if (out_format == SS_DEM_GDAL && !ss_dem_gdal_available()) {
		err = ss_error_input("-o %s: GeoTIFF output needs a build with GDAL (libgdal-dev); "
		                     "write .asc, .png or .h5", rep->output);
		goto out;
	}
	if ((err = ss_output_check_folder(rep->output, o->output == NULL)) ||
	    (err = check_not_existing(rep->output, o->force)))
		goto out;
	if (o->bedrock) {
		struct ss_dem_read_options bo = o->read;
		if ((err = ss_dem_read(o->bedrock, "--bedrock", &bo, &bedrock)))
			goto out;
		if (bedrock.nx != dem.nx || bedrock.ny != dem.ny) {
			err = ss_error_input("--bedrock %s is %d x %d cells: expected the DEM's %d x %d",
			                     o->bedrock, bedrock.nx, bedrock.ny, dem.nx, dem.ny);
			goto out;
		}
	}
	if ((err = build_stepper(o, &dem, o->bedrock ? &bedrock : NULL, &st)))
		goto out;

	const struct ss_grid *g = &st.grid;
	rep->nx = g->nx;
	rep->ny = g->ny;
	rep->dx = g->dx;
	rep->dy = g->dy;
	const size_t cells = ss_grid_storage_cells(g);
	if (!(h0 = ss_alloc(cells, sizeof *h0, "initial heights"))) {
		err = SS_ERR_FAIL;
		goto out;
	}
	memcpy(h0, st.height, cells * sizeof *h0);
	rep->volume_before = flow_volume(&st);
	rep->max_slope_before_deg = steepest_sand_face_deg(&st);

	if (!o->output && (err = ss_output_make_folder(rep->output)))
		goto out;
	const int series = out_format == SS_DEM_H5;
	double every = o->output_every;
	if (series && isnan(every))
		every = isfinite(o->max_time) ? o->max_time / 20.0 : INFINITY;
	if (series) {
		struct ss_snapshot_meta meta = {
			.title = o->dem, .history = o->history ? o->history : "",
			.case_text = "", .closure = ss_closure_name(o->closure),
			.repose_angle_deg = o->angle_deg, .nu = o->nu, .gamma = o->gamma,
			.bedrock = st.bedrock,
		};
		if ((err = ss_snapshot_create(&snap, rep->output, g, st.cell_types, &meta)) ||
		    (err = write_series_snapshot(snap, &st, started)))
			goto out;
	}

	double last_print = started;
	const int show = !o->quiet && isatty(fileno(stderr));
	struct ss_advance_options adv = {
		.steady_tol = o->tol,
		.progress = show ? progress_print : NULL,
		.context = &last_print,
		.stop = o->stop_signal,
	};
	enum ss_advance_end end = SS_ADVANCE_REACHED;
	for (long long k = 1; st.time < o->max_time; k++) {
		const double target = fmin((double)k * every, o->max_time);
		end = ss_stepper_advance(&st, target, &adv);
		if (end == SS_ADVANCE_NONFINITE || end == SS_ADVANCE_STALLED) {
			err = ss_error_fail("the surface became %s at t = %g s (step %lld)",
			                    end == SS_ADVANCE_NONFINITE ? "non-finite"
			                    : "too steep for the time step", st.time, st.steps);
			goto out;
		}
		if (snap && (err = write_series_snapshot(snap, &st, started)))
			goto out;
		if (end == SS_ADVANCE_STEADY || end == SS_ADVANCE_INTERRUPTED || isinf(target))
			break;
	}
	if (show)
		fputc('\n', stderr);
	if (end == SS_ADVANCE_INTERRUPTED) {
		fflush(stdout);
		fprintf(stderr, "sandslide: interrupted at t = %g s (step %lld): '%s' holds the "
		        "surface as it was then, not relaxed\n", st.time, st.steps, rep->output);
	}
	rep->steady = end == SS_ADVANCE_STEADY;
	rep->steps = st.steps;
	rep->time = st.time;
	rep->inflow = st.inflow;
	rep->outflow = st.outflow;
	rep->volume_after = flow_volume(&st);
	rep->max_slope_after_deg = steepest_sand_face_deg(&st);
	double moved = 0.0;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st.cell_types, k) != SS_CELL_FLOW ||
			    st.height[k] == h0[k])
				continue;
			rep->cells_moved++;
			moved += fabs(st.height[k] - h0[k]);
		}
	}
	rep->volume_moved = 0.5 * moved * g->dx * g->dy;

	if (!series) {
		heights_to_raster(&st, &dem);
		if ((err = ss_dem_write(rep->output, out_format, &dem)))
			goto out;
	}
	rep->wall_seconds = ss_parallel_wall_seconds() - started;
	if (o->report && (err = write_report(o->report, o, rep)))
		goto out;
	if (!o->quiet) {
		printf("wrote %s: %d x %d cells, %s after %lld steps (t = %g s)\n", rep->output,
		       rep->nx, rep->ny, rep->steady ? "steady" : "NOT steady by --max-time",
		       rep->steps, rep->time);
		printf("cells moved %lld, volume moved %.6g m^3, steepest sand face %.4f -> "
		       "%.4f deg (repose %g), wall %.3f s\n", rep->cells_moved, rep->volume_moved,
		       rep->max_slope_before_deg, rep->max_slope_after_deg, o->angle_deg,
		       rep->wall_seconds);
	}
out:
	if (ss_snapshot_destroy(snap) && !err)
		err = SS_ERR_FAIL;
	ss_free(h0);
	ss_stepper_release(&st);
	ss_raster_release(&bedrock);
	ss_raster_release(&dem);
	return err;
}
