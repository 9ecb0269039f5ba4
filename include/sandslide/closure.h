/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * closure.h - the sliding term f_sl(s) of the degenerate parabolic sliding
 * model (DPSM) and everything derived from it point-wise.
 *
 *   dh/dt = nu div[ f_sl(s) grad h / s ] + q,    s = |grad h|      [Paper eq. 1]
 *
 * With sin a = s / sqrt(1 + s^2), sc = sin a_cr and b = sin a / sc
 * (doc/model.md#closures, [Paper] sections 2.1-2.3, eqs. 2, 10-11, 13-14, 17-18):
 *
 *   coulomb            max(s - tan a_cr, 0) / sqrt(1 + s^2)
 *   bingham            (1/b)(2 + 1/b) max(b - 1, 0)^2
 *   herschel-bulkley   (1/b)(1 + gamma + gamma/b) max(b - 1, 0)^(1 + 1/gamma)
 *   casson             (1/b)^2 (10 b^1.5 + 6 b + 3 b^0.5 + 1) max(sqrt b - 1, 0)^3
 *
 * f_sl is exactly 0 for s <= tan a_cr, so a subcritical surface never moves.
 * The functions here are static inline and pure so that every kernel and
 * every test calls the very same arithmetic (bit-identical results).
 */
#ifndef SANDSLIDE_CLOSURE_H
#define SANDSLIDE_CLOSURE_H

#include <math.h>

enum ss_closure_kind {
	SS_CLOSURE_COULOMB,
	SS_CLOSURE_BINGHAM,
	SS_CLOSURE_HERSCHEL_BULKLEY,
	SS_CLOSURE_CASSON,
};

struct ss_closure {
	enum ss_closure_kind kind;
	double repose_angle_deg; /* a_cr, degrees, in (0, 90) */
	double tan_cr;           /* tan a_cr: critical slope (dimensionless) */
	double sin_cr;           /* sin a_cr */
	double gamma;            /* Herschel-Bulkley exponent (> 0); 1 otherwise */
	double power;            /* 1 + 1/gamma: degeneracy power of HB */
	double nu;               /* effective diffusion coefficient, m^2/s */
};

/* Fill *c; returns SS_OK or SS_ERR_INPUT with a message naming the value at
 * fault (angle outside (0, 90), gamma <= 0, nu <= 0 or not finite). */
int ss_closure_init(struct ss_closure *c, enum ss_closure_kind kind,
                    double repose_angle_deg, double gamma, double nu);

/* "coulomb", "bingham", "herschel-bulkley", "casson". */
const char *ss_closure_name(enum ss_closure_kind kind);
/* Parse a closure name; returns 0 on success, -1 if unknown. */
int ss_closure_parse(const char *name, enum ss_closure_kind *kind);
/* The accepted names, for error messages. */
#define SS_CLOSURE_NAMES "coulomb, bingham, herschel-bulkley, casson"

/* f_sl(s) for s >= 0 (dimensionless), for closure kind `kind`; kernels pass
 * a constant kind so the switch is resolved outside their loops. */
static inline double ss_closure_eval_kind(enum ss_closure_kind kind,
                                          const struct ss_closure *c, double s)
{
	if (!(s > c->tan_cr))
		return 0.0;
	const double sin_a = s / sqrt(1.0 + s * s);
	const double b = sin_a / c->sin_cr;
	const double r = 1.0 / b;              /* sin a_cr / sin a */
	switch (kind) {
	case SS_CLOSURE_COULOMB:
		return (s - c->tan_cr) / sqrt(1.0 + s * s);
	/* s > tan a_cr can still round to b < 1 by an ulp at steep repose
	 * angles: max(., 0) as in doc/model.md#closures keeps pow() away from NaN */
	case SS_CLOSURE_BINGHAM: {
		const double e = fmax(b - 1.0, 0.0);
		return r * (2.0 + r) * (e * e);
	}
	case SS_CLOSURE_HERSCHEL_BULKLEY:
		return r * (1.0 + c->gamma + c->gamma * r) * pow(fmax(b - 1.0, 0.0), c->power);
	case SS_CLOSURE_CASSON: {
		const double q = sqrt(b), e = fmax(q - 1.0, 0.0);
		return r * r * (10.0 * b * q + 6.0 * b + 3.0 * q + 1.0) * (e * e * e);
	}
	}
	return 0.0;
}

/* f_sl(s) for s >= 0 (dimensionless). */
static inline double ss_closure_eval(const struct ss_closure *c, double s)
{
	return ss_closure_eval_kind(c->kind, c, s);
}

/* f_sl'(s), the derivative with respect to the slope s (one-sided from above
 * at s = tan a_cr; 0 below).  Used for the CFL bound, doc/model.md#the-cfl-bound. */
static inline double ss_closure_derivative(const struct ss_closure *c, double s)
{
	if (!(s > c->tan_cr))
		return 0.0;
	const double w = 1.0 + s * s;
	const double dsin_ds = 1.0 / (w * sqrt(w));      /* d(sin a)/ds */
	const double b = s / sqrt(w) / c->sin_cr;
	const double db_ds = dsin_ds / c->sin_cr;
	double df_db;
	switch (c->kind) {
	case SS_CLOSURE_COULOMB:
		return (1.0 + s * c->tan_cr) * dsin_ds;
	case SS_CLOSURE_BINGHAM:
	case SS_CLOSURE_HERSCHEL_BULKLEY: {
		/* f = (A/b + G/b^2) e^p, e = b - 1, A = 1 + gamma, G = gamma */
		const double g = c->kind == SS_CLOSURE_BINGHAM ? 1.0 : c->gamma;
		const double p = c->kind == SS_CLOSURE_BINGHAM ? 2.0 : c->power;
		const double A = 1.0 + g, e = fmax(b - 1.0, 0.0);
		const double ep1 = pow(e, p - 1.0);
		df_db = (-A / (b * b) - 2.0 * g / (b * b * b)) * ep1 * e
		        + (A / b + g / (b * b)) * p * ep1;
		break;
	}
	case SS_CLOSURE_CASSON: {
		/* with r = sqrt b: f = P(r) (r - 1)^3 / r^4 */
		const double r = sqrt(b), e = fmax(r - 1.0, 0.0);
		const double P = 10.0 * r * r * r + 6.0 * r * r + 3.0 * r + 1.0;
		const double dP = 30.0 * r * r + 12.0 * r + 3.0;
		const double r4 = r * r * r * r;
		const double df_dr = (dP * e * e * e + 3.0 * P * e * e) / r4
		                     - 4.0 * P * e * e * e / (r4 * r);
		df_db = df_dr / (2.0 * r);
		break;
	}
	default:
		return 0.0;
	}
	return df_db * db_ds;
}

/* The stability rate of a face at slope s, lambda/nu = max(f'(s), f(s)/s)
 * (doc/model.md#forward-euler: dt = cfl / (2 lambda_max (1/dx^2 + 1/dy^2))). */
static inline double ss_closure_lambda(const struct ss_closure *c, double s)
{
	if (!(s > c->tan_cr))
		return 0.0;
	const double d = ss_closure_derivative(c, s);
	const double q = ss_closure_eval(c, s) / s;
	return d > q ? d : q;
}

/* Flux across a face per unit face length and per unit nu:
 * -f_sl(s) g_n / s with s = sqrt(g_n^2 + g_t^2), g_n the gradient normal to
 * the face and g_t the tangential one (doc/model.md#face-flux).  Exactly 0 for
 * s <= tan a_cr, including s = 0. */
static inline double ss_closure_face_flux_kind(enum ss_closure_kind kind,
                                               const struct ss_closure *c,
                                               double g_n, double g_t)
{
	const double s = sqrt(g_n * g_n + g_t * g_t);
	if (!(s > c->tan_cr))
		return 0.0;
	return -ss_closure_eval_kind(kind, c, s) / s * g_n;
}

static inline double ss_closure_face_flux(const struct ss_closure *c,
                                          double g_n, double g_t)
{
	return ss_closure_face_flux_kind(c->kind, c, g_n, g_t);
}

/*
 * The CFL rule every kernel uses (doc/model.md#the-cfl-bound; any upper bound of
 * lambda_max): Lambda(S) = max of lambda(s)/nu over s in [0, S], tabulated
 * once per closure at angles k * (90 deg / SS_CFL_TABLE_SIZE), each entry the
 * maximum over 16 samples per interval up to that angle (and the one-sided
 * limit just above tan a_cr), raised by a relative margin of 1e-6 that covers
 * the peak falling between samples (measured: below 1e-8).  A sweep only
 * needs the largest face slope S; the table is indexed by the angle atan(S)
 * rounded up, so the bound holds for every face of the state.
 */
#define SS_CFL_TABLE_SIZE 4096
struct ss_cfl_bound {
	double tan_cr;                            /* below it Lambda is 0 */
	double lambda_max[SS_CFL_TABLE_SIZE + 1]; /* Lambda at angle k, /nu */
};

void ss_cfl_bound_init(struct ss_cfl_bound *t, const struct ss_closure *c);
/* Lambda(S)/nu for the largest face slope S >= 0 (0 when S <= tan a_cr). */
double ss_cfl_bound_lookup(const struct ss_cfl_bound *t, double s_max);
/* bound[k], k < SS_CFL_TABLE_SIZE: the largest slope whose entry of the
 * table is at most k, so that the entry ss_cfl_bound_lookup picks for s is
 * the first k with s <= bound[k] (SS_CFL_TABLE_SIZE if none), found by
 * comparisons: how the GPU looks it up without atan(), whose last bit
 * differs between C libraries (doc/gpu.md).  The same for every closure. */
void ss_cfl_bound_thresholds(double bound[SS_CFL_TABLE_SIZE]);
/* Widen t to bound closure c too, whose nu is c->nu where t's is nu_t:
 * Lambda_t(S) >= (c->nu / nu_t) Lambda_c(S) for every S (several materials,
 * doc/model.md#materials). */
void ss_cfl_bound_widen(struct ss_cfl_bound *t, const struct ss_closure *c, double nu_t);

#endif
