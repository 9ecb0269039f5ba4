/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sweep_fast.c - the in-place sweep over active tiles (see sweep.h).
 *
 * Row buffers: in a tile of columns [i0, i1) (W = i1 - i0 cells) a buffer
 * holds cells i0 - 1 .. i1 at positions x = i - i0 + 1 = 0 .. W + 1.  fx[x],
 * x = 0 .. W, is the flux through the x-face between positions x and x + 1;
 * fy_south[x] and fy_north[x], x = 1 .. W, through the y-faces below and
 * above cell x.  The arithmetic of every face and cell is that of the
 * reference sweep (sweep.c): the same gradients in the same order, the same
 * face function (face.c), the same update expression.
 *
 * Compiled once per instruction-set path (core/cpu_paths.h): the functions
 * with loops over cells in every copy, named with the copy's suffix
 * (SS_PATH_FN); the set-up, and the public functions that call the copy of
 * the path in use once per call, in the generic copy only.  A copy calls
 * its own path's face flux.
 */
#include "core/sweep.h"

#include <math.h>
#include <string.h>

#include "core/cpu_paths.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

/* Packed cell types (grid.h): t is the packed array, k a storage index. */
static inline uint8_t type_at(const uint8_t *t, ptrdiff_t k)
{
	return (uint8_t)ss_cell_type_get(t, k);
}

/* ss_face_carries (sweep.h) for widened types, with the same truth table
 * but & and | for && and ||: a short-circuit is control flow, which stops
 * the row loops that call this from vectorising. */
static inline int64_t wide_carries(int64_t a, int64_t b)
{
	return (a != SS_CELL_WALL) & (b != SS_CELL_WALL) &
	       ((a == SS_CELL_FLOW) | (b == SS_CELL_FLOW));
}

/*
 * Maxima of values >= +0 (s^2, |dh/dt|) as integer maxima of their bit
 * patterns: for such doubles the unsigned order of the bits is the numeric
 * order, and every NaN lies above +infinity.  An integer max vectorises (a
 * floating-point one does not without -ffast-math), and a NaN wins it.
 */
static inline uint64_t bits_of(double x)
{
	uint64_t u;
	memcpy(&u, &x, sizeof u);
	return u;
}

static inline double double_of(uint64_t u)
{
	double x;
	memcpy(&x, &u, sizeof x);
	return x;
}

/* The maximum whose bits are m (0 for none); a NaN sets *bad. */
static inline double max_of_bits(uint64_t m, int *bad)
{
	const double max = double_of(m);
	*bad |= max != max;
	return max;
}

/*
 * The bits of s^2 of one face, between cells a and b = a + normal (0 if it
 * cannot carry flux): g_n over the face, g_t the mean of both cells'
 * central differences along it (neighbour offset `along`), a wall
 * neighbour replaced by the cell itself.  The expressions of the reference
 * sweep (sweep.c), for single faces; the row loops below spell them out so
 * that they vectorise.
 */
static inline uint64_t face_slope2_bits(const double *h, const uint8_t *t,
                                        ptrdiff_t a, ptrdiff_t normal, ptrdiff_t along,
                                        double inv_spacing, double inv_2along)
{
	const ptrdiff_t b = a + normal;
	const double cda = ((type_at(t, a + along) == SS_CELL_WALL ? h[a] : h[a + along]) -
	                    (type_at(t, a - along) == SS_CELL_WALL ? h[a] : h[a - along])) *
	                   inv_2along;
	const double cdb = ((type_at(t, b + along) == SS_CELL_WALL ? h[b] : h[b + along]) -
	                    (type_at(t, b - along) == SS_CELL_WALL ? h[b] : h[b - along])) *
	                   inv_2along;
	const double gn = (h[b] - h[a]) * inv_spacing, gt = 0.5 * (cda + cdb);
	return ss_face_carries(type_at(t, a), type_at(t, b)) ? bits_of(gn * gn + gt * gt) : 0;
}

/* The larger of a and b as a select (fmax() is a library call). */
static inline double max2(double a, double b)
{
	return b > a ? b : a;
}

/* Packed types of cells k .. k + n - 1 widened to 64 bits (n <= TYPE_CHUNK
 * + 2): the border measures below work on chunks of this many cells. */
enum { TYPE_CHUNK = 256 };

static inline void unpack_wide(const uint8_t *restrict t, ptrdiff_t k, int n,
                               int64_t *restrict out)
{
	for (int x = 0; x < n; x++)
		out[x] = type_at(t, k + x);
}

/*
 * Largest s^2 of the x-faces (i - 1 | i), ia <= i <= ib, of row j, read
 * from the grid (the rows j - 1 .. j + 1 must hold one state).
 *
 * slope2_x_faces and slope2_y_faces are one measure along the two axes,
 * written twice on purpose: each spells its stencil with fixed offsets
 * (x: three rows, neighbours in the row above and below; y: two rows,
 * neighbours left and right) so that its loops vectorise on contiguous
 * loads, as the tile kernel spells its x- and y-face loops apart.
 */
static double slope2_x_faces(const struct ss_grid *g, const double *h,
                             const uint8_t *t, int plain, int j, int ia, int ib,
                             int *bad)
{
	const double inv_dx = 1.0 / g->dx, inv_2dy = 0.5 / g->dy;
	const ptrdiff_t km = ss_grid_index(g, 0, j - 1), k0 = km + g->stride, kp = k0 + g->stride;
	const double *hm = h + km, *h0 = h + k0, *hp = h + kp;
	uint64_t m = 0;
	if (plain) {
		/* g_n = (h[i] - h[i-1]) / dx, g_t = (cd_y[i-1] + cd_y[i]) / 2 */
		for (int i = ia; i <= ib; i++) {
			const double cda = (hp[i - 1] - hm[i - 1]) * inv_2dy;
			const double cdb = (hp[i] - hm[i]) * inv_2dy;
			const double gn = (h0[i] - h0[i - 1]) * inv_dx, gt = 0.5 * (cda + cdb);
			const uint64_t q = bits_of(gn * gn + gt * gt);
			m = q > m ? q : m;
		}
	} else {
		/* a chunk of packed types at a time, widened so the loop
		 * vectorises (as in the tile rows) */
		int64_t tm[TYPE_CHUNK + 2], t0[TYPE_CHUNK + 2], tp[TYPE_CHUNK + 2];
		for (int c0 = ia; c0 <= ib; c0 += TYPE_CHUNK) {
			const int c1 = ib - c0 < TYPE_CHUNK ? ib : c0 + TYPE_CHUNK - 1;
			const int n = c1 - c0 + 2;   /* cells c0 - 1 .. c1 */
			unpack_wide(t, km + c0 - 1, n, tm);
			unpack_wide(t, k0 + c0 - 1, n, t0);
			unpack_wide(t, kp + c0 - 1, n, tp);
			const double *hm_c = hm + c0 - 1, *h0_c = h0 + c0 - 1, *hp_c = hp + c0 - 1;
			for (int x = 1; x < n; x++) {
				const double cda = ((tp[x - 1] == SS_CELL_WALL ? h0_c[x - 1] : hp_c[x - 1]) -
				                    (tm[x - 1] == SS_CELL_WALL ? h0_c[x - 1] : hm_c[x - 1])) *
				                   inv_2dy;
				const double cdb = ((tp[x] == SS_CELL_WALL ? h0_c[x] : hp_c[x]) -
				                    (tm[x] == SS_CELL_WALL ? h0_c[x] : hm_c[x])) * inv_2dy;
				const double gn = (h0_c[x] - h0_c[x - 1]) * inv_dx, gt = 0.5 * (cda + cdb);
				const uint64_t q = wide_carries(t0[x - 1], t0[x])
				                   ? bits_of(gn * gn + gt * gt) : 0;
				m = q > m ? q : m;
			}
		}
	}
	return max_of_bits(m, bad);
}

/* Largest s^2 of the y-faces (j - 1 | j) of cells ia <= i <= ib. */
static double slope2_y_faces(const struct ss_grid *g, const double *h,
                             const uint8_t *t, int plain, int j, int ia, int ib,
                             int *bad)
{
	const double inv_dy = 1.0 / g->dy, inv_2dx = 0.5 / g->dx;
	const ptrdiff_t ka = ss_grid_index(g, 0, j - 1), kb = ka + g->stride;
	const double *ha = h + ka, *hb = h + kb;
	uint64_t m = 0;
	if (plain) {
		/* g_n = (h[i, j] - h[i, j-1]) / dy, g_t = (cd_x[i, j-1] + cd_x[i, j]) / 2 */
		for (int i = ia; i <= ib; i++) {
			const double cda = (ha[i + 1] - ha[i - 1]) * inv_2dx;
			const double cdb = (hb[i + 1] - hb[i - 1]) * inv_2dx;
			const double gn = (hb[i] - ha[i]) * inv_dy, gt = 0.5 * (cda + cdb);
			const uint64_t q = bits_of(gn * gn + gt * gt);
			m = q > m ? q : m;
		}
	} else {
		int64_t ta[TYPE_CHUNK + 2], tb[TYPE_CHUNK + 2];
		for (int c0 = ia; c0 <= ib; c0 += TYPE_CHUNK) {
			const int c1 = ib - c0 < TYPE_CHUNK ? ib : c0 + TYPE_CHUNK - 1;
			const int n = c1 - c0 + 3;   /* cells c0 - 1 .. c1 + 1 */
			unpack_wide(t, ka + c0 - 1, n, ta);
			unpack_wide(t, kb + c0 - 1, n, tb);
			const double *ha_c = ha + c0 - 1, *hb_c = hb + c0 - 1;
			for (int x = 1; x < n - 1; x++) {
				const double cda = ((ta[x + 1] == SS_CELL_WALL ? ha_c[x] : ha_c[x + 1]) -
				                    (ta[x - 1] == SS_CELL_WALL ? ha_c[x] : ha_c[x - 1])) *
				                   inv_2dx;
				const double cdb = ((tb[x + 1] == SS_CELL_WALL ? hb_c[x] : hb_c[x + 1]) -
				                    (tb[x - 1] == SS_CELL_WALL ? hb_c[x] : hb_c[x - 1])) *
				                   inv_2dx;
				const double gn = (hb_c[x] - ha_c[x]) * inv_dy, gt = 0.5 * (cda + cdb);
				const uint64_t q = wide_carries(ta[x], tb[x]) ? bits_of(gn * gn + gt * gt) : 0;
				m = q > m ? q : m;
			}
		}
	}
	return max_of_bits(m, bad);
}

