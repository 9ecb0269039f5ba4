/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * resample.c - cells onto pixels (step 1 of a frame, render.h).
 *
 * A picture of width x height pixels covers the grid of nx x ny cells, so
 * pixel k of an axis covers the source interval [k f, (k+1) f) in cell
 * units, f = n_cells / n_pixels.  Heights are then
 *
 *   shrinking (f >= 1)  the area average over that interval: the overlap
 *                       of each cell is its weight, so a 16384^2 grid
 *                       drawn on 1024^2 pixels averages 16 x 16 cells;
 *   growing   (f < 1)   bilinear between the two nearest cell centres, so
 *                       that a 50 x 50 grid drawn at 10 px per cell gives
 *                       smooth hillshading and contour lines rather than
 *                       flat squares.
 *
 * Both are separable weights, w(x) w(y), and wall cells and cells without
 * data get none: a pixel's height is sum(w h) / sum(w) over its flow and
 * open cells, so walls never pull the sand surface down.  Cell types are resampled with the area
 * weights in both cases: a pixel takes the type covering most of it, so
 * walls keep their cell-sharp edges when a small grid is enlarged.
 *
 * The weighted sums are accumulated a block of cell rows at a time, so a
 * snapshot streams from the file without ever being whole in memory.
 */
#include "internal.h"

#include <math.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"

static void axis_release(struct ss_render_axis *a)
{
	ss_free(a->first);
	ss_free(a->count);
	ss_free(a->w);
	memset(a, 0, sizeof *a);
}

