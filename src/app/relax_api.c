/*
 * relax_api.c - `relax` for callers that cannot lay out its structs (see
 * relax.h): the report as JSON in a buffer, and a flat entry point on
 * arrays.  Python's ctypes module (python/sandslide) is the caller this is
 * written for: the struct layouts change between versions, names and
 * strings do not.  The options set by name are relax_options.c's.
 */
#include "sandslide/relax.h"

#include <math.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"
#include "sandslide/watch.h"

void ss_relax_options_set_watch(struct ss_relax_options *o, struct ss_watch *w)
{
	o->stop_signal = w ? ss_watch_stop_flag(w) : NULL;
	o->progress = w ? ss_watch_progress : NULL;
	o->progress_context = w;
}

int ss_relax_report_json(const struct ss_relax_options *o, const struct ss_relax_report *r,
                         char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	ss_strbuf_printf(&b, "{\n  \"input\": ");
	ss_strbuf_json_string(&b, o->dem ? o->dem : "");
	ss_strbuf_printf(&b, ",\n  \"output\": ");
	ss_strbuf_json_string(&b, r->output);
	ss_strbuf_printf(&b, ",\n  \"nx\": %d, \"ny\": %d, \"dx\": ", r->nx, r->ny);
	ss_strbuf_json_number(&b, r->dx, 17);
	ss_strbuf_printf(&b, ", \"dy\": ");
	ss_strbuf_json_number(&b, r->dy, 17);
	ss_strbuf_printf(&b, ",\n  \"closure\": \"%s\", \"repose_angle_deg\": ",
	                 ss_closure_name(o->model.closure));
	ss_strbuf_json_number(&b, o->model.angle_deg, 17);
	ss_strbuf_printf(&b, ", \"nu\": ");
	ss_strbuf_json_number(&b, o->model.nu, 17);
	ss_strbuf_printf(&b, ",\n  \"steady\": %s, \"end\": ", r->steady ? "true" : "false");
	ss_strbuf_json_string(&b, r->end ? r->end : "");
	ss_strbuf_printf(&b, ", \"tol\": ");
	ss_strbuf_json_number(&b, o->model.steady_tol, 17);
	ss_strbuf_printf(&b, ",\n  \"steps\": %lld, \"time\": ", r->steps);
	ss_strbuf_json_number(&b, r->time, 17);
	ss_strbuf_printf(&b, ", \"wall_seconds\": ");
	ss_strbuf_json_number(&b, r->wall_seconds, 6);
	ss_strbuf_printf(&b, ", \"read_seconds\": ");
	ss_strbuf_json_number(&b, r->read_seconds, 6);
	ss_strbuf_printf(&b, ", \"write_seconds\": ");
	ss_strbuf_json_number(&b, r->write_seconds, 6);
	ss_strbuf_printf(&b, ",\n  \"ranks\": %d, \"bytes_per_cell\": ", r->ranks);
	ss_strbuf_json_number(&b, r->bytes_per_cell, 17);
	ss_strbuf_printf(&b, ", \"memory_peak_bytes\": ");
	ss_strbuf_json_number(&b, r->memory_peak_bytes, 17);
	ss_strbuf_printf(&b, ",\n  \"integrator\": \"%s\", \"stencil_evaluations\": %lld, "
	                 "\"slope_tol\": ", r->integrator ? r->integrator : "", r->evaluations);
	ss_strbuf_json_number(&b, o->model.steady_slope_tol, 17);
	ss_strbuf_printf(&b, ",\n  \"cells_moved\": %lld, \"volume_moved\": ", r->cells_moved);
	ss_strbuf_json_number(&b, r->volume_moved, 17);
	ss_strbuf_printf(&b, ",\n  \"volume_before\": ");
	ss_strbuf_json_number(&b, r->volume_before, 17);
	ss_strbuf_printf(&b, ", \"volume_after\": ");
	ss_strbuf_json_number(&b, r->volume_after, 17);
	ss_strbuf_printf(&b, ",\n  \"inflow\": ");
	ss_strbuf_json_number(&b, r->inflow, 17);
	ss_strbuf_printf(&b, ", \"outflow\": ");
	ss_strbuf_json_number(&b, r->outflow, 17);
	ss_strbuf_printf(&b, ",\n  \"max_slope_before_deg\": ");
	ss_strbuf_json_number(&b, r->max_slope_before_deg, 17);
	ss_strbuf_printf(&b, ", \"max_slope_after_deg\": ");
	ss_strbuf_json_number(&b, r->max_slope_after_deg, 17);
	ss_strbuf_printf(&b, "\n}\n");
	if (b.len >= size)
		return ss_error_input("the relax report needs %zu bytes: the buffer has %zu",
		                      b.len + 1, size);
	return SS_OK;
}

/* nx x ny values into r (initialised here): NaN is no data (flagged, 0 as
 * rasters store it), an infinite value refused naming `what` and the cell. */
static int raster_from(const char *what, int nx, int ny, double dx, double dy,
                       const double *values, struct ss_raster *r)
{
	const size_t cells = (size_t)nx * (size_t)ny;
	int err = ss_raster_init(r, nx, ny);
	if (err)
		return err;
	r->cellsize = dx;
	r->cellsize_y = dy;
	for (size_t m = 0; m < cells; m++) {
		if (isinf(values[m]))
			return ss_error_input("%s: cell (%zu, %zu) (column from the west, row from the "
			                      "south) is %g: expected a finite height, or NaN for no "
			                      "data", what, m % (size_t)nx, m / (size_t)nx, values[m]);
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
	struct ss_relax_options local = *o;
	if (!local.dem)
		local.dem = "(array)";
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

	struct ss_raster in, rock, out;
	memset(&rock, 0, sizeof rock);
	memset(&out, 0, sizeof out);
	int err = raster_from(local.dem, nx, ny, dx, dy, heights, &in);
	if (!err && bedrock) {
		err = raster_from(local.bedrock, nx, ny, dx, dy, bedrock, &rock);
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
		local.output_raster = &out;
		struct ss_relax_report rep;
		err = ss_relax_run(&local, &rep);
		if (!err && report_json)
			err = ss_relax_report_json(&local, &rep, report_json, report_size);
	}
	if (!err)
		for (size_t m = 0; m < (size_t)nx * ny; m++)
			relaxed[m] = in.nodata && in.nodata[m] ? NAN : out.values[m];
	ss_raster_release(&out);
	ss_raster_release(&rock);
	ss_raster_release(&in);
	return err;
}

int ss_relax_file_json(const struct ss_relax_options *o, char *report_json, size_t report_size)
{
	struct ss_relax_report r;
	const int err = ss_relax_run(o, &r);
	return err ? err : ss_relax_report_json(o, &r, report_json, report_size);
}