/*
 * In a plain tile, the largest s^2 of the x-faces (i - 1 | i) of row j - 1
 * and the y-faces (j - 1 | j) of cells i, ia <= i <= ib, in one pass (the
 * interior measure behind the update; rows j - 2 .. j must be new).  The
 * same expressions as slope2_x_faces and slope2_y_faces.
 */
static double slope2_plain_pair(const struct ss_grid *g, const double *h, int j,
                                int ia, int ib, int *bad)
{
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	const double *ha = h + ss_grid_index(g, 0, j - 2);
	const double *hb = h + ss_grid_index(g, 0, j - 1);
	const double *hc = h + ss_grid_index(g, 0, j);
	uint64_t m = 0;
	for (int i = ia; i <= ib; i++) {
		const double cda = (hc[i - 1] - ha[i - 1]) * inv_2dy;
		const double cdb = (hc[i] - ha[i]) * inv_2dy;
		const double gnx = (hb[i] - hb[i - 1]) * inv_dx, gtx = 0.5 * (cda + cdb);
		const double cxb = (hb[i + 1] - hb[i - 1]) * inv_2dx;
		const double cxc = (hc[i + 1] - hc[i - 1]) * inv_2dx;
		const double gny = (hc[i] - hb[i]) * inv_dy, gty = 0.5 * (cxb + cxc);
		const uint64_t qx = bits_of(gnx * gnx + gtx * gtx);
		const uint64_t qy = bits_of(gny * gny + gty * gty);
		const uint64_t q = qx > qy ? qx : qy;
		m = q > m ? q : m;
	}
	return max_of_bits(m, bad);
}

/*
 * Largest s^2 of the x-faces (i_x - 1 | i_x) of rows ja .. jb - 1 and the
 * y-faces (j - 1 | j) of cell i_y, ja <= j <= jb: a column of a tile's west
 * or east edge in one loop (the same expressions as slope2_x_faces and
 * slope2_y_faces).
 */
static double slope2_column(const struct ss_grid *g, const double *h,
                            const uint8_t *t, int plain, int i_x, int i_y, int ja,
                            int jb, int *bad)
{
	const ptrdiff_t s = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	uint64_t m = 0;
	if (plain) {
		/* no walls near: face_slope2_bits without the types */
		for (int j = ja; j <= jb; j++) {
			const double *c = h + ss_grid_index(g, i_y, j), *b = c - s;
			const double gn = (c[0] - b[0]) * inv_dy;
			const double gt = 0.5 * ((b[1] - b[-1]) * inv_2dx + (c[1] - c[-1]) * inv_2dx);
			uint64_t q = bits_of(gn * gn + gt * gt);
			m = q > m ? q : m;
			if (j < jb) {
				const double *e = h + ss_grid_index(g, i_x, j), *w = e - 1;
				const double gnx = (e[0] - w[0]) * inv_dx;
				const double gtx = 0.5 * ((w[s] - w[-s]) * inv_2dy + (e[s] - e[-s]) * inv_2dy);
				q = bits_of(gnx * gnx + gtx * gtx);
				m = q > m ? q : m;
			}
		}
		return max_of_bits(m, bad);
	}
	for (int j = ja; j <= jb; j++) {
		uint64_t q = face_slope2_bits(h, t, ss_grid_index(g, i_y, j) - s, s, 1,
		                              inv_dy, inv_2dx);
		m = q > m ? q : m;
		if (j < jb) {
			q = face_slope2_bits(h, t, ss_grid_index(g, i_x, j) - 1, 1, s, inv_dx,
			                     inv_2dy);
			m = q > m ? q : m;
		}
	}
	return max_of_bits(m, bad);
}

/*
 * The same in a tile with walls or open cells, from the tile's widened type
 * rows ta, tb, tc of rows j - 2 .. j (by buffer position x = i - i0 + 1),
 * positions xa .. xb.
 */
static double slope2_mixed_pair(const struct ss_grid *g, const double *h, int j,
                                int i0, int xa, int xb, const int64_t *restrict ta,
                                const int64_t *restrict tb, const int64_t *restrict tc,
                                int *bad)
{
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	/* rows by position: cell i0 - 1 + x */
	const double *ha = h + ss_grid_index(g, i0 - 1, j - 2);
	const double *hb = h + ss_grid_index(g, i0 - 1, j - 1);
	const double *hc = h + ss_grid_index(g, i0 - 1, j);
	uint64_t m = 0;
	for (int x = xa; x <= xb; x++) {
		/* x-face (x - 1 | x) of row j - 1 */
		const double cda = ((tc[x - 1] == SS_CELL_WALL ? hb[x - 1] : hc[x - 1]) -
		                    (ta[x - 1] == SS_CELL_WALL ? hb[x - 1] : ha[x - 1])) * inv_2dy;
		const double cdb = ((tc[x] == SS_CELL_WALL ? hb[x] : hc[x]) -
		                    (ta[x] == SS_CELL_WALL ? hb[x] : ha[x])) * inv_2dy;
		const double gnx = (hb[x] - hb[x - 1]) * inv_dx, gtx = 0.5 * (cda + cdb);
		const int64_t cx = wide_carries(tb[x - 1], tb[x]);
		/* y-face (j - 1 | j) of position x */
		const double cxb = ((tb[x + 1] == SS_CELL_WALL ? hb[x] : hb[x + 1]) -
		                    (tb[x - 1] == SS_CELL_WALL ? hb[x] : hb[x - 1])) * inv_2dx;
		const double cxc = ((tc[x + 1] == SS_CELL_WALL ? hc[x] : hc[x + 1]) -
		                    (tc[x - 1] == SS_CELL_WALL ? hc[x] : hc[x - 1])) * inv_2dx;
		const double gny = (hc[x] - hb[x]) * inv_dy, gty = 0.5 * (cxb + cxc);
		const int64_t cy = wide_carries(tb[x], tc[x]);
		const uint64_t qx = cx ? bits_of(gnx * gnx + gtx * gtx) : 0;
		const uint64_t qy = cy ? bits_of(gny * gny + gty * gty) : 0;
		const uint64_t q = qx > qy ? qx : qy;
		m = q > m ? q : m;
	}
	return max_of_bits(m, bad);
}

/* Largest s^2 over every face of the grid that can carry flux. */
static double slope2_all(const struct ss_grid *g, const double *h,
                         const uint8_t *t, int *bad)
{
	double m = 0.0;
	int nan = 0;
	#pragma omp parallel for schedule(static) reduction(max:m) reduction(|:nan)
	for (int j = 0; j <= g->ny; j++) {
		double q = slope2_y_faces(g, h, t, 0, j, 0, g->nx - 1, &nan);
		if (j < g->ny)
			q = max2(q, slope2_x_faces(g, h, t, 0, j, 0, g->nx, &nan));
		m = q > m ? q : m;
	}
	*bad |= nan;
	return m;
}

double SS_PATH_FN(ss_sweep_max_slope)(const struct ss_grid *g, const double *restrict height,
                                      const uint8_t *restrict cell_types)
{
	int bad = 0;
	const double m = slope2_all(g, height, cell_types, &bad);
	return bad ? NAN : sqrt(m);
}

/* 1 when the stencil of the face between a and a + normal (both cells and
 * their neighbours along the face) lies in sand thicker than `bare`: a
 * flow cell there holds more than bare above the bedrock b. */
static inline int stencil_in_sand(const double *h, const double *b, const uint8_t *t,
                                  ptrdiff_t a, ptrdiff_t normal, ptrdiff_t along,
                                  double bare)
{
	const ptrdiff_t cells[6] = {a, a + normal, a + along, a - along, a + normal + along,
	                            a + normal - along};
	int in_sand = 1;
	for (int m = 0; m < 6; m++)
		in_sand &= type_at(t, cells[m]) != SS_CELL_FLOW || h[cells[m]] - b[cells[m]] > bare;
	return in_sand;
}

double SS_PATH_FN(ss_sweep_max_sand_slope)(const struct ss_grid *g,
                                           const double *restrict height,
                                           const uint8_t *restrict cell_types,
                                           const double *restrict bedrock, double bare)
{
	const ptrdiff_t s = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	uint64_t m = 0;
	/* the x-faces (i - 1 | i) of rows 0 .. ny - 1, the y-faces (j - 1 | j)
	 * of columns 0 .. nx - 1, with the kernel's arithmetic (s^2 as bits) */
	#pragma omp parallel for schedule(static) reduction(max:m)
	for (int j = 0; j <= g->ny; j++) {
		for (int i = 0; i <= g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			uint64_t q = 0;
			if (j < g->ny && stencil_in_sand(height, bedrock, cell_types, k - 1, 1, s, bare))
				q = face_slope2_bits(height, cell_types, k - 1, 1, s, inv_dx, inv_2dy);
			if (i < g->nx && stencil_in_sand(height, bedrock, cell_types, k - s, s, 1, bare)) {
				const uint64_t y = face_slope2_bits(height, cell_types, k - s, s, 1, inv_dy,
				                                    inv_2dx);
				q = y > q ? y : q;
			}
			m = q > m ? q : m;
		}
	}
	int bad = 0;
	const double m2 = max_of_bits(m, &bad);
	return bad ? NAN : sqrt(m2);
}

