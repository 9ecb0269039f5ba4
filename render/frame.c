/*
 * frame.c - one frame: the options, the picture's size, the plan shared by
 * the frames of a series (resampling weights, pixel types, height scale),
 * and the three steps of render.h put together.
 */
#include "internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"

#define AUTO_MIN_SIDE 512       /* px: small grids are enlarged to this */
#define MAX_PIXELS (1ll << 30)  /* a larger picture is surely a mistake */

void ss_render_options_default(struct ss_render_options *o)
{
	memset(o, 0, sizeof *o);
	o->style = SS_RENDER_SHADED;
	o->cmap = SS_RENDER_CMAP_DUNE;
	o->zmin = o->zmax = NAN;
	o->azimuth_deg = 315.0;
	o->altitude_deg = 45.0;
	o->zscale = 1.0;
	o->view_azimuth_deg = 200.0;
	o->view_elevation_deg = 45.0;
	o->compression = 6;
}

int ss_render_options_check(const struct ss_render_options *o)
{
	if (!isfinite(o->azimuth_deg))
		return ss_error_input("--azimuth %g: expected a finite angle in degrees",
		                      o->azimuth_deg);
	if (!(o->altitude_deg > 0.0 && o->altitude_deg <= 90.0))
		return ss_error_input("--altitude %g: expected an angle in (0, 90] degrees",
		                      o->altitude_deg);
	if (!(o->zscale > 0.0) || !isfinite(o->zscale))
		return ss_error_input("--zscale %g: expected a finite number > 0", o->zscale);
	if (!(o->contour >= 0.0) || !isfinite(o->contour))
		return ss_error_input("--contour %g: expected a spacing in m > 0", o->contour);
	if (o->max_size != 0 && (o->max_size < 8 || o->max_size > 65536))
		return ss_error_input("--max-size %d: expected 8 to 65536 px", o->max_size);
	if (o->scale < 0 || o->scale > 100)
		return ss_error_input("--scale %d: expected 1 to 100 px per cell", o->scale);
	if (!isfinite(o->view_azimuth_deg))
		return ss_error_input("--view-azimuth %g: expected a finite angle in degrees",
		                      o->view_azimuth_deg);
	if (!(o->view_elevation_deg > 0.0 && o->view_elevation_deg < 90.0))
		return ss_error_input("--view-elevation %g: expected an angle in (0, 90) degrees",
		                      o->view_elevation_deg);
	if (o->compression < 0 || o->compression > 9)
		return ss_error_input("PNG compression %d: expected 0 to 9", o->compression);
	if (isinf(o->zmin) || isinf(o->zmax))
		return ss_error_input("--zmin/--zmax must be finite");
	if (!isnan(o->zmin) && !isnan(o->zmax) && !(o->zmin < o->zmax))
		return ss_error_input("--zmin %g is not below --zmax %g: the height scale needs "
		                      "zmin < zmax", o->zmin, o->zmax);
	if (o->style == SS_RENDER_GRAY16 && (o->label || o->colorbar))
		return ss_error_input("--label and --colorbar do not apply to --style gray16 "
		                      "(its pixels are data: heights)");
	if (o->contour > 0.0 && o->style != SS_RENDER_SHADED)
		return ss_error_input("--contour applies to --style shaded only");
	return SS_OK;
}

void ss_render_picture_size(int nx, int ny, double dx, double dy,
                            const struct ss_render_options *o, int *width, int *height)
{
	/* pixels are square: one per cell along the finer axis, times K */
	const double lx = nx * dx, ly = ny * dy, p0 = fmin(dx, dy);
	const double w1 = lx / p0, h1 = ly / p0;
	int k = o->scale;
	if (k <= 0) {
		k = 1;
		if (o->style != SS_RENDER_GRAY16 && fmax(w1, h1) < AUTO_MIN_SIDE)
			k = (int)ceil(AUTO_MIN_SIDE / fmax(w1, h1) - 1e-9);
	}
	double w = w1 * k, h = h1 * k;
	if (o->max_size > 0 && fmax(w, h) > o->max_size) {
		const double shrink = o->max_size / fmax(w, h);
		w *= shrink;
		h *= shrink;
	}
	*width = w < 1.0 ? 1 : (int)lround(w);
	*height = h < 1.0 ? 1 : (int)lround(h);
}

void ss_render_plan_release(struct ss_render_plan *p)
{
	ss_render_resampler_release(&p->rs);
	ss_free(p->pixel_type);
	p->pixel_type = NULL;
}

