/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * print.c - what the commands print (see print.h).
 */
#include "cli/print.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

static void format_duration(double s, char *buf, size_t size)
{
	if (!isfinite(s) || s < 0)
		snprintf(buf, size, "?");
	else if (s < 60)
		snprintf(buf, size, "%.0fs", s);
	else if (s < 3600)
		snprintf(buf, size, "%dm%02ds", (int)(s / 60), (int)fmod(s, 60));
	else
		snprintf(buf, size, "%dh%02dm", (int)(s / 3600), (int)fmod(s / 60, 60));
}

/* The progress line of this process. */
static struct {
	double last_print;          /* wall seconds of the last line */
	int shown;                  /* a line is on the terminal */
} progress;

/* fit's line, at most four times a second. */
static void fit_progress(const struct ss_fit_progress *p)
{
	const double now = ss_parallel_wall_seconds();
	if (now - progress.last_print < 0.25)
		return;
	progress.last_print = now;
	progress.shown = 1;
	fprintf(stderr, "\r  fitting %s (%d of %d): %-11s %lld forward runs, best cost %.4g   ",
	        p->closure, p->closure_index + 1, p->closure_count, p->stage, p->runs,
	        p->best_cost);
	fflush(stderr);
}

void cli_print_progress(void *context, const struct ss_progress *p)
{
	(void)context;
	if (p->fit) {
		fit_progress(p->fit);
		return;
	}
	if (p->wall_seconds - progress.last_print < 0.5)
		return;
	progress.last_print = p->wall_seconds;
	progress.shown = 1;
	const double rate = (double)p->steps_here * p->cells / fmax(p->wall_seconds, 1e-9);
	char tail[64];
	if (isfinite(p->end)) {
		/* the remaining time at the pace of this process so far */
		const double done = p->time - p->time_start;
		char d[24];
		format_duration(done > 0.0 ? p->wall_seconds * (p->end - p->time) / done : NAN,
		                d, sizeof d);
		snprintf(tail, sizeof tail, "/ %.6g s  ETA %s", p->end, d);
	} else {
		snprintf(tail, sizeof tail, "s (steady below %.1e m/s)", p->steady_tol);
	}
	fprintf(stderr, "\r  t = %.6g %s  steps %lld  %.3g cells/s  max|dh/dt| %.2e m/s   ",
	        p->time, tail, p->steps, rate, p->rate_max);
	fflush(stderr);
}

void cli_progress_done(void)
{
	if (progress.shown)
		fputc('\n', stderr);
	progress.shown = 0;
}

void cli_print_run_plan(void *context, const struct ss_run_plan *p)
{
	(void)context;
	if (ss_comm_rank() != 0)
		return;
	char each[32], all[32], have[32] = "";
	ss_format_bytes(p->snapshot_bytes, each);
	if (p->free_bytes >= 0.0)
		snprintf(have, sizeof have, "%s", ss_format_bytes(p->free_bytes, all));
	if (isinf(p->snapshots))
		printf("writing %s: %s a snapshot%s, as many as the run takes to be steady; %s%s\n",
		       p->output, each, p->deflate ? " before deflate" : "", have,
		       *have ? " free" : "free space unknown");
	else
		printf("writing %s: %s%s (%.0f snapshot%s of %s%s); %s%s\n", p->output,
		       p->at_most ? "at most " : "", ss_format_bytes(p->bytes, all), p->snapshots,
		       p->snapshots == 1 ? "" : "s", each, p->deflate ? " before deflate" : "",
		       *have ? have : "free space unknown", *have ? " free" : "");
}