#if SS_PATH == SS_PATH_GENERIC
double ss_sweep_face_sliding(const double *h, const uint8_t *t, ptrdiff_t a, ptrdiff_t normal,
                             ptrdiff_t along, double inv_spacing, double inv_2along,
                             const struct ss_closure *c, double *s2)
{
	*s2 = double_of(face_slope2_bits(h, t, a, normal, along, inv_spacing, inv_2along));
	const double s = sqrt(*s2), g_n = (h[a + normal] - h[a]) * inv_spacing;
	return s > 0.0 ? ss_closure_eval(c, s) * fabs(g_n) / s : 0.0;
}

/* f_d(s) |g_n| / s / f_tol_d of one face (ss_sweep_material_excess); 0 where it
 * carries nothing or lies on rock. */
static double face_excess(const double *h, const uint8_t *t, const uint16_t *material,
                          const struct ss_closure *materials, double slope_tol,
                          const double *bedrock, double bare, ptrdiff_t a, ptrdiff_t normal,
                          ptrdiff_t along, double inv_spacing, double inv_2along)
{
	if (bedrock && !stencil_in_sand(h, bedrock, t, a, normal, along, bare))
		return 0.0;
	const uint16_t d = ss_face_material(material, a, a + normal);
	const double tol_slope = materials[d].tan_cr + slope_tol;
	const double f_tol = slope_tol / sqrt(1.0 + tol_slope * tol_slope);   /* f_coulomb */
	/* the sliding flux across the face: a face beside a steeper material
	 * may be steeper than its own angle along the face (g_t) and still
	 * carry nothing across it */
	double s2;
	const double e = ss_sweep_face_sliding(h, t, a, normal, along, inv_spacing, inv_2along,
	                                       &materials[d], &s2) / f_tol;
	return s2 != s2 ? NAN : e;
}

double ss_sweep_material_excess(const struct ss_grid *g, const double *restrict height,
                                const uint8_t *restrict cell_types,
                                const uint16_t *restrict material,
                                const struct ss_closure *materials,
                                const double *restrict bedrock, double bare,
                                double slope_tol)
{
	const ptrdiff_t s = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	double worst = 0.0;
	int bad = 0;
	#pragma omp parallel for schedule(static) reduction(max:worst) reduction(|:bad)
	for (int j = 0; j <= g->ny; j++) {
		for (int i = 0; i <= g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			double e = 0.0, y = 0.0;
			if (j < g->ny)
				e = face_excess(height, cell_types, material, materials, slope_tol, bedrock,
				                bare, k - 1, 1, s, inv_dx, inv_2dy);
			if (i < g->nx)
				y = face_excess(height, cell_types, material, materials, slope_tol, bedrock,
				                bare, k - s, s, 1, inv_dy, inv_2dx);
			bad |= e != e || y != y;
			worst = fmax(worst, fmax(e, y));
		}
	}
	return bad ? NAN : worst;
}
#endif

/* ---- set-up ---------------------------------------------------------- */

static size_t row_doubles(const struct ss_tiling *t)
{
	return ((size_t)t->tile_nx + 2 + 7) / 8 * 8;   /* 64 B aligned rows */
}

#if SS_PATH == SS_PATH_GENERIC
/* The per-tile flags, ring rows, row buffers and open-face tables of f
 * (f->tiling, f->tiles and f->threads set). */
static int alloc_tables(struct ss_sweep_fast *f, const struct ss_grid *g,
                        size_t open_face_count)
{
	const struct ss_tiling *t = &f->tiling;
	const size_t tiles = (size_t)f->tiles;

	f->scratch_doubles = 17 * row_doubles(t) + 2 * (((size_t)t->tile_ny + 7) / 8 * 8);
	f->sweep = ss_alloc(tiles, 1, "tile flags");
	f->sweep_next = ss_alloc(tiles, 1, "tile flags");
	f->moving = ss_alloc(tiles, 1, "tile flags");
	f->edges_changed = ss_alloc(tiles, 1, "tile flags");
	f->plain = ss_alloc(tiles, 1, "tile flags");
	f->has_source = ss_alloc(tiles, 1, "tile flags");
	f->superstep_swept = ss_alloc(tiles, 1, "tile flags");
	f->moving_superstep = ss_alloc(tiles, 1, "tile flags");
	f->edges_superstep = ss_alloc(tiles, 1, "tile flags");
	f->swept_last = ss_alloc(tiles, 1, "tile flags");
	f->edges_out_south = ss_alloc((size_t)t->tiles_x, 1, "tile flags");
	f->edges_out_north = ss_alloc((size_t)t->tiles_x, 1, "tile flags");
	f->row_list = ss_alloc((size_t)t->tiles_y, sizeof *f->row_list, "tile rows");
	f->ring_south = ss_alloc((size_t)t->tiles_y * g->stride, sizeof(double), "ring rows");
	f->ring_north = ss_alloc((size_t)t->tiles_y * g->stride, sizeof(double), "ring rows");
	f->scratch = ss_alloc((size_t)f->threads * f->scratch_doubles, sizeof(double),
	                      "sweep row buffers");
	f->open_first = ss_alloc(tiles + 1, sizeof *f->open_first, "open faces");
	f->open_slots = ss_alloc(open_face_count ? open_face_count : 1,
	                         sizeof *f->open_slots, "open faces");
	if (!f->sweep || !f->sweep_next || !f->moving || !f->edges_changed || !f->plain ||
	    !f->has_source || !f->superstep_swept || !f->moving_superstep ||
	    !f->edges_superstep || !f->swept_last || !f->row_list ||
	    !f->edges_out_south || !f->edges_out_north || !f->ring_south || !f->ring_north ||
	    !f->scratch || !f->open_first || !f->open_slots)
		return SS_ERR_FAIL;
	return SS_OK;
}

/* Plain tiles: every cell of the tile and of its ring flows, so their row
 * loops need no types. */
static void mark_plain_tiles(struct ss_sweep_fast *f, const struct ss_grid *g,
                             const uint8_t *cell_types)
{
	const struct ss_tiling *t = &f->tiling;

	for (int ty = 0; ty < t->tiles_y; ty++) {
		for (int tx = 0; tx < t->tiles_x; tx++) {
			const struct ss_tile_span s = ss_tiling_span(t, g, tx, ty);
			int plain = 1;
			for (int j = s.j0 - 1; j <= s.j1 && plain; j++)
				for (int i = s.i0 - 1; i <= s.i1; i++)
					plain &= type_at(cell_types, ss_grid_index(g, i, j)) == SS_CELL_FLOW;
			f->plain[ty * t->tiles_x + tx] = (uint8_t)plain;
		}
	}
}

/* Open face m as the sweep finds it: the row and buffer position in the
 * tile of its flow cell, and which of the row's faces it is.  Returns that
 * tile. */
static size_t open_slot_of(const struct ss_tiling *t, const struct ss_grid *g,
                           const struct ss_open_face *o, size_t m,
                           struct ss_open_face_slot *slot)
{
	const ptrdiff_t stride = g->stride;
	const ptrdiff_t step = o->axis == 0 ? 1 : stride;
	/* the face is west (south) of o->index; the flow cell is the side
	 * positive flux leaves */
	const ptrdiff_t cell = o->sign > 0 ? o->index - step : o->index;
	const int i = (int)(cell % stride) - SS_GRID_GHOST;
	const int j = (int)(cell / stride) - SS_GRID_GHOST;
	const int tx = i / t->tile_nx, ty = j / t->tile_ny;
	const int i0 = tx * t->tile_nx;

	slot->face = m;
	slot->j = j;
	if (o->axis == 0) {
		const int i_east = (int)(o->index % stride) - SS_GRID_GHOST;
		slot->which = 0;
		slot->x = i_east - i0;
	} else {
		slot->which = o->sign > 0 ? 2 : 1;
		slot->x = i - i0 + 1;
	}
	return (size_t)ty * t->tiles_x + tx;
}

/* The open faces into f->open_slots grouped by tile, f->open_first[t] ..
 * f->open_first[t + 1] those of tile t: a counting sort, stable, so each
 * tile's stay in row order (the ledger's list is). */
static int sort_open_slots(struct ss_sweep_fast *f, const struct ss_grid *g,
                           const struct ss_open_face *open_faces, size_t count)
{
	const size_t n = count ? count : 1, tiles = (size_t)f->tiles;
	struct ss_open_face_slot *slots = ss_alloc(n, sizeof *slots, "open faces");
	size_t *tile_of = ss_alloc(n, sizeof *tile_of, "open faces");
	size_t *fill = ss_alloc(tiles, sizeof *fill, "open faces");
	int status = SS_ERR_FAIL;

	if (!slots || !tile_of || !fill)
		goto out_free;
	for (size_t m = 0; m < count; m++) {
		tile_of[m] = open_slot_of(&f->tiling, g, &open_faces[m], m, &slots[m]);
		f->open_first[tile_of[m] + 1]++;
	}
	for (size_t k = 0; k < tiles; k++)
		f->open_first[k + 1] += f->open_first[k];
	for (size_t m = 0; m < count; m++)
		f->open_slots[f->open_first[tile_of[m]] + fill[tile_of[m]]++] = slots[m];
	status = SS_OK;
out_free:
	ss_free(fill);
	ss_free(tile_of);
	ss_free(slots);
	return status;
}

int ss_sweep_fast_init(struct ss_sweep_fast *f, const struct ss_grid *g,
                       const struct ss_tiling *tiling, int threads,
                       int periodic_x, int periodic_y,
                       const uint8_t *cell_types,
                       const struct ss_open_face *open_faces,
                       size_t open_face_count)
{
	memset(f, 0, sizeof *f);
	f->tiling = *tiling;
	f->tiles = tiling->tiles_x * tiling->tiles_y;
	f->threads = threads > 0 ? threads : 1;
	f->periodic_x = periodic_x;
	f->periodic_y = periodic_y;
	if (alloc_tables(f, g, open_face_count) ||
	    sort_open_slots(f, g, open_faces, open_face_count)) {
		ss_sweep_fast_release(f);
		return SS_ERR_FAIL;
	}
	mark_plain_tiles(f, g, cell_types);
	memset(f->sweep, 1, (size_t)f->tiles);
	memset(f->superstep_swept, 0, (size_t)f->tiles);
	memset(f->moving_superstep, 0, (size_t)f->tiles);
	memset(f->edges_superstep, 0, (size_t)f->tiles);
	memset(f->swept_last, 0, (size_t)f->tiles);
	return SS_OK;
}

