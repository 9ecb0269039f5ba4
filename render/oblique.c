/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * oblique.c - a perspective view of the sand surface from an elevated
 * camera, like the 3-D panels of [Paper] Figs. 5-6, drawn in software as
 * z-buffered triangles.
 *
 * Scene (x east, y north, z up, metres; z = zscale (h - zmin)):
 *   - the sand surface: a triangle mesh through the pixel centres of the
 *     resampled raster, two triangles per square, each vertex coloured by
 *     the colour map and lit like the shaded style (Horn gradient);
 *     vertices on walls take the mean height of their sand neighbours, so
 *     the surface runs under the wall blocks without a step;
 *   - walls: a block per wall pixel, sides only where the neighbour is
 *     not a wall, and a block along each grid side that is a wall
 *     (wall_m thick).  Each wall (a 4-connected set of wall pixels) is
 *     WALL_RISE of the height range taller than the highest sand that
 *     touches it in this frame, and never above the scale's top (a grid
 *     side follows the sand along it, WALL_RISE above it):
 *     walls as tall as the scale would hide the sand behind them for most
 *     of a video, while a room fills, and a column among low sand would
 *     hide what lies behind it;
 *   - a skirt down to a base 8 % of the range below zmin along the edges
 *     of the grid, so the sand reads as a solid slab;
 *   - cells without data (a DEM's outline, its holes) are absent: no
 *     triangle with a vertex on one is drawn, the skirt runs along the
 *     edge of the triangles that are, and a grid side that is a wall is
 *     drawn only if some cell along it has data (plan.c).
 * Camera: at compass bearing view_azimuth and elevation view_elevation
 * from the centre of the scene's box (the grid with its wall sides, up to
 * the scale's top plus WALL_RISE), far enough that the box's bounding
 * sphere fills a 30 degree field of view; the picture frames the projected
 * box.  The framing depends only on the grid and the height scale, so
 * every frame of a series has the same camera.
 *
 * Rasterising: pixel centres inside a triangle (edge functions) take the
 * depth 1/Z interpolated linearly on screen (exact for perspective) and
 * the vertex colours (Gouraud).  A pixel keeps the nearest triangle; on a
 * tie the one drawn first.  The picture is split into bands of rows
 * shared between threads; each band draws every triangle in the same
 * order, so the bits do not depend on the number of threads.
 */
#include "internal.h"

#include <math.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"

#define WALL_RISE 0.06          /* wall tops above the sand, fraction of the range */
#define BASE_DEPTH 0.08         /* slab base below zmin, fraction of the range */
#define FIELD_OF_VIEW_DEG 30.0
#define MARGIN 0.03             /* of the picture width, on every side */
#define AMBIENT 0.4

static const uint8_t wall_rgb[3] = {0x8c, 0x8c, 0x96};   /* lit faces of the blocks */
static const uint8_t skirt_rgb[3] = {0x9a, 0x86, 0x64};  /* the slab's sides */

struct camera {
	double ex, ey, ez;          /* eye, m */
	double r[3], u[3], f[3];    /* right, up, forward (unit) */
	double sx0, sy1;            /* projected left and top of the box */
	double scale;               /* px per unit of projected coordinate */
	double margin;              /* px */
	int width, height;          /* px */
	double z_floor, z_wall;     /* m, scene heights of the base and of the
	                             * highest wall top (the framing) */
	double x0, x1, y0, y1;      /* m, the scene's extent with its wall sides */
};

static void project(const struct camera *c, double x, double y, double z, double *sx,
                    double *sy, double *iz)
{
	const double vx = x - c->ex, vy = y - c->ey, vz = z - c->ez;
	const double X = vx * c->r[0] + vy * c->r[1] + vz * c->r[2];
	const double Y = vx * c->u[0] + vy * c->u[1] + vz * c->u[2];
	const double Z = vx * c->f[0] + vy * c->f[1] + vz * c->f[2];
	*iz = 1.0 / Z;
	*sx = X / Z;
	*sy = Y / Z;
}

/* The camera for a raster and height scale; width is the picture's. */
static void camera_init(struct camera *c, const struct ss_render_raster *ra,
                        const struct ss_render_options *o, double zmin, double zmax)
{
	const double range = o->zscale * (zmax - zmin);
	c->z_floor = -BASE_DEPTH * range;
	c->z_wall = (1.0 + WALL_RISE) * range;
	c->x0 = -ra->wall_m[SS_WEST];
	c->x1 = ra->width * ra->px_dx + ra->wall_m[SS_EAST];
	c->y0 = -ra->wall_m[SS_SOUTH];
	c->y1 = ra->height * ra->px_dy + ra->wall_m[SS_NORTH];
	const double lx = c->x1 - c->x0, ly = c->y1 - c->y0;
	const double cx = 0.5 * (c->x0 + c->x1), cy = 0.5 * (c->y0 + c->y1);
	const double cz = 0.5 * (c->z_floor + c->z_wall), dz = c->z_wall - c->z_floor;
	const double radius = 0.5 * sqrt(lx * lx + ly * ly + dz * dz);
	const double dist = radius / sin(0.5 * FIELD_OF_VIEW_DEG * M_PI / 180.0);
	const double az = o->view_azimuth_deg * M_PI / 180.0;
	const double el = o->view_elevation_deg * M_PI / 180.0;
	const double d[3] = {sin(az) * cos(el), cos(az) * cos(el), sin(el)};
	c->ex = cx + dist * d[0];
	c->ey = cy + dist * d[1];
	c->ez = cz + dist * d[2];
	c->f[0] = -d[0], c->f[1] = -d[1], c->f[2] = -d[2];
	/* right is horizontal whatever the elevation: no singularity overhead */
	c->r[0] = -cos(az), c->r[1] = sin(az), c->r[2] = 0.0;
	c->u[0] = c->r[1] * c->f[2] - c->r[2] * c->f[1];
	c->u[1] = c->r[2] * c->f[0] - c->r[0] * c->f[2];
	c->u[2] = c->r[0] * c->f[1] - c->r[1] * c->f[0];

	double sx0 = INFINITY, sx1 = -INFINITY, sy0 = INFINITY, sy1 = -INFINITY;
	for (int k = 0; k < 8; k++) {
		double sx, sy, iz;
		project(c, k & 1 ? c->x1 : c->x0, k & 2 ? c->y1 : c->y0,
		        k & 4 ? c->z_wall : c->z_floor, &sx, &sy, &iz);
		sx0 = fmin(sx0, sx), sx1 = fmax(sx1, sx);
		sy0 = fmin(sy0, sy), sy1 = fmax(sy1, sy);
	}
	c->width = ra->width > 64 ? ra->width : 64;
	c->margin = MARGIN * c->width;
	c->scale = (c->width - 2.0 * c->margin) / (sx1 - sx0);
	c->sx0 = sx0;
	c->sy1 = sy1;
	int h = (int)ceil((sy1 - sy0) * c->scale + 2.0 * c->margin);
	c->height = h < 16 ? 16 : h > 4 * c->width ? 4 * c->width : h;
}

void ss_render_oblique_size(const struct ss_render_raster *r,
                            const struct ss_render_options *o, double zmin, double zmax,
                            int *width, int *height)
{
	struct camera c;
	camera_init(&c, r, o, zmin, zmax);
	*width = c.width;
	*height = c.height;
}

/* A projected vertex: picture coordinates, 1/depth and colour. */
struct vtx {
	float x, y, iz;
	uint8_t c[3];
};

static struct vtx make_vtx(const struct camera *c, double x, double y, double z,
                           const uint8_t rgb[3], double brightness)
{
	struct vtx v;
	double sx, sy, iz;
	project(c, x, y, z, &sx, &sy, &iz);
	v.x = (float)(c->margin + (sx - c->sx0) * c->scale);
	v.y = (float)(c->margin + (c->sy1 - sy) * c->scale);
	v.iz = (float)iz;
	for (int k = 0; k < 3; k++)
		v.c[k] = (uint8_t)(rgb[k] * brightness + 0.5);
	return v;
}

/* Brightness of a flat face of unit normal n. */
static double face_light(const struct ss_render_light *l, double nx, double ny, double nz)
{
	const double d = nx * l->lx + ny * l->ly + nz * l->lz;
	return AMBIENT + (1.0 - AMBIENT) * (d > 0.0 ? d : 0.0);
}

/* What one band of rows draws into. */
struct target {
	struct ss_render_image *img;
	float *depth;               /* 1/Z per pixel; 0: nothing yet */
	int width;                  /* columns of the view (the picture may be
	                             * wider: a colour bar) */
	int y0, y1;                 /* rows of the band */
};

static inline double edge(const struct vtx *a, const struct vtx *b, double px, double py)
{
	return ((double)b->x - a->x) * (py - a->y) - ((double)b->y - a->y) * (px - a->x);
}

static void draw_triangle(struct target *t, const struct vtx *a, const struct vtx *b,
                          const struct vtx *c)
{
	const double area = edge(a, b, c->x, c->y);
	if (fabs(area) < 1e-12)
		return;
	const double ymin = fmin(a->y, fmin(b->y, c->y)), ymax = fmax(a->y, fmax(b->y, c->y));
	int ya = (int)ceil(ymin - 0.5), yb = (int)floor(ymax - 0.5);
	if (ya < t->y0)
		ya = t->y0;
	if (yb > t->y1 - 1)
		yb = t->y1 - 1;
	if (ya > yb)
		return;
	const double xmin = fmin(a->x, fmin(b->x, c->x)), xmax = fmax(a->x, fmax(b->x, c->x));
	int xa = (int)ceil(xmin - 0.5), xb = (int)floor(xmax - 0.5);
	if (xa < 0)
		xa = 0;
	if (xb > t->width - 1)
		xb = t->width - 1;
	const double inv = 1.0 / area, eps = -1e-9;
	for (int y = ya; y <= yb; y++) {
		const double py = y + 0.5;
		for (int x = xa; x <= xb; x++) {
			const double px = x + 0.5;
			const double wa = edge(b, c, px, py) * inv, wb = edge(c, a, px, py) * inv;
			const double wc = 1.0 - wa - wb;
			if (wa < eps || wb < eps || wc < eps)
				continue;
			const float iz = (float)(wa * a->iz + wb * b->iz + wc * c->iz);
			const size_t k = (size_t)y * t->img->width + x;
			if (iz <= t->depth[k])
				continue;
			t->depth[k] = iz;
			uint8_t *p = t->img->pixels + (size_t)y * t->img->row_bytes + 3 * (size_t)x;
			for (int ch = 0; ch < 3; ch++)
				p[ch] = (uint8_t)(wa * a->c[ch] + wb * b->c[ch] + wc * c->c[ch] + 0.5);
		}
	}
}

static void draw_quad(struct target *t, const struct vtx *a, const struct vtx *b,
                      const struct vtx *c, const struct vtx *d)
{
	draw_triangle(t, a, b, c);
	draw_triangle(t, a, c, d);
}

/* Is the quad's bounding box clear of the band? */
static int outside_band(const struct target *t, float y_lo, float y_hi)
{
	return y_hi < t->y0 - 1 || y_lo > t->y1 + 1;
}

/* Height of the surface mesh at raster pixel k: walls, cells without data
 * and NaN take the mean of their sand neighbours (or the base if they have
 * none). */
static double mesh_height(const struct ss_render_raster *r, int x, int y, double base)
{
	const size_t k = (size_t)y * r->width + x;
	if (!ss_render_no_sand(r->type[k]) && !isnan(ss_render_raster_h(r, x, y)))
		return ss_render_raster_h(r, x, y);
	double sum = 0.0;
	int n = 0;
	for (int v = -1; v <= 1; v++)
		for (int u = -1; u <= 1; u++) {
			const int xn = x + u, yn = y + v;
			if (xn < 0 || yn < 0 || xn >= r->width || yn >= r->height)
				continue;
			const size_t m = (size_t)yn * r->width + xn;
			if (!ss_render_no_sand(r->type[m]) && !isnan(ss_render_raster_h(r, xn, yn))) {
				sum += ss_render_raster_h(r, xn, yn);
				n++;
			}
		}
	return n ? sum / n : base;
}

/* The surface's vertices, one per raster pixel. */
static void surface_vertices(const struct ss_render_raster *r, const struct camera *c,
                             const struct ss_render_options *o, double zmin, double zmax,
                             struct vtx *v, int parallel)
{
	(void)parallel;   /* used by the pragmas only */
	uint8_t lut[256][3];
	ss_render_cmap_table(o->cmap, lut);
	struct ss_render_light light;
	ss_render_light_init(&light, o->azimuth_deg, o->altitude_deg, o->zscale);
	static const uint8_t open[3] = {SS_RENDER_OPEN_RGB}, nodata[3] = {SS_RENDER_NODATA_RGB};
	const int W = r->width, H = r->height;
	const double base = zmin - BASE_DEPTH * (zmax - zmin);

	#pragma omp parallel for schedule(static) if(parallel)
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			const size_t k = (size_t)y * W + x;
			const double h = mesh_height(r, x, y, base);
			const double wx = (x + 0.5) * r->px_dx, wy = (H - y - 0.5) * r->px_dy;
			double b = 1.0;
			const uint8_t *rgb = wall_rgb;   /* under a block, or not drawn */
			if (ss_render_no_sand(r->type[k])) {
				rgb = wall_rgb;
			} else if (isnan(ss_render_raster_h(r, x, y))) {
				rgb = nodata;
			} else {
				double gx, gy;
				ss_render_gradient(r, x, y, &gx, &gy);
				b = ss_render_hillshade(&light, gx, gy);
				rgb = r->type[k] == SS_CELL_OPEN ? open : lut[ss_render_cmap_index(h, zmin, zmax)];
			}
			v[k] = make_vtx(c, wx, wy, o->zscale * (h - zmin), rgb, b);
		}
}

