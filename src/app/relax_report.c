/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax_report.c - relax's report as JSON (its field table, report.h), and
 * relax for callers that cannot lay out its structs (see relax.h): on
 * arrays, and on files with the report in a buffer.  Python's ctypes
 * module (python/sandslide) is the caller this is written for: the struct
 * layouts change between versions, names and strings do not.
 */
#include "sandslide/relax.h"

#include <math.h>
#include <string.h>

#include "base/report.h"
#include "base/strings.h"
#include "sandslide/error.h"

static const char *closure_name(int kind)
{
	return ss_closure_name((enum ss_closure_kind)kind);
}

#define FIELD(n, k, m) {.name = n, .kind = k, .offset = AT(m)}
/* a field that starts a line of the JSON */
#define LINE(n, k, m) {.name = n, .kind = k, .offset = AT(m), .line = 1}
#define AT(m) offsetof(struct ss_relax_report, m)

static const struct ss_field fields[] = {
	FIELD("input", SS_FIELD_TEXT, input),
	LINE("output", SS_FIELD_CHARS, output),
	LINE("nx", SS_FIELD_INT, nx),
	FIELD("ny", SS_FIELD_INT, ny),
	FIELD("dx", SS_FIELD_REAL, dx),
	FIELD("dy", SS_FIELD_REAL, dy),
	{.name = "closure", .kind = SS_FIELD_NAME, .offset = AT(model.closure), .line = 1,
	 .name_of = closure_name},
	FIELD("repose_angle_deg", SS_FIELD_REAL, model.angle_deg),
	FIELD("nu", SS_FIELD_REAL, model.nu),
	LINE("materials", SS_FIELD_INT, materials),
	FIELD("repose_angle_min_deg", SS_FIELD_REAL, repose_min_deg),
	FIELD("repose_angle_max_deg", SS_FIELD_REAL, repose_max_deg),
	LINE("steady", SS_FIELD_BOOL, steady),
	FIELD("end", SS_FIELD_TEXT, end),
	FIELD("tol", SS_FIELD_REAL, model.steady_tol),
	LINE("steps", SS_FIELD_COUNT, steps),
	FIELD("time", SS_FIELD_REAL, time),
	FIELD("wall_seconds", SS_FIELD_SECONDS, wall_seconds),
	FIELD("read_seconds", SS_FIELD_SECONDS, read_seconds),
	FIELD("write_seconds", SS_FIELD_SECONDS, write_seconds),
	LINE("ranks", SS_FIELD_INT, ranks),
	FIELD("bytes_per_cell", SS_FIELD_REAL, bytes_per_cell),
	FIELD("memory_peak_bytes", SS_FIELD_REAL, memory_peak_bytes),
	LINE("integrator", SS_FIELD_TEXT, integrator),
	FIELD("stencil_evaluations", SS_FIELD_COUNT, evaluations),
	FIELD("rest_steps", SS_FIELD_COUNT, rest_steps),
	FIELD("rest_evaluations", SS_FIELD_COUNT, rest_evaluations),
	FIELD("slope_tol", SS_FIELD_REAL, model.steady_slope_tol),
	LINE("cells_moved", SS_FIELD_COUNT, cells_moved),
	FIELD("volume_moved", SS_FIELD_REAL, volume_moved),
	LINE("volume_before", SS_FIELD_REAL, volume_before),
	FIELD("volume_after", SS_FIELD_REAL, volume_after),
	LINE("inflow", SS_FIELD_REAL, inflow),
	FIELD("outflow", SS_FIELD_REAL, outflow),
	LINE("pour_cells", SS_FIELD_COUNT, pour_cells),
	FIELD("pour_cells_nodata", SS_FIELD_COUNT, pour_cells_nodata),
	LINE("max_slope_before_deg", SS_FIELD_REAL, max_slope_before_deg),
	FIELD("max_slope_after_deg", SS_FIELD_REAL, max_slope_after_deg),
};

int ss_relax_report_json(const struct ss_relax_report *r, char *buf, size_t size)
{
	return ss_report_json(fields, sizeof fields / sizeof *fields, r, "the relax report", buf,
	                      size);
}

/* nx x ny values into r (initialised here): NaN is no data (flagged, 0 as
 * rasters store it), an infinite value refused naming `what`, the cell and
 * the `expected` value. */