void ss_sweep_fast_release(struct ss_sweep_fast *f)
{
	ss_free(f->open_slots);
	ss_free(f->open_first);
	ss_free(f->scratch);
	ss_free(f->ring_north);
	ss_free(f->ring_south);
	ss_free(f->row_list);
	ss_free(f->edges_out_north);
	ss_free(f->edges_out_south);
	ss_free(f->swept_last);
	ss_free(f->edges_superstep);
	ss_free(f->moving_superstep);
	ss_free(f->superstep_swept);
	ss_free(f->has_source);
	ss_free(f->plain);
	ss_free(f->edges_changed);
	ss_free(f->moving);
	ss_free(f->sweep_next);
	ss_free(f->sweep);
	memset(f, 0, sizeof *f);
}
#endif

void SS_PATH_FN(ss_sweep_fast_wake_all)(struct ss_sweep_fast *f, const struct ss_grid *g,
                                        const double *height, const uint8_t *cell_types)
{
	int bad = 0;
	memset(f->sweep, 1, (size_t)f->tiles);
	if (f->swept_last)
		memset(f->swept_last, 0, (size_t)f->tiles);
	f->s2_interior = slope2_all(g, height, cell_types, &bad);
	f->nonfinite = bad;
}

static int list_rows(struct ss_sweep_fast *f);

/* ss_sweep_fast_save_rings copies in one thread up to this many cells per
 * ring (2 x 8 B each; 16384: 256 kB) */
#define SAVE_RINGS_SERIAL_CELLS 16384.0

#if SS_PATH == SS_PATH_GENERIC
void ss_sweep_fast_save_rings(struct ss_sweep_fast *f, const struct ss_grid *g,
                              const double *height)
{
	const struct ss_tiling *t = &f->tiling;
	const int rows = list_rows(f);
	const ptrdiff_t stride = g->stride;
	/* two rows of doubles per tile row: on a room-sized grid a few tens of
	 * kB, copied faster than a sleeping thread wakes for a parallel
	 * region (one per RKL2 stage) */
	const int parallel = rows > 1 && (double)rows * g->nx > SAVE_RINGS_SERIAL_CELLS;

	#pragma omp parallel for schedule(dynamic, 1) num_threads(f->threads) if(parallel)
	for (int r = 0; r < rows; r++) {
		const int ty = f->row_list[r];
		for (int tx = 0; tx < t->tiles_x; tx++) {
			if (!f->sweep[ty * t->tiles_x + tx])
				continue;
			const struct ss_tile_span s = ss_tiling_span(&f->tiling, g, tx, ty);
			const size_t n = (size_t)(s.i1 - s.i0 + 2);
			memcpy(f->ring_south + ty * stride + s.i0,
			       height + ss_grid_index(g, s.i0 - 1, s.j0 - 1), n * sizeof(double));
			memcpy(f->ring_north + ty * stride + s.i0,
			       height + ss_grid_index(g, s.i0 - 1, s.j1), n * sizeof(double));
		}
	}
}

void ss_sweep_fast_mark_sources(struct ss_sweep_fast *f, const struct ss_grid *g,
                                const double *source_rate)
{
	const struct ss_tiling *t = &f->tiling;
	#pragma omp parallel for schedule(static)
	for (int ty = 0; ty < t->tiles_y; ty++) {
		for (int tx = 0; tx < t->tiles_x; tx++) {
			const struct ss_tile_span s = ss_tiling_span(&f->tiling, g, tx, ty);
			int on = 0;
			for (int j = s.j0; j < s.j1 && source_rate && !on; j++)
				for (int i = s.i0; i < s.i1; i++)
					on |= source_rate[ss_grid_index(g, i, j)] != 0.0;
			f->has_source[ty * t->tiles_x + tx] = (uint8_t)on;
			if (on)
				f->sweep[ty * t->tiles_x + tx] = 1;
		}
	}
}

double ss_sweep_fast_awake(const struct ss_sweep_fast *f)
{
	double n = 0.0;
	for (int k = 0; k < f->tiles; k++)
		n += f->sweep[k];
	return n;
}
#endif

/* Tile rows holding a tile to sweep, into f->row_list; returns the count. */
static int list_rows(struct ss_sweep_fast *f)
{
	const struct ss_tiling *t = &f->tiling;
	int n = 0;
	for (int ty = 0; ty < t->tiles_y; ty++) {
		const uint8_t *s = f->sweep + (size_t)ty * t->tiles_x;
		int any = 0;
		for (int tx = 0; tx < t->tiles_x; tx++)
			any |= s[tx];
		if (any)
			f->row_list[n++] = ty;
	}
	return n;
}

double SS_PATH_FN(ss_sweep_fast_begin)(struct ss_sweep_fast *f, const struct ss_grid *g,
                                       const double *height, const uint8_t *cell_types)
{
	const struct ss_tiling *t = &f->tiling;
	const int rows = list_rows(f);
	const ptrdiff_t stride = g->stride;
	double m = 0.0;
	int bad = 0;

	/* no threads for a single tile row: a fork and join would cost more */
	#pragma omp parallel for schedule(dynamic, 1) num_threads(f->threads) \
		reduction(max:m) reduction(|:bad) if(rows > 1)
	for (int r = 0; r < rows; r++) {
		const int ty = f->row_list[r];
		for (int tx = 0; tx < t->tiles_x; tx++) {
			const int tile = ty * t->tiles_x + tx;
			if (!f->sweep[tile])
				continue;
			const struct ss_tile_span s = ss_tiling_span(&f->tiling, g, tx, ty);
			const int plain = f->plain[tile];
			const size_t n = (size_t)(s.i1 - s.i0 + 2);
			memcpy(f->ring_south + ty * stride + s.i0,
			       height + ss_grid_index(g, s.i0 - 1, s.j0 - 1), n * sizeof(double));
			memcpy(f->ring_north + ty * stride + s.i0,
			       height + ss_grid_index(g, s.i0 - 1, s.j1), n * sizeof(double));
			/* the faces whose stencil reaches into the ring */
			double q = slope2_x_faces(g, height, cell_types, plain, s.j0, s.i0, s.i1, &bad);
			q = max2(q, slope2_x_faces(g, height, cell_types, plain, s.j1 - 1, s.i0, s.i1, &bad));
			q = max2(q, slope2_y_faces(g, height, cell_types, plain, s.j0, s.i0, s.i1 - 1, &bad));
			q = max2(q, slope2_y_faces(g, height, cell_types, plain, s.j1, s.i0, s.i1 - 1, &bad));
			/* the west and east columns: x-faces i0 and i1 of rows j0 + 1 ..
			 * j1 - 2, y-faces of cells i0 and i1 - 1 for j0 + 1 .. j1 - 1 */
			if (s.j1 - s.j0 >= 2) {
				q = max2(q, slope2_column(g, height, cell_types, plain, s.i0, s.i0, s.j0 + 1,
				                          s.j1 - 1, &bad));
				q = max2(q, slope2_column(g, height, cell_types, plain, s.i1, s.i1 - 1,
				                          s.j0 + 1, s.j1 - 1, &bad));
			}
			m = q > m ? q : m;
		}
	}
	f->nonfinite |= bad;
	m = max2(m, f->s2_interior);
	return f->nonfinite ? NAN : sqrt(m);
}

/* ---- the tile kernel -------------------------------------------------- */

/*
 * What every tile of a step shares: the arguments of ss_sweep_fast_step and
 * what follows from them, built once per step and read by every thread.
 * The phase helpers take what their loops need into locals first: a store
 * to the heights could otherwise, for the compiler, change a field.
 */
struct tile_ctx {
	struct ss_sweep_fast *f;
	const struct ss_grid *g;
	const struct ss_face_rule *rule;
	const double *restrict src;    /* source rate, m/s by storage index; NULL: none */
	const double *restrict bed;    /* bedrock, m by storage index; NULL: none */
	const uint8_t *restrict type;  /* packed cell types (grid.h) */
	double *restrict h;            /* heights, m by storage index, swept in place */
	double *restrict open_flux;    /* m^2/s, by the ledger's open-face list */
	ptrdiff_t stride;              /* g->stride */
	double dt;                     /* s */
	const struct ss_sweep_stage *stage;  /* an RKL2 stage, or NULL: Euler */
	double inv_dx, inv_dy;         /* 1/dx, 1/dy, 1/m */
	double inv_2dx, inv_2dy;       /* 1/(2 dx), 1/(2 dy): central differences */
	double limit_x, limit_y;       /* 0.25 dx/dt, 0.25 dy/dt, m/s (ss_face_limit) */
};

/*
 * The three-row ring a tile's row loop reads from, by buffer position x (cell
 * i0 - 1 + x), while it sweeps row j: the old heights of rows j - 1, j and
 * j + 1, their central differences along x (positions 1 .. W), the fluxes
 * through the y-faces (j - 1 | j) and (j | j + 1), and the widened types of
 * rows j - 2 .. j + 1.  ring_rotate moves it one row north by turning
 * pointers; no row is copied.
 */
struct ring {
	double *prev, *cur, *next;              /* old h, m */
	double *cdx_prev, *cdx_cur, *cdx_next;  /* dh/dx, central */
	double *fy_south, *fy_north;            /* F, m^2/s, positions 1 .. W */
	int64_t *type_back, *type_prev, *type_cur, *type_next;  /* rows j - 2 .. j + 1 */
};

static inline void ring_rotate(struct ring *r)
{
	double *row = r->prev, *cdx = r->cdx_prev, *fy = r->fy_south;
	int64_t *type = r->type_back;

	r->prev = r->cur;
	r->cur = r->next;
	r->next = row;
	r->cdx_prev = r->cdx_cur;
	r->cdx_cur = r->cdx_next;
	r->cdx_next = cdx;
	r->fy_south = r->fy_north;
	r->fy_north = fy;
	r->type_back = r->type_prev;
	r->type_prev = r->type_cur;
	r->type_cur = r->type_next;
	r->type_next = type;
}

