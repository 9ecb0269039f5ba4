/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * face.c - the point-wise face flux (see face.h for the formulas).
 *
 * Faces are taken in chunks that fit the first-level cache: one loop forms
 * s^2 and the point at which to evaluate, one computes the reciprocal
 * square roots, one the closure.  Every loop is branch-free so that the
 * compiler vectorises it; a face below the critical slope is evaluated at
 * s^2 = 1 (where every formula is finite) and its result replaced by 0.
 *
 * Compiled once per instruction-set path (core/cpu_paths.h): the AVX-512
 * copy computes the reciprocal square roots with vrsqrt14pd, the others
 * with 1/sqrt; the rest is the same source, vectorised for each path.  The
 * rule's set-up and the public functions, which call the copy of the path
 * in use, are in the generic copy only.
 */
#include "core/face.h"

#include <math.h>
#include <stdint.h>

#include "core/cpu_paths.h"

#if SS_PATH == SS_PATH_AVX512
#include <immintrin.h>
#endif

enum { CHUNK = 128 };

/* max(x, 0) as a select: fmax() is a library call unless -ffast-math, and
 * stops vectorisation.  A NaN gives 0, as fmax(NaN, 0) does. */
static inline double positive_part(double x)
{
	return x > 0.0 ? x : 0.0;
}

#if SS_PATH == SS_PATH_GENERIC
void ss_face_rule_init(struct ss_face_rule *r, const struct ss_closure *c)
{
	r->nu = c->nu;
	r->tan_cr = c->tan_cr;
	/* the largest s^2 whose square root is <= tan a_cr: then s^2 > tan_cr2
	 * exactly when sqrt(s^2) > tan a_cr, the test of closure.h and of the
	 * CFL bound, without a square root per face */
	double q = c->tan_cr * c->tan_cr;
	while (sqrt(q) > c->tan_cr)
		q = nextafter(q, 0.0);
	while (sqrt(nextafter(q, INFINITY)) <= c->tan_cr)
		q = nextafter(q, INFINITY);
	r->tan_cr2 = q;
	r->sin_cr = c->sin_cr;
	r->inv_sin_cr = 1.0 / c->sin_cr;
	r->gamma = c->gamma;
	r->power = c->power;
	switch (c->kind) {
	case SS_CLOSURE_COULOMB:
		r->form = SS_FACE_COULOMB;
		break;
	case SS_CLOSURE_BINGHAM:
		r->form = SS_FACE_BINGHAM;
		break;
	case SS_CLOSURE_HERSCHEL_BULKLEY:
		r->form = c->gamma == 0.5 ? SS_FACE_HB_CUBE
		        : c->gamma == 2.0 ? SS_FACE_HB_THREE_HALVES
		        : c->gamma == 1.0 ? SS_FACE_BINGHAM : SS_FACE_HB_POW;
		break;
	case SS_CLOSURE_CASSON:
		r->form = SS_FACE_CASSON;
		break;
	}
}
#endif

#if SS_PATH == SS_PATH_AVX512
/* vrsqrt14pd has a relative error below 2^-14; each Newton step
 * y <- y (3/2 - x/2 y^2) squares it, so two give full double precision up
 * to a few roundings.  The last partial vector is masked, so a face gets
 * the same bits wherever it sits in a row. */
static inline __m512d rsqrt_newton(__m512d v)
{
	const __m512d three_halves = _mm512_set1_pd(1.5), half = _mm512_set1_pd(0.5);
	const __m512d h = _mm512_mul_pd(half, v);
	__m512d r = _mm512_rsqrt14_pd(v);
	r = _mm512_mul_pd(r, _mm512_sub_pd(three_halves, _mm512_mul_pd(h, _mm512_mul_pd(r, r))));
	r = _mm512_mul_pd(r, _mm512_sub_pd(three_halves, _mm512_mul_pd(h, _mm512_mul_pd(r, r))));
	return r;
}

static inline __mmask8 tail_mask(int left)
{
	return left >= 8 ? (__mmask8)0xFF : (__mmask8)((1u << left) - 1u);
}