/* Is pixel (x, y) a vertex of the surface, a cell with data? */
static inline int has_data(const struct ss_render_raster *r, int x, int y)
{
	return r->type[(size_t)y * r->width + x] != SS_RENDER_CELL_NODATA;
}

/* Is triangle `half` (0: a b e, north-east; 1: a e d, south-west) of the
 * square with north-west corner (x, y) drawn?  Outside the grid: no. */
static int triangle_drawn(const struct ss_render_raster *r, int x, int y, int half)
{
	if (x < 0 || y < 0 || x + 1 >= r->width || y + 1 >= r->height)
		return 0;
	return has_data(r, x, y) && has_data(r, x + 1, y + 1) &&
	       has_data(r, half ? x : x + 1, half ? y + 1 : y);
}

/* The sides of the slab along the grid's edges, between neighbouring
 * edge vertices (with cells without data: under the drawn triangles). */
static void draw_skirt(struct target *t, const struct ss_render_raster *r,
                       const struct camera *c, const struct ss_render_light *light,
                       const struct vtx *v, int any_nodata)
{
	const int W = r->width, H = r->height;
	/* edges: south (y = H-1, normal -y), north (y = 0, +y), west, east */
	for (int side = 0; side < 4; side++) {
		const int along_x = side < 2, n = along_x ? W : H;
		const double nx = side == 2 ? -1.0 : side == 3 ? 1.0 : 0.0;
		const double ny = side == 0 ? -1.0 : side == 1 ? 1.0 : 0.0;
		const double b = face_light(light, nx, ny, 0.0);
		for (int s = 0; s + 1 < n; s++) {
			const int x0 = along_x ? s : side == 2 ? 0 : W - 1;
			const int y0 = along_x ? (side == 0 ? H - 1 : 0) : s;
			const int x1 = along_x ? s + 1 : x0, y1 = along_x ? y0 : s + 1;
			const size_t k0 = (size_t)y0 * W + x0, k1 = (size_t)y1 * W + x1;
			if (r->type[k0] == SS_CELL_WALL && r->type[k1] == SS_CELL_WALL)
				continue;
			/* the triangle on the edge: south and west ones are the
			 * south-west halves of their squares */
			if (any_nodata && !triangle_drawn(r, along_x ? s : side == 2 ? 0 : W - 2,
			                                  along_x ? (side == 0 ? H - 2 : 0) : s,
			                                  side == 0 || side == 2))
				continue;
			const struct vtx *a = &v[k0], *d = &v[k1];
			const struct vtx b0 = make_vtx(c, (x0 + 0.5) * r->px_dx, (H - y0 - 0.5) * r->px_dy,
			                               c->z_floor, skirt_rgb, b);
			const struct vtx b1 = make_vtx(c, (x1 + 0.5) * r->px_dx, (H - y1 - 0.5) * r->px_dy,
			                               c->z_floor, skirt_rgb, b);
			struct vtx ta = *a, td = *d;   /* the top edge in the skirt's colour */
			for (int ch = 0; ch < 3; ch++)
				ta.c[ch] = td.c[ch] = (uint8_t)(skirt_rgb[ch] * b + 0.5);
			if (outside_band(t, fminf(fminf(ta.y, td.y), fminf(b0.y, b1.y)),
			                 fmaxf(fmaxf(ta.y, td.y), fmaxf(b0.y, b1.y))))
				continue;
			draw_quad(t, &ta, &td, &b1, &b0);
		}
	}
}

