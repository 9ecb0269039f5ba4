/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sweep.c - the reference two-pass stencil (see sweep.h for the scheme).
 *
 * Deliberately plain: one face per call of the face function, fluxes kept
 * in two full arrays.  The tests hold the fast sweep to it bit for bit.
 */
#include "core/sweep.h"

#include "sandslide/boundary.h"

#include <math.h>
#include <stddef.h>

/* face_point.h spells the cell types and side kinds as its own constants
 * (nvcc reads it) */
_Static_assert((int)SS_POINT_FLOW == (int)SS_CELL_FLOW && (int)SS_POINT_WALL == (int)SS_CELL_WALL &&
               (int)SS_POINT_OPEN == (int)SS_CELL_OPEN, "face_point.h's cell types are grid.h's");
_Static_assert((int)SS_POINT_SIDE_WALL == (int)SS_SIDE_WALL &&
               (int)SS_POINT_SIDE_OPEN == (int)SS_SIDE_OPEN &&
               (int)SS_POINT_SIDE_PERIODIC == (int)SS_SIDE_PERIODIC,
               "face_point.h's side kinds are boundary.h's");

void ss_tiling_init(struct ss_tiling *t, const struct ss_grid *g,
                    int tile_nx, int tile_ny)
{
	/* default: 256 x 128, smaller on small grids (about 4 x 8 tiles, at
	 * least 32 x 8) so that settled parts of them can be skipped */
	if (tile_nx < 1) {
		const int n = (g->nx / 4 + 7) / 8 * 8;
		tile_nx = n < 32 ? 32 : n > SS_TILE_NX_DEFAULT ? SS_TILE_NX_DEFAULT : n;
	}
	if (tile_ny < 1) {
		const int n = g->ny / 8;
		tile_ny = n < 8 ? 8 : n > SS_TILE_NY_DEFAULT ? SS_TILE_NY_DEFAULT : n;
	}
	t->tile_nx = tile_nx;
	t->tile_ny = tile_ny;
	t->tiles_x = (g->nx + t->tile_nx - 1) / t->tile_nx;
	t->tiles_y = (g->ny + t->tile_ny - 1) / t->tile_ny;
}

/* Tile number `tile` of t, counted row by row: the unit of the passes'
 * parallel loops. */
static inline struct ss_tile_span span_of(const struct ss_tiling *t,
                                          const struct ss_grid *g, int tile)
{
	return ss_tiling_span(t, g, tile % t->tiles_x, tile / t->tiles_x);
}

/* The faces tile sp writes: the x-faces (i - 1 | i) of its rows for
 * i0 <= i < x_end, the y-faces (j - 1 | j) of its columns for
 * j0 <= j < y_end.  The last tile of a row (column) also owns the east
 * (north) face of the block, so that each face has one writer. */
struct face_ends {
	int x_end, y_end;
};

static inline struct face_ends faces_of(const struct ss_grid *g, struct ss_tile_span sp)
{
	struct face_ends e;
	e.x_end = sp.i1 == g->nx ? sp.i1 + 1 : sp.i1;
	e.y_end = sp.j1 == g->ny ? sp.j1 + 1 : sp.j1;
	return e;
}

/*
 * The flux through the face between cells a (west/south) and b = a + normal
 * (east/north): g_n across the face, g_t the mean of both cells' central
 * differences along it (offset `along`; face_point.h, the formulas the GPU's
 * kernels share).  The flux is the path's (ss_face_fluxes: the AVX-512
 * path's reciprocal square roots are its own).  sweep_fast.c spells the same
 * expressions again, a row of faces at a time so that they vectorise: two
 * copies on purpose, this one the plain statement the other is tested
 * against bit for bit.
 */