void SS_PATH_FN(ss_face_rsqrt)(int n, const double *restrict x, double *restrict y)
{
	for (int k = 0; k < n; k += 8) {
		const __mmask8 m = tail_mask(n - k);
		const __m512d v = _mm512_mask_loadu_pd(_mm512_set1_pd(1.0), m, x + k);
		_mm512_mask_storeu_pd(y + k, m, rsqrt_newton(v));
	}
}

/* Pass 1 of a chunk: s^2 where a face slides (1 elsewhere), 1/s, 1/w, the
 * sliding flag; returns whether any face slides. */
static int slopes_and_rsqrt(int m, double tan_cr2, const double *restrict gn,
                            const double *restrict gt, double *restrict s2,
                            double *restrict inv_s, double *restrict inv_w,
                            double *restrict slides)
{
	const __m512d one = _mm512_set1_pd(1.0), tc2 = _mm512_set1_pd(tan_cr2);
	__mmask8 any = 0;
	for (int k = 0; k < m; k += 8) {
		const __mmask8 lanes = tail_mask(m - k);
		const __m512d a = _mm512_maskz_loadu_pd(lanes, gn + k);
		const __m512d b = _mm512_maskz_loadu_pd(lanes, gt + k);
		const __m512d q = _mm512_add_pd(_mm512_mul_pd(a, a), _mm512_mul_pd(b, b));
		const __mmask8 sl = _mm512_cmp_pd_mask(q, tc2, _CMP_GT_OQ) & lanes;
		const __m512d e = _mm512_mask_blend_pd(sl, one, q);
		any |= sl;
		_mm512_mask_storeu_pd(s2 + k, lanes, e);
		_mm512_mask_storeu_pd(inv_s + k, lanes, rsqrt_newton(e));
		_mm512_mask_storeu_pd(inv_w + k, lanes, rsqrt_newton(_mm512_add_pd(one, e)));
		_mm512_mask_storeu_pd(slides + k, lanes, _mm512_mask_blend_pd(sl, _mm512_setzero_pd(), one));
	}
	return any != 0;
}
#else
void SS_PATH_FN(ss_face_rsqrt)(int n, const double *restrict x, double *restrict y)
{
	for (int k = 0; k < n; k++)
		y[k] = 1.0 / sqrt(x[k]);
}

static int slopes_and_rsqrt(int m, double tan_cr2, const double *restrict gn,
                            const double *restrict gt, double *restrict s2,
                            double *restrict inv_s, double *restrict inv_w,
                            double *restrict slides)
{
	int any = 0;
	for (int k = 0; k < m; k++) {
		const double q = gn[k] * gn[k] + gt[k] * gt[k];
		const int sl = q > tan_cr2;
		s2[k] = sl ? q : 1.0;
		slides[k] = sl ? 1.0 : 0.0;
		any |= sl;
	}
	for (int k = 0; k < m; k++) {
		inv_s[k] = 1.0 / sqrt(s2[k]);
		inv_w[k] = 1.0 / sqrt(1.0 + s2[k]);
	}
	return any;
}
#endif

