/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * command.c - `sandslide render`: the chosen snapshots of a file as
 * frames (all of them in time order, or a Python slice of them in its
 * order), a video of them and a viewer (render.h).
 *
 * Everything that can be checked is checked before the first frame is
 * written: the file, the frame selection, the output folder, the video's
 * folder, the viewer's file (html.c) and the height scale.  The scale is
 * the whole file's lowest and highest height on flow and open cells unless
 * --zmin/--zmax give it, so colours mean the same heights in every frame.
 * Each frame is rendered once: its PNG bytes go to the folder, the viewer
 * (--html) or both.
 *
 * Parallel work: a series of frames small enough to hold one per thread
 * goes frame by frame to the threads (encoding a PNG is serial, so this is
 * what keeps both cores busy); larger frames are rendered one at a time
 * with their rows split between the threads.  The pictures are the same
 * bits either way.
 */
#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sandslide/error.h"
#include "sandslide/parallel.h"

/* Frames up to this size are rendered one per thread. */
#define FRAME_PARALLEL_MAX_PIXELS (16ll << 20)

/* One integer of a frame range into *out, *given 0 when it is empty;
 * -1 if malformed. */
static int parse_index(const char *s, size_t len, long long *out, int *given)
{
	*given = len > 0;
	*out = 0;
	if (len == 0)
		return 0;
	char buf[32], *end;
	if (len >= sizeof buf)
		return -1;
	memcpy(buf, s, len);
	buf[len] = '\0';
	errno = 0;
	*out = strtoll(buf, &end, 10);
	return *end || errno || end == buf ? -1 : 0;
}

/* A bound of a slice as Python's slice.indices() takes it: negative
 * counts from the end, then clamped to [lo, hi]. */
static long long slice_bound(long long v, long long count, long long lo, long long hi)
{
	if (v < 0)
		v = v < -count ? lo : v + count;   /* no overflow for any v */
	return v < lo ? lo : v > hi ? hi : v;
}

/*
 * The snapshots named by "A", one index (negative counts from the end; it
 * must be in the series), or by "A:B:STEP", a Python slice of the count
 * snapshots: A, A+STEP, ... up to B exclusive, each part optional, bounds
 * counted from the end when negative and clamped to the series, a negative
 * STEP going backwards (from the last snapshot by default, so "::-1" is
 * every snapshot in reverse), STEP 0 refused.  In that order; SS_ERR_INPUT
 * if the selection is empty.
 */