/* A block over [x0, x1] x [y0, y1] from the base up to zt (m): its top,
 * and the sides in `sides` (bit s: south, east, north, west for s =
 * 0..3). */
static void draw_block(struct target *t, const struct camera *c,
                       const struct ss_render_light *light, double x0, double x1, double y0,
                       double y1, double zt, unsigned sides)
{
	const double zb = c->z_floor;
	struct vtx top[4], bot[4];
	const double bt = face_light(light, 0, 0, 1);
	const double xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
	for (int k = 0; k < 4; k++) {
		top[k] = make_vtx(c, xs[k], ys[k], zt, wall_rgb, bt);
		bot[k] = make_vtx(c, xs[k], ys[k], zb, wall_rgb, 1.0);
	}
	/* quick reject on the projection of the whole block */
	float lo = top[0].y, hi = top[0].y;
	for (int k = 0; k < 4; k++) {
		lo = fminf(lo, fminf(top[k].y, bot[k].y));
		hi = fmaxf(hi, fmaxf(top[k].y, bot[k].y));
	}
	if (outside_band(t, lo, hi))
		return;
	draw_quad(t, &top[0], &top[1], &top[2], &top[3]);
	static const double normal[4][2] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
	for (int s = 0; s < 4; s++) {
		if (!(sides & 1u << s))
			continue;
		const double b = face_light(light, normal[s][0], normal[s][1], 0.0);
		struct vtx a = top[s], d = top[(s + 1) & 3], p = bot[(s + 1) & 3], q = bot[s];
		for (int ch = 0; ch < 3; ch++) {
			const uint8_t v = (uint8_t)(wall_rgb[ch] * b + 0.5);
			a.c[ch] = d.c[ch] = p.c[ch] = q.c[ch] = v;
		}
		draw_quad(t, &a, &d, &p, &q);
	}
}