/* A thread's buffers, rows of row_doubles() from f->scratch; by position. */
struct row_buffers {
	struct ring ring;          /* where each tile's ring starts */
	double *cdy;               /* dh/dy, central, of row j, positions 0 .. W + 1 */
	double *gn, *gt;           /* g_n, g_t of a row of faces; then gn + 1 the rates */
	double *fx;                /* F of the x-faces of row j, positions 0 .. W */
	uint16_t *face_rule;       /* several materials: each face's rule (face.h) */
	double *west_old;          /* old column i0 - 1 of the tile, by j - j0 */
	double *east_save;         /* old column i1 - 1, the next tile's west_old */
};

static struct row_buffers buffers_of(const struct ss_sweep_fast *f, int thread)
{
	const size_t w = row_doubles(&f->tiling);
	double *p = f->scratch + (size_t)thread * f->scratch_doubles;
	struct row_buffers b;
	b.ring.prev = p;
	b.ring.cur = p + w;
	b.ring.next = p + 2 * w;
	b.ring.cdx_prev = p + 3 * w;
	b.ring.cdx_cur = p + 4 * w;
	b.ring.cdx_next = p + 5 * w;
	b.cdy = p + 6 * w;
	b.gn = p + 7 * w;
	b.gt = p + 8 * w;
	b.fx = p + 9 * w;
	b.ring.fy_south = p + 10 * w;
	b.ring.fy_north = p + 11 * w;
	b.ring.type_prev = (int64_t *)(p + 12 * w);
	b.ring.type_cur = (int64_t *)(p + 13 * w);
	b.ring.type_next = (int64_t *)(p + 14 * w);
	b.ring.type_back = (int64_t *)(p + 15 * w);
	b.west_old = p + 16 * w;
	b.east_save = b.west_old + ((size_t)f->tiling.tile_ny + 7) / 8 * 8;
	/* last: the buffers of one material keep the places they had */
	b.face_rule = (uint16_t *)(b.east_save + ((size_t)f->tiling.tile_ny + 7) / 8 * 8);
	return b;
}

/* Types of the cells at positions 0 .. W + 1 of row j, from the packed
 * types t, widened to 64 bits for the row loops: a select between doubles
 * on a 64-bit condition vectorises, on a byte it does not. */
static inline void widen_types(const struct ss_grid *g, int W, int i0, int j,
                               const uint8_t *restrict t, int64_t *restrict wide)
{
	const ptrdiff_t k = ss_grid_index(g, i0 - 1, j);
	for (int x = 0; x <= W + 1; x++)
		wide[x] = type_at(t, k + x);
}

/* Central differences along x of buffer row b (types tt by position),
 * positions 1 .. W. */
static inline void central_x(int plain, int W, double inv_2dx,
                             const double *restrict b, const int64_t *restrict tt,
                             double *restrict cd)
{
	if (plain) {
		/* cd[x] = (h[x+1] - h[x-1]) / 2dx */
		for (int x = 1; x <= W; x++)
			cd[x] = (b[x + 1] - b[x - 1]) * inv_2dx;
	} else {
		/* the same, a wall neighbour replaced by h[x] (mirror ghost) */
		for (int x = 1; x <= W; x++) {
			const double hp = tt[x + 1] == SS_CELL_WALL ? b[x] : b[x + 1];
			const double hm = tt[x - 1] == SS_CELL_WALL ? b[x] : b[x - 1];
			cd[x] = (hp - hm) * inv_2dx;
		}
	}
}

/* Fluxes of n faces from (g_n, g_t); faces that cannot carry flux get 0.
 * ta, tb: types of the cells on either side (NULL in a plain tile);
 * face_rule: each face's rule in rule->table (NULL: one rule).  Returns whether a
 * face that can carry flux is above its critical slope. */
static inline int face_row(const struct ss_face_rule *rule, int n,
                           const double *restrict gn, const double *restrict gt,
                           const int64_t *restrict ta, const int64_t *restrict tb,
                           const uint16_t *restrict face_rule, double *restrict flux)
{
	const double tan_cr2 = rule->tan_cr2;
	const int any = face_rule
		? SS_PATH_FN(ss_face_fluxes_mixed)(rule->table, n, face_rule, gn, gt, flux)
		: SS_PATH_FN(ss_face_fluxes)(rule, n, gn, gt, flux);
	int sliding = 0;
	if (!ta)
		return any;
	if (any && face_rule) {
		/* the same with each face's threshold */
		const double *restrict tan_cr2s = rule->table->tan_cr2;
		for (int k = 0; k < n; k++) {
			const int64_t carries = wide_carries(ta[k], tb[k]);
			flux[k] = carries ? flux[k] : 0.0;
			sliding |= carries & (gn[k] * gn[k] + gt[k] * gt[k] > tan_cr2s[face_rule[k]]);
		}
	} else if (any) {
		/* F = 0 where the face cannot carry flux; sliding: s^2 > tan^2 a_cr */
		for (int k = 0; k < n; k++) {
			const int64_t carries = wide_carries(ta[k], tb[k]);
			flux[k] = carries ? flux[k] : 0.0;
			sliding |= carries & (gn[k] * gn[k] + gt[k] * gt[k] > tan_cr2);
		}
	}
	return sliding;
}

/* y-faces between buffer rows a (south) and b (north), positions 1 .. W. */
static inline int y_faces(const struct ss_face_rule *rule, int plain, int W,
                          double inv_dy, const double *restrict a,
                          const double *restrict b, const double *restrict cdx_a,
                          const double *restrict cdx_b, const int64_t *ta,
                          const int64_t *tb, const uint16_t *restrict mat_a,
                          const uint16_t *restrict mat_b, struct row_buffers *w,
                          double *restrict fy)
{
	/* g_n = (b[x] - a[x]) / dy, g_t = (cdx_a[x] + cdx_b[x]) / 2 */
	for (int x = 1; x <= W; x++) {
		w->gn[x] = (b[x] - a[x]) * inv_dy;
		w->gt[x] = 0.5 * (cdx_a[x] + cdx_b[x]);
	}
	if (mat_a) {
		/* the rule of the larger angle (ss_face_material) */
		for (int x = 1; x <= W; x++)
			w->face_rule[x] = mat_b[x] > mat_a[x] ? mat_b[x] : mat_a[x];
	}
	return face_row(rule, W, w->gn + 1, w->gt + 1, plain ? NULL : ta + 1,
	                plain ? NULL : tb + 1, mat_a ? w->face_rule + 1 : NULL, fy + 1);
}

/* Bedrock limits (ss_face_limit) on the faces between buffer rows a and b
 * (positions 1 .. W); bed_a, bed_b: bedrock of those rows by position. */
static inline void limit_y_faces(int W, double limit, const double *restrict a,
                                 const double *restrict b, const double *restrict bed_a,
                                 const double *restrict bed_b, double *restrict fy)
{
	/* |F| <= (h - b) dy / (4 dt) of the cell it leaves */
	for (int x = 1; x <= W; x++)
		fy[x] = ss_face_limit(fy[x], a[x] - bed_a[x], b[x] - bed_b[x], limit);
}

/* Old row j of the tile into buf: the tile's cells and the east neighbour
 * from the grid (not yet swept this step), the west neighbour from west. */
static inline void load_row(double *restrict buf, const double *restrict h_row,
                            int i0, int W, double west)
{
	memcpy(buf + 1, h_row + i0, (size_t)W * sizeof(double));
	buf[0] = west;
	buf[W + 1] = h_row[i0 + W];
}

/* One tile while it is swept: where it is, and what its rows found. */
struct tile {
	int index;                 /* ty * tiles_x + tx */
	int i0, W, j0, j1;         /* cells [i0, i0 + W) x [j0, j1) */
	int plain;                 /* f->plain[index] */
	const double *ring_north;  /* the saved old row j1, by position */
	const struct ss_open_face_slot *slot, *slot_end;  /* open faces to write */
	int moving;                /* a face above the critical slope, or a source */
	int edges;                 /* SS_EDGE_* of the edges whose cells changed */
	int bad;                   /* a NaN slope or rate was seen */
	double rate_max;           /* max |dh/dt| over its flow cells, m/s */
	double s2_max;             /* max s^2 over the faces measured behind */
	double estimate;           /* RKL2 stage 1: the largest error estimate, m */
};

struct tile_result {
	double rate_max, s2_max, estimate;
	int bad;
};

/* The y-faces (j | j + 1) between ring rows cur and next into fy_north,
 * with the central differences of next and the bedrock limit; returns
 * whether one is above the critical slope. */
static inline int north_y_faces(const struct tile_ctx *c, const struct tile *t,
                                struct row_buffers *w, const struct ring *r, int j)
{
	central_x(t->plain, t->W, c->inv_2dx, r->next, r->type_next, r->cdx_next);
	const uint16_t *mat = c->rule->material
		? c->rule->material + ss_grid_index(c->g, t->i0 - 1, j) : NULL;
	const int moving = y_faces(c->rule, t->plain, t->W, c->inv_dy, r->cur, r->next,
	                           r->cdx_cur, r->cdx_next, r->type_cur, r->type_next, mat,
	                           mat ? mat + c->stride : NULL, w, r->fy_north);
	if (c->bed) {
		const double *bed_cur = c->bed + ss_grid_index(c->g, t->i0 - 1, j);
		limit_y_faces(t->W, c->limit_y, r->cur, r->next, bed_cur, bed_cur + c->stride,
		              r->fy_north);
	}
	return moving;
}

/*
 * Start of tile (tx, ty): its span and open faces; the old west column from
 * the grid unless the tile to the west handed it over; then the ring as if
 * row j0 - 1 had just been swept: cur the saved south ring row, next row j0,
 * the y-faces (j0 - 1 | j0) between them, turned to stand at row j0.
 */