void cli_print_run_end(const struct ss_run_summary *s, int quiet)
{
	if (ss_comm_rank() != 0)
		return;
	if (s->end == SS_RUN_INTERRUPTED) {
		fflush(stdout);
		fprintf(stderr, "sandslide: interrupted at t = %g s (step %lld): snapshot %lld is "
		        "in '%s'; continue with\n    sandslide run --restart %s\n", s->time,
		        s->steps, s->snapshots - 1, s->output, s->output);
		return;
	}
	if (quiet)
		return;
	for (int k = 0; k < s->note_count; k++)
		printf("note: %s\n", s->notes[k]);
	printf("wrote %s: %lld snapshot%s to t = %g s, %lld %s%s\n", s->output, s->snapshots,
	       s->snapshots == 1 ? "" : "s", s->time, s->steps,
	       strcmp(s->integrator, "rkl2") ? "steps (euler)" : "super-steps (rkl2)",
	       s->end == SS_RUN_STEADY ? " (steady)"
	       : s->end == SS_RUN_NOT_STEADY ? " (not steady by max_time)" : "");
	/* with ranks: rank 0's phases, and its time in MPI calls */
	char ranks[48] = "", mpi[48] = "", peak[32];
	if (s->ranks > 1) {
		snprintf(ranks, sizeof ranks, "%d ranks x ", s->ranks);
		snprintf(mpi, sizeof mpi, ", mpi %.3f s", s->comm_seconds);
	}
	/* the rate counts the cells of the tiles swept, not those the fast
	 * sweep skipped as asleep: a large quiet grid would otherwise claim
	 * rates no memory system can feed (doc/running.md) */
	const double kernel = fmax(s->measure_seconds + s->sweep_seconds, 1e-9);
	printf("wall %.3f s: slope %.3f s, sweep %.3f s, output %.3f s%s; %lld stencil "
	       "evaluations, %.3g cell-updates/s (swept tiles only; %.3g counting every cell) "
	       "on %s%d thread%s; %.0f B per cell, peak %s%s\n",
	       s->wall_seconds, s->measure_seconds, s->sweep_seconds, s->output_seconds, mpi,
	       s->evaluations, s->cell_updates_here / kernel,
	       (double)s->evaluations_here * s->cells / kernel, ranks, s->threads,
	       s->threads == 1 ? "" : "s", s->bytes_per_cell,
	       ss_format_bytes(s->memory_peak_bytes, peak), s->ranks > 1 ? " a rank" : "");
}

void cli_print_relax_end(const struct ss_relax_report *r, int quiet)
{
	if (ss_comm_rank() != 0)
		return;
	if (r->interrupted) {
		fflush(stdout);
		fprintf(stderr, "sandslide: interrupted at t = %g s (step %lld): '%s' holds the "
		        "surface as it was then, not relaxed\n", r->time, r->steps, r->output);
	}
	if (quiet)
		return;
	char rest[64] = "";
	if (r->rest_steps > 0)
		snprintf(rest, sizeof rest, " and %lld super-steps to rest", r->rest_steps);
	printf("wrote %s: %d x %d cells, %s after %lld %s%s (t = %g s, %lld stencil "
	       "evaluations)\n", r->output, r->nx, r->ny, r->steady ? "steady"
	       : r->interrupted ? "NOT steady (interrupted)" : "NOT steady by --max-time",
	       r->steps - r->rest_steps,
	       strcmp(r->integrator, "rkl2") ? "steps (euler)" : "super-steps (rkl2)", rest,
	       r->time, r->evaluations);
	char ranks[48] = "", peak[32];
	if (r->ranks > 1)
		snprintf(ranks, sizeof ranks, "%d ranks x ", r->ranks);
	char repose[96];
	if (r->materials > 1)
		snprintf(repose, sizeof repose, "repose %g to %g in %d materials", r->repose_min_deg,
		         r->repose_max_deg, r->materials);
	else if (r->model.static_angle_deg > r->repose_min_deg)
		snprintf(repose, sizeof repose, "repose %g, static %g", r->repose_min_deg,
		         r->model.static_angle_deg);
	else
		snprintf(repose, sizeof repose, "repose %g", r->repose_min_deg);
	printf("cells moved %lld, volume moved %.6g m^3, steepest sand face %.4f -> "
	       "%.4f deg (%s), wall %.3f s on %s%d thread%s\n", r->cells_moved,
	       r->volume_moved, r->max_slope_before_deg, r->max_slope_after_deg, repose,
	       r->wall_seconds, ranks, ss_parallel_max_threads(),
	       ss_parallel_max_threads() == 1 ? "" : "s");
	printf("read %.3f s, write %.3f s; memory: %.0f B per cell, peak %s%s\n",
	       r->read_seconds, r->write_seconds, r->bytes_per_cell,
	       ss_format_bytes(r->memory_peak_bytes, peak), r->ranks > 1 ? " (the largest rank)" : "");
	/* sand poured, and sand that left through open sides or open nodata
	 * cells: what the volume change is made of */
	printf("volume %.9g -> %.9g m^3: poured %.6g m^3, left through open cells and "
	       "sides %.6g m^3\n", r->volume_before, r->volume_after, r->inflow, r->outflow);
	/* a pour partly on cells without data pours less than its area
	 * suggests: say how much landed where */
	if (r->pour_cells_nodata > 0)
		printf("note: --add-sand covers %lld cells, %lld of them without data: the %.6g m^3 "
		       "was poured on the other %lld, centres x %g .. %g, y %g .. %g\n",
		       r->pour_cells, r->pour_cells_nodata, r->inflow,
		       r->pour_cells - r->pour_cells_nodata, r->pour_extent[0], r->pour_extent[1],
		       r->pour_extent[2], r->pour_extent[3]);
}

