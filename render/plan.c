/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * plan.c - what the frames of a series share: the look's options checked,
 * the picture's size, and the plan (struct ss_render_plan: resampling
 * weights, pixel types, height scale, the frame's layout with its wall
 * sides and the oblique camera's bearing); the cells' gradients of an
 * enlarged grid; and a frame's pixel heights drawn with it (a style, the
 * wall sides, the label and the colour bar).  frame.c reads those heights
 * from a snapshot or a field and puts the steps of render.h together.
 */
#include "internal.h"

#include <math.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"

#define AUTO_MIN_SIDE 512       /* px: small grids are enlarged to this */
#define MAX_PIXELS (1ll << 30)  /* a larger picture is surely a mistake */

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
	if (isinf(o->view_azimuth_deg))
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
	ss_render_font_destroy(p->font);
	p->font = NULL;
}

/* Thickness of a wall side: a cell, and at least 1 % of the longer side
 * of the map so it shows on large grids (3 px at least). */
static int border_px(const struct ss_render_resampler *rs)
{
	const int cell = (int)ceil(fmax((double)rs->width / rs->nx, (double)rs->height / rs->ny));
	const int t = (int)ceil(0.01 * fmax(rs->width, rs->height));
	return cell > t ? (cell > 3 ? cell : 3) : (t > 3 ? t : 3);
}

/*
 * The oblique camera's default bearing: from the open side.  The camera
 * looks from the grid's centre away from the centroid of the walls (wall
 * pixels and wall sides, by area), turned 30 degrees for a three-quarter
 * view, so that the walls stand behind the sand rather than in front of
 * it (the door case: from the east-south-east, over the cone, through the
 * door into the room).  With no walls, or walls all round, 200 (south-
 * south-west).
 */
static double view_azimuth(const struct ss_render_plan *p)
{
	const int W = p->rs.width, H = p->rs.height;
	const double lx = W * p->rs.px_dx, ly = H * p->rs.px_dy;
	double area = 0.0, mx = 0.0, my = 0.0;   /* wall area and its moments, m */
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			if (p->pixel_type[(size_t)y * W + x] == SS_CELL_WALL) {
				area += 1.0;
				mx += x + 0.5;
				my += H - y - 0.5;
			}
	const double a_px = p->rs.px_dx * p->rs.px_dy;
	area *= a_px;
	mx *= a_px * p->rs.px_dx;
	my *= a_px * p->rs.px_dy;
	const double *t = p->wall_m;   /* the sides: strips along the grid */
	const double side_area[4] = {t[SS_WEST] * ly, t[SS_EAST] * ly, t[SS_SOUTH] * lx,
	                             t[SS_NORTH] * lx};
	const double side_x[4] = {-0.5 * t[SS_WEST], lx + 0.5 * t[SS_EAST], 0.5 * lx, 0.5 * lx};
	const double side_y[4] = {0.5 * ly, 0.5 * ly, -0.5 * t[SS_SOUTH], ly + 0.5 * t[SS_NORTH]};
	for (int s = 0; s < 4; s++) {
		area += side_area[s];
		mx += side_area[s] * side_x[s];
		my += side_area[s] * side_y[s];
	}
	if (!(area > 0.0))
		return 200.0;
	const double vx = 0.5 * lx - mx / area, vy = 0.5 * ly - my / area;   /* walls -> centre */
	if (hypot(vx, vy) < 0.05 * hypot(lx, ly))
		return 200.0;
	const double bearing = atan2(vx, vy) * (180.0 / M_PI) + 30.0;   /* clockwise from north */
	return bearing < 0.0 ? bearing + 360.0 : bearing;
}

/* Has a cell along grid side `side` data?  A wall side along cells that
 * all lack it (a DEM's outline) holds no sand and is not drawn: the data
 * would stand in a box of walls. */
static int side_has_data(const uint8_t *cell_type, ptrdiff_t stride, int nx, int ny, int side)
{
	if (!cell_type)
		return 1;
	const int along_x = side == SS_SOUTH || side == SS_NORTH, n = along_x ? nx : ny;
	for (int k = 0; k < n; k++) {
		const int i = along_x ? k : side == SS_WEST ? 0 : nx - 1;
		const int j = along_x ? (side == SS_SOUTH ? 0 : ny - 1) : k;
		if (ss_render_type_of(cell_type[(ptrdiff_t)j * stride + i]) != SS_RENDER_CELL_NODATA)
			return 1;
	}
	return 0;
}

