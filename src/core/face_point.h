/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * face_point.h - the face flux and the cell update of one face and one
 * cell, written once for the processor and the GPU (doc/gpu.md#the-same-bits).
 *
 * face.c's loops (every CPU path) and the reference sweep (sweep.c) call
 * these functions; the CUDA kernels (src/cuda/) include this header too,
 * where SS_POINT makes each function __host__ __device__.  Both sides are
 * compiled without contraction (gcc -ffp-contract=off, nvcc -fmad=false,
 * tests/gpu/check_ptx.sh) and with IEEE division and square root, so a
 * product and a sum are each rounded once wherever they run: the device
 * gives the bits of the CPU's generic path (1/sqrt; face.h) for every form
 * but Herschel-Bulkley by pow(), whose pow() is the C library's on one side
 * and CUDA's on the other (doc/model.md#the-gpu-and-the-cpu).
 *
 * The formulas (face.h, doc/model.md#face-flux):
 *
 *   s^2 = g_n^2 + g_t^2, sliding when s^2 > tan_cr2 (else F = 0, and the
 *   closure is evaluated at s^2 = 1, where every form is finite)
 *   1/s = 1/sqrt(s^2),  1/w = 1/sqrt(1 + s^2),  F = -(nu g_n) f/s
 *
 * Plain C99 that nvcc's C++ also reads: no restrict on pointers a kernel
 * passes (SS_POINT_RESTRICT), no compound literals.
 */
#ifndef SANDSLIDE_CORE_FACE_POINT_H
#define SANDSLIDE_CORE_FACE_POINT_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __CUDACC__
#define SS_POINT __host__ __device__ static inline
#define SS_POINT_RESTRICT __restrict__
#else
#define SS_POINT static inline
#define SS_POINT_RESTRICT restrict
#endif

/* The cell types of grid.h, as bytes (sweep.h unpacks them). */
enum { SS_POINT_FLOW = 0, SS_POINT_WALL = 1, SS_POINT_OPEN = 2 };
/* The side kinds of boundary.h (sweep.c checks both). */
enum { SS_POINT_SIDE_WALL = 0, SS_POINT_SIDE_OPEN = 1, SS_POINT_SIDE_PERIODIC = 2 };

/* The formula a sweep instantiates; a Herschel-Bulkley power with a short
 * exact form gets its own. */
enum ss_face_form {
	SS_FACE_COULOMB,
	SS_FACE_BINGHAM,
	SS_FACE_HB_POW,            /* e^p by pow() */
	SS_FACE_HB_CUBE,           /* gamma = 1/2: e^3 */
	SS_FACE_HB_THREE_HALVES,   /* gamma = 2: e sqrt(e) */
	SS_FACE_CASSON,
};

/* One rule's numbers by value, as a kernel takes them (face.h's
 * ss_face_point_rule makes it from a struct ss_face_rule). */
struct ss_point_rule {
	int form;                  /* enum ss_face_form */
	double nu;                 /* m^2/s */
	double tan_cr, tan_cr2;    /* tan a_cr; the largest s^2 with sqrt <= it */
	double sin_cr, inv_sin_cr;
	double gamma, power;       /* Herschel-Bulkley */
};

/* max(x, 0) as a select (vectorises; fmax is a call): NaN gives 0. */
SS_POINT double ss_point_positive_part(double x)
{
	return x > 0.0 ? x : 0.0;
}

/* 1/sqrt(x): the generic path's reciprocal square root (face.h). */
SS_POINT double ss_point_rsqrt(double x)
{
	return 1.0 / sqrt(x);
}

/* ---- f_sl(s)/s from s^2, 1/s and 1/w, each form ---------------------- */

/* coulomb: f/s = max(s - tan a_cr, 0) / (w s) */
SS_POINT double ss_point_coulomb(double s2, double inv_s, double inv_w, double tan_cr)
{
	const double s = s2 * inv_s;
	return ss_point_positive_part(s - tan_cr) * inv_w * inv_s;
}

/* bingham: f/s = (1/b)(2 + 1/b) e^2 / s, b = sin a / sin a_cr, e = (b - 1)_+ */
SS_POINT double ss_point_bingham(double s2, double inv_s, double inv_w, double sin_cr,
                                 double inv_sin_cr)
{
	const double s = s2 * inv_s, w = (1.0 + s2) * inv_w;
	const double b = s * inv_w * inv_sin_cr, rb = w * inv_s * sin_cr;
	const double e = ss_point_positive_part(b - 1.0);
	return rb * (2.0 + rb) * (e * e) * inv_s;
}

/* The excess e = (b - 1)_+ of Herschel-Bulkley and Bingham. */
SS_POINT double ss_point_excess(double s2, double inv_s, double inv_w, double inv_sin_cr)
{
	const double s = s2 * inv_s;
	return ss_point_positive_part(s * inv_w * inv_sin_cr - 1.0);
}

/* herschel-bulkley: f/s = (1/b)(1 + gamma + gamma/b) e^(1 + 1/gamma) / s,
 * e^3 for SS_FACE_HB_CUBE, e sqrt(e) for SS_FACE_HB_THREE_HALVES, and for
 * SS_FACE_HB_POW the coefficient times e (ss_point_f_over_s applies
 * e^(p - 1) where e > 0: face.c does it in a loop of its own). */
SS_POINT double ss_point_herschel_bulkley(int form, double s2, double inv_s, double inv_w,
                                          double sin_cr, double inv_sin_cr, double gamma)
{
	const double s = s2 * inv_s, w = (1.0 + s2) * inv_w;
	const double b = s * inv_w * inv_sin_cr, rb = w * inv_s * sin_cr;
	const double e = ss_point_positive_part(b - 1.0);
	const double ep = form == SS_FACE_HB_CUBE ? e * e * e
	                : form == SS_FACE_HB_THREE_HALVES ? e * sqrt(e)
	                : e;
	return rb * (1.0 + gamma + gamma * rb) * ep * inv_s;
}

/* casson: f/s = (1/b)^2 (10 b q + 6 b + 3 q + 1) e^3 / s, q = sqrt b,
 * e = (q - 1)_+ */
SS_POINT double ss_point_casson(double s2, double inv_s, double inv_w, double sin_cr,
                                double inv_sin_cr)
{
	const double s = s2 * inv_s, w = (1.0 + s2) * inv_w;
	const double b = s * inv_w * inv_sin_cr, rb = w * inv_s * sin_cr;
	const double q = sqrt(b), e = ss_point_positive_part(q - 1.0);
	return rb * rb * (10.0 * b * q + 6.0 * b + 3.0 * q + 1.0) * (e * e * e) * inv_s;
}

SS_POINT double ss_point_f_over_s(const struct ss_point_rule *r, double s2, double inv_s,
                                  double inv_w)
{
	switch (r->form) {
	case SS_FACE_COULOMB:
		return ss_point_coulomb(s2, inv_s, inv_w, r->tan_cr);
	case SS_FACE_BINGHAM:
		return ss_point_bingham(s2, inv_s, inv_w, r->sin_cr, r->inv_sin_cr);
	case SS_FACE_CASSON:
		return ss_point_casson(s2, inv_s, inv_w, r->sin_cr, r->inv_sin_cr);
	default: {
		double c = ss_point_herschel_bulkley(r->form, s2, inv_s, inv_w, r->sin_cr,
		                                     r->inv_sin_cr, r->gamma);
		if (r->form == SS_FACE_HB_POW) {
			const double e = ss_point_excess(s2, inv_s, inv_w, r->inv_sin_cr);
			if (e > 0.0)
				c *= pow(e, r->power - 1.0);
		}
		return c;
	}
	}
}

/* F = -(nu g_n) f/s on a sliding face, else exactly 0. */
SS_POINT double ss_point_flux_of(int slides, double nu, double g_n, double f_over_s)
{
	return slides ? -(nu * g_n) * f_over_s : 0.0;
}

/* The flux of one face from its two gradients: what ss_face_fluxes
 * computes on the generic path. */
SS_POINT double ss_point_flux(const struct ss_point_rule *r, double g_n, double g_t)
{
	const double q = g_n * g_n + g_t * g_t;
	const int slides = q > r->tan_cr2;
	const double s2 = slides ? q : 1.0;
	const double inv_s = ss_point_rsqrt(s2), inv_w = ss_point_rsqrt(1.0 + s2);
	return ss_point_flux_of(slides, r->nu, g_n, ss_point_f_over_s(r, s2, inv_s, inv_w));
}

/* ---- one face of a grid, one cell ----------------------------------- */

/* A face carries flux when neither side is a wall and one side flows: a
 * face between two open cells, or touching a wall, carries 0 (both sweeps
 * ask it of every face; the fast one also as wide_carries). */
SS_POINT int ss_face_carries(uint8_t a, uint8_t b)
{
	return a != SS_POINT_WALL && b != SS_POINT_WALL &&
	       (a == SS_POINT_FLOW || b == SS_POINT_FLOW);
}

/* The height of a ghost cell beyond a side of kind `kind`, as boundary.c
 * fills it: the far cell's (`far`) beyond a periodic side, 0 beyond a wall
 * (the stencil mirrors across a wall by its type), the open level beyond
 * an open side. */
SS_POINT double ss_point_ghost(int kind, double far, double open_level)
{
	return kind == SS_POINT_SIDE_PERIODIC ? far : kind == SS_POINT_SIDE_WALL ? 0.0 : open_level;
}

/* Central difference of h at cell k along the direction with neighbour
 * offset `step`, a wall neighbour replaced by the cell itself
 * (doc/model.md#mirror-ghost-at-walls), times 1/(2 spacing). */
SS_POINT double ss_point_central_difference(const double *SS_POINT_RESTRICT h,
                                            const uint8_t *SS_POINT_RESTRICT type,
                                            ptrdiff_t k, ptrdiff_t step, double inv_2spacing)
{
	const double hp = type[k + step] == SS_POINT_WALL ? h[k] : h[k + step];
	const double hm = type[k - step] == SS_POINT_WALL ? h[k] : h[k - step];
	return (hp - hm) * inv_2spacing;
}

/* Whether the face between cells a (west/south) and a + normal
 * (east/north) carries flux, and if so its gradients: g_n across it, g_t
 * the mean of both cells' central differences along it (neighbour offset
 * `along`). */
SS_POINT int ss_point_face_gradients(const double *SS_POINT_RESTRICT h,
                                     const uint8_t *SS_POINT_RESTRICT type, ptrdiff_t a,
                                     ptrdiff_t normal, ptrdiff_t along, double inv_spacing,
                                     double inv_2along, double *g_n, double *g_t)
{
	const ptrdiff_t b = a + normal;
	if (!ss_face_carries(type[a], type[b]))
		return 0;
	*g_n = (h[b] - h[a]) * inv_spacing;
	*g_t = 0.5 * (ss_point_central_difference(h, type, a, along, inv_2along) +
	              ss_point_central_difference(h, type, b, along, inv_2along));
	return 1;
}

/* s^2 of a face that carries flux, 0 of one that does not (the maximum
 * slope the time step is sized from; NaN stays NaN). */
SS_POINT double ss_point_face_slope2(const double *SS_POINT_RESTRICT h,
                                     const uint8_t *SS_POINT_RESTRICT type, ptrdiff_t a,
                                     ptrdiff_t normal, ptrdiff_t along, double inv_spacing,
                                     double inv_2along)
{
	double g_n, g_t;
	return ss_point_face_gradients(h, type, a, normal, along, inv_spacing, inv_2along, &g_n,
	                               &g_t) ? g_n * g_n + g_t * g_t : 0.0;
}

/* The flux of the face between a and a + normal under one rule. */
SS_POINT double ss_point_face(const struct ss_point_rule *r, const double *SS_POINT_RESTRICT h,
                              const uint8_t *SS_POINT_RESTRICT type, ptrdiff_t a,
                              ptrdiff_t normal, ptrdiff_t along, double inv_spacing,
                              double inv_2along)
{
	double g_n, g_t;
	return ss_point_face_gradients(h, type, a, normal, along, inv_spacing, inv_2along, &g_n,
	                               &g_t) ? ss_point_flux(r, g_n, g_t) : 0.0;
}

/*
 * The largest s^2 of the faces cell k owns: its west and south ones, and
 * the block's east (north) face in the last column (row), as the
 * reference sweep's tiles own them; a NaN counts as +inf, so that it
 * cannot vanish in a maximum.  The GPU's slope pass reduces these.
 */
SS_POINT double ss_point_cell_slope2(const double *SS_POINT_RESTRICT h,
                                     const uint8_t *SS_POINT_RESTRICT type, ptrdiff_t k,
                                     ptrdiff_t stride, int last_column, int last_row,
                                     double inv_dx, double inv_dy, double inv_2dx,
                                     double inv_2dy)
{
	double f[4];
	f[0] = ss_point_face_slope2(h, type, k - 1, 1, stride, inv_dx, inv_2dy);
	f[1] = ss_point_face_slope2(h, type, k - stride, stride, 1, inv_dy, inv_2dx);
	f[2] = last_column ? ss_point_face_slope2(h, type, k, 1, stride, inv_dx, inv_2dy) : 0.0;
	f[3] = last_row ? ss_point_face_slope2(h, type, k, stride, 1, inv_dy, inv_2dx) : 0.0;
	double s2 = 0.0;
	for (int m = 0; m < 4; m++)
		s2 = f[m] != f[m] ? INFINITY : f[m] > s2 ? f[m] : s2;
	return s2;
}

/* dh/dt from a cell's four face fluxes: -(F_e - F_w)/dx - (F_n - F_s)/dy,
 * in the order of the reference sweep (sweep.c). */
SS_POINT double ss_point_rate(double flux_w, double flux_e, double flux_s, double flux_n,
                              double inv_dx, double inv_dy)
{
	return (flux_w - flux_e) * inv_dx + (flux_s - flux_n) * inv_dy;
}

/*
 * The rate dh/dt of cell k (storage index, rows `stride` apart) under one
 * rule, its four faces computed here: what a two-buffer kernel does per
 * cell (src/cuda/euler.cu).  Each face is computed by both its cells, from
 * the same numbers in the same order: the same bits as the reference
 * sweep's one flux per face.
 */
SS_POINT double ss_point_cell_rate(const struct ss_point_rule *r,
                                   const double *SS_POINT_RESTRICT h,
                                   const uint8_t *SS_POINT_RESTRICT type, ptrdiff_t k,
                                   ptrdiff_t stride, double inv_dx, double inv_dy,
                                   double inv_2dx, double inv_2dy)
{
	const double w = ss_point_face(r, h, type, k - 1, 1, stride, inv_dx, inv_2dy);
	const double e = ss_point_face(r, h, type, k, 1, stride, inv_dx, inv_2dy);
	const double s = ss_point_face(r, h, type, k - stride, stride, 1, inv_dy, inv_2dx);
	const double n = ss_point_face(r, h, type, k, stride, 1, inv_dy, inv_2dx);
	return ss_point_rate(w, e, s, n, inv_dx, inv_dy);
}

/* Forward Euler on a flow cell: h + dt rate; any other cell keeps h. */
SS_POINT double ss_point_euler(double h, double dt, double rate, int flows)
{
	return flows ? h + dt * rate : h;
}

/*
 * The CFL table's entry for the largest slope s (closure.h,
 * ss_cfl_bound_lookup: k = ceil(atan(s) / (pi/2 / size)), clamped), found
 * without atan(): bound[k] is the largest s whose entry is at most k
 * (ss_cfl_bound_thresholds), so the entry is the first k with
 * s <= bound[k].  atan differs in its last bit between C libraries and
 * CUDA; a comparison does not.  Called on s > tan a_cr.
 */
SS_POINT int ss_point_cfl_entry(const double *SS_POINT_RESTRICT bound, int size, double s)
{
	int lo = 0, hi = size;       /* the entry is in lo..hi */
	while (lo < hi) {
		const int mid = (lo + hi) / 2;
		if (s <= bound[mid])
			hi = mid;
		else
			lo = mid + 1;
	}
	return lo;
}

/*
 * The forward-Euler step from the largest face slope's square s2_max
 * (doc/model.md#forward-euler, (11); bench's rule): Lambda = nu table[entry]
 * above tan a_cr, the idle rate lambda_idle when nothing slides,
 * dt = cfl / (2 Lambda (1/dx^2 + 1/dy^2)), inv_d2 the bracket.  lambda:
 * the CFL table /nu (closure.h), bound its thresholds.
 */
SS_POINT double ss_point_step_size(double s2_max, const double *SS_POINT_RESTRICT lambda,
                                   const double *SS_POINT_RESTRICT bound, int table_size,
                                   double tan_cr, double nu, double lambda_idle, double cfl,
                                   double inv_d2)
{
	const double s_max = sqrt(s2_max);
	double rate = s_max > tan_cr ? nu * lambda[ss_point_cfl_entry(bound, table_size, s_max)]
	                             : 0.0;
	rate = rate > 0.0 ? rate : lambda_idle;
	return cfl / (2.0 * rate * inv_d2);
}

#endif