/* The walls of a frame: top[label[k]] (m) for wall pixel k, and the scene
 * heights of the surface along each grid side that is a wall (edge_z[side],
 * from its south or west end). */
struct wall_tops {
	int *label;                 /* width * height; -1: not a wall */
	double *top;
	int n_walls;
	double *edge_z[4];
};

/* A block up to zt (m) on wall pixel (x, y), with sides facing non-walls. */
static void draw_wall(struct target *t, const struct ss_render_raster *r,
                      const struct camera *c, const struct ss_render_light *light, int x,
                      int y, double zt)
{
	const int W = r->width, H = r->height;
	static const int nb[4][2] = {{0, 1}, {1, 0}, {0, -1}, {-1, 0}};   /* S E N W */
	unsigned sides = 0;
	for (int s = 0; s < 4; s++) {
		const int xn = x + nb[s][0], yn = y + nb[s][1];
		if (!(xn >= 0 && yn >= 0 && xn < W && yn < H &&
		      r->type[(size_t)yn * W + xn] == SS_CELL_WALL))
			sides |= 1u << s;
	}
	draw_block(t, c, light, x * r->px_dx, (x + 1) * r->px_dx, (H - y - 1) * r->px_dy,
	           (H - y) * r->px_dy, zt, sides);
}

/* A quad of one colour: the face of normal n. */
static void draw_face(struct target *t, const struct camera *c,
                      const struct ss_render_light *light, double p[4][3], double nx,
                      double ny, double nz)
{
	const double b = face_light(light, nx, ny, nz);
	struct vtx v[4];
	float lo = INFINITY, hi = -INFINITY;
	for (int k = 0; k < 4; k++) {
		v[k] = make_vtx(c, p[k][0], p[k][1], p[k][2], wall_rgb, b);
		lo = fminf(lo, v[k].y);
		hi = fmaxf(hi, v[k].y);
	}
	if (!outside_band(t, lo, hi))
		draw_quad(t, &v[0], &v[1], &v[2], &v[3]);
}

