/*
 * shade.c - the two map styles (step 2 of a frame, render.h).
 *
 * shaded   colour = colour map of height x brightness.  The brightness is
 *          the hillshade of Horn's method [Horn 1981]: the gradient from
 *          the 3 x 3 neighbourhood with weights 1 2 1,
 *
 *            dh/dx = ((c + 2f + i) - (a + 2d + g)) / (8 dx)     a b c
 *            dh/dy = ((a + 2b + c) - (g + 2h + i)) / (8 dy)     d e f
 *                                                               g h i
 *          (a b c the northern row), gives the normal n ~ (-z dh/dx,
 *          -z dh/dy, 1) with z the vertical exaggeration, and the
 *          brightness is ambient + (1 - ambient) max(n . L, 0) for the unit
 *          vector L towards the light.  40 % ambient keeps faces turned
 *          away from the light readable in colour.  Walls are one dark
 *          colour and open cells one light colour, unshaded, so they read
 *          as "not sand" at a glance.  Contour lines every dz metres are
 *          drawn on the pixel below each level: pixel p is on the line of
 *          level k dz when p lies below it and a 4-neighbour at or above
 *          it, so lines are one pixel wide and flat ground lying exactly on
 *          a level draws none.
 *
 * gray16   16-bit grey: 0 is "no sand here" (walls, NaN; marked transparent
 *          by the PNG's tRNS chunk) and heights map linearly onto 1..65535,
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

/* Height of neighbour (x, y), or `centre` where there is no sand surface. */
static inline double neighbour(const struct ss_render_raster *r, int x, int y, double centre)
{
	if (x < 0 || y < 0 || x >= r->width || y >= r->height)
		return centre;
	const size_t k = (size_t)y * r->width + x;
	const double v = r->h[k];
	return r->type[k] == SS_CELL_WALL || isnan(v) ? centre : v;
}

void ss_render_gradient(const struct ss_render_raster *r, int x, int y, double *gx,
                        double *gy)
{
	const int u = r->step_x, v = r->step_y;
	const double e = r->h[(size_t)y * r->width + x];
	const double a = neighbour(r, x - u, y - v, e), b = neighbour(r, x, y - v, e),
	             c = neighbour(r, x + u, y - v, e), d = neighbour(r, x - u, y, e),
	             f = neighbour(r, x + u, y, e), g = neighbour(r, x - u, y + v, e),
	             h = neighbour(r, x, y + v, e), i = neighbour(r, x + u, y + v, e);
	*gx = ((c + 2.0 * f + i) - (a + 2.0 * d + g)) / (8.0 * u * r->px_dx);
	*gy = ((a + 2.0 * b + c) - (g + 2.0 * h + i)) / (8.0 * v * r->px_dy);
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
		const size_t k = (size_t)yn * r->width + xn;
		if (r->type[k] == SS_CELL_FLOW && floor(r->h[k] / dz) > level)
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
	              nodata[3] = {SS_RENDER_NODATA_RGB};
	const double dz = o->contour;
	const int W = r->width, H = r->height;

	#pragma omp parallel for schedule(static) if(parallel)
	for (int y = 0; y < H; y++) {
		uint8_t *row = img->pixels + (size_t)y * img->row_bytes;
		for (int x = 0; x < W; x++) {
			const size_t k = (size_t)y * W + x;
			const double v = r->h[k];
			const uint8_t *c = r->type[k] == SS_CELL_WALL ? wall
			                 : r->type[k] == SS_CELL_OPEN ? open
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
			for (int ch = 0; ch < 3; ch++)
				p[ch] = (uint8_t)(m[ch] * b + 0.5);
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
		for (int x = 0; x < W; x++) {
			const size_t k = (size_t)y * W + x;
			const double v = r->h[k];
			if (r->type[k] == SS_CELL_WALL || isnan(v)) {
				row[x] = 0;
				continue;
			}
			const double s = (v - zmin) * to_steps;
			row[x] = (uint16_t)(1 + (s <= 0.0 ? 0 : s >= 65534.0 ? 65534 : (long)(s + 0.5)));
		}
	}
}
