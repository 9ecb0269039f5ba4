/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * shade.c - the two map styles (step 2 of a frame, render.h).
 *
 * shaded   colour = colour map of height x brightness.  The brightness is
 *          the hillshade of Horn's method [Horn] (doc/references.md): the gradient from
 *          the 3 x 3 neighbourhood with weights 1 2 1,
 *
 *            dh/dx = ((c + 2f + i) - (a + 2d + g)) / (8 dx)     a b c
 *            dh/dy = ((a + 2b + c) - (g + 2h + i)) / (8 dy)     d e f
 *                                                               g h i
 *          (a b c the northern row; where a point is a wall or outside,
 *          its row or column takes a one-sided difference, so slopes next
 *          to walls are not flattened), gives the normal n ~ (-z dh/dx,
 *          -z dh/dy, 1) with z the vertical exaggeration, and the
 *          brightness is ambient + (1 - ambient) max(n . L, 0) for the unit
 *          vector L towards the light.  40 % ambient keeps faces turned
 *          away from the light readable in colour.  Walls are one dark
 *          colour and open cells one light colour, unshaded, so they read
 *          as "not sand" at a glance; cells without data are the
 *          background, white, as if the map ended there.  Contour lines every dz metres are
 *          drawn on the pixel below each level: pixel p is on the line of
 *          level k dz when p lies below it and a 4-neighbour at or above
 *          it, so lines are one pixel wide and flat ground lying exactly on
 *          a level draws none.
 *
 * gray16   16-bit grey: 0 is "no sand here" (walls, cells without data,
 *          NaN; marked transparent by the PNG's tRNS chunk) and heights map
 *          linearly onto 1..65535,
 *
 *            v = 1 + round((h - zmin) / (zmax - zmin) * 65534)   (clamped)
 *
 *          so h = zmin + (v - 1) (zmax - zmin) / 65534 recovers them to
 *          half a step; the PNG's text chunks carry zmin and zmax.
 */
#include "internal.h"

#include <math.h>

#include "sandslide/grid.h"

#define AMBIENT 0.4             /* brightness of a face the light misses */
#define CONTOUR_DARKEN 0.55     /* a contour pixel keeps 45 % of its colour */

/* Is there a sand surface at pixel (x, y)? */
static inline int has_sand(const struct ss_render_raster *r, int x, int y)
{
	if (x < 0 || y < 0 || x >= r->width || y >= r->height)
		return 0;
	return !ss_render_no_sand(r->type[(size_t)y * r->width + x]) &&
	       !isnan(ss_render_raster_h(r, x, y));
}

static inline double at(const struct ss_render_raster *r, int x, int y)
{
	return ss_render_raster_h(r, x, y);
}

/* Difference quotient per pixel through (x, y) along (ux, uy), from points
 * n px away: central where both have sand, one-sided where one has, 0
 * where neither; returns 0 if (x, y) itself has none. */
static inline int slope_through(const struct ss_render_raster *r, int x, int y, int ux, int uy,
                                int n, double *slope)
{
	if (!has_sand(r, x, y))
		return 0;
	const int fwd = has_sand(r, x + n * ux, y + n * uy);
	const int back = has_sand(r, x - n * ux, y - n * uy);
	const double c = at(r, x, y);
	if (fwd && back)
		*slope = (at(r, x + n * ux, y + n * uy) - at(r, x - n * ux, y - n * uy)) / (2.0 * n);
	else if (fwd)
		*slope = (at(r, x + n * ux, y + n * uy) - c) / n;
	else if (back)
		*slope = (c - at(r, x - n * ux, y - n * uy)) / n;
	else
		*slope = 0.0;
	return 1;
}

/* Horn's weighted mean of the difference quotients along three parallel
 * lines `across` px apart (weights 1 2 1), over the lines with sand. */
static double horn(const struct ss_render_raster *r, int x, int y, int ux, int uy, int n,
                   int across)
{
	static const double weight[3] = {1.0, 2.0, 1.0};
	double sum = 0.0, wsum = 0.0, s;
	for (int k = -1; k <= 1; k++)
		if (slope_through(r, x + k * across * uy, y + k * across * ux, ux, uy, n, &s)) {
			sum += weight[k + 1] * s;
			wsum += weight[k + 1];
		}
	return wsum > 0.0 ? sum / wsum : 0.0;
}

/* Horn's formula itself where all nine points have sand (most pixels);
 * 0 if one has not. */
static inline int gradient_inside(const struct ss_render_raster *r, int x, int y, double *gx,
                                  double *gy)
{
	const int u = r->step_x, v = r->step_y;
	if (x < u || y < v || x >= r->width - u || y >= r->height - v)
		return 0;
	const size_t w = (size_t)r->width;
	const uint8_t *tn = r->type + (size_t)(y - v) * w + x, *tc = r->type + (size_t)y * w + x,
	              *ts = r->type + (size_t)(y + v) * w + x;
	if (ss_render_no_sand(tn[-u] | tn[0] | tn[u] | tc[-u] | tc[u] | ts[-u] | ts[0] | ts[u]))
		return 0;   /* a wall (1) or no data (3) sets bit 0 (internal.h) */
	const double *hn = r->h + (ptrdiff_t)(y - v) * r->stride + x;
	const double *hc = r->h + (ptrdiff_t)y * r->stride + x;
	const double *hs = r->h + (ptrdiff_t)(y + v) * r->stride + x;
	const double a = hn[-u], b = hn[0], c = hn[u], d = hc[-u], f = hc[u], g = hs[-u],
	             h = hs[0], i = hs[u];
	*gx = ((c + 2.0 * f + i) - (a + 2.0 * d + g)) / (8.0 * u * r->px_dx);
	*gy = ((a + 2.0 * b + c) - (g + 2.0 * h + i)) / (8.0 * v * r->px_dy);
	return !isnan(*gx) && !isnan(*gy);
}

void ss_render_gradient(const struct ss_render_raster *r, int x, int y, double *gx,
                        double *gy)
{
	if (r->gx) {
		const size_t k = (size_t)y * r->width + x;
		*gx = r->gx[k];
		*gy = r->gy[k];
		return;
	}
	if (gradient_inside(r, x, y, gx, gy))
		return;
	/* pixel rows run east, pixel columns south: north is -y */
	*gx = horn(r, x, y, 1, 0, r->step_x, r->step_y) / r->px_dx;
	*gy = -horn(r, x, y, 0, 1, r->step_y, r->step_x) / r->px_dy;
}

void ss_render_light_init(struct ss_render_light *l, double azimuth_deg,
                          double altitude_deg, double zscale)
{
	const double az = azimuth_deg * (M_PI / 180.0), alt = altitude_deg * (M_PI / 180.0);
	/* compass azimuth: clockwise from north, so east = sin, north = cos */
	l->lx = sin(az) * cos(alt);
	l->ly = cos(az) * cos(alt);
	l->lz = sin(alt);
	l->zscale = zscale;
}

double ss_render_hillshade(const struct ss_render_light *l, double gx, double gy)
{
	const double px = -l->zscale * gx, py = -l->zscale * gy;
	const double cos_i = (px * l->lx + py * l->ly + l->lz) / sqrt(1.0 + px * px + py * py);
	return AMBIENT + (1.0 - AMBIENT) * (cos_i > 0.0 ? cos_i : 0.0);
}

/* Is pixel (x, y), of height v, just below a contour level that a
 * 4-neighbour reaches? */
static int on_contour(const struct ss_render_raster *r, int x, int y, double v, double dz)
{
	const double level = floor(v / dz);
	static const int dxy[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
	for (int n = 0; n < 4; n++) {
		const int xn = x + dxy[n][0], yn = y + dxy[n][1];
		if (xn < 0 || yn < 0 || xn >= r->width || yn >= r->height)
			continue;
		if (r->type[(size_t)yn * r->width + xn] == SS_CELL_FLOW &&
		    floor(ss_render_raster_h(r, xn, yn) / dz) > level)
			return 1;
	}
	return 0;
}

void ss_render_shaded(const struct ss_render_raster *r, const struct ss_render_options *o,
                      double zmin, double zmax, struct ss_render_image *img, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	uint8_t lut[256][3];
	ss_render_cmap_table(o->cmap, lut);
	struct ss_render_light light;
	ss_render_light_init(&light, o->azimuth_deg, o->altitude_deg, o->zscale);
	const uint8_t wall[3] = {SS_RENDER_WALL_RGB}, open[3] = {SS_RENDER_OPEN_RGB},
	              nodata[3] = {SS_RENDER_NODATA_RGB},
	              absent[3] = {SS_RENDER_BACKGROUND, SS_RENDER_BACKGROUND,
	                           SS_RENDER_BACKGROUND};
	const double dz = o->contour;
	const int W = r->width, H = r->height;

	#pragma omp parallel for schedule(static) if(parallel)
	for (int y = 0; y < H; y++) {
		uint8_t *row = img->pixels + (size_t)y * img->row_bytes;
		const uint8_t *types = r->type + (size_t)y * W;
		const double *hrow = r->h + (ptrdiff_t)y * r->stride;
		for (int x = 0; x < W; x++) {
			const double v = hrow[x];
			const uint8_t *c = types[x] == SS_CELL_WALL ? wall
			                 : types[x] == SS_CELL_OPEN ? open
			                 : types[x] == SS_RENDER_CELL_NODATA ? absent
			                 : isnan(v) ? nodata : NULL;
			uint8_t *p = row + 3 * (size_t)x;
			if (c) {
				p[0] = c[0], p[1] = c[1], p[2] = c[2];
				continue;
			}
			double gx, gy;
			ss_render_gradient(r, x, y, &gx, &gy);
			double b = ss_render_hillshade(&light, gx, gy);
			if (dz > 0.0 && on_contour(r, x, y, v, dz))
				b *= 1.0 - CONTOUR_DARKEN;
			const uint8_t *m = lut[ss_render_cmap_index(v, zmin, zmax)];
			p[0] = (uint8_t)(m[0] * b + 0.5);
			p[1] = (uint8_t)(m[1] * b + 0.5);
			p[2] = (uint8_t)(m[2] * b + 0.5);
		}
	}
}

void ss_render_gray16(const struct ss_render_raster *r, double zmin, double zmax,
                      struct ss_render_image *img, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const int W = r->width, H = r->height;
	const double to_steps = 65534.0 / (zmax - zmin);

	#pragma omp parallel for schedule(static) if(parallel)
	for (int y = 0; y < H; y++) {
		uint16_t *row = (uint16_t *)(img->pixels + (size_t)y * img->row_bytes);
		const uint8_t *types = r->type + (size_t)y * W;
		const double *hrow = r->h + (ptrdiff_t)y * r->stride;
		for (int x = 0; x < W; x++) {
			const double v = hrow[x];
			if (ss_render_no_sand(types[x]) || isnan(v)) {
				row[x] = 0;
				continue;
			}
			const double s = (v - zmin) * to_steps;
			row[x] = (uint16_t)(1 + (s <= 0.0 ? 0 : s >= 65534.0 ? 65534 : (long)(s + 0.5)));
		}
	}
}