int ss_render_plan_init(struct ss_render_plan *p, const struct ss_render_options *look,
                        int nx, int ny, double dx, double dy, const uint8_t *cell_type,
                        ptrdiff_t type_stride, unsigned wall_sides, double zmin,
                        double zmax, int parallel)
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

	/* gray16's pixels are data, one per cell: nothing is drawn round them */
	const int border = look->style == SS_RENDER_GRAY16 ? 0 : border_px(&p->rs);
	for (int side = 0; side < 4; side++) {
		const int drawn = wall_sides & 1u << side &&
		                  side_has_data(cell_type, type_stride, nx, ny, side);
		p->border[side] = drawn ? border : 0;
		p->wall_m[side] = p->border[side] * (side < 2 ? p->rs.px_dx : p->rs.px_dy);
	}
	p->pic_w = w + p->border[SS_WEST] + p->border[SS_EAST];
	p->pic_h = h + p->border[SS_SOUTH] + p->border[SS_NORTH];
	if (look->style == SS_RENDER_OBLIQUE) {
		if (isnan(p->look.view_azimuth_deg))
			p->look.view_azimuth_deg = view_azimuth(p);
		struct ss_render_raster r = {w, h, p->rs.px_dx, p->rs.px_dy, NULL, w, NULL, 1, 1,
		                             NULL, NULL, {0}};
		memcpy(r.wall_m, p->wall_m, sizeof r.wall_m);
		ss_render_oblique_size(&r, &p->look, zmin, zmax, &p->pic_w, &p->pic_h);
	}
	/* the text's font, sized with the picture: made once here (its glyphs
	 * rendered), then only read by the frames, on any thread */
	int err;
	if ((look->label || look->colorbar) &&
	    (err = ss_render_font_create(&p->font, ss_render_font_px(p->pic_w, p->pic_h)))) {
		ss_render_plan_release(p);
		return err;
	}
	p->label_h = look->label ? ss_render_label_height(p->font) : 0;
	p->image_w = p->pic_w;
	p->image_h = p->label_h + p->pic_h;
	if (look->colorbar)
		p->image_w += ss_render_colorbar_width(p->font, zmin, zmax);
	return SS_OK;
}

/* Resample one cell field (south first, stride) onto float pixels. */
static void resample_to_float(const struct ss_render_plan *p, const double *field,
                              ptrdiff_t stride, const uint8_t *cell_type,
                              ptrdiff_t type_stride, double *acc_hw, double *acc_w,
                              float *out, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const ptrdiff_t n = (ptrdiff_t)p->rs.width * p->rs.height;
	memset(acc_hw, 0, (size_t)n * sizeof *acc_hw);
	memset(acc_w, 0, (size_t)n * sizeof *acc_w);
	ss_render_resample_rows(&p->rs, field, stride, cell_type, type_stride, 0, p->rs.ny, acc_hw,
	                        acc_w, parallel);
	ss_render_resample_finish(&p->rs, acc_hw, acc_w, parallel);
	#pragma omp parallel for schedule(static) if(parallel)
	for (ptrdiff_t k = 0; k < n; k++)
		out[k] = isnan(acc_hw[k]) ? 0.0f : (float)acc_hw[k];
}