void cli_bench_header(void *context, const struct ss_bench_header *h)
{
	const struct cli_bench *b = context;
	if (b->json) {
		printf("{\n  \"nx\": %d, \"ny\": %d, \"tile_nx\": %d, \"tile_ny\": %d,\n"
		       "  \"repeats\": %d, \"rsqrt\": \"%s\", \"angles\": %d,\n",
		       h->nx, h->ny, h->tile_nx, h->tile_ny, h->repeats, h->rsqrt, h->angles);
		if (h->device) {
			/* the GPU's name, and its bandwidth under "gpu" */
			char text[512];
			struct ss_strbuf json = {text, sizeof text, 0};
			ss_strbuf_json_string(&json, h->device);
			printf("  \"device\": %s,\n", text);
		}
		printf("  \"bandwidth_bytes_per_s\": {");
		for (int t = 0; t < h->thread_count; t++)
			if (h->device)
				printf("\"gpu\": %.6g", h->bandwidth[t]);
			else
				printf("%s\"%d\": %.6g", t ? ", " : "", h->threads[t], h->bandwidth[t]);
		printf("},\n  \"cases\": [");
	} else {
		char angles[64] = "";
		if (h->angles > 1)
			snprintf(angles, sizeof angles, ", %d repose angles (materials)", h->angles);
		printf("sandslide bench: %d x %d cells, tiles %dx%d, %d repeats per case, "
		       "reciprocal sqrt: %s%s\n", h->nx, h->ny, h->tile_nx, h->tile_ny, h->repeats,
		       h->rsqrt, angles);
		if (h->device) {
			printf("device %s\n", h->device);
			printf("memory bandwidth (device-to-device copy of %zu doubles): %.1f GB/s\n",
			       h->probe_doubles, h->bandwidth[0] * 1e-9);
		} else {
			printf("memory bandwidth (read+write one array of %zu doubles):", h->probe_doubles);
			for (int t = 0; t < h->thread_count; t++)
				printf(" %d thread%s %.1f GB/s%s", h->threads[t],
				       h->threads[t] > 1 ? "s" : "", h->bandwidth[t] * 1e-9,
				       t + 1 < h->thread_count ? "," : "\n");
		}
		if (h->note)
			printf("note: %s\n", h->note);
		printf("\n%-14s %-22s %7s  %-34s %6s %6s %6s %8s\n", "surface", "closure", "threads",
		       "cell-updates/s median [min, max]", "steps", "active", "B/cell", "roofline");
	}
	fflush(stdout);
}