static inline struct tile tile_begin(const struct tile_ctx *c, struct row_buffers *w,
                                     struct ring *r, int tx, int ty, int west_swept)
{
	const struct ss_sweep_fast *f = c->f;
	const struct ss_grid *g = c->g;
	const struct ss_tile_span s = ss_tiling_span(&f->tiling, g, tx, ty);
	struct tile t = { .i0 = s.i0, .W = s.i1 - s.i0, .j0 = s.j0, .j1 = s.j1 };

	t.index = ty * f->tiling.tiles_x + tx;
	t.plain = f->plain[t.index];
	t.ring_north = f->ring_north + ty * c->stride + t.i0;
	t.slot = f->open_slots + f->open_first[t.index];
	t.slot_end = f->open_slots + f->open_first[t.index + 1];
	t.moving = f->has_source[t.index];
	if (!west_swept)
		for (int j = t.j0; j < t.j1; j++)
			w->west_old[j - t.j0] = c->h[ss_grid_index(g, t.i0 - 1, j)];
	memcpy(r->cur, f->ring_south + ty * c->stride + t.i0,
	       (size_t)(t.W + 2) * sizeof(double));
	load_row(r->next, c->h + ss_grid_index(g, 0, t.j0), t.i0, t.W, w->west_old[0]);
	if (!t.plain) {
		widen_types(g, t.W, t.i0, t.j0 - 1, c->type, r->type_cur);
		widen_types(g, t.W, t.i0, t.j0, c->type, r->type_next);
	}
	central_x(t.plain, t.W, c->inv_2dx, r->cur, r->type_cur, r->cdx_cur);
	t.moving |= north_y_faces(c, &t, w, r, t.j0 - 1);
	ring_rotate(r);
	return t;
}

/* Old row j + 1 into the ring's next (from the saved north ring row for the
 * tile's last row), with its widened types. */
static inline void ring_load_next(const struct tile_ctx *c, const struct tile *t,
                                  const struct row_buffers *w, struct ring *r, int j)
{
	const struct ss_grid *g = c->g;
	const int i0 = t->i0, W = t->W;

	if (j + 2 < t->j1) {
		/* each row of a tile starts a new page, where the hardware
		 * prefetcher starts cold: ask for the row after next */
		const char *ahead = (const char *)(c->h + ss_grid_index(g, i0, j + 2));
		for (size_t b = 0; b < (size_t)W * sizeof(double); b += 64)
			__builtin_prefetch(ahead + b, 1, 3);
	}
	if (j + 1 < t->j1)
		load_row(r->next, c->h + ss_grid_index(g, 0, j + 1), i0, W,
		         w->west_old[j + 1 - t->j0]);
	else
		memcpy(r->next, t->ring_north, (size_t)(W + 2) * sizeof(double));
	if (!t->plain)
		widen_types(g, W, i0, j + 1, c->type, r->type_next);
}

/* The x-faces of row j (positions 0 .. W) into w->fx, bedrock-limited, and
 * the y-faces (j | j + 1); the y-faces (j - 1 | j) the row before gave.
 * Returns whether a face is above the critical slope. */
static inline int row_fluxes(const struct tile_ctx *c, const struct tile *t,
                             struct row_buffers *w, const struct ring *r, int j)
{
	const int W = t->W;
	const double *prev = r->prev, *cur = r->cur, *next = r->next;
	const double inv_dx = c->inv_dx, inv_2dy = c->inv_2dy;

	if (t->plain) {
		/* cd_y[x] = (h[x, j+1] - h[x, j-1]) / 2dy */
		for (int x = 0; x <= W + 1; x++)
			w->cdy[x] = (next[x] - prev[x]) * inv_2dy;
	} else {
		/* the same, a wall neighbour replaced by h[x, j] (mirror ghost) */
		for (int x = 0; x <= W + 1; x++) {
			const double hp = r->type_next[x] == SS_CELL_WALL ? cur[x] : next[x];
			const double hm = r->type_prev[x] == SS_CELL_WALL ? cur[x] : prev[x];
			w->cdy[x] = (hp - hm) * inv_2dy;
		}
	}
	/* g_n = (h[x+1] - h[x]) / dx, g_t = (cd_y[x] + cd_y[x+1]) / 2 */
	for (int x = 0; x <= W; x++) {
		w->gn[x] = (cur[x + 1] - cur[x]) * inv_dx;
		w->gt[x] = 0.5 * (w->cdy[x] + w->cdy[x + 1]);
	}
	const uint16_t *restrict mat = c->rule->material;
	if (mat) {
		/* the rule of the larger angle (ss_face_material) */
		mat += ss_grid_index(c->g, t->i0 - 1, j);
		for (int x = 0; x <= W; x++)
			w->face_rule[x] = mat[x + 1] > mat[x] ? mat[x + 1] : mat[x];
	}
	int moving = face_row(c->rule, W + 1, w->gn, w->gt, t->plain ? NULL : r->type_cur,
	                      t->plain ? NULL : r->type_cur + 1, mat ? w->face_rule : NULL, w->fx);
	if (c->bed) {
		const double *bed_cur = c->bed + ss_grid_index(c->g, t->i0 - 1, j);
		const double limit_x = c->limit_x;
		/* |F| <= (h - b) dx / (4 dt) of the cell it leaves */
		for (int x = 0; x <= W; x++)
			w->fx[x] = ss_face_limit(w->fx[x], cur[x] - bed_cur[x],
			                         cur[x + 1] - bed_cur[x + 1], limit_x);
	}
	moving |= north_y_faces(c, t, w, r, j);
	return moving;
}

/* The rates dh/dt of row j's cells into w->gn + 1 (by x - 1), which the
 * face loops no longer need; returns that array. */
static inline double *row_rates(const struct tile_ctx *c, const struct tile *t,
                                struct row_buffers *w, const struct ring *r, int j)
{
	const int W = t->W;
	const double *fx = w->fx, *fy_south = r->fy_south, *fy_north = r->fy_north;
	const double inv_dx = c->inv_dx, inv_dy = c->inv_dy;
	double *rate = w->gn + 1;

	/* dh/dt = -(F_e - F_w)/dx - (F_n - F_s)/dy + q */
	for (int x = 1; x <= W; x++)
		rate[x - 1] = (fx[x - 1] - fx[x]) * inv_dx +
		              (fy_south[x] - fy_north[x]) * inv_dy;
	if (c->src) {
		const double *src_row = c->src + ss_grid_index(c->g, t->i0, j);
		for (int x = 0; x < W; x++)
			rate[x] += src_row[x];
	}
	return rate;
}

/* An RKL2 stage (ss_sweep_stage_delta) on the flow cells of row j, in
 * place; max |D_j| into t->rate_max (INFINITY on NaN), and whether a cell
 * changed into t->moving: a tile that changed in any stage is swept at the
 * start of the next super-step. */
static inline void row_stage(const struct tile_ctx *c, struct tile *t,
                             const double *restrict rate, const struct ring *r, int j)
{
	const struct ss_sweep_stage *sg = c->stage;
	const int W = t->W, first = sg->first, plain = t->plain;
	const ptrdiff_t k0 = ss_grid_index(c->g, t->i0, j);
	double *restrict y0 = sg->y0 + k0, *restrict d1 = sg->d1 + k0;
	double *restrict d2 = sg->d2 + k0, *restrict m0 = sg->m0 + k0;
	double *restrict hn = c->h + k0;
	const double *restrict cur = r->cur + 1;
	const int64_t *restrict tc = r->type_cur + 1;
	uint64_t row_max = 0;
	int changed = 0;

	if (sg->estimate_only) {
		/* a tile not swept in the super-step did not change in it, and its
		 * M was 0 at its start: its d1 and m0 may be older */
		const int swept = c->f->swept_last[t->index];
		double est_max = 0.0;
		for (int x = 0; x < W; x++) {
			const int flows = plain || tc[x] == SS_CELL_FLOW;
			const double change = swept ? d1[x] : 0.0, m_old = swept ? m0[x] : 0.0;
			const double e = flows ? ss_sweep_stage_estimate(sg->estimate_tau, change, m_old,
			                                                 rate[x]) : 0.0;
			est_max = e > est_max || e != e ? e : est_max;
		}
		t->estimate = est_max != est_max ? INFINITY : max2(t->estimate, est_max);
		return;
	}
	/* the weights in registers (a copy no store can alias) and stage 1's
	 * set-up in a loop of its own: the stage loop below then has no
	 * branch but selects, and the compiler vectorises it (on a room-sized
	 * grid it was a fifth of an evaluation, one cell at a time) */
	const double mu = sg->mu, nu = sg->nu, tau_mu = sg->tau_mu, tau_gamma = sg->tau_gamma;
	if (first) {
		for (int x = 0; x < W; x++) {
			const int flows = plain || tc[x] == SS_CELL_FLOW;
			y0[x] = cur[x];
			d1[x] = 0.0;
			d2[x] = 0.0;
			m0[x] = flows ? rate[x] : 0.0;
		}
	}
	/* two loops, not one with `plain | (type == flow)`: gcc then splits
	 * the one on `plain` itself and leaves the plain copy, the common one,
	 * unvectorised (perf, 2026-12-05) */
	if (plain) {
		/* every cell flows */
		#pragma omp simd reduction(max:row_max) reduction(|:changed)
		for (int x = 0; x < W; x++) {
			const double y1 = cur[x], d_old = d1[x];
			const double d = ss_sweep_stage_weigh(mu, nu, tau_mu, tau_gamma, d_old, d2[x],
			                                      rate[x], m0[x]);
			const double h = y0[x] + d;
			d2[x] = d_old;
			d1[x] = d;
			hn[x] = h;
			changed |= h != y1;
			const uint64_t a = bits_of(fabs(d));
			row_max = a > row_max ? a : row_max;
		}
	} else {
		/* the same on flow cells; the others keep their height, D = 0 */
		#pragma omp simd reduction(max:row_max) reduction(|:changed)
		for (int x = 0; x < W; x++) {
			const int flows = tc[x] == SS_CELL_FLOW;
			const double y1 = cur[x], d_old = d1[x];
			const double delta = ss_sweep_stage_weigh(mu, nu, tau_mu, tau_gamma, d_old,
			                                          d2[x], rate[x], m0[x]);
			const double d = flows ? delta : 0.0;
			const double h = flows ? y0[x] + delta : y1;
			d2[x] = d_old;
			d1[x] = d;
			hn[x] = h;
			changed |= h != y1;
			const uint64_t a = flows ? bits_of(fabs(delta)) : 0;
			row_max = a > row_max ? a : row_max;
		}
	}
	const double row_change_max = double_of(row_max);
	const int row_nan = row_change_max != row_change_max;
	t->rate_max = row_nan ? INFINITY : max2(t->rate_max, row_change_max);
	t->bad |= row_nan;
	t->moving |= changed;
}

