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
 * Each face's expressions are face_point.h's functions (ss_point_coulomb,
 * ...), which the GPU's kernels compile too (doc/gpu.md#the-same-bits):
 * called in these loops they are inlined and vectorised as before.
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
#include <string.h>

#include "core/cpu_paths.h"
#include "sandslide/error.h"

#if SS_PATH == SS_PATH_AVX512
#include <immintrin.h>
#endif

enum { CHUNK = 128 };

/* The loops below take the rule's numbers as constants (step 0) or per
 * face (step 1): inlined into each caller so that step and the form are
 * constants there, and the uniform copy keeps its numbers in registers. */
#define FACE_INLINE static inline __attribute__((always_inline))

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
	r->table = NULL;
	r->material = NULL;
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
 * sliding flag; returns whether any face slides.  The threshold of face k
 * is tan_cr2[k] (step 1: a rule per face) or tan_cr2[0] (step 0: one rule). */
FACE_INLINE int slopes_and_rsqrt(int m, const double *restrict tan_cr2, int step,
                                   const double *restrict gn,
                                   const double *restrict gt, double *restrict s2,
                                   double *restrict inv_s, double *restrict inv_w,
                                   double *restrict slides)
{
	const __m512d one = _mm512_set1_pd(1.0), tc2_one = _mm512_set1_pd(tan_cr2[0]);
	__mmask8 any = 0;
	for (int k = 0; k < m; k += 8) {
		const __mmask8 lanes = tail_mask(m - k);
		const __m512d tc2 = step ? _mm512_maskz_loadu_pd(lanes, tan_cr2 + k) : tc2_one;
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
		y[k] = ss_point_rsqrt(x[k]);
}

FACE_INLINE int slopes_and_rsqrt(int m, const double *restrict tan_cr2, int step,
                                   const double *restrict gn,
                                   const double *restrict gt, double *restrict s2,
                                   double *restrict inv_s, double *restrict inv_w,
                                   double *restrict slides)
{
	const double tan_cr2_one = tan_cr2[0];
	int any = 0;
	for (int k = 0; k < m; k++) {
		const double q = gn[k] * gn[k] + gt[k] * gt[k];   /* ss_point_flux's s^2 */
		const int sl = q > (step ? tan_cr2[k] : tan_cr2_one);
		s2[k] = sl ? q : 1.0;
		slides[k] = sl ? 1.0 : 0.0;
		any |= sl;
	}
	for (int k = 0; k < m; k++) {
		inv_s[k] = ss_point_rsqrt(s2[k]);
		inv_w[k] = ss_point_rsqrt(1.0 + s2[k]);
	}
	return any;
}
#endif

/* out[k] = table[rule[k]], k < m: a face's number of its rule.  With at
 * most 8 rules on the AVX-512 path, a permutation of one register (the
 * gathers it replaces cost a face about as much as its arithmetic). */
static inline void gather_rules(int m, const uint16_t *restrict rule, const double *restrict table,
                                int count, double *restrict out)
{
#if SS_PATH == SS_PATH_AVX512
	if (count <= 8) {
		const __m512d numbers = _mm512_maskz_loadu_pd(tail_mask(count), table);
		for (int k = 0; k < m; k += 8) {
			const __mmask8 lanes = tail_mask(m - k);
			const __m512i r = _mm512_cvtepu16_epi64(_mm_maskz_loadu_epi16(lanes, rule + k));
			_mm512_mask_storeu_pd(out + k, lanes, _mm512_permutexvar_pd(r, numbers));
		}
		return;
	}
#else
	(void)count;
#endif
	#pragma omp simd
	for (int k = 0; k < m; k++)
		out[k] = table[rule[k]];
}

/* A closure's numbers for the faces of a chunk: face k's at [k * step]
 * (step 0: one rule's, step 1: a rule per face). */
struct numbers {
	const double *tan_cr, *sin_cr, *inv_sin_cr, *gamma, *power;
};

/* f_sl(s)/s for the m faces of a chunk from s^2 (s2), 1/s and 1/w. */
FACE_INLINE void f_over_s(enum ss_face_form form, const struct numbers *p, int step,
                            int m, const double *restrict s2,
                            const double *restrict inv_s,
                            const double *restrict inv_w, double *restrict out)
{
	const double *restrict tan_crs = p->tan_cr, *restrict sin_crs = p->sin_cr;
	const double *restrict inv_sin_crs = p->inv_sin_cr, *restrict gammas = p->gamma;
	const double *restrict powers = p->power;
	/* one rule: its numbers in registers, as constants of the loops */
	const double tan_cr = tan_crs[0], sin_cr = sin_crs[0], inv_sin_cr = inv_sin_crs[0];
	const double gamma = gammas[0];
#define TAN_CR (step ? tan_crs[k] : tan_cr)
#define SIN_CR (step ? sin_crs[k] : sin_cr)
#define INV_SIN_CR (step ? inv_sin_crs[k] : inv_sin_cr)
#define GAMMA (step ? gammas[k] : gamma)
	switch (form) {
	case SS_FACE_COULOMB:
		for (int k = 0; k < m; k++)
			out[k] = ss_point_coulomb(s2[k], inv_s[k], inv_w[k], TAN_CR);
		break;
	case SS_FACE_BINGHAM:
		for (int k = 0; k < m; k++)
			out[k] = ss_point_bingham(s2[k], inv_s[k], inv_w[k], SIN_CR, INV_SIN_CR);
		break;
	case SS_FACE_HB_CUBE:
	case SS_FACE_HB_THREE_HALVES:
	case SS_FACE_HB_POW:
		for (int k = 0; k < m; k++)
			out[k] = ss_point_herschel_bulkley(form, s2[k], inv_s[k], inv_w[k], SIN_CR,
			                                   INV_SIN_CR, GAMMA);
		if (form == SS_FACE_HB_POW) {
			/* out = coefficient * e: divide e back out only where it is
			 * positive, i.e. apply e^(p-1) to the sliding faces */
			for (int k = 0; k < m; k++) {
				const double e = ss_point_excess(s2[k], inv_s[k], inv_w[k], INV_SIN_CR);
				if (e > 0.0)
					out[k] *= pow(e, (step ? powers[k] : powers[0]) - 1.0);
			}
		}
		break;
	case SS_FACE_CASSON:
		for (int k = 0; k < m; k++)
			out[k] = ss_point_casson(s2[k], inv_s[k], inv_w[k], SIN_CR, INV_SIN_CR);
		break;
	}
#undef TAN_CR
#undef SIN_CR
#undef INV_SIN_CR
#undef GAMMA
}

/* f_sl/s of a chunk's faces in form `form`: each form a call with a
 * constant `form`, so that the inlined f_over_s keeps only that form's
 * loop (no switch per face). */
FACE_INLINE void f_over_s_of(enum ss_face_form form, const struct numbers *p, int step,
                               int m, const double *restrict s2, const double *restrict inv_s,
                               const double *restrict inv_w, double *restrict out)
{
#define FORM(f) case f: f_over_s(f, p, step, m, s2, inv_s, inv_w, out); break
	switch (form) {
	FORM(SS_FACE_COULOMB);
	FORM(SS_FACE_BINGHAM);
	FORM(SS_FACE_HB_POW);
	FORM(SS_FACE_HB_CUBE);
	FORM(SS_FACE_HB_THREE_HALVES);
	FORM(SS_FACE_CASSON);
	}
#undef FORM
}

int SS_PATH_FN(ss_face_fluxes)(const struct ss_face_rule *r, int n,
                               const double *restrict g_n, const double *restrict g_t,
                               double *restrict flux)
{
	double s2[CHUNK], inv_s[CHUNK], inv_w[CHUNK], fos[CHUNK], slides[CHUNK];
	const double nu = r->nu;
	const struct numbers one = {&r->tan_cr, &r->sin_cr, &r->inv_sin_cr, &r->gamma, &r->power};
	int any = 0;
	for (int base = 0; base < n; base += CHUNK) {
		const int m = n - base < CHUNK ? n - base : CHUNK;
		const double *restrict gn = g_n + base;
		any |= slopes_and_rsqrt(m, &r->tan_cr2, 0, gn, g_t + base, s2, inv_s, inv_w, slides);
		f_over_s_of(r->form, &one, 0, m, s2, inv_s, inv_w, fos);
		for (int k = 0; k < m; k++)
			flux[base + k] = ss_point_flux_of(slides[k] != 0.0, nu, gn[k], fos[k]);
	}
	return any;
}

#if SS_PATH == SS_PATH_AVX512
/* Coulomb faces of at most 8 rules in one pass, each face's numbers
 * permuted out of registers and nothing stored but the flux: the
 * expressions of slopes_and_rsqrt, f_over_s and the flux below, in their
 * order, so the same bits (test_sweep compares them with single rules).
 * The chunked passes stored and reloaded six numbers a face. */
static int coulomb_in_registers(const struct ss_face_table *t, int n,
                                const uint16_t *restrict rule, const double *restrict g_n,
                                const double *restrict g_t, double *restrict flux)
{
	const __mmask8 rules = tail_mask(t->count);
	const __m512d tan_cr2s = _mm512_maskz_loadu_pd(rules, t->tan_cr2);
	const __m512d tan_crs = _mm512_maskz_loadu_pd(rules, t->tan_cr);
	const __m512d nus = _mm512_maskz_loadu_pd(rules, t->nu);
	const __m512d one = _mm512_set1_pd(1.0), zero = _mm512_setzero_pd();
	const __m512d sign = _mm512_set1_pd(-0.0);
	__mmask8 any = 0;
	for (int k = 0; k < n; k += 8) {
		const __mmask8 lanes = tail_mask(n - k);
		const __m512i r = _mm512_cvtepu16_epi64(_mm_maskz_loadu_epi16(lanes, rule + k));
		const __m512d a = _mm512_maskz_loadu_pd(lanes, g_n + k);
		const __m512d b = _mm512_maskz_loadu_pd(lanes, g_t + k);
		/* s^2 where the face slides, 1 elsewhere; 1/s, 1/w */
		const __m512d q = _mm512_add_pd(_mm512_mul_pd(a, a), _mm512_mul_pd(b, b));
		const __mmask8 slides =
			_mm512_cmp_pd_mask(q, _mm512_permutexvar_pd(r, tan_cr2s), _CMP_GT_OQ) & lanes;
		const __m512d e = _mm512_mask_blend_pd(slides, one, q);
		any |= slides;
		const __m512d inv_s = rsqrt_newton(e), inv_w = rsqrt_newton(_mm512_add_pd(one, e));
		/* f/s = (s - tan a_cr)_+ / w / s, s = s^2 / s */
		const __m512d d = _mm512_sub_pd(_mm512_mul_pd(e, inv_s),
		                                _mm512_permutexvar_pd(r, tan_crs));
		const __m512d positive = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(d, zero, _CMP_GT_OQ), d);
		const __m512d fos = _mm512_mul_pd(_mm512_mul_pd(positive, inv_w), inv_s);
		/* F = -(nu g_n) f/s where it slides, 0 elsewhere */
		const __m512d nu = t->one_nu ? _mm512_set1_pd(t->nu[0]) : _mm512_permutexvar_pd(r, nus);
		const __m512d minus = _mm512_xor_pd(_mm512_mul_pd(nu, a), sign);
		_mm512_mask_storeu_pd(flux + k, lanes,
		                      _mm512_maskz_mov_pd(slides, _mm512_mul_pd(minus, fos)));
	}
	return any != 0;
}
#endif