void cli_bench_result(void *context, const struct ss_bench_result *r)
{
	struct cli_bench *b = context;
	const char *surface = ss_bench_surface_name(r->surface);
	if (b->json) {
		printf("%s\n    {\"surface\": \"%s\", \"closure\": \"%s\", \"threads\": %d, "
		       "\"cell_updates_per_s\": {\"median\": %.6g, \"min\": %.6g, \"max\": %.6g}, "
		       "\"steps_per_repeat\": %lld, \"active_fraction\": %.6g, "
		       "\"bytes_per_cell\": %.3g, \"roofline_cell_updates_per_s\": %.6g, "
		       "\"roofline_fraction\": %.6g}", b->rows ? "," : "", surface, r->closure,
		       r->threads, r->median, r->min, r->max, r->steps, r->active_fraction,
		       r->bytes_per_cell, r->roofline, r->median / r->roofline);
	} else {
		char range[64];
		snprintf(range, sizeof range, "%.3g [%.3g, %.3g]", r->median, r->min, r->max);
		char threads[16] = "gpu";
		if (r->threads > 0)
			snprintf(threads, sizeof threads, "%d", r->threads);
		printf("%-14s %-22s %7s  %-34s %6lld %6.3f %6.2f %8.3f\n", surface, r->closure,
		       threads, range, r->steps, r->active_fraction, r->bytes_per_cell,
		       r->median / r->roofline);
	}
	b->rows++;
	fflush(stdout);
}

void cli_bench_done(const struct cli_bench *b)
{
	if (b->json)
		printf("\n  ]\n}\n");
}

static void print_diag_row(const struct ss_snapshot_summary *s, long long k)
{
	const struct ss_diagnostics *d = &s->diag[k];
	printf("  %5lld %12.6g %13.6e %11.4e %11.4e %10.5g %9.4f %9.0f %7.3f %9.3f\n", k,
	       s->time[k], d->volume, d->inflow, d->outflow, d->max_height, d->max_slope_deg,
	       d->steps, d->active_fraction, d->wall_seconds);
}

/* The snapshots' diagnostics (first and last ten of more than twenty) and
 * the volume balance. */
static void print_series(const struct ss_snapshot_summary *s)
{
	printf("snapshots  %lld, t = %g .. %g s\n", s->count, s->time[0], s->time[s->count - 1]);
	printf("  %5s %12s %13s %11s %11s %10s %9s %9s %7s %9s\n", "index", "time_s",
	       "volume_m3", "inflow_m3", "outflow_m3", "max_h_m", "slope_deg", "steps",
	       "active", "wall_s");
	for (long long k = 0; k < s->count; k++) {
		if (s->count > 20 && k == 10) {
			printf("  %5s (%lld more)\n", "...", s->count - 20);
			k = s->count - 10;
		}
		print_diag_row(s, k);
	}
	const struct ss_diagnostics *first = &s->diag[0], *last = &s->diag[s->count - 1];
	const double balance = (last->volume - first->volume) - (last->inflow - last->outflow);
	const double scale = fmax(fmax(fabs(last->volume), fabs(first->volume)),
	                          fmax(last->inflow, last->outflow));
	printf("volume balance  (V_last - V_0) - (inflow - outflow) = %.3e m^3 "
	       "(%.2e relative)\n", balance, scale > 0 ? fabs(balance) / scale : 0.0);
}