static inline double face_flux(const struct ss_face_rule *rule,
                               const double *restrict h,
                               const uint8_t *restrict type, ptrdiff_t a,
                               ptrdiff_t normal, ptrdiff_t along,
                               double inv_spacing, double inv_2along,
                               double *restrict s2_max)
{
	const ptrdiff_t b = a + normal;
	double g_n, g_t;
	if (!ss_point_face_gradients(h, type, a, normal, along, inv_spacing, inv_2along, &g_n,
	                             &g_t))
		return 0.0;
	const double s2 = g_n * g_n + g_t * g_t;
	/* a NaN slope must not vanish in the maximum */
	if (s2 > *s2_max || s2 != s2)
		*s2_max = s2 != s2 ? INFINITY : s2;
	double flux;
	if (rule->material) {
		const uint16_t face_rule = ss_face_material(rule->material, a, b);
		ss_face_fluxes_mixed(rule->table, 1, &face_rule, &g_n, &g_t, &flux);
	} else {
		ss_face_fluxes(rule, 1, &g_n, &g_t, &flux);
	}
	return flux;
}

double ss_sweep_fluxes(const struct ss_grid *g, const struct ss_tiling *t,
                       const struct ss_face_rule *rule,
                       const double *restrict h,
                       const uint8_t *restrict type,
                       double *restrict flux_x, double *restrict flux_y)
{
	const int tiles = t->tiles_x * t->tiles_y;
	const ptrdiff_t stride = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	const double inv_2dx = 0.5 / g->dx, inv_2dy = 0.5 / g->dy;
	double s2_max = 0.0;

	#pragma omp parallel for schedule(static) reduction(max:s2_max)
	for (int tile = 0; tile < tiles; tile++) {
		const struct ss_tile_span sp = span_of(t, g, tile);
		const struct face_ends e = faces_of(g, sp);
		double s2 = 0.0;
		for (int j = sp.j0; j < sp.j1; j++) {
			for (int i = sp.i0; i < e.x_end; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				flux_x[k] = face_flux(rule, h, type, k - 1, 1, stride,
				                      inv_dx, inv_2dy, &s2);
			}
		}
		for (int j = sp.j0; j < e.y_end; j++) {
			for (int i = sp.i0; i < sp.i1; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				flux_y[k] = face_flux(rule, h, type, k - stride, stride, 1,
				                      inv_dy, inv_2dx, &s2);
			}
		}
		if (s2 > s2_max)
			s2_max = s2;
	}
	return sqrt(s2_max);
}

/* The face loops of ss_sweep_fluxes again, and not folded into them: the
 * limit needs dt, which the stepper takes from the largest slope that pass
 * returns. */
void ss_sweep_limit(const struct ss_grid *g, const struct ss_tiling *t, double dt,
                    const double *restrict height, const double *restrict bedrock,
                    double *restrict flux_x, double *restrict flux_y)
{
	const int tiles = t->tiles_x * t->tiles_y;
	const ptrdiff_t stride = g->stride;
	const double limit_x = 0.25 * g->dx / dt, limit_y = 0.25 * g->dy / dt;

	#pragma omp parallel for schedule(static)
	for (int tile = 0; tile < tiles; tile++) {
		const struct ss_tile_span sp = span_of(t, g, tile);
		const struct face_ends e = faces_of(g, sp);
		for (int j = sp.j0; j < sp.j1; j++) {
			for (int i = sp.i0; i < e.x_end; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				flux_x[k] = ss_face_limit(flux_x[k], height[k - 1] - bedrock[k - 1],
				                          height[k] - bedrock[k], limit_x);
			}
		}
		for (int j = sp.j0; j < e.y_end; j++) {
			for (int i = sp.i0; i < sp.i1; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				flux_y[k] = ss_face_limit(flux_y[k], height[k - stride] - bedrock[k - stride],
				                          height[k] - bedrock[k], limit_y);
			}
		}
	}
}

/* dh/dt of the cell at storage index k from pass 1's fluxes:
 * -(F_e - F_w)/dx - (F_n - F_s)/dy + q; the one expression of both updates. */
