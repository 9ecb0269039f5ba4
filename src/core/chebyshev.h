/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * chebyshev.h - the coefficients of a Chebyshev super-step towards rest:
 * Chebyshev acceleration of forward Euler (the Chebyshev semi-iterative
 * method; Golub & Varga, Numer. Math. 3, 1961; Saad, "Iterative Methods
 * for Sparse Linear Systems", 2nd ed., SIAM 2003, section 12.3, Algorithm
 * 12.1), written as the stages of a super-step in the delta form of the
 * RKL2 stages (rkl2.h, sweep.h), so that the same kernels run it:
 *
 *   D_1 = tau_mu_1 M(Y_0)
 *   D_j = mu_j D_{j-1} + nu_j D_{j-2} + tau_mu_j M(Y_{j-1}),   j = 2 .. s
 *   Y_j = Y_0 + D_j
 *
 * with, for the rates of the linearised stencil in [a, b] (1/s; b the
 * largest, what forward Euler's stable step is 2/b of),
 *
 *   theta = (b + a)/2,  delta = (b - a)/2,  sigma = theta/delta,
 *   rho_0 = 1/sigma,    rho_k = 1 / (2 sigma - rho_{k-1}),
 *   tau_mu_1 = 1/theta, mu_j = 1 + rho_{j-1} rho_{j-2},
 *   nu_j = -rho_{j-1} rho_{j-2},  tau_mu_j = 2 rho_{j-1} / delta.
 *
 * A mode of rate lambda is multiplied over the super-step by
 *
 *   p_s(lambda) = T_s((theta - lambda)/delta) / T_s(sigma)     (T_s Chebyshev)
 *
 * which is 1 at lambda = 0 (a state at rest stays at rest, and the stages
 * are combinations of flux divergences, so the volume is kept), lies in
 * [-1/T_s(sigma), 1/T_s(sigma)] on [a, b] and in (0, 1] on [0, a]: every
 * mode of [0, b] decays, those of [a, b] by at least T_s(sigma), and over
 * all of [a, b] this is the fastest decay any s evaluations give.  Unlike
 * RKL2, whose stiff modes keep up to 0.7 of themselves per super-step,
 * whatever its length, it damps the grid-scale remainder that makes an
 * approach to rest crawl.  It is not accurate in time: a super-step moves
 * the slow modes as forward Euler moves them over
 *
 *   tau = -p_s'(0) = T_s'(sigma) / (delta T_s(sigma))
 *
 * (the super-step's length; a constant rate c adds c tau), and the fast
 * ones faster than they would decay.
 */
#ifndef SANDSLIDE_CORE_CHEBYSHEV_H
#define SANDSLIDE_CORE_CHEBYSHEV_H

struct ss_chebyshev {
	int s;              /* stages */
	double a, b;        /* the rates damped, 1/s */
	double theta, delta, sigma;
	double rho_1, rho_2; /* rho_{j-1}, rho_{j-2} after stage j */
	double tau;         /* the super-step's length for the slow modes, s */
};

struct ss_chebyshev_stage {
	double mu, nu;      /* weights of D_{j-1}, D_{j-2} */
	double tau_mu;      /* weight of M(Y_{j-1}), s */
};

/* Set c up for an s-stage super-step (s >= 1) damping the rates [a, b],
 * 0 < a < b. */
void ss_chebyshev_init(struct ss_chebyshev *c, int s, double a, double b);

/* The coefficients of stage j = 1, 2, ... s, in that order (the rho
 * recurrence is carried in c). */
struct ss_chebyshev_stage ss_chebyshev_next(struct ss_chebyshev *c, int j);

/* p_s(lambda): what the super-step multiplies a mode of rate lambda by (for
 * the tests). */
double ss_chebyshev_factor(const struct ss_chebyshev *c, double lambda);

/* The rate lambda of the mode that dominates a super-step, from what the
 * super-step did to it: ratio = (its change) / (its rate at the start),
 * which for one mode is (1 - p_s(lambda)) / lambda.  0 when ratio >= tau
 * (slower than the super-step tells apart), 1 / ratio beyond the first
 * zero of p_s. */
double ss_chebyshev_slow_rate(const struct ss_chebyshev *c, double ratio);

#endif