/* The same, the rule of face k gathered from the table: the same
 * expressions with each face's numbers, so the bits of a face are those of
 * ss_face_fluxes with its rule.  Faces of different forms evaluate each
 * form present and keep their own. */
int SS_PATH_FN(ss_face_fluxes_mixed)(const struct ss_face_table *t, int n,
                                     const uint16_t *restrict rule,
                                     const double *restrict g_n, const double *restrict g_t,
                                     double *restrict flux)
{
#if SS_PATH == SS_PATH_AVX512
	if (t->forms == 1u << SS_FACE_COULOMB && t->count <= 8)
		return coulomb_in_registers(t, n, rule, g_n, g_t, flux);
#endif
	double s2[CHUNK], inv_s[CHUNK], inv_w[CHUNK], fos[CHUNK], slides[CHUNK];
	double nu[CHUNK], tan_cr2[CHUNK], tan_cr[CHUNK], sin_cr[CHUNK], inv_sin_cr[CHUNK];
	double gamma[CHUNK], power[CHUNK], other[CHUNK];
	const struct numbers each = {tan_cr, sin_cr, inv_sin_cr, gamma, power};
	const unsigned forms = t->forms;
	const int single = (forms & (forms - 1)) == 0;
	const int angles = forms != 1u << SS_FACE_COULOMB;   /* sin a_cr needed */
	const int hb = (forms & (1u << SS_FACE_HB_POW | 1u << SS_FACE_HB_CUBE |
	                         1u << SS_FACE_HB_THREE_HALVES)) != 0;
	/* the table's arrays as locals: loads through t in the loops would be
	 * reloaded after every store, and the gathers not vectorised */
	const double *restrict nus = t->nu, *restrict tan_cr2s = t->tan_cr2;
	const double *restrict tan_crs = t->tan_cr, *restrict sin_crs = t->sin_cr;
	const double *restrict inv_sin_crs = t->inv_sin_cr, *restrict gammas = t->gamma;
	const double *restrict powers = t->power;
	const double nu_one = nus[0];
	const int count = t->count;
	int any = 0;
	for (int base = 0; base < n; base += CHUNK) {
		const int m = n - base < CHUNK ? n - base : CHUNK;
		const double *restrict gn = g_n + base;
		const uint16_t *restrict rk = rule + base;
		if (!t->one_nu)
			gather_rules(m, rk, nus, count, nu);
		gather_rules(m, rk, tan_cr2s, count, tan_cr2);
		gather_rules(m, rk, tan_crs, count, tan_cr);
		if (angles) {
			gather_rules(m, rk, sin_crs, count, sin_cr);
			gather_rules(m, rk, inv_sin_crs, count, inv_sin_cr);
		}
		if (hb) {
			gather_rules(m, rk, gammas, count, gamma);
			gather_rules(m, rk, powers, count, power);
		}
		any |= slopes_and_rsqrt(m, tan_cr2, 1, gn, g_t + base, s2, inv_s, inv_w, slides);
		if (single) {
			f_over_s_of((enum ss_face_form)t->form[0], &each, 1, m, s2, inv_s, inv_w, fos);
		} else {
			memset(fos, 0, sizeof fos);
			for (int f = 0; f <= SS_FACE_CASSON; f++) {
				if (!(forms & 1u << f))
					continue;
				f_over_s_of((enum ss_face_form)f, &each, 1, m, s2, inv_s, inv_w, other);
				for (int k = 0; k < m; k++)
					fos[k] = t->form[rk[k]] == f ? other[k] : fos[k];
			}
		}
		if (t->one_nu)
			for (int k = 0; k < m; k++)
				flux[base + k] = ss_point_flux_of(slides[k] != 0.0, nu_one, gn[k], fos[k]);
		else
			for (int k = 0; k < m; k++)
				flux[base + k] = ss_point_flux_of(slides[k] != 0.0, nu[k], gn[k], fos[k]);
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

int ss_face_fluxes_mixed(const struct ss_face_table *t, int n, const uint16_t *restrict rule,
                         const double *restrict g_n, const double *restrict g_t,
                         double *restrict flux)
{
	const enum ss_cpu_path p = ss_cpu_path();
	return SS_PATH_CALL(p, ss_face_fluxes_mixed, t, n, rule, g_n, g_t, flux);
}

int ss_face_table_create(struct ss_face_table *t, const struct ss_closure *c, int count)
{
	memset(t, 0, sizeof *t);
	double **arrays[] = {&t->nu, &t->tan_cr, &t->tan_cr2, &t->sin_cr, &t->inv_sin_cr,
	                     &t->gamma, &t->power};
	for (size_t a = 0; a < sizeof arrays / sizeof *arrays; a++)
		if (!(*arrays[a] = ss_alloc((size_t)count, sizeof(double), "material rules")))
			return SS_ERR_FAIL;
	if (!(t->form = ss_alloc((size_t)count, 1, "material rules")))
		return SS_ERR_FAIL;
	t->count = count;
	for (int k = 0; k < count; k++) {
		struct ss_face_rule r;
		ss_face_rule_init(&r, &c[k]);
		t->nu[k] = r.nu;
		t->tan_cr[k] = r.tan_cr;
		t->tan_cr2[k] = r.tan_cr2;
		t->sin_cr[k] = r.sin_cr;
		t->inv_sin_cr[k] = r.inv_sin_cr;
		t->gamma[k] = r.gamma;
		t->power[k] = r.power;
		t->form[k] = (uint8_t)r.form;
		t->forms |= 1u << r.form;
		t->one_nu = k == 0 || (t->one_nu && r.nu == t->nu[0]);
	}
	return SS_OK;
}

void ss_face_table_release(struct ss_face_table *t)
{
	ss_free(t->nu);
	ss_free(t->tan_cr);
	ss_free(t->tan_cr2);
	ss_free(t->sin_cr);
	ss_free(t->inv_sin_cr);
	ss_free(t->gamma);
	ss_free(t->power);
	ss_free(t->form);
	memset(t, 0, sizeof *t);
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