/* f_sl(s)/s for the m faces of a chunk from s^2 (s2), 1/s and 1/w. */
static inline void f_over_s(enum ss_face_form form, const struct ss_face_rule *r,
                            int m, const double *restrict s2,
                            const double *restrict inv_s,
                            const double *restrict inv_w, double *restrict out)
{
	const double tan_cr = r->tan_cr, sin_cr = r->sin_cr, inv_sin_cr = r->inv_sin_cr;
	const double gamma = r->gamma, one_gamma = 1.0 + r->gamma;
	switch (form) {
	case SS_FACE_COULOMB:
		for (int k = 0; k < m; k++) {
			const double s = s2[k] * inv_s[k];
			out[k] = positive_part(s - tan_cr) * inv_w[k] * inv_s[k];
		}
		break;
	case SS_FACE_BINGHAM:
		for (int k = 0; k < m; k++) {
			const double s = s2[k] * inv_s[k], w = (1.0 + s2[k]) * inv_w[k];
			const double b = s * inv_w[k] * inv_sin_cr, rb = w * inv_s[k] * sin_cr;
			const double e = positive_part(b - 1.0);
			out[k] = rb * (2.0 + rb) * (e * e) * inv_s[k];
		}
		break;
	case SS_FACE_HB_CUBE:
	case SS_FACE_HB_THREE_HALVES:
	case SS_FACE_HB_POW:
		for (int k = 0; k < m; k++) {
			const double s = s2[k] * inv_s[k], w = (1.0 + s2[k]) * inv_w[k];
			const double b = s * inv_w[k] * inv_sin_cr, rb = w * inv_s[k] * sin_cr;
			const double e = positive_part(b - 1.0);
			const double ep = form == SS_FACE_HB_CUBE ? e * e * e
			                : form == SS_FACE_HB_THREE_HALVES ? e * sqrt(e)
			                : e;   /* raised to the power below */
			out[k] = rb * (one_gamma + gamma * rb) * ep * inv_s[k];
		}
		if (form == SS_FACE_HB_POW) {
			/* out = coefficient * e: divide e back out only where it is
			 * positive, i.e. apply e^(p-1) to the sliding faces */
			for (int k = 0; k < m; k++) {
				const double s = s2[k] * inv_s[k];
				const double e = positive_part(s * inv_w[k] * inv_sin_cr - 1.0);
				if (e > 0.0)
					out[k] *= pow(e, r->power - 1.0);
			}
		}
		break;
	case SS_FACE_CASSON:
		for (int k = 0; k < m; k++) {
			const double s = s2[k] * inv_s[k], w = (1.0 + s2[k]) * inv_w[k];
			const double b = s * inv_w[k] * inv_sin_cr, rb = w * inv_s[k] * sin_cr;
			const double q = sqrt(b), e = positive_part(q - 1.0);
			out[k] = rb * rb * (10.0 * b * q + 6.0 * b + 3.0 * q + 1.0) *
			         (e * e * e) * inv_s[k];
		}
		break;
	}
}

int SS_PATH_FN(ss_face_fluxes)(const struct ss_face_rule *r, int n,
                               const double *restrict g_n, const double *restrict g_t,
                               double *restrict flux)
{
	double s2[CHUNK], inv_s[CHUNK], inv_w[CHUNK], fos[CHUNK], slides[CHUNK];
	const double nu = r->nu;
	int any = 0;
	for (int base = 0; base < n; base += CHUNK) {
		const int m = n - base < CHUNK ? n - base : CHUNK;
		const double *restrict gn = g_n + base;
		any |= slopes_and_rsqrt(m, r->tan_cr2, gn, g_t + base, s2, inv_s, inv_w, slides);
		/* each form a call with a constant `form`, so that the inlined
		 * f_over_s keeps only that form's loop (no switch per face) */
#define FORM(form) case form: f_over_s(form, r, m, s2, inv_s, inv_w, fos); break
		switch (r->form) {
		FORM(SS_FACE_COULOMB);
		FORM(SS_FACE_BINGHAM);
		FORM(SS_FACE_HB_POW);
		FORM(SS_FACE_HB_CUBE);
		FORM(SS_FACE_HB_THREE_HALVES);
		FORM(SS_FACE_CASSON);
		}
#undef FORM
		for (int k = 0; k < m; k++)
			flux[base + k] = slides[k] != 0.0 ? -(nu * gn[k]) * fos[k] : 0.0;
	}
	return any;
}

#if SS_PATH == SS_PATH_GENERIC
/* The path is read for each call: each row of faces of the fast sweep (a
 * load and a branch against a row's hundreds of operations), each face of
 * the reference sweep. */
int ss_face_fluxes(const struct ss_face_rule *r, int n,
                   const double *restrict g_n, const double *restrict g_t,
                   double *restrict flux)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_face_fluxes, r, n, g_n, g_t, flux);
}

void ss_face_rsqrt(int n, const double *restrict x, double *restrict y)
{
	const enum ss_cpu_path p = ss_cpu_path();
	SS_PATH_CALL(p, ss_face_rsqrt, n, x, y);
}

const char *ss_face_rsqrt_method(void)
{
	return ss_cpu_path() == SS_CPU_AVX512 ? "vrsqrt14pd + 2 Newton steps (AVX-512)"
	                                      : "1/sqrt";
}
#endif
