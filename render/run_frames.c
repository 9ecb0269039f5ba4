/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * run_frames.c - frames of a run as it writes its snapshots (`sandslide run
 * --frames DIR`, render.h).
 *
 * Each snapshot is read back from the output file the run has just
 * flushed: the renderer depends on the file format of doc/output.md only,
 * never on the stepper's arrays.  (HDF5 shares one open file within a
 * process, so this sees exactly what the writer wrote.)
 *
 * A series needs one height scale before its last snapshot exists.  The
 * maximum principle of the model bounds it: no height goes below the
 * lowest of the initial surface and the open level, or above the highest
 * of them plus what the sources can add to one cell over the whole run.
 * The bound can be loose (sand that flows away never piles that high);
 * --zmin/--zmax, or `sandslide render` afterwards, give a tighter scale.
 */
#include "internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sandslide/error.h"

struct ss_render_frames {
	char *dir;
	struct ss_render_options look;
	int dir_made;
	long long count;            /* frames written */
	int planned;                /* plan holds the series' scale */
	struct ss_render_plan plan;
};

int ss_render_frames_create(struct ss_render_frames **out, const char *dir,
                            const struct ss_render_options *look)
{
	*out = NULL;
	int err = ss_render_options_check(look);
	if (err || (err = ss_render_check_dir(dir, 0)))
		return err;
	struct ss_render_frames *fr = calloc(1, sizeof *fr);
	if (!fr || !(fr->dir = strdup(dir))) {
		free(fr);
		return ss_error_fail("out of memory");
	}
	fr->look = *look;
	*out = fr;
	return SS_OK;
}

void ss_render_frames_destroy(struct ss_render_frames *fr)
{
	if (!fr)
		return;
	if (fr->planned)
		ss_render_plan_release(&fr->plan);
	free(fr->dir);
	free(fr);
}

long long ss_render_frames_count(const struct ss_render_frames *fr)
{
	return fr->count;
}

/* The scale of the series from snapshot `index` (the first) and the bounds. */
static int series_scale(struct ss_render_frames *fr, struct ss_render_source *s,
                        long long index, const struct ss_render_frames_bounds *b,
                        double *zmin, double *zmax)
{
	double lo, hi;
	int err = ss_render_source_range(s, index, index, &lo, &hi);
	if (err)
		return err;
	if (b->any_open_side) {
		lo = fmin(lo, b->open_level);
		hi = fmax(hi, b->open_level);
	}
	if (lo <= hi && isfinite(b->source_rise))
		hi += b->source_rise;
	*zmin = fr->look.zmin;
	*zmax = fr->look.zmax;
	return ss_render_scale_resolve(zmin, zmax, lo, hi, "the run");
}

int ss_render_frames_add(struct ss_render_frames *fr, const char *path, long long index,
                         const struct ss_render_frames_bounds *bounds)
{
	struct ss_render_source s;
	int err = ss_render_source_open(&s, path);
	if (err)
		return err;
	if (index < 0 || index >= s.file.count) {
		err = ss_error_fail("'%s' has no snapshot %lld to render", path, index);
		goto out_source;
	}
	if (!fr->dir_made) {
		if ((err = ss_render_check_dir(fr->dir, 1)))
			goto out_source;
		fr->dir_made = 1;
	}
	/* without a bound (a source that never stops) each frame gets its own scale */
	const int fixed = isfinite(bounds->source_rise) ||
	                  (!isnan(fr->look.zmin) && !isnan(fr->look.zmax));
	if (!fr->planned || !fixed) {
		double zmin, zmax;
		if (fr->planned)
			ss_render_plan_release(&fr->plan);
		fr->planned = 0;
		if ((err = series_scale(fr, &s, index, bounds, &zmin, &zmax)) ||
		    (err = ss_render_plan_init(&fr->plan, &fr->look, s.file.nx, s.file.ny, s.file.dx,
		                               s.file.dy, s.cell_type, s.file.nx, s.file.wall_sides,
		                               zmin, zmax, 1)))
			goto out_source;
		fr->planned = 1;
	}
	char frame[4200];
	ss_render_frame_path(fr->dir, fr->count, frame, sizeof frame);
	if (!(err = ss_render_plan_snapshot(&fr->plan, &s, index, frame, 1)))
		fr->count++;
out_source:
	ss_render_source_close(&s);
	return err;
}