int ss_render_plan_gradients(const struct ss_render_plan *p, const double *h,
                             ptrdiff_t stride, const uint8_t *cell_type,
                             ptrdiff_t type_stride, float **gx, float **gy, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	const int nx = p->rs.nx, ny = p->rs.ny;
	const size_t cells = (size_t)nx * ny, pixels = (size_t)p->rs.width * p->rs.height;
	*gx = *gy = NULL;
	uint8_t *types = ss_alloc(cells, 1, "cell types, north first");
	double *cgx = ss_alloc(cells, sizeof *cgx, "cell gradients");
	double *cgy = ss_alloc(cells, sizeof *cgy, "cell gradients");
	double *acc_hw = ss_alloc(pixels, sizeof *acc_hw, "resampled gradients");
	double *acc_w = ss_alloc(pixels, sizeof *acc_w, "resampling weights");
	*gx = ss_alloc(pixels, sizeof **gx, "pixel gradients");
	*gy = ss_alloc(pixels, sizeof **gy, "pixel gradients");
	int err = types && cgx && cgy && acc_hw && acc_w && *gx && *gy ? SS_OK : SS_ERR_FAIL;
	if (!err) {
		/* the cells as a raster of their own: one px per cell, north first */
		#pragma omp parallel for schedule(static) if(parallel)
		for (int y = 0; y < ny; y++)
			for (int x = 0; x < nx; x++) {
				const int t = cell_type ? cell_type[(ptrdiff_t)(ny - 1 - y) * type_stride + x]
				                        : SS_CELL_FLOW;
				types[(size_t)y * nx + x] = ss_render_type_of(t);
			}
		const struct ss_render_raster cr = {
			nx, ny, p->rs.px_dx * p->rs.width / nx, p->rs.px_dy * p->rs.height / ny,
			h + (ptrdiff_t)(ny - 1) * stride, -stride, types, 1, 1, NULL, NULL, {0},
		};
		/* cgx, cgy south first, like the heights the resampler takes */
		#pragma omp parallel for schedule(static) if(parallel)
		for (int y = 0; y < ny; y++)
			for (int x = 0; x < nx; x++) {
				const size_t k = (size_t)(ny - 1 - y) * nx + x;
				const double v = ss_render_raster_h(&cr, x, y);
				cgx[k] = cgy[k] = 0.0;
				if (!ss_render_no_sand(types[(size_t)y * nx + x]) && !isnan(v))
					ss_render_gradient(&cr, x, y, &cgx[k], &cgy[k]);
			}
		resample_to_float(p, cgx, nx, cell_type, type_stride, acc_hw, acc_w, *gx, parallel);
		resample_to_float(p, cgy, nx, cell_type, type_stride, acc_hw, acc_w, *gy, parallel);
	}
	ss_free(types);
	ss_free(cgx);
	ss_free(cgy);
	ss_free(acc_hw);
	ss_free(acc_w);
	if (err) {
		ss_free(*gx);
		ss_free(*gy);
		*gx = *gy = NULL;
	}
	return err;
}

/* The walls outside the grid's wall sides, in the walls' colour. */
static void draw_wall_sides(const struct ss_render_plan *p, struct ss_render_image *img)
{
	static const uint8_t wall[3] = {SS_RENDER_WALL_RGB};
	const int x0 = p->border[SS_WEST], x1 = p->pic_w - p->border[SS_EAST];
	const int y0 = p->label_h + p->border[SS_NORTH];
	const int y1 = p->label_h + p->pic_h - p->border[SS_SOUTH];
	for (int y = p->label_h; y < p->label_h + p->pic_h; y++) {
		uint8_t *row = img->pixels + (size_t)y * img->row_bytes;
		for (int x = 0; x < p->pic_w; x++)
			if (x < x0 || x >= x1 || y < y0 || y >= y1)
				memcpy(row + 3 * (size_t)x, wall, 3);
	}
}

int ss_render_plan_draw(const struct ss_render_plan *p, const double *pixel_h,
                        ptrdiff_t stride, const float *gx, const float *gy, double time,
                        struct ss_render_image *img, int parallel)
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
	struct ss_render_raster r = {
		p->rs.width, p->rs.height, p->rs.px_dx, p->rs.px_dy, pixel_h, stride, p->pixel_type,
		p->rs.width > p->rs.nx ? (int)lround((double)p->rs.width / p->rs.nx) : 1,
		p->rs.height > p->rs.ny ? (int)lround((double)p->rs.height / p->rs.ny) : 1,
		gx, gy, {0},
	};
	memcpy(r.wall_m, p->wall_m, sizeof r.wall_m);
	/* the picture's part of the frame, below the label strip; the map's
	 * part of that, inside the wall sides */
	struct ss_render_image pic = *img, map = *img;
	pic.pixels += (size_t)p->label_h * img->row_bytes;
	pic.height = p->pic_h;
	map.pixels = pic.pixels + (size_t)p->border[SS_NORTH] * img->row_bytes +
	             3 * (size_t)p->border[SS_WEST];
	map.width = p->rs.width;
	map.height = p->rs.height;
	switch (o->style) {
	case SS_RENDER_GRAY16:
		ss_render_gray16(&r, p->zmin, p->zmax, img, parallel);
		break;
	case SS_RENDER_OBLIQUE:
		if (ss_render_oblique(&r, o, p->zmin, p->zmax, &pic, parallel)) {
			ss_render_image_release(img);
			return SS_ERR_FAIL;
		}
		break;
	case SS_RENDER_SHADED:
	default:
		draw_wall_sides(p, img);
		ss_render_shaded(&r, o, p->zmin, p->zmax, &map, parallel);
		break;
	}
	if (o->colorbar)
		ss_render_draw_colorbar(img, p->font, p->pic_w, p->label_h, p->pic_h, o->cmap,
		                        p->zmin, p->zmax);
	if (o->label)
		ss_render_draw_label(img, p->font, p->pic_w, time);
	return SS_OK;
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