static int select_range(const char *spec, long long count, long long **out, long long *n)
{
	const char *c1 = strchr(spec, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
	long long a, b, step = 1;
	int has_a, has_b, has_step = 0, bad;
	if (!c1) {
		bad = parse_index(spec, strlen(spec), &a, &has_a) || !has_a;
		if (!bad && (a < -count || a >= count))
			return ss_error_input("--frames '%s' is outside the series: it has %lld snapshots, "
			                      "0 to %lld (or -%lld to -1 from the end)", spec, count,
			                      count - 1, count);
		a = a < 0 ? a + count : a;
		b = a + 1;
	} else {
		bad = parse_index(spec, (size_t)(c1 - spec), &a, &has_a) ||
		      parse_index(c1 + 1, c2 ? (size_t)(c2 - c1 - 1) : strlen(c1 + 1), &b, &has_b) ||
		      (c2 && (strchr(c2 + 1, ':') ||
		              parse_index(c2 + 1, strlen(c2 + 1), &step, &has_step)));
		step = has_step ? step : 1;
		if (!bad && step == 0)
			return ss_error_input("--frames '%s': STEP is 0; expected a step of 1 or more, or "
			                      "-1 or less to go backwards", spec);
		if (!bad && step > 0) {
			a = has_a ? slice_bound(a, count, 0, count) : 0;
			b = has_b ? slice_bound(b, count, 0, count) : count;
		} else if (!bad) {
			a = has_a ? slice_bound(a, count, -1, count - 1) : count - 1;
			b = has_b ? slice_bound(b, count, -1, count - 1) : -1;
		}
	}
	if (bad)
		return ss_error_input("--frames '%s': expected A:B:STEP, a Python slice (snapshots "
		                      "A, A+STEP, ... before B; negative counts from the end; parts "
		                      "may be left out) or one index A", spec);
	/* a step longer than the series takes one snapshot however long it is:
	 * bounded, so that nothing below overflows */
	step = step > count ? count : step < -count ? -count : step;
	/* the count of range(a, b, step) */
	*n = step > 0 ? (b > a ? (b - a - 1) / step + 1 : 0)
	              : (a > b ? (a - b - 1) / -step + 1 : 0);
	if (*n == 0)
		return ss_error_input("--frames '%s' selects no snapshot of the %lld (0 to %lld): "
		                      "the slice is empty", spec, count, count - 1);
	*out = malloc((size_t)*n * sizeof **out);
	if (!*out)
		return ss_error_fail("out of memory");
	for (long long k = 0; k < *n; k++)
		(*out)[k] = a + k * step;
	return SS_OK;
}

/* The snapshot nearest time t; SS_ERR_INPUT outside the series' times. */
static int select_time(const struct ss_render_source *s, double t, long long **out,
                       long long *n)
{
	double lo = INFINITY, hi = -INFINITY;
	long long best = 0;
	for (long long k = 0; k < s->file.count; k++) {
		lo = fmin(lo, s->file.time[k]);
		hi = fmax(hi, s->file.time[k]);
		if (fabs(s->file.time[k] - t) < fabs(s->file.time[best] - t))
			best = k;
	}
	if (!(t >= lo && t <= hi))
		return ss_error_input("--time %g is outside the series: its snapshots run from "
		                      "t = %g to %g s", t, lo, hi);
	*out = malloc(sizeof **out);
	if (!*out)
		return ss_error_fail("out of memory");
	(*out)[0] = best;
	*n = 1;
	return SS_OK;
}

/* The folder part of a path ("." if none). */
static void parent_of(const char *path, char *out, size_t size)
{
	size_t n = strlen(path);
	while (n > 1 && path[n - 1] == '/')   /* "frames/" is the folder "frames" */
		n--;
	const char *slash = NULL;
	for (size_t k = 0; k < n; k++)
		if (path[k] == '/')
			slash = path + k;
	if (!slash)
		snprintf(out, size, ".");
	else
		snprintf(out, size, "%.*s", (int)(slash - path) + (slash == path), path);
}

int ss_render_check_dir(const char *dir, int create)
{
	struct stat sb;
	if (stat(dir, &sb) == 0) {
		if (!S_ISDIR(sb.st_mode))
			return ss_error_input("cannot write frames to '%s': it is not a folder", dir);
		if (access(dir, W_OK | X_OK) != 0)
			return ss_error_input("cannot write frames to '%s': the folder is not writable",
			                      dir);
		return SS_OK;
	}
	char parent[4096];
	parent_of(dir, parent, sizeof parent);
	if (stat(parent, &sb) != 0 || !S_ISDIR(sb.st_mode))
		return ss_error_input("cannot create the frame folder '%s': folder '%s' does not "
		                      "exist", dir, parent);
	if (access(parent, W_OK | X_OK) != 0)
		return ss_error_input("cannot create the frame folder '%s': folder '%s' is not "
		                      "writable", dir, parent);
	if (create && mkdir(dir, 0777) != 0 && errno != EEXIST)
		return ss_error_input("cannot create the frame folder '%s': %s", dir, strerror(errno));
	return SS_OK;
}

static int check_video_path(const char *video)
{
	char parent[4096];
	struct stat sb;
	parent_of(video, parent, sizeof parent);
	if (stat(parent, &sb) != 0 || !S_ISDIR(sb.st_mode))
		return ss_error_input("cannot write the video '%s': folder '%s' does not exist",
		                      video, parent);
	if (access(parent, W_OK | X_OK) != 0)
		return ss_error_input("cannot write the video '%s': folder '%s' is not writable",
		                      video, parent);
	if (stat(video, &sb) == 0 && S_ISDIR(sb.st_mode))
		return ss_error_input("cannot write the video '%s': it is a folder", video);
	return SS_OK;
}

/*
 * The frames of a video that no -o keeps: a folder made for them beside
 * the video (its folder is writable, which was checked; /tmp may be a
 * small tmpfs), hidden and unique, removed with them once the video is
 * made or has failed.
 */
static int make_frame_folder(const char *video, char *dir, size_t size)
{
	char parent[4096];
	parent_of(video, parent, sizeof parent);
	snprintf(dir, size, "%s/.sandslide-frames-XXXXXX", parent);
	if (!mkdtemp(dir))
		return ss_error_fail("cannot make a folder for the frames of the video '%s' in "
		                     "'%s': %s", video, parent, strerror(errno));
	return SS_OK;
}

/* Remove the frames 0 .. n - 1 in dir and dir itself.  Best effort: the
 * video is made (or its failure reported) by then, and a folder that
 * will not go away is left, hidden, rather than turned into a failure. */
static void remove_frame_folder(const char *dir, long long n)
{
	char path[4200];
	for (long long k = 0; k < n; k++) {
		ss_render_frame_path(dir, k, path, sizeof path);
		remove(path);
	}
	rmdir(dir);
}

/* Without force, nothing that exists is replaced: not the frames about
 * to be written (frame_00000.png .. of the n chosen) nor the video. */
static int check_not_there(const struct ss_render_series_options *o, long long n)
{
	if (o->job.force)
		return SS_OK;
	long long first = -1, there = 0;
	char path[4200];
	for (long long k = 0; o->output_dir && k < n; k++) {
		ss_render_frame_path(o->output_dir, k, path, sizeof path);
		if (access(path, F_OK) == 0) {
			there++;
			first = first < 0 ? k : first;
		}
	}
	if (there)
		ss_render_frame_path(o->output_dir, first, path, sizeof path);
	if (there == 1)
		return ss_error_input("'%s' exists: give --force to replace it, or -o another "
		                      "folder", path);
	if (there)
		return ss_error_input("'%s' exists, and %lld more of the %lld frames to write: give "
		                      "--force to replace them, or -o another folder", path,
		                      there - 1, n);
	if (o->video && access(o->video, F_OK) == 0)
		return ss_error_input("'%s' exists: give --force to replace it", o->video);
	return SS_OK;
}

/* The chosen snapshots, in the order they are drawn: --frames', else all
 * in the file's order, which is time order (a series' times increase). */
static int select_frames(const struct ss_render_series_options *o,
                         const struct ss_render_source *s, long long **sel, long long *n)
{
	int err;
	if (o->frames && !isnan(o->time))
		return ss_error_input("--frames and --time choose snapshots in two ways: give one");
	if (o->frames)
		err = select_range(o->frames, s->file.count, sel, n);
	else if (!isnan(o->time))
		err = select_time(s, o->time, sel, n);
	else
		err = select_range("0:", s->file.count, sel, n);
	return err;
}

/* One frame: its PNG to the folder (dir, or NULL) and to the viewer (html,
 * or NULL). */
static int render_one(const struct ss_render_plan *p, struct ss_render_source *s, long long k,
                      long long t, const char *dir, struct ss_render_html *html, int parallel)
{
	double *pixel_h = NULL;
	if (html && ss_render_html_wants_pixels(html)) {
		pixel_h = ss_alloc((size_t)p->rs.width * (size_t)p->rs.height, sizeof *pixel_h,
		                   "pixel heights");
		if (!pixel_h)
			return SS_ERR_FAIL;
	}
	struct ss_render_image img;
	unsigned char *png = NULL;
	size_t size = 0;
	int err = ss_render_plan_image(p, s, t, &img, pixel_h, parallel);
	if (!err)
		err = ss_render_encode_png(&img, p->look.compression, &png, &size);
	ss_render_image_release(&img);
	if (!err && dir) {
		char path[4200];
		ss_render_frame_path(dir, k, path, sizeof path);
		err = ss_render_write_file(path, png, size);
	}
	if (!err && html) {
		err = ss_render_html_add(html, k, t, png, size, pixel_h);
		png = NULL;   /* the viewer's now */
	}
	free(png);
	ss_free(pixel_h);
	return err;
}

/* Render the frames; the first failure stops the others. */
static int render_frames(const struct ss_render_plan *p, struct ss_render_source *s,
                         const long long *sel, long long n, const char *dir,
                         struct ss_render_html *html)
{
	const int by_frames = n > 1 && ss_parallel_max_threads() > 1 &&
	                      (long long)p->image_w * p->image_h <= FRAME_PARALLEL_MAX_PIXELS;
	int err = SS_OK;
	/* the first failure's message: reported in the thread that rendered
	 * the frame, whose last message it is (error.h), and handed to this
	 * one (shared by the region's threads, written under the critical) */
	char first[SS_ERROR_MESSAGE_MAX] = "";

	#pragma omp parallel for schedule(dynamic, 1) if(by_frames)
	for (long long k = 0; k < n; k++) {
		int failed;
		#pragma omp atomic read
		failed = err;
		if (failed)
			continue;
		const int e = render_one(p, s, k, sel[k], dir, html, !by_frames);
		if (e) {
			#pragma omp critical(ss_render_first_error)
			if (!err) {
				err = e;
				snprintf(first, sizeof first, "%s", ss_error_last_message());
			}
		}
	}
	return err ? ss_error_adopt(err, first) : SS_OK;
}

/* The height scale: the options', else the whole file's lowest and
 * highest sand. */
static int series_scale(const struct ss_render_series_options *o, struct ss_render_source *s,
                        double *zmin, double *zmax)
{
	*zmin = o->look.zmin;
	*zmax = o->look.zmax;
	if (!isnan(*zmin) && !isnan(*zmax))
		return SS_OK;
	double lo, hi;
	char what[4200];
	snprintf(what, sizeof what, "'%s'", o->input);
	const int err = ss_render_source_range(s, 0, s->file.count - 1, &lo, &hi);
	return err ? err : ss_render_scale_resolve(zmin, zmax, lo, hi, what);
}

/* What the frames were, for the report. */
static void report_frames(const struct ss_render_series_options *o,
                          const struct ss_render_source *s, const struct ss_render_plan *p,
                          const long long *sel, long long n,
                          struct ss_render_series_report *r)
{
	r->frames = n;
	r->width = p->image_w;
	r->height = p->image_h;
	r->t_first = s->file.time[sel[0]];
	r->t_last = s->file.time[sel[n - 1]];
	r->zmin = p->zmin;
	r->zmax = p->zmax;
	r->threads = ss_parallel_max_threads();
	r->stale[0] = '\0';
	if (o->output_dir) {
		ss_render_frame_path(o->output_dir, n, r->stale, sizeof r->stale);
		if (access(r->stale, F_OK) != 0)
			r->stale[0] = '\0';
	}
}

int ss_render_series(const struct ss_render_series_options *o,
                     struct ss_render_series_report *report)
{
	const double started = ss_parallel_wall_seconds();
	char tmp_dir[4200] = "";    /* the frames of a video alone */
	memset(report, 0, sizeof *report);
	int err = ss_render_options_check(&o->look);
	if (err)
		return err;
	if ((o->video || o->html) && (o->fps < 0 || o->fps > 240))
		return ss_error_input("--fps %d: expected 1 to 240 frames per second", o->fps);
	if (!o->output_dir && !o->video && !o->html)
		return ss_error_input("no folder for the frames: give one, or --html to put the "
		                      "frames in a viewer, or --video to make a video of them");
	/* a video alone keeps no frames: without ffmpeg there would be nothing */
	if (o->video && !o->output_dir && !ss_render_ffmpeg_found())
		return ss_error_input("cannot make the video '%s': ffmpeg is not on PATH (Debian: "
		                      "apt-get install ffmpeg); give -o DIR to keep the frames "
		                      "instead", o->video);

	struct ss_render_source s;
	if ((err = ss_render_source_open(&s, o->input)))
		return err;
	long long *sel = NULL, n = 0;
	double zmin, zmax;
	if (s.file.count == 0) {
		err = ss_error_input("'%s' holds no snapshots: nothing to render", o->input);
		goto out_source;
	}
	if ((err = select_frames(o, &s, &sel, &n)) ||
	    (o->output_dir && (err = ss_render_check_dir(o->output_dir, 0))) ||
	    (o->video && (err = check_video_path(o->video))) || (err = check_not_there(o, n)) ||
	    (o->html && (err = ss_render_html_check_path(o->html, o->job.force))) ||
	    (err = series_scale(o, &s, &zmin, &zmax)))
		goto out_source;
	struct ss_render_plan plan;
	if ((err = ss_render_plan_init(&plan, &o->look, s.file.nx, s.file.ny, s.file.dx, s.file.dy,
	                               s.cell_type, s.file.nx, s.file.wall_sides, zmin, zmax, 1)))
		goto out_source;
	struct ss_render_html *html = NULL;
	if (o->html && (err = ss_render_html_create(&html, &plan, &s, sel, n,
	                                            !isnan(o->look.zmin) || !isnan(o->look.zmax))))
		goto out_plan;
	/* the frames' folder: -o's, or for a video alone a temporary one */
	const char *dir = o->output_dir;
	if (o->output_dir && (err = ss_render_check_dir(o->output_dir, 1)))
		goto out_html;
	if (!dir && o->video) {
		if ((err = make_frame_folder(o->video, tmp_dir, sizeof tmp_dir)))
			goto out_html;
		dir = tmp_dir;
	}

	const double t0 = ss_parallel_wall_seconds();
	if ((err = render_frames(&plan, &s, sel, n, dir, html)))
		goto out_html;
	report->render_seconds = ss_parallel_wall_seconds() - t0;
	report_frames(o, &s, &plan, sel, n, report);
	report->fps = o->fps ? o->fps : ss_render_fps_for(n);
	if (html) {
		size_t bytes;
		if ((err = ss_render_html_write(html, o->html, report->fps, &bytes)))
			goto out_html;
		report->html_bytes = (long long)bytes;
	}
	report->seconds = ss_parallel_wall_seconds() - started;
	if (o->video)
		err = ss_render_video(dir, n, report->fps, o->video, &report->video);

out_html:
	if (tmp_dir[0])
		remove_frame_folder(tmp_dir, n);
	ss_render_html_destroy(html);
out_plan:
	ss_render_plan_release(&plan);
out_source:
	free(sel);
	ss_render_source_close(&s);
	return err;
}