/*
 * The wall along a grid side that is a wall: a strip wall_m thick outside
 * the surface's outermost vertices (half a pixel inside the grid, so no
 * gap shows), whose top follows the sand along the edge WALL_RISE of the
 * range above it.  A terrain's edge (relax's sides are walls) then stays
 * in view behind a low lip instead of behind a wall as tall as its
 * highest point.  The west and east strips run on over the corners of a
 * south or north wall.
 */
static void draw_wall_side(struct target *t, const struct ss_render_raster *r,
                           const struct camera *c, const struct ss_render_light *light,
                           const double *edge_z, int side)
{
	const int W = r->width, H = r->height, along_x = side >= SS_SOUTH;
	const int n = along_x ? W : H;
	const double *m = r->wall_m;
	const double hx = 0.5 * r->px_dx, hy = 0.5 * r->px_dy;
	const double lx = W * r->px_dx, ly = H * r->px_dy;
	/* the inner line and the outward direction */
	const double in = side == SS_WEST ? hx : side == SS_EAST ? lx - hx
	                : side == SS_SOUTH ? hy : ly - hy;
	const double out = side == SS_WEST || side == SS_SOUTH ? -1.0 : 1.0;
	const double range = c->z_wall / (1.0 + WALL_RISE);   /* the scale, zscale'd */
	/* along the side: first and last pixel centres, extended over corners */
	const double step = along_x ? r->px_dx : r->px_dy;
	const double a0 = 0.5 * step - (along_x ? 0.0 : m[SS_SOUTH]);
	const double a1 = (n - 0.5) * step + (along_x ? 0.0 : m[SS_NORTH]);
	double a_0 = 0.0, t0 = 0.0, s0 = 0.0;   /* along, top, sand of the previous point */
	for (int k = -1; k <= n; k++) {
		const int e = k < 0 ? 0 : k >= n ? n - 1 : k;
		const double a = k < 0 ? a0 : k >= n ? a1 : (k + 0.5) * step;
		const double zs = edge_z[e];
		const double zt = fmin(zs + WALL_RISE * range, c->z_wall);
		if (k > -1 && a > a_0) {
			double q[4][3];
#define AT(i, u, v, z) (q[i][0] = along_x ? (u) : (v), q[i][1] = along_x ? (v) : (u), \
			q[i][2] = (z))
			/* top */
			AT(0, a_0, in, t0), AT(1, a, in, zt), AT(2, a, in + out * m[side], zt),
			AT(3, a_0, in + out * m[side], t0);
			draw_face(t, c, light, q, 0.0, 0.0, 1.0);
			/* outer face, down to the base */
			AT(0, a_0, in + out * m[side], t0), AT(1, a, in + out * m[side], zt),
			AT(2, a, in + out * m[side], c->z_floor), AT(3, a_0, in + out * m[side], c->z_floor);
			draw_face(t, c, light, q, along_x ? 0.0 : out, along_x ? out : 0.0, 0.0);
			/* inner face, down to the sand */
			AT(0, a_0, in, t0), AT(1, a, in, zt), AT(2, a, in, zs), AT(3, a_0, in, s0);
			draw_face(t, c, light, q, along_x ? 0.0 : -out, along_x ? -out : 0.0, 0.0);
#undef AT
		}
		a_0 = a, t0 = zt, s0 = zs;
	}
	/* the two ends, closed from the top to the base */
	for (int end = 0; end < 2; end++) {
		const double a = end ? a1 : a0;
		const double zt = fmin(edge_z[end ? n - 1 : 0] + WALL_RISE * range, c->z_wall);
		double q[4][3];
		const double u[4] = {a, a, a, a}, v[4] = {in, in + out * m[side], in + out * m[side], in};
		const double z[4] = {zt, zt, c->z_floor, c->z_floor};
		for (int k = 0; k < 4; k++) {
			q[k][0] = along_x ? u[k] : v[k];
			q[k][1] = along_x ? v[k] : u[k];
			q[k][2] = z[k];
		}
		const double dir = end ? 1.0 : -1.0;
		draw_face(t, c, light, q, along_x ? dir : 0.0, along_x ? 0.0 : dir, 0.0);
	}
}