void cli_print_info(const char *path, const struct ss_snapshot_summary *s)
{
	printf("file       %s (%s)\n", path, s->source);
	printf("title      %s\n", s->title);
	/* exact: %g would round a UTM northing of 5479330.25 m to 5.47933e+06 */
	printf("grid       %d x %d cells, dx = %s m, dy = %s m, lower-left corner (%s, %s) m\n",
	       s->nx, s->ny, SS_REAL(s->dx), SS_REAL(s->dy), SS_REAL(s->origin_x),
	       SS_REAL(s->origin_y));
	printf("cells      %lld flow, %lld wall, %lld open", s->flow_cells, s->wall_cells,
	       s->open_cells);
	if (s->nodata_cells > 0)
		printf(", %lld without data", s->nodata_cells);
	printf("\n");
	printf("model      %s, repose angle %g deg, nu = %g m^2/s", s->closure,
	       s->repose_angle_deg, s->nu);
	if (!strcmp(s->closure, "herschel-bulkley"))
		printf(", gamma = %g", s->gamma);
	printf("\n");
	if (s->integrator[0] && s->count > 0)
		printf("integrator %s: %.0f stencil evaluations in %.0f %s to the last snapshot\n",
		       s->integrator, s->diag[s->count - 1].evaluations, s->diag[s->count - 1].steps,
		       strcmp(s->integrator, "rkl2") ? "steps" : "super-steps");
	if (s->count == 0)
		printf("snapshots  none\n");
	else
		print_series(s);
}

void cli_print_render_bench(const struct ss_render_bench_report *r)
{
	const double mpx = (double)r->n * r->n * 1e-6;
	printf("shaded %d x %d (%.1f Mpixel), %d threads, %d repeats: median %.3f s = %.1f "
	       "Mpixel/s (min %.3f s, max %.3f s)\n", r->n, r->n, mpx, r->threads, r->repeats,
	       r->median, mpx / r->median, r->min, r->max);
	printf("ss_render_field (plan and scale included): %.3f s\n", r->field);
	for (int l = 0; l < 2; l++)
		printf("png encoding, zlib level %d (serial): %.3f s = %.1f Mpixel/s, %.1f MB\n",
		       r->png_levels[l], r->png[l], mpx / r->png[l], r->png_bytes[l] * 1e-6);
}

void cli_print_render_series(const struct ss_render_series_options *o,
                             const struct ss_render_series_report *r, int quiet)
{
	const size_t len = o->output_dir ? strlen(o->output_dir) : 0;
	const double seconds = fmax(r->render_seconds, 1e-9);
	if (!quiet && o->output_dir) {
		printf("wrote %lld frame%s of %d x %d px to %s%s (t = %g .. %g s, %s, heights %g .. "
		       "%g m) in %.2f s: %.1f frames/s, %.1f Mpixel/s on %d thread%s\n", r->frames,
		       r->frames == 1 ? "" : "s", r->width, r->height, o->output_dir,
		       len && o->output_dir[len - 1] == '/' ? "" : "/", r->t_first, r->t_last,
		       ss_render_style_name(o->look.style), r->zmin, r->zmax, r->seconds,
		       r->frames / seconds, (double)r->frames * r->width * r->height / seconds * 1e-6,
		       r->threads, r->threads == 1 ? "" : "s");
		if (r->stale[0])
			printf("note: %s and maybe later frames are left from an earlier render; they "
			       "are not part of this series\n", r->stale);
	}
	if (r->video == SS_RENDER_VIDEO_NO_FFMPEG) {
		fflush(stdout);
		fprintf(stderr, "sandslide: ffmpeg is not on PATH, so no video was made; the %lld "
		        "frames are kept in '%s' (Debian: apt-get install ffmpeg)\n", r->frames,
		        o->output_dir);
	} else if (r->video == SS_RENDER_VIDEO_MADE && !quiet) {
		printf("wrote %s: %lld frames at %d frames/s\n", o->video, r->frames, r->fps);
	}
	if (r->html_bytes && !quiet) {
		const double b = (double)r->html_bytes;
		printf("wrote %s: %lld frame%s of %d x %d px, ", o->html, r->frames,
		       r->frames == 1 ? "" : "s", r->width, r->height);
		printf(b < 1e6 ? "%.0f kB\n" : "%.1f MB\n", b < 1e6 ? b * 1e-3 : b * 1e-6);
	}
}
