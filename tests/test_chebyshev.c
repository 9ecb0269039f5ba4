/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_chebyshev.c - the coefficients of a Chebyshev super-step towards
 * rest (core/chebyshev.h), run on the scalar problem y' = -lambda y, whose
 * exact answer over a super-step is its polynomial p_s(lambda):
 *
 *   the stages' recurrence gives p_s(lambda) = T_s((theta - lambda)/delta)
 *   / T_s(sigma) for rates in and below [a, b];
 *   p_s(0) = 1: a state at rest stays at rest;
 *   a constant rate c adds c tau over the super-step (tau its length);
 *   every rate of [a, b] is damped to at most 1/T_s(sigma), and every rate
 *   of (0, a) decays (0 < p_s < 1): nothing in [0, b] grows;
 *   the rate of one mode is found again from what a super-step did to it
 *   (ss_chebyshev_slow_rate): to 1 % below a, to 10 % from a to the first
 *   zero of p_s (where (1 - p_s) / lambda need not fall monotonically).
 */
#include "check.h"

#include "core/chebyshev.h"

/* The super-step on y' = -lambda y + c from y0, through the stage form. */
static double superstep(int s, double a, double b, double lambda, double c, double y0,
                        double *tau)
{
	struct ss_chebyshev ch;
	ss_chebyshev_init(&ch, s, a, b);
	double d1 = 0.0, d2 = 0.0;   /* D_{j-1}, D_{j-2} */
	for (int j = 1; j <= s; j++) {
		const struct ss_chebyshev_stage k = ss_chebyshev_next(&ch, j);
		const double m = -lambda * (y0 + d1) + c;
		const double d = k.mu * d1 + k.nu * d2 + k.tau_mu * m;
		d2 = d1;
		d1 = d;
	}
	*tau = ch.tau;
	return y0 + d1;
}

static void the_stages_give_the_chebyshev_polynomial(void)
{
	const int stages[] = {1, 2, 5, 17, 100, 400};
	for (size_t n = 0; n < sizeof stages / sizeof *stages; n++) {
		const int s = stages[n];
		const double b = 3.0, a = 0.5 * b / ((double)s * s);
		struct ss_chebyshev ch;
		ss_chebyshev_init(&ch, s, a, b);
		double tau;
		for (int k = 0; k <= 40; k++) {
			const double lambda = b * k / 40.0;
			const double y = superstep(s, a, b, lambda, 0.0, 1.0, &tau);
			CHECK_NEAR(y, ss_chebyshev_factor(&ch, lambda), 1e-9,
			           "s = %d, lambda = %g: the stages against T_s", s, lambda);
			CHECK(fabs(y) <= 1.0 + 1e-12, "s = %d, lambda = %g: |p_s| = %g > 1", s, lambda,
			      fabs(y));
			if (lambda >= a)
				CHECK(fabs(y) <= 1.0 / cosh(s * acosh(ch.sigma)) + 1e-12,
				      "s = %d, lambda = %g: damped by %g only", s, lambda, fabs(y));
			else if (lambda > 0.0)
				CHECK(y > 0.0 && y < 1.0, "s = %d, lambda = %g below a: p_s = %g", s,
				      lambda, y);
		}
		CHECK(superstep(s, a, b, 0.0, 0.0, 1.0, &tau) == 1.0,
		      "s = %d: a state at rest moved", s);
		const double rise = superstep(s, a, b, 0.0, 2.5, 0.0, &tau);
		CHECK_REL(rise, 2.5 * tau, 1e-12, "s = %d: a constant rate over tau = %g", s, tau);
		/* the slow modes move as forward Euler over tau: p_s ~ 1 - lambda tau */
		const double small = 1e-6 * a;
		CHECK_REL(1.0 - superstep(s, a, b, small, 0.0, 1.0, &tau), small * tau, 1e-5,
		          "s = %d: the slope of p_s at 0 is -tau", s);
	}
}

/* One mode y' = -lambda y through a super-step: its change over its rate
 * at the start names lambda, wherever it lies below the first zero. */
static void the_rate_of_one_mode_is_found_again(void)
{
	const int stages[] = {2, 8, 13, 64, 500};
	for (size_t n = 0; n < sizeof stages / sizeof *stages; n++) {
		const int s = stages[n];
		const double b = 7.0, a = b / ((double)s * s);
		struct ss_chebyshev ch;
		ss_chebyshev_init(&ch, s, a, b);
		const double zero = ch.theta - ch.delta * cos(M_PI / (2.0 * s));
		const double where[] = {1e-4, 0.01, 0.3, 1.0, 1.7, 0.99 * zero / a};
		for (size_t k = 0; k < sizeof where / sizeof *where; k++) {
			const double lambda = where[k] * a;
			double tau;
			const double change = 1.0 - superstep(s, a, b, lambda, 0.0, 1.0, &tau);
			CHECK_REL(ss_chebyshev_slow_rate(&ch, change / lambda), lambda,
			          lambda <= a ? 0.01 : 0.1,
			          "s = %d: the rate %g a of one mode", s, where[k]);
		}
		CHECK(ss_chebyshev_slow_rate(&ch, ch.tau) == 0.0,
		      "s = %d: a change of tau times the rate is slower than anything", s);
	}
}

int main(void)
{
	RUN(the_stages_give_the_chebyshev_polynomial);
	RUN(the_rate_of_one_mode_is_found_again);
	return check_report();
}