/* The slab's side under the surface edge from vertex (x0, y0) to (x1, y1),
 * its outer normal (nx, ny) on the map (x east, y north). */
static void draw_skirt_edge(struct target *t, const struct ss_render_raster *r,
                            const struct camera *c, const struct ss_render_light *light,
                            const struct vtx *v, int x0, int y0, int x1, int y1, double nx,
                            double ny)
{
	const int W = r->width, H = r->height;
	const double b = face_light(light, nx, ny, 0.0);
	struct vtx ta = v[(size_t)y0 * W + x0], td = v[(size_t)y1 * W + x1];
	for (int ch = 0; ch < 3; ch++)
		ta.c[ch] = td.c[ch] = (uint8_t)(skirt_rgb[ch] * b + 0.5);
	const struct vtx b0 = make_vtx(c, (x0 + 0.5) * r->px_dx, (H - y0 - 0.5) * r->px_dy,
	                               c->z_floor, skirt_rgb, b);
	const struct vtx b1 = make_vtx(c, (x1 + 0.5) * r->px_dx, (H - y1 - 0.5) * r->px_dy,
	                               c->z_floor, skirt_rgb, b);
	if (outside_band(t, fminf(fminf(ta.y, td.y), fminf(b0.y, b1.y)),
	                 fmaxf(fmaxf(ta.y, td.y), fmaxf(b0.y, b1.y))))
		return;
	draw_quad(t, &ta, &td, &b1, &b0);
}

/* The skirt along the edges between drawn triangles and cells without
 * data inside the grid (draw_skirt does the grid's own edges): each edge
 * of a drawn triangle whose neighbour across it is not drawn. */