static inline double rate_at(const double *restrict flux_x, const double *restrict flux_y,
                             const double *restrict source_rate, ptrdiff_t k,
                             ptrdiff_t stride, double inv_dx, double inv_dy)
{
	const double rate = ss_point_rate(flux_x[k], flux_x[k + 1], flux_y[k], flux_y[k + stride],
	                                  inv_dx, inv_dy);
	return source_rate ? rate + source_rate[k] : rate;
}

double ss_sweep_update(const struct ss_grid *g, const struct ss_tiling *t,
                       double dt, const double *restrict flux_x,
                       const double *restrict flux_y,
                       const double *restrict source_rate,
                       const uint8_t *restrict cell_type,
                       double *restrict height)
{
	const int tiles = t->tiles_x * t->tiles_y;
	const ptrdiff_t stride = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	double rate_max = 0.0;

	#pragma omp parallel for schedule(static) reduction(max:rate_max)
	for (int tile = 0; tile < tiles; tile++) {
		const struct ss_tile_span sp = span_of(t, g, tile);
		for (int j = sp.j0; j < sp.j1; j++) {
			for (int i = sp.i0; i < sp.i1; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				const double rate = rate_at(flux_x, flux_y, source_rate, k, stride,
				                            inv_dx, inv_dy);
				const int flows = cell_type[k] == SS_CELL_FLOW;
				height[k] = ss_point_euler(height[k], dt, rate, flows);
				const double a = flows ? fabs(rate) : 0.0;
				/* a NaN rate must not vanish in the maximum */
				if (a > rate_max || a != a)
					rate_max = a != a ? INFINITY : a;
			}
		}
	}
	return rate_max;
}

double ss_sweep_stage_update(const struct ss_grid *g, const struct ss_tiling *t,
                             const struct ss_sweep_stage *stage,
                             const double *restrict flux_x,
                             const double *restrict flux_y,
                             const double *restrict source_rate,
                             const uint8_t *restrict cell_type,
                             double *restrict height)
{
	const int tiles = t->tiles_x * t->tiles_y;
	const ptrdiff_t stride = g->stride;
	const double inv_dx = 1.0 / g->dx, inv_dy = 1.0 / g->dy;
	double *restrict y0 = stage->y0, *restrict d1 = stage->d1, *restrict d2 = stage->d2;
	double *restrict m0 = stage->m0;
	double change_max = 0.0, estimate = 0.0;

	#pragma omp parallel for schedule(static) reduction(max:change_max, estimate)
	for (int tile = 0; tile < tiles; tile++) {
		const struct ss_tile_span sp = span_of(t, g, tile);
		for (int j = sp.j0; j < sp.j1; j++) {
			for (int i = sp.i0; i < sp.i1; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				const double rate = rate_at(flux_x, flux_y, source_rate, k, stride,
				                            inv_dx, inv_dy);
				const int flows = cell_type[k] == SS_CELL_FLOW;
				const double y1 = height[k];
				if (stage->estimate_only) {
					const double e = flows
						? ss_sweep_stage_estimate(stage->estimate_tau, d1[k],
						                          m0[k], rate)
						: 0.0;
					if (e > estimate || e != e)
						estimate = e != e ? INFINITY : e;
					continue;
				}
				if (stage->first) {
					y0[k] = y1;
					d1[k] = 0.0;
					d2[k] = 0.0;
					m0[k] = flows ? rate : 0.0;
				}
				const double d = flows ? ss_sweep_stage_delta(stage, d1[k], d2[k], rate, m0[k])
				                       : 0.0;
				height[k] = flows ? y0[k] + d : y1;
				d2[k] = d1[k];
				d1[k] = d;
				const double a = fabs(d);
				if (a > change_max || a != a)
					change_max = a != a ? INFINITY : a;
			}
		}
	}
	if (stage->estimate_only)
		*stage->estimate = estimate;
	return change_max;
}