int ss_render_plan_init(struct ss_render_plan *p, const struct ss_render_options *look,
                        int nx, int ny, double dx, double dy, const uint8_t *cell_type,
                        ptrdiff_t type_stride, double zmin, double zmax, int parallel)
{
	memset(p, 0, sizeof *p);
	p->look = *look;
	p->zmin = zmin;
	p->zmax = zmax;
	int w, h;
	ss_render_picture_size(nx, ny, dx, dy, look, &w, &h);
	if ((long long)w * h > MAX_PIXELS)
		return ss_error_input("a picture of %d x %d px is too large: lower --scale or set "
		                      "--max-size", w, h);
	if (ss_render_resampler_init(&p->rs, nx, ny, dx, dy, w, h))
		return SS_ERR_FAIL;
	p->pixel_type = ss_alloc((size_t)w * (size_t)h, 1, "pixel types");
	if (!p->pixel_type) {
		ss_render_plan_release(p);
		return SS_ERR_FAIL;
	}
	ss_render_resample_types(&p->rs, cell_type, type_stride, p->pixel_type, parallel);

	p->pic_w = w;
	p->pic_h = h;
	if (look->style == SS_RENDER_OBLIQUE) {
		const struct ss_render_raster r = {w, h, p->rs.px_dx, p->rs.px_dy, NULL, w, NULL, 1, 1};
		ss_render_oblique_size(&r, look, zmin, zmax, &p->pic_w, &p->pic_h);
	}
	p->image_w = p->pic_w;
	p->image_h = p->pic_h;
	if (look->colorbar)
		p->image_w += ss_render_colorbar_width(p->pic_w, p->pic_h, zmin, zmax);
	return SS_OK;
}

int ss_render_plan_draw(const struct ss_render_plan *p, const double *pixel_h,
                        ptrdiff_t stride, double time, struct ss_render_image *img,
                        int parallel)
{
	const struct ss_render_options *o = &p->look;
	const int gray = o->style == SS_RENDER_GRAY16;
	if (ss_render_image_init(img, p->image_w, p->image_h, gray ? 1 : 3, gray ? 16 : 8))
		return SS_ERR_FAIL;
	img->time = time;
	img->zmin = p->zmin;
	img->zmax = p->zmax;
	img->style = o->style;
	if (o->style != SS_RENDER_OBLIQUE) {
		img->px_dx = p->rs.px_dx;
		img->px_dy = p->rs.px_dy;
	}
	const struct ss_render_raster r = {
		p->rs.width, p->rs.height, p->rs.px_dx, p->rs.px_dy, pixel_h, stride, p->pixel_type,
		p->rs.width > p->rs.nx ? (int)lround((double)p->rs.width / p->rs.nx) : 1,
		p->rs.height > p->rs.ny ? (int)lround((double)p->rs.height / p->rs.ny) : 1,
	};
	switch (o->style) {
	case SS_RENDER_GRAY16:
		ss_render_gray16(&r, p->zmin, p->zmax, img, parallel);
		break;
	case SS_RENDER_OBLIQUE:
		if (ss_render_oblique(&r, o, p->zmin, p->zmax, img, parallel)) {
			ss_render_image_release(img);
			return SS_ERR_FAIL;
		}
		break;
	case SS_RENDER_SHADED:
	default:
		ss_render_shaded(&r, o, p->zmin, p->zmax, img, parallel);
		break;
	}
	if (o->colorbar)
		ss_render_draw_colorbar(img, p->pic_w, p->pic_h, o->cmap, p->zmin, p->zmax);
	if (o->label)
		ss_render_draw_label(img, p->pic_w, p->pic_h, time);
	return SS_OK;
}

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

/* The pixel heights of snapshot t: one pixel per cell reads the snapshot
 * as it is (rows flipped by a negative stride, no copy); otherwise the
 * cells stream through the resampler a block of rows at a time. */
static int snapshot_heights(const struct ss_render_plan *p, struct ss_render_source *s,
                            long long t, double **buf, double **acc_w, const double **h,
                            ptrdiff_t *stride, int parallel)
{
	struct ss_snapshot_file *f = &s->file;
	*acc_w = NULL;
	const int block = ss_snapshot_file_block_rows(f);
	if (ss_render_resampler_is_identity(&p->rs)) {
		*buf = ss_alloc((size_t)f->nx * (size_t)f->ny, sizeof **buf, "snapshot heights");
		if (!*buf)
			return SS_ERR_FAIL;
		for (int j0 = 0; j0 < f->ny; j0 += block) {
			const int rows = f->ny - j0 < block ? f->ny - j0 : block;
			int err = ss_snapshot_file_read_rows(f, t, j0, rows, *buf + (size_t)j0 * f->nx);
			if (err)
				return err;
		}
		*h = *buf + (size_t)(f->ny - 1) * f->nx;
		*stride = -(ptrdiff_t)f->nx;
		return SS_OK;
	}
	double *rows_buf = ss_alloc((size_t)block * (size_t)f->nx, sizeof *rows_buf, "height rows");
	if (!rows_buf || alloc_accumulators(p, buf, acc_w)) {
		ss_free(rows_buf);
		return SS_ERR_FAIL;
	}
	int err = SS_OK;
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		if (!(err = ss_snapshot_file_read_rows(f, t, j0, rows, rows_buf)))
			ss_render_resample_rows(&p->rs, rows_buf, f->nx, s->cell_type, f->nx, j0, rows,
			                        *buf, *acc_w, parallel);
	}
	ss_free(rows_buf);
	if (!err)
		ss_render_resample_finish(&p->rs, *buf, *acc_w, parallel);
	*h = *buf;
	*stride = p->rs.width;
	return err;
}

