/*
 * series_render.c - `sandslide render`: the frames of a file, in time
 * order, and the video (render.h).
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

/* One integer of a frame range; empty gives `def`.  -1 if malformed. */
static int parse_index(const char *s, size_t len, long long def, long long *out)
{
	if (len == 0) {
		*out = def;
		return 0;
	}
	char buf[32], *end;
	if (len >= sizeof buf)
		return -1;
	memcpy(buf, s, len);
	buf[len] = '\0';
	errno = 0;
	*out = strtoll(buf, &end, 10);
	return *end || errno || end == buf ? -1 : 0;
}

/* The snapshots named by "A:B:STEP" (a Python slice without clamping:
 * negative counts from the end, B exclusive) or "A"; SS_ERR_INPUT if the
 * range leaves the series or is empty. */
static int select_range(const char *spec, long long count, long long **out, long long *n)
{
	const char *c1 = strchr(spec, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
	long long a, b, step = 1;
	int bad;
	if (!c1) {
		bad = parse_index(spec, strlen(spec), 0, &a) || strlen(spec) == 0;
		b = a < 0 ? a + count + 1 : a + 1;
	} else {
		bad = parse_index(spec, (size_t)(c1 - spec), 0, &a) ||
		      parse_index(c1 + 1, c2 ? (size_t)(c2 - c1 - 1) : strlen(c1 + 1), count, &b) ||
		      (c2 && (parse_index(c2 + 1, strlen(c2 + 1), 1, &step) || strchr(c2 + 1, ':')));
		if (!bad && b < 0)
			b += count;
	}
	if (bad || step < 1)
		return ss_error_input("--frames '%s': expected A:B:STEP (snapshots A, A+STEP, ... "
		                      "before B; negative counts from the end) or one index A", spec);
	if (a < 0)
		a += count;
	if (a < 0 || a >= count || b < 0 || b > count)
		return ss_error_input("--frames '%s' is outside the series: it has %lld snapshots, "
		                      "0 to %lld", spec, count, count - 1);
	if (b <= a)
		return ss_error_input("--frames '%s' selects no snapshot (the end %lld is not after "
		                      "the start %lld)", spec, b, a);
	*n = (b - a + step - 1) / step;
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

/* Frames go out in time order, whatever order the file has. */
struct timed {
	double t;
	long long k;
};

static int by_time(const void *pa, const void *pb)
{
	const struct timed *a = pa, *b = pb;
	if (a->t != b->t)
		return a->t < b->t ? -1 : 1;
	return a->k < b->k ? -1 : a->k > b->k;
}

static int sort_by_time(const struct ss_render_source *s, long long *sel, long long n)
{
	struct timed *v = malloc((size_t)n * sizeof *v);
	if (!v)
		return ss_error_fail("out of memory");
	for (long long k = 0; k < n; k++)
		v[k] = (struct timed){s->file.time[sel[k]], sel[k]};
	qsort(v, (size_t)n, sizeof *v, by_time);
	for (long long k = 0; k < n; k++)
		sel[k] = v[k].k;
	free(v);
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

/* Without force, nothing that exists is replaced: not the frames about
 * to be written (frame_00000.png .. of the n chosen) nor the video. */
static int check_not_there(const struct ss_render_series_options *o, long long n)
{
	if (o->force)
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

/* The chosen snapshots, in time order. */
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
	return err ? err : sort_by_time(s, *sel, *n);
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
			if (!err)
				err = e;
		}
	}
	return err;
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
	memset(report, 0, sizeof *report);
	int err = ss_render_options_check(&o->look);
	if (err)
		return err;
	if ((o->video || o->html) && (o->fps < 1 || o->fps > 240))
		return ss_error_input("--fps %d: expected 1 to 240 frames per second", o->fps);
	if (!o->output_dir && (o->video || !o->html))
		return ss_error_input("no folder for the frames: %s", o->video ? "--video needs one"
		                      : "give one, or --html to put the frames in a viewer");

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
	    (o->html && (err = ss_render_html_check_path(o->html, o->force))) ||
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
	if (o->output_dir && (err = ss_render_check_dir(o->output_dir, 1)))
		goto out_html;

	const double t0 = ss_parallel_wall_seconds();
	if ((err = render_frames(&plan, &s, sel, n, o->output_dir, html)))
		goto out_html;
	report->render_seconds = ss_parallel_wall_seconds() - t0;
	report_frames(o, &s, &plan, sel, n, report);
	if (html) {
		size_t bytes;
		if ((err = ss_render_html_write(html, o->html, o->fps, &bytes)))
			goto out_html;
		report->html_bytes = (long long)bytes;
	}
	report->seconds = ss_parallel_wall_seconds() - started;
	if (o->video)
		err = ss_render_video(o->output_dir, n, o->fps, o->video, &report->video);

out_html:
	ss_render_html_destroy(html);
out_plan:
	ss_render_plan_release(&plan);
out_source:
	free(sel);
	ss_render_source_close(&s);
	return err;
}