static int raster_from(const char *what, const char *expected, int nx, int ny, double dx,
                       double dy, const double *values, struct ss_raster *r)
{
	const size_t cells = (size_t)nx * (size_t)ny;
	int err = ss_raster_init(r, nx, ny);
	if (err)
		return err;
	r->cellsize = dx;
	r->cellsize_y = dy;
	for (size_t m = 0; m < cells; m++) {
		if (isinf(values[m]))
			return ss_error_input("%s: %s is %g: expected %s, or NaN for no data", what,
			                      SS_CELL((long long)(m % (size_t)nx), (long long)(m / (size_t)nx),
			                              (m % (size_t)nx + 0.5) * dx,
			                              (m / (size_t)nx + 0.5) * dy), values[m], expected);
		if (!isnan(values[m])) {
			r->values[m] = values[m];
			continue;
		}
		if (!r->nodata && !(r->nodata = ss_alloc(cells, 1, "nodata flags")))
			return SS_ERR_FAIL;
		r->nodata[m] = 1;
	}
	return SS_OK;
}

int ss_relax_heights(const struct ss_relax_options *o, int nx, int ny, double dx, double dy,
                     const double *heights, const double *bedrock, double *relaxed,
                     char *report_json, size_t report_size)
{
	return ss_relax_heights_angles(o, nx, ny, dx, dy, heights, bedrock, NULL, relaxed,
	                               report_json, report_size);
}

int ss_relax_heights_angles(const struct ss_relax_options *o, int nx, int ny, double dx,
                            double dy, const double *heights, const double *bedrock,
                            const double *angles, double *relaxed, char *report_json,
                            size_t report_size)
{
	struct ss_relax_options local = *o;
	if (!local.dem)
		local.dem = "(array)";
	if (angles && !local.model.angle_file)
		local.model.angle_file = "(array)";
	if (bedrock && !local.bedrock)
		local.bedrock = "(array)";
	if (!bedrock)
		local.bedrock = NULL;   /* a path would be read: arrays in, arrays out */
	local.read.cellsize = NAN;   /* it would override dx */
	if (nx < 1 || ny < 1)
		return ss_error_input("%s: %d x %d cells: expected at least one of each", local.dem,
		                      nx, ny);
	if (!(dx > 0.0 && isfinite(dx)))
		return ss_error_input("dx '%g': expected m > 0", dx);
	if (!(dy > 0.0 && isfinite(dy)))
		return ss_error_input("dy '%g': expected m > 0", dy);

	struct ss_raster in, rock, angle, out;
	memset(&rock, 0, sizeof rock);
	memset(&angle, 0, sizeof angle);
	memset(&out, 0, sizeof out);
	int err = raster_from(local.dem, "a finite height", nx, ny, dx, dy, heights, &in);
	if (!err && angles)   /* a path would be read: the array is the angles */
		err = raster_from(local.model.angle_file, "degrees in (0, 90)", nx, ny, dx, dy,
		                  angles, &angle);
	if (!err && bedrock) {
		err = raster_from(local.bedrock, "a finite height", nx, ny, dx, dy, bedrock, &rock);
		/* no bedrock under no data is fine (nothing moves there); under
		 * sand, NaN goes on to the stepper, which refuses it naming the cell */
		for (size_t m = 0; !err && m < (size_t)nx * ny; m++)
			if (rock.nodata && rock.nodata[m] && !(in.nodata && in.nodata[m]))
				rock.values[m] = NAN;
	}
	if (!err)
		err = ss_raster_init(&out, nx, ny);
	if (!err) {
		local.input_raster = &in;
		local.bedrock_raster = bedrock ? &rock : NULL;
		local.angle_raster = angles ? &angle : NULL;
		local.output_raster = &out;
		struct ss_relax_report rep;
		err = ss_relax_run(&local, &rep);
		if (!err && report_json)
			err = ss_relax_report_json(&rep, report_json, report_size);
	}
	if (!err)
		for (size_t m = 0; m < (size_t)nx * ny; m++)
			relaxed[m] = in.nodata && in.nodata[m] ? NAN : out.values[m];
	ss_raster_release(&out);
	ss_raster_release(&angle);
	ss_raster_release(&rock);
	ss_raster_release(&in);
	return err;
}

int ss_relax_file_json(const struct ss_relax_options *o, char *report_json, size_t report_size)
{
	struct ss_relax_report r;
	const int err = ss_relax_run(o, &r);
	return err ? err : ss_relax_report_json(&r, report_json, report_size);
}
