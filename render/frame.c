/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * frame.c - one frame: its pixel heights, read from a snapshot of a
 * source (a block of rows at a time through the resampler, or whole when
 * the picture has a pixel per cell or enlarges the grid) or taken from a
 * field in memory (ss_render_field), drawn with a plan (plan.c) and, for
 * a file, encoded as PNG; the frames' file names.
 */
#include "internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"

/* Accumulators of the resampled heights: two arrays of the pixels. */
static int alloc_accumulators(const struct ss_render_plan *p, double **hw, double **w)
{
	const size_t n = (size_t)p->rs.width * (size_t)p->rs.height;
	*hw = ss_alloc(n, sizeof **hw, "resampled heights");
	*w = *hw ? ss_alloc(n, sizeof **w, "resampling weights") : NULL;
	if (!*w) {
		ss_free(*hw);
		*hw = NULL;
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

/* The heights of a frame: the pixels' (h, stride) and, on an enlarged
 * grid, the gradients; what holds them is freed by frame_release. */
struct frame_heights {
	const double *h;
	ptrdiff_t stride;
	double *buf, *acc_w, *cells;
	float *gx, *gy;
};

static void frame_release(struct frame_heights *f)
{
	ss_free(f->buf);
	ss_free(f->acc_w);
	ss_free(f->cells);
	ss_free(f->gx);
	ss_free(f->gy);
	memset(f, 0, sizeof *f);
}

/* The whole of snapshot t, south row first, into *out (nx * ny). */
static int read_snapshot(struct ss_render_source *s, long long t, double **out)
{
	struct ss_snapshot_file *f = &s->file;
	const int block = ss_snapshot_file_block_rows(f);
	*out = ss_alloc((size_t)f->nx * (size_t)f->ny, sizeof **out, "snapshot heights");
	if (!*out)
		return SS_ERR_FAIL;
	for (int j0 = 0; j0 < f->ny; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		int err = ss_snapshot_file_read_rows(f, t, j0, rows, *out + (size_t)j0 * f->nx);
		if (err)
			return err;
	}
	return SS_OK;
}

/* The pixel heights of snapshot t: one pixel per cell reads the snapshot
 * as it is (rows flipped by a negative stride, no copy); an enlarged grid
 * is read whole (it is smaller than the picture) for its gradients;
 * otherwise the cells stream through the resampler a block of rows at a
 * time, so a 16384^2 snapshot never needs to be in memory at once. */
static int snapshot_heights(const struct ss_render_plan *p, struct ss_render_source *s,
                            long long t, struct frame_heights *fh, int parallel)
{
	struct ss_snapshot_file *f = &s->file;
	memset(fh, 0, sizeof *fh);
	int err;
	if (ss_render_resampler_is_identity(&p->rs)) {
		if ((err = read_snapshot(s, t, &fh->buf)))
			return err;
		fh->h = fh->buf + (size_t)(f->ny - 1) * f->nx;
		fh->stride = -(ptrdiff_t)f->nx;
		return SS_OK;
	}
	if (alloc_accumulators(p, &fh->buf, &fh->acc_w))
		return SS_ERR_FAIL;
	fh->h = fh->buf;
	fh->stride = p->rs.width;
	if (ss_render_plan_enlarges(p)) {
		if ((err = read_snapshot(s, t, &fh->cells)))
			return err;
		ss_render_resample_rows(&p->rs, fh->cells, f->nx, s->cell_type, f->nx, 0, f->ny,
		                        fh->buf, fh->acc_w, parallel);
		ss_render_resample_finish(&p->rs, fh->buf, fh->acc_w, parallel);
		return ss_render_plan_gradients(p, fh->cells, f->nx, s->cell_type, f->nx, &fh->gx,
		                                &fh->gy, parallel);
	}
	const int block = ss_snapshot_file_block_rows(f);
	double *rows_buf = ss_alloc((size_t)block * (size_t)f->nx, sizeof *rows_buf, "height rows");
	if (!rows_buf)
		return SS_ERR_FAIL;
	err = SS_OK;
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		if (!(err = ss_snapshot_file_read_rows(f, t, j0, rows, rows_buf)))
			ss_render_resample_rows(&p->rs, rows_buf, f->nx, s->cell_type, f->nx, j0, rows,
			                        fh->buf, fh->acc_w, parallel);
	}
	ss_free(rows_buf);
	if (!err)
		ss_render_resample_finish(&p->rs, fh->buf, fh->acc_w, parallel);
	return err;
}

int ss_render_plan_image(const struct ss_render_plan *p, struct ss_render_source *s,
                         long long t, struct ss_render_image *img, double *pixel_h,
                         int parallel)
{
	struct frame_heights fh;
	memset(img, 0, sizeof *img);
	int err = snapshot_heights(p, s, t, &fh, parallel);
	if (!err)
		err = ss_render_plan_draw(p, fh.h, fh.stride, fh.gx, fh.gy, s->file.time[t], img,
		                          parallel);
	if (!err) {
		img->snapshot = t;
		snprintf(img->source, sizeof img->source, "%s", s->file.name);
		if (p->look.style != SS_RENDER_OBLIQUE) {   /* the map's lower-left corner */
			img->x0 = s->file.origin_x - p->border[SS_WEST] * p->rs.px_dx;
			img->y0 = s->file.origin_y - p->border[SS_SOUTH] * p->rs.px_dy;
		}
		if (pixel_h)
			for (int y = 0; y < p->rs.height; y++)
				memcpy(pixel_h + (size_t)y * p->rs.width, fh.h + (ptrdiff_t)y * fh.stride,
				       (size_t)p->rs.width * sizeof *pixel_h);
	}
	frame_release(&fh);
	return err;
}

int ss_render_plan_snapshot(const struct ss_render_plan *p, struct ss_render_source *s,
                            long long t, const char *path, int parallel)
{
	struct ss_render_image img;
	int err = ss_render_plan_image(p, s, t, &img, NULL, parallel);
	if (!err)
		err = ss_render_write_png(&img, path, p->look.compression);
	ss_render_image_release(&img);
	return err;
}

/* Range of the finite heights on flow and open cells of a field. */
static void field_range(const struct ss_render_field *f, double *lo, double *hi)
{
	double a = INFINITY, b = -INFINITY;
	#pragma omp parallel for schedule(static) reduction(min:a) reduction(max:b)
	for (int j = 0; j < f->ny; j++)
		for (int i = 0; i < f->nx; i++) {
			const ptrdiff_t k = (ptrdiff_t)j * f->stride + i;
			const double v = f->height[k];
			if ((!f->cell_type || !ss_render_no_sand(ss_render_type_of(f->cell_type[k]))) &&
			    isfinite(v)) {
				a = v < a ? v : a;
				b = v > b ? v : b;
			}
		}
	*lo = a;
	*hi = b;
}

int ss_render_field(const struct ss_render_field *f, const struct ss_render_options *o,
                    struct ss_render_image *img)
{
	memset(img, 0, sizeof *img);
	int err = ss_render_options_check(o);
	if (err)
		return err;
	if (f->nx < 1 || f->ny < 1 || f->stride < f->nx || !(f->dx > 0.0) || !(f->dy > 0.0))
		return ss_error_input("cannot render a field of %d x %d cells (stride %td, "
		                      "dx %s, dy %s)", f->nx, f->ny, f->stride, SS_REAL(f->dx),
		                      SS_REAL(f->dy));
	double zmin = o->zmin, zmax = o->zmax;
	if (isnan(zmin) || isnan(zmax)) {
		double lo, hi;
		field_range(f, &lo, &hi);
		if ((err = ss_render_scale_resolve(&zmin, &zmax, lo, hi, "the field")))
			return err;
	}
	struct ss_render_plan p;
	if ((err = ss_render_plan_init(&p, o, f->nx, f->ny, f->dx, f->dy, f->cell_type, f->stride,
	                               f->wall_sides, zmin, zmax, 1)))
		return err;
	if (ss_render_resampler_is_identity(&p.rs)) {   /* the cells are the pixels */
		err = ss_render_plan_draw(&p, f->height + (ptrdiff_t)(f->ny - 1) * f->stride,
		                          -f->stride, NULL, NULL, f->time, img, 1);
		goto out_plan;
	}
	double *hw, *w;
	float *gx = NULL, *gy = NULL;
	if ((err = alloc_accumulators(&p, &hw, &w)))
		goto out_plan;
	ss_render_resample_rows(&p.rs, f->height, f->stride, f->cell_type, f->stride, 0, f->ny,
	                        hw, w, 1);
	ss_render_resample_finish(&p.rs, hw, w, 1);
	if (!ss_render_plan_enlarges(&p) ||
	    !(err = ss_render_plan_gradients(&p, f->height, f->stride, f->cell_type, f->stride,
	                                     &gx, &gy, 1)))
		err = ss_render_plan_draw(&p, hw, p.rs.width, gx, gy, f->time, img, 1);
	ss_free(gx);
	ss_free(gy);
	ss_free(w);
	ss_free(hw);
out_plan:
	ss_render_plan_release(&p);
	return err;
}

void ss_render_frame_path(const char *dir, long long k, char *out, size_t size)
{
	const size_t n = strlen(dir);
	snprintf(out, size, "%s%sframe_%05lld.png", dir, n && dir[n - 1] == '/' ? "" : "/", k);
}