static void draw_outline_skirt(struct target *t, const struct ss_render_raster *r,
                               const struct camera *c, const struct ss_render_light *light,
                               const struct vtx *v)
{
	const int W = r->width, H = r->height;
	const double s = sqrt(0.5);
	for (int y = 0; y + 1 < H; y++)
		for (int x = 0; x + 1 < W; x++) {
			if (triangle_drawn(r, x, y, 0)) {   /* a b e: north, east, diagonal */
				if (y > 0 && !triangle_drawn(r, x, y - 1, 1))
					draw_skirt_edge(t, r, c, light, v, x, y, x + 1, y, 0.0, 1.0);
				if (x + 2 < W && !triangle_drawn(r, x + 1, y, 1))
					draw_skirt_edge(t, r, c, light, v, x + 1, y, x + 1, y + 1, 1.0, 0.0);
				if (!triangle_drawn(r, x, y, 1))
					draw_skirt_edge(t, r, c, light, v, x, y, x + 1, y + 1, -s, -s);
			}
			if (triangle_drawn(r, x, y, 1)) {   /* a e d: south, west, diagonal */
				if (y + 2 < H && !triangle_drawn(r, x, y + 1, 0))
					draw_skirt_edge(t, r, c, light, v, x, y + 1, x + 1, y + 1, 0.0, -1.0);
				if (x > 0 && !triangle_drawn(r, x - 1, y, 0))
					draw_skirt_edge(t, r, c, light, v, x, y, x, y + 1, -1.0, 0.0);
				if (!triangle_drawn(r, x, y, 0))
					draw_skirt_edge(t, r, c, light, v, x, y, x + 1, y + 1, s, s);
			}
		}
}

static void draw_band(struct target *t, const struct ss_render_raster *r,
                      const struct camera *c, const struct ss_render_light *light,
                      const struct vtx *v, const struct wall_tops *tops, int any_nodata)
{
	const int W = r->width, H = r->height;
	for (int y = 0; y + 1 < H; y++)
		for (int x = 0; x + 1 < W; x++) {
			const struct vtx *a = &v[(size_t)y * W + x], *b = a + 1;
			const struct vtx *d = a + W, *e = d + 1;
			const float lo = fminf(fminf(a->y, b->y), fminf(d->y, e->y));
			const float hi = fmaxf(fmaxf(a->y, b->y), fmaxf(d->y, e->y));
			if (outside_band(t, lo, hi))
				continue;
			if (!any_nodata) {
				draw_quad(t, a, b, e, d);
				continue;
			}
			if (triangle_drawn(r, x, y, 0))
				draw_triangle(t, a, b, e);
			if (triangle_drawn(r, x, y, 1))
				draw_triangle(t, a, e, d);
		}
	draw_skirt(t, r, c, light, v, any_nodata);
	if (any_nodata)
		draw_outline_skirt(t, r, c, light, v);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			const size_t k = (size_t)y * W + x;
			if (r->type[k] == SS_CELL_WALL)
				draw_wall(t, r, c, light, x, y, tops->top[tops->label[k]]);
		}
	for (int side = 0; side < 4; side++)
		if (tops->edge_z[side])
			draw_wall_side(t, r, c, light, tops->edge_z[side], side);
}

static void wall_tops_release(struct wall_tops *w)
{
	ss_free(w->label);
	ss_free(w->top);
	for (int side = 0; side < 4; side++)
		ss_free(w->edge_z[side]);
	memset(w, 0, sizeof *w);
}

/* Raise a top to sand height v (m) if v is sand, finite and higher. */
static inline void touch(double *top, double v)
{
	if (v > *top)   /* NaN is never higher */
		*top = v;
}

/*
 * The walls of a frame and their tops: the 4-connected sets of wall
 * pixels (a flood fill with a stack), each as tall as the highest sand
 * among the 8 neighbours of its pixels, the grid sides as the highest sand
 * along them; then WALL_RISE of the range above that, in scene heights,
 * at most the framing's top.  Serial: a fill does not split into rows.
 */