static int axis_alloc(struct ss_render_axis *a, int n_out, int span)
{
	a->n_out = n_out;
	a->span = span;
	a->first = ss_alloc((size_t)n_out, sizeof *a->first, "resampling weights");
	a->count = ss_alloc((size_t)n_out, sizeof *a->count, "resampling weights");
	a->w = ss_alloc((size_t)n_out * (size_t)span, sizeof *a->w, "resampling weights");
	if (!a->first || !a->count || !a->w) {
		axis_release(a);
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

/* Area weights: the overlap of each cell with the pixel's interval. */
static int axis_box(struct ss_render_axis *a, int n_src, int n_out)
{
	const double f = (double)n_src / n_out;
	if (axis_alloc(a, n_out, (int)ceil(f) + 1))
		return SS_ERR_FAIL;
	for (int k = 0; k < n_out; k++) {
		/* k * n_src is exact, so an integer factor gives exact bounds */
		const double lo = (double)k * n_src / n_out, hi = (double)(k + 1) * n_src / n_out;
		int i0 = (int)floor(lo), i1 = (int)ceil(hi) - 1;
		if (i1 > n_src - 1)
			i1 = n_src - 1;
		if (i1 < i0)
			i1 = i0;
		a->first[k] = i0;
		a->count[k] = i1 - i0 + 1;
		for (int i = i0; i <= i1; i++) {
			const double w = fmin(hi, i + 1.0) - fmax(lo, (double)i);
			a->w[(size_t)k * a->span + (i - i0)] = w > 0.0 ? w : 0.0;
		}
	}
	return SS_OK;
}

/* Bilinear weights between the two cell centres around the pixel centre;
 * beyond the outer centres the edge cell alone. */
static int axis_linear(struct ss_render_axis *a, int n_src, int n_out)
{
	const double f = (double)n_src / n_out;
	if (axis_alloc(a, n_out, 2))
		return SS_ERR_FAIL;
	for (int k = 0; k < n_out; k++) {
		const double s = (k + 0.5) * f - 0.5;   /* in cell-centre units */
		const int i0 = (int)floor(s);
		double *w = a->w + (size_t)k * 2;
		if (i0 < 0 || i0 >= n_src - 1) {
			a->first[k] = i0 < 0 ? 0 : n_src - 1;
			a->count[k] = 1;
			w[0] = 1.0;
		} else {
			const double t = s - i0;
			a->first[k] = i0;
			a->count[k] = 2;
			w[0] = 1.0 - t;
			w[1] = t;
		}
	}
	return SS_OK;
}

void ss_render_resampler_release(struct ss_render_resampler *r)
{
	axis_release(&r->bx);
	axis_release(&r->by);
	axis_release(&r->ix);
	axis_release(&r->iy);
}

int ss_render_resampler_init(struct ss_render_resampler *r, int nx, int ny, double dx,
                             double dy, int width, int height)
{
	memset(r, 0, sizeof *r);
	r->nx = nx;
	r->ny = ny;
	r->width = width;
	r->height = height;
	r->px_dx = nx * dx / width;
	r->px_dy = ny * dy / height;
	int err = axis_box(&r->bx, nx, width) || axis_box(&r->by, ny, height) ||
	          (width <= nx ? axis_box(&r->ix, nx, width) : axis_linear(&r->ix, nx, width)) ||
	          (height <= ny ? axis_box(&r->iy, ny, height) : axis_linear(&r->iy, ny, height));
	if (err) {
		ss_render_resampler_release(r);
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

void ss_render_resample_types(const struct ss_render_resampler *r, const uint8_t *cell_type,
                              ptrdiff_t stride, uint8_t *pixel_type, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const int W = r->width, H = r->height;
	const struct ss_render_axis *bx = &r->bx, *by = &r->by;

	if (ss_render_resampler_is_identity(r)) {   /* the rows flipped, north first */
		#pragma omp parallel for schedule(static) if(parallel)
		for (int py = 0; py < H; py++)
			for (int px = 0; px < W; px++) {
				const int t = cell_type ? cell_type[(ptrdiff_t)(H - 1 - py) * stride + px]
				                        : SS_CELL_FLOW;
				pixel_type[(size_t)py * W + px] = ss_render_type_of(t);
			}
		return;
	}

	#pragma omp parallel for schedule(static) if(parallel)
	for (int py = 0; py < H; py++) {
		const int q = H - 1 - py;   /* pixel rows from the south, like cells */
		for (int px = 0; px < W; px++) {
			double area[4] = {0.0, 0.0, 0.0, 0.0};   /* flow, wall, open, no data */
			for (int m = 0; m < by->count[q]; m++) {
				const int j = by->first[q] + m;
				const double wy = by->w[(size_t)q * by->span + m];
				for (int n = 0; n < bx->count[px]; n++) {
					const int i = bx->first[px] + n;
					const int t = cell_type ? cell_type[(ptrdiff_t)j * stride + i] : SS_CELL_FLOW;
					area[ss_render_type_of(t)] += wy * bx->w[(size_t)px * bx->span + n];
				}
			}
			uint8_t t = SS_CELL_WALL;
			double most = area[SS_CELL_WALL];
			if (area[SS_RENDER_CELL_NODATA] > most)
				t = SS_RENDER_CELL_NODATA, most = area[SS_RENDER_CELL_NODATA];
			if (area[SS_CELL_OPEN] > most)
				t = SS_CELL_OPEN, most = area[SS_CELL_OPEN];
			if (area[SS_CELL_FLOW] > most)
				t = SS_CELL_FLOW;
			pixel_type[(size_t)py * W + px] = t;
		}
	}
}

void ss_render_resample_rows(const struct ss_render_resampler *r, const double *h,
                             ptrdiff_t stride, const uint8_t *cell_type,
                             ptrdiff_t type_stride, int j0, int rows, double *acc_hw,
                             double *acc_w, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const int W = r->width, H = r->height;
	const struct ss_render_axis *ix = &r->ix, *iy = &r->iy;

	#pragma omp parallel for schedule(static) if(parallel)
	for (int py = 0; py < H; py++) {
		const int q = H - 1 - py;
		double *restrict hw = acc_hw + (size_t)py * W;
		double *restrict w = acc_w + (size_t)py * W;
		for (int m = 0; m < iy->count[q]; m++) {
			const int j = iy->first[q] + m;
			const double wy = iy->w[(size_t)q * iy->span + m];
			if (j < j0 || j >= j0 + rows || wy == 0.0)
				continue;
			const double *restrict hr = h + (ptrdiff_t)(j - j0) * stride;
			const uint8_t *restrict tr = cell_type ? cell_type + (ptrdiff_t)j * type_stride
			                                       : NULL;
			for (int px = 0; px < W; px++) {
				const int i0 = ix->first[px], n = ix->count[px];
				const double *wx = ix->w + (size_t)px * ix->span;
				double s_hw = 0.0, s_w = 0.0;
				for (int k = 0; k < n; k++) {
					if (tr && ss_render_no_sand(tr[i0 + k]))
						continue;
					s_hw += wx[k] * hr[i0 + k];
					s_w += wx[k];
				}
				hw[px] += wy * s_hw;
				w[px] += wy * s_w;
			}
		}
	}
}

void ss_render_resample_finish(const struct ss_render_resampler *r, double *acc_hw,
                               const double *acc_w, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const ptrdiff_t n = (ptrdiff_t)r->width * r->height;

	#pragma omp parallel for schedule(static) if(parallel)
	for (ptrdiff_t k = 0; k < n; k++)
		acc_hw[k] = acc_w[k] > 0.0 ? acc_hw[k] / acc_w[k] : NAN;
}