/* Forward Euler on the flow cells of row j, in place, as ss_sweep_update
 * (or an RKL2 stage, row_stage); max |dh/dt| into t (INFINITY on NaN);
 * keeps the old east cell for the next tile. */
static inline void row_update(const struct tile_ctx *c, struct tile *t,
                              struct row_buffers *w, const struct ring *r, int j)
{
	const int W = t->W;
	const double *cur = r->cur;
	const double dt = c->dt;
	const double *rate = row_rates(c, t, w, r, j);

	w->east_save[j - t->j0] = cur[W];
	if (c->stage) {
		row_stage(c, t, rate, r, j);
		return;
	}
	uint64_t row_max = 0;
	const int64_t *tc = r->type_cur + 1;
	double *hn = c->h + ss_grid_index(c->g, 0, j) + t->i0;
	if (t->plain) {
		/* h += dt dh/dt; max |dh/dt| as the integer max of its bits */
		for (int x = 0; x < W; x++) {
			hn[x] = cur[x + 1] + dt * rate[x];
			const uint64_t a = bits_of(fabs(rate[x]));
			row_max = a > row_max ? a : row_max;
		}
	} else {
		/* the same on flow cells only */
		for (int x = 0; x < W; x++) {
			const int flows = tc[x] == SS_CELL_FLOW;
			hn[x] = flows ? cur[x + 1] + dt * rate[x] : cur[x + 1];
			const uint64_t a = flows ? bits_of(fabs(rate[x])) : 0;
			row_max = a > row_max ? a : row_max;
		}
	}
	const double row_rate_max = double_of(row_max);
	const int row_nan = row_rate_max != row_rate_max;
	t->rate_max = row_nan ? INFINITY : max2(t->rate_max, row_rate_max);
	t->bad |= row_nan;
}

/* SS_EDGE_* of the tile's edges where row j changed a cell (new h against
 * the ring's old row): the neighbours that see them must be swept next. */
static inline int row_edges(const struct tile_ctx *c, const struct tile *t,
                            const struct ring *r, int j)
{
	const double *h_row = c->h + ss_grid_index(c->g, 0, j), *cur = r->cur;
	const int i0 = t->i0, W = t->W;
	int edges = 0;

	if (h_row[i0] != cur[1])
		edges |= SS_EDGE_WEST;
	if (h_row[i0 + W - 1] != cur[W])
		edges |= SS_EDGE_EAST;
	if (j == t->j0 || j == t->j1 - 1) {
		int changed = 0;
		for (int x = 1; x <= W; x++)
			changed |= h_row[i0 + x - 1] != cur[x];
		if (changed)
			edges |= (j == t->j0 ? SS_EDGE_SOUTH : 0) | (j == t->j1 - 1 ? SS_EDGE_NORTH : 0);
	}
	return edges;
}

/* The fluxes of row j's faces to open cells, for the ledger's balance. */
static inline void row_open_fluxes(const struct tile_ctx *c, struct tile *t,
                                   const struct row_buffers *w, const struct ring *r,
                                   int j)
{
	const struct ss_open_face_slot *slot = t->slot;

	for (; slot < t->slot_end && slot->j == j; slot++)
		c->open_flux[slot->face] = slot->which == 0 ? w->fx[slot->x]
		                         : slot->which == 1 ? r->fy_south[slot->x]
		                         : r->fy_north[slot->x];
	t->slot = slot;
}

/*
 * The new state's slopes one row behind the update, while the rows are in
 * cache: at row j the faces whose stencil rows j - 2 .. j are all new.  The
 * faces whose stencil reaches into another tile are left to
 * ss_sweep_fast_begin.
 */
static inline void row_measure_behind(const struct tile_ctx *c, struct tile *t,
                                      const struct ring *r, int j)
{
	const struct ss_grid *g = c->g;
	const int i0 = t->i0, W = t->W, plain = t->plain;
	int bad = 0;

	if (j >= t->j0 + 2) {
		/* x-faces of row j - 1 and y-faces (j - 1 | j) */
		t->s2_max = max2(t->s2_max, plain
		                 ? slope2_plain_pair(g, c->h, j, i0 + 1, i0 + W - 2, &bad)
		                 : slope2_mixed_pair(g, c->h, j, i0, 2, W - 1, r->type_back,
		                                     r->type_prev, r->type_cur, &bad));
		if (W >= 2)   /* the last interior x-face, not paired */
			t->s2_max = max2(t->s2_max, slope2_x_faces(g, c->h, c->type, plain, j - 1,
			                                           i0 + W - 1, i0 + W - 1, &bad));
	} else if (j >= t->j0 + 1) {
		/* j = j0 + 1: the y-faces (j0 | j0 + 1); row j0's x-faces reach
		 * row j0 - 1.  Spelled >= on purpose: gcc then splits the row
		 * loop at j0 + 1, not j0 + 2, and with == the sweep ran 7-10 %
		 * slower (gcc 12, 1 thread, 2048^2 and 4096^2: the same work,
		 * more time in load_row's memcpy) */
		t->s2_max = max2(t->s2_max, slope2_y_faces(g, c->h, c->type, plain, j, i0 + 1,
		                                           i0 + W - 2, &bad));
	}
	t->bad |= bad;
}

/*
 * A tile first swept in a later stage of a super-step was not swept before
 * in it: its heights are Y_0 = Y_1 = ..., D = 0 and M(Y_0) = 0 on it (a tile is
 * left out of a stage only when it cannot change).  Its stage arrays say so
 * before the stage reads them.
 */
static void stage_tile_start(const struct tile_ctx *c, const struct tile *t)
{
	const struct ss_sweep_stage *sg = c->stage;
	for (int j = t->j0; j < t->j1; j++) {
		const ptrdiff_t k0 = ss_grid_index(c->g, t->i0, j);
		memcpy(sg->y0 + k0, c->h + k0, (size_t)t->W * sizeof(double));
		memset(sg->d1 + k0, 0, (size_t)t->W * sizeof(double));
		memset(sg->d2 + k0, 0, (size_t)t->W * sizeof(double));
		memset(sg->m0 + k0, 0, (size_t)t->W * sizeof(double));
	}
}

/*
 * Sweep tile (tx, ty) in place: every flow cell advances by one forward
 * Euler step of doc/model.md#forward-euler,
 *
 *     h += dt (-(F_e - F_w)/dx - (F_n - F_s)/dy + q),
 *     F = -nu f_sl(s) g_n / s,   s = sqrt(g_n^2 + g_t^2),
 *
 * with g_n the difference across a face over the spacing and g_t the mean
 * of the two cells' central differences along it (a wall neighbour replaced
 * by the cell: mirror ghost), F = 0 where ss_face_carries says no, then the
 * bedrock limit.  The arithmetic of every face and cell is the reference
 * sweep's (sweep.c), so the bits are the same.
 *
 * Why it reads this way: the heights are the only grid-sized array, so the
 * old state lives in a three-row ring (row j + 1 is copied before row j is
 * overwritten; the tile rows around keep theirs in f->ring_south/north, the
 * tile to the west hands over its old east column).  Each face is computed
 * once: the y-faces (j | j + 1) serve rows j and j + 1.  The slopes of the
 * new state are measured one row behind, while in cache, so the next dt
 * needs no pass of its own.  Also notes for plan_next whether the tile moved
 * and which of its edges changed, and writes the fluxes of its open faces.
 */
static inline struct tile_result sweep_tile(const struct tile_ctx *c,
                                            struct row_buffers *w, int tx, int ty,
                                            int west_swept)
{
	struct ring r = w->ring;
	struct tile t = tile_begin(c, w, &r, tx, ty, west_swept);

	if (c->stage && !c->stage->first && !c->stage->estimate_only &&
	    !c->f->superstep_swept[t.index])
		stage_tile_start(c, &t);

	for (int j = t.j0; j < t.j1; j++) {
		ring_load_next(c, &t, w, &r, j);
		t.moving |= row_fluxes(c, &t, w, &r, j);
		row_update(c, &t, w, &r, j);
		t.edges |= row_edges(c, &t, &r, j);
		row_open_fluxes(c, &t, w, &r, j);
		row_measure_behind(c, &t, &r, j);
		ring_rotate(&r);
	}
	c->f->moving[t.index] = (uint8_t)(t.moving != 0);
	c->f->edges_changed[t.index] = (uint8_t)t.edges;
	return (struct tile_result){ t.rate_max, t.s2_max, t.estimate, t.bad };
}

/* Which tiles the next step sweeps: those that moved, those under a source,
 * and the neighbours that see a changed edge (diagonal ones when both edges
 * at the shared corner changed, which includes every changed corner). */