static int wall_tops_init(struct wall_tops *w, const struct ss_render_raster *r,
                          const struct ss_render_options *o, const struct camera *c,
                          double zmin, double zmax)
{
	const int W = r->width, H = r->height;
	const size_t n = (size_t)W * H;
	memset(w, 0, sizeof *w);
	int *stack = ss_alloc(n, sizeof *stack, "wall fill stack");
	w->label = ss_alloc(n, sizeof *w->label, "wall labels");
	if (!stack || !w->label) {
		ss_free(stack);
		wall_tops_release(w);
		return SS_ERR_FAIL;
	}
	for (size_t k = 0; k < n; k++)
		w->label[k] = -1;
	for (size_t k = 0; k < n; k++) {
		if (r->type[k] != SS_CELL_WALL || w->label[k] >= 0)
			continue;
		size_t top = 0;
		stack[top++] = (int)k;
		w->label[k] = w->n_walls;
		while (top) {
			const int m = stack[--top], x = m % W, y = m / W;
			static const int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
			for (int d = 0; d < 4; d++) {
				const int xn = x + nb[d][0], yn = y + nb[d][1];
				if (xn < 0 || yn < 0 || xn >= W || yn >= H)
					continue;
				const size_t q = (size_t)yn * W + xn;
				if (r->type[q] == SS_CELL_WALL && w->label[q] < 0) {
					w->label[q] = w->n_walls;
					stack[top++] = (int)q;
				}
			}
		}
		w->n_walls++;
	}
	ss_free(stack);
	w->top = ss_alloc((size_t)w->n_walls + 1, sizeof *w->top, "wall tops");
	int err = w->top ? SS_OK : SS_ERR_FAIL;
	for (int side = 0; side < 4 && !err; side++)
		if (r->wall_m[side] > 0.0 &&
		    !(w->edge_z[side] = ss_alloc(side < 2 ? H : W, sizeof *w->edge_z[side],
		                                 "wall side heights")))
			err = SS_ERR_FAIL;
	if (err) {
		wall_tops_release(w);
		return err;
	}
	const double base = zmin - BASE_DEPTH * (zmax - zmin);
	for (int side = 0; side < 4; side++)
		for (int k = 0; w->edge_z[side] && k < (side < 2 ? H : W); k++) {
			const int x = side == SS_WEST ? 0 : side == SS_EAST ? W - 1 : k;
			const int y = side < 2 ? H - 1 - k : side == SS_SOUTH ? H - 1 : 0;
			w->edge_z[side][k] = o->zscale * (mesh_height(r, x, y, base) - zmin);
		}
	for (int k = 0; k < w->n_walls; k++)
		w->top[k] = -INFINITY;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			const size_t k = (size_t)y * W + x;
			if (ss_render_no_sand(r->type[k]))
				continue;
			const double v = ss_render_raster_h(r, x, y);
			for (int b = -1; b <= 1; b++)
				for (int a = -1; a <= 1; a++) {
					const int xn = x + a, yn = y + b;
					if (xn < 0 || yn < 0 || xn >= W || yn >= H)
						continue;
					const int label = w->label[(size_t)yn * W + xn];
					if (label >= 0)
						touch(&w->top[label], v);
				}
		}
	const double range = o->zscale * (zmax - zmin);
	for (int k = 0; k < w->n_walls; k++) {
		const double h = isfinite(w->top[k]) ? fmax(fmin(w->top[k], zmax), zmin) : zmin;
		w->top[k] = fmin(o->zscale * (h - zmin) + WALL_RISE * range, c->z_wall);
	}
	return SS_OK;
}

int ss_render_oblique(const struct ss_render_raster *r, const struct ss_render_options *o,
                      double zmin, double zmax, struct ss_render_image *img, int parallel)
{
	struct camera c;
	camera_init(&c, r, o, zmin, zmax);
	if (img->width < c.width || img->height != c.height)
		SS_BUG("oblique picture %d x %d, camera %d x %d", img->width, img->height, c.width,
		       c.height);
	const size_t n = (size_t)r->width * r->height;
	struct wall_tops tops;
	if (wall_tops_init(&tops, r, o, &c, zmin, zmax))
		return SS_ERR_FAIL;
	struct vtx *v = ss_alloc(n, sizeof *v, "oblique vertices");
	float *depth = ss_alloc((size_t)img->width * img->height, sizeof *depth, "depth buffer");
	if (!v || !depth) {
		ss_free(v);
		ss_free(depth);
		wall_tops_release(&tops);
		return SS_ERR_FAIL;
	}
	for (int y = 0; y < img->height; y++)   /* the sky */
		memset(img->pixels + (size_t)y * img->row_bytes, SS_RENDER_BACKGROUND,
		       3 * (size_t)c.width);
	surface_vertices(r, &c, o, zmin, zmax, v, parallel);
	int any_nodata = 0;
	for (size_t k = 0; k < n && !any_nodata; k++)
		any_nodata = r->type[k] == SS_RENDER_CELL_NODATA;
	struct ss_render_light light;
	ss_render_light_init(&light, o->azimuth_deg, o->altitude_deg, o->zscale);

	/* bands of rows: several per thread so uneven bands balance out */
	const int threads = parallel ? ss_parallel_max_threads() : 1;
	const int bands = threads > 1 ? 4 * threads : 1;
	const int rows = (img->height + bands - 1) / bands;
	#pragma omp parallel for schedule(dynamic, 1) if(parallel)
	for (int band = 0; band < bands; band++) {
		struct target t = {img, depth, c.width, band * rows, (band + 1) * rows};
		if (t.y1 > img->height)
			t.y1 = img->height;
		if (t.y0 < t.y1)
			draw_band(&t, r, &c, &light, v, &tops, any_nodata);
	}
	ss_free(depth);
	ss_free(v);
	wall_tops_release(&tops);
	return SS_OK;
}