int ss_render_plan_image(const struct ss_render_plan *p, struct ss_render_source *s,
                         long long t, struct ss_render_image *img, double *pixel_h,
                         int parallel)
{
	double *buf = NULL, *w = NULL;
	const double *h;
	ptrdiff_t stride;
	memset(img, 0, sizeof *img);
	int err = snapshot_heights(p, s, t, &buf, &w, &h, &stride, parallel);
	if (!err)
		err = ss_render_plan_draw(p, h, stride, s->file.time[t], img, parallel);
	if (!err) {
		img->snapshot = t;
		snprintf(img->source, sizeof img->source, "%s", s->file.name);
		if (p->look.style != SS_RENDER_OBLIQUE) {
			img->x0 = s->file.origin_x;
			img->y0 = s->file.origin_y;
		}
		if (pixel_h)
			for (int y = 0; y < p->rs.height; y++)
				memcpy(pixel_h + (size_t)y * p->rs.width, h + (ptrdiff_t)y * stride,
				       (size_t)p->rs.width * sizeof *pixel_h);
	}
	ss_free(w);
	ss_free(buf);
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
			if ((!f->cell_type || f->cell_type[k] != SS_CELL_WALL) && isfinite(v)) {
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
		                      "dx %g, dy %g)", f->nx, f->ny, f->stride, f->dx, f->dy);
	double zmin = o->zmin, zmax = o->zmax;
	if (isnan(zmin) || isnan(zmax)) {
		double lo, hi;
		field_range(f, &lo, &hi);
		if ((err = ss_render_scale_resolve(&zmin, &zmax, lo, hi, "the field")))
			return err;
	}
	struct ss_render_plan p;
	if ((err = ss_render_plan_init(&p, o, f->nx, f->ny, f->dx, f->dy, f->cell_type, f->stride,
	                               zmin, zmax, 1)))
		return err;
	if (ss_render_resampler_is_identity(&p.rs)) {   /* the cells are the pixels */
		err = ss_render_plan_draw(&p, f->height + (ptrdiff_t)(f->ny - 1) * f->stride,
		                          -f->stride, f->time, img, 1);
		goto out_plan;
	}
	double *hw, *w;
	if ((err = alloc_accumulators(&p, &hw, &w)))
		goto out_plan;
	ss_render_resample_rows(&p.rs, f->height, f->stride, f->cell_type, f->stride, 0, f->ny,
	                        hw, w, 1);
	ss_render_resample_finish(&p.rs, hw, w, 1);
	err = ss_render_plan_draw(&p, hw, p.rs.width, f->time, img, 1);
	ss_free(w);
	ss_free(hw);
out_plan:
	ss_render_plan_release(&p);
	return err;
}

int ss_render_scale_resolve(double *zmin, double *zmax, double lo, double hi,
                            const char *what)
{
	const int given_min = !isnan(*zmin), given_max = !isnan(*zmax);
	if (!(lo <= hi)) {          /* no sand anywhere: any scale will do */
		lo = 0.0;
		hi = 1.0;
	} else if (lo == hi) {      /* flat: centre it in the colour map */
		lo -= 0.5;
		hi += 0.5;
	}
	if (!given_min)
		*zmin = lo;
	if (!given_max)
		*zmax = hi;
	if (*zmin < *zmax)
		return SS_OK;
	if (given_min && given_max)
		return ss_error_input("--zmin %g is not below --zmax %g: the height scale needs "
		                      "zmin < zmax", *zmin, *zmax);
	if (given_min)
		return ss_error_input("--zmin %g is not below the highest height of %s (%g m): "
		                      "give --zmax too", *zmin, what, *zmax);
	return ss_error_input("--zmax %g is not above the lowest height of %s (%g m): "
	                      "give --zmin too", *zmax, what, *zmin);
}

void ss_render_frame_path(const char *dir, long long k, char *out, size_t size)
{
	const size_t n = strlen(dir);
	snprintf(out, size, "%s%sframe_%05lld.png", dir, n && dir[n - 1] == '/' ? "" : "/", k);
}