static void plan_next_from(struct ss_sweep_fast *f, const uint8_t *swept,
                           const uint8_t *moving, const uint8_t *edges_changed)
{
	const int nx = f->tiling.tiles_x, ny = f->tiling.tiles_y;
	uint8_t *next = f->sweep_next;
	memset(next, 0, (size_t)f->tiles);
	/* what the ranks beside see of the first and last tile rows */
	for (int tx = 0; tx < nx; tx++) {
		const int first = tx, last = (ny - 1) * nx + tx;
		f->edges_out_south[tx] = swept[first] ? edges_changed[first] : 0;
		f->edges_out_north[tx] = swept[last] ? edges_changed[last] : 0;
	}
	for (int ty = 0; ty < ny; ty++) {
		for (int tx = 0; tx < nx; tx++) {
			const int tile = ty * nx + tx;
			if (f->has_source[tile])
				next[tile] = 1;
			if (!swept[tile])
				continue;
			if (moving[tile])
				next[tile] = 1;
			const int e = edges_changed[tile];
			if (!e)
				continue;
			for (int dy = -1; dy <= 1; dy++) {
				for (int dx = -1; dx <= 1; dx++) {
					if (!dx && !dy)
						continue;
					const int need = (dx < 0 ? SS_EDGE_WEST : dx > 0 ? SS_EDGE_EAST : 0) |
					                 (dy < 0 ? SS_EDGE_SOUTH : dy > 0 ? SS_EDGE_NORTH : 0);
					if ((e & need) != need)
						continue;
					int ux = tx + dx, uy = ty + dy;
					if (ux < 0 || ux >= nx) {
						if (!f->periodic_x)
							continue;
						ux = (ux + nx) % nx;
					}
					if (uy < 0 || uy >= ny) {
						if (!f->periodic_y)
							continue;
						uy = (uy + ny) % ny;
					}
					next[uy * nx + ux] = 1;
				}
			}
		}
	}
	uint8_t *tmp = f->sweep;
	f->sweep = f->sweep_next;
	f->sweep_next = tmp;
}

#if SS_PATH == SS_PATH_GENERIC
void ss_sweep_fast_wake_across(struct ss_sweep_fast *f, const uint8_t *from_south,
                               const uint8_t *from_north)
{
	const int nx = f->tiling.tiles_x, ny = f->tiling.tiles_y;
	for (int side = 0; side < 2; side++) {
		/* the tile row beside: its edge facing us, and our row it wakes */
		const uint8_t *row = side == 0 ? from_south : from_north;
		const int facing = side == 0 ? SS_EDGE_NORTH : SS_EDGE_SOUTH;
		uint8_t *wake = f->sweep + (size_t)(side == 0 ? 0 : ny - 1) * nx;
		if (!row)
			continue;
		for (int tx = 0; tx < nx; tx++) {
			const int e = row[tx];
			for (int dx = -1; dx <= 1 && (e & facing); dx++) {
				const int need = facing | (dx < 0 ? SS_EDGE_WEST : dx > 0 ? SS_EDGE_EAST : 0);
				if ((e & need) != need)
					continue;
				int ux = tx + dx;
				if (ux < 0 || ux >= nx) {
					if (!f->periodic_x)
						continue;
					ux = (ux + nx) % nx;
				}
				wake[ux] = 1;
			}
		}
	}
}
#endif

static void plan_next(struct ss_sweep_fast *f)
{
	plan_next_from(f, f->sweep, f->moving, f->edges_changed);
}

/*
 * The tiles of the next stage: those the last one planned, and every tile
 * swept earlier in the super-step (its stages go on changing it, through
 * Y_{j-1} - Y_0 and M(Y_0)).  After the last stage, those of the next
 * super-step: every tile that moved or changed in any stage, and the
 * neighbours of every edge that changed in any stage.
 */
static void plan_next_stage(struct ss_sweep_fast *f, int last)
{
	for (int k = 0; k < f->tiles; k++) {
		if (!f->sweep[k])
			continue;
		f->superstep_swept[k] = 1;
		f->moving_superstep[k] |= f->moving[k];
		f->edges_superstep[k] |= f->edges_changed[k];
	}
	if (!last) {
		plan_next(f);
		for (int k = 0; k < f->tiles; k++)
			f->sweep[k] |= f->superstep_swept[k];
		return;
	}
	plan_next_from(f, f->superstep_swept, f->moving_superstep, f->edges_superstep);
	uint8_t *done = f->superstep_swept;      /* it becomes swept_last */
	f->superstep_swept = f->swept_last;
	f->swept_last = done;
	memset(f->superstep_swept, 0, (size_t)f->tiles);
	memset(f->moving_superstep, 0, (size_t)f->tiles);
	memset(f->edges_superstep, 0, (size_t)f->tiles);
}

/* The tiles of f->sweep, a tile row per thread at a time; returns the
 * largest rate (or change) the tiles found, INFINITY on NaN. */
static double sweep_tiles(struct ss_sweep_fast *f, const struct tile_ctx *c)
{
	const struct ss_tiling *t = &f->tiling;
	const int rows = list_rows(f);
	double rate_max = 0.0, s2_max = 0.0, estimate = 0.0;
	int bad = 0;

	#pragma omp parallel num_threads(f->threads) \
		reduction(max:rate_max, s2_max, estimate) reduction(|:bad) if(rows > 1)
	{
		struct row_buffers w = buffers_of(f, ss_parallel_thread_id());
		#pragma omp for schedule(dynamic, 1)
		for (int r = 0; r < rows; r++) {
			const int ty = f->row_list[r];
			int west_swept = 0;
			for (int tx = 0; tx < t->tiles_x; tx++) {
				if (!f->sweep[ty * t->tiles_x + tx]) {
					west_swept = 0;
					continue;
				}
				const struct tile_result res = sweep_tile(c, &w, tx, ty, west_swept);
				rate_max = max2(rate_max, res.rate_max);
				s2_max = max2(s2_max, res.s2_max);
				estimate = max2(estimate, res.estimate);
				bad |= res.bad;
				/* this tile's old east column is the next one's west ring */
				double *tmp = w.west_old;
				w.west_old = w.east_save;
				w.east_save = tmp;
				west_swept = 1;
			}
		}
	}
	f->s2_interior = s2_max;
	f->nonfinite |= bad;
	if (c->stage && c->stage->estimate_only)
		*c->stage->estimate = estimate;
	return bad ? INFINITY : rate_max;
}

static struct tile_ctx context_of(struct ss_sweep_fast *f, const struct ss_grid *g,
                                  const struct ss_face_rule *rule, double dt,
                                  const double *restrict source_rate,
                                  const double *restrict bedrock,
                                  const uint8_t *restrict cell_types,
                                  double *restrict height, double *restrict open_flux)
{
	return (struct tile_ctx){
		.f = f, .g = g, .rule = rule,
		.src = source_rate, .bed = bedrock, .type = cell_types,
		.h = height, .open_flux = open_flux,
		.stride = g->stride, .dt = dt,
		.inv_dx = 1.0 / g->dx, .inv_dy = 1.0 / g->dy,
		.inv_2dx = 0.5 / g->dx, .inv_2dy = 0.5 / g->dy,
		.limit_x = 0.25 * g->dx / dt, .limit_y = 0.25 * g->dy / dt,
	};
}

double SS_PATH_FN(ss_sweep_fast_step)(struct ss_sweep_fast *f, const struct ss_grid *g,
                                      const struct ss_face_rule *rule, double dt,
                                      const double *restrict source_rate,
                                      const double *restrict bedrock,
                                      const uint8_t *restrict cell_types,
                                      double *restrict height, double *restrict open_flux)
{
	const struct tile_ctx ctx = context_of(f, g, rule, dt, source_rate, bedrock,
	                                       cell_types, height, open_flux);
	const double rate_max = sweep_tiles(f, &ctx);
	plan_next(f);
	return rate_max;
}

double SS_PATH_FN(ss_sweep_fast_stage)(struct ss_sweep_fast *f, const struct ss_grid *g,
                                       const struct ss_face_rule *rule,
                                       const struct ss_sweep_stage *stage, int last,
                                       const double *restrict source_rate,
                                       const uint8_t *restrict cell_types,
                                       double *restrict height, double *restrict open_flux)
{
	struct tile_ctx ctx = context_of(f, g, rule, 1.0, source_rate, NULL, cell_types,
	                                 height, open_flux);
	ctx.stage = stage;
	const double change_max = sweep_tiles(f, &ctx);
	if (!stage->estimate_only)
		plan_next_stage(f, last);
	return change_max;
}

#if SS_PATH == SS_PATH_GENERIC
/* ---- the public functions: the copy of the path in use ---------------- */

double ss_sweep_max_slope(const struct ss_grid *g, const double *restrict height,
                          const uint8_t *restrict cell_types)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_sweep_max_slope, g, height, cell_types);
}

double ss_sweep_max_sand_slope(const struct ss_grid *g, const double *restrict height,
                               const uint8_t *restrict cell_types,
                               const double *restrict bedrock, double bare)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_sweep_max_sand_slope, g, height, cell_types, bedrock, bare);
}

void ss_sweep_fast_wake_all(struct ss_sweep_fast *f, const struct ss_grid *g,
                            const double *height, const uint8_t *cell_types)
{
	const enum ss_cpu_path p = ss_cpu_path();
	SS_PATH_CALL(p, ss_sweep_fast_wake_all, f, g, height, cell_types);
}

double ss_sweep_fast_begin(struct ss_sweep_fast *f, const struct ss_grid *g,
                           const double *height, const uint8_t *cell_types)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_sweep_fast_begin, f, g, height, cell_types);
}

double ss_sweep_fast_step(struct ss_sweep_fast *f, const struct ss_grid *g,
                          const struct ss_face_rule *rule, double dt,
                          const double *restrict source_rate,
                          const double *restrict bedrock,
                          const uint8_t *restrict cell_types,
                          double *restrict height, double *restrict open_flux)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_sweep_fast_step, f, g, rule, dt, source_rate, bedrock,
	                    cell_types, height, open_flux);
}

double ss_sweep_fast_stage(struct ss_sweep_fast *f, const struct ss_grid *g,
                           const struct ss_face_rule *rule,
                           const struct ss_sweep_stage *stage, int last,
                           const double *restrict source_rate,
                           const uint8_t *restrict cell_types,
                           double *restrict height, double *restrict open_flux)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_sweep_fast_stage, f, g, rule, stage, last, source_rate,
	                    cell_types, height, open_flux);
}
#endif
