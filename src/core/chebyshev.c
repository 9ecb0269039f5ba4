/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * chebyshev.c - Chebyshev super-steps towards rest (chebyshev.h).
 */
#include "core/chebyshev.h"

#include <math.h>

void ss_chebyshev_init(struct ss_chebyshev *c, int s, double a, double b)
{
	c->s = s;
	c->a = a;
	c->b = b;
	c->theta = 0.5 * (b + a);
	c->delta = 0.5 * (b - a);
	c->sigma = c->theta / c->delta;
	c->rho_1 = c->rho_2 = 0.0;
	/* tau = T_s'(sigma) / (delta T_s(sigma)): with sigma = cosh(phi),
	 * T_s = cosh(s phi) and T_s' = s sinh(s phi) / sinh(phi) */
	const double phi = acosh(c->sigma);
	c->tau = s * tanh(s * phi) / (c->delta * sinh(phi));
}

struct ss_chebyshev_stage ss_chebyshev_next(struct ss_chebyshev *c, int j)
{
	struct ss_chebyshev_stage k;
	if (j == 1) {
		c->rho_1 = 1.0 / c->sigma;   /* rho_0 */
		k.mu = k.nu = 0.0;
		k.tau_mu = 1.0 / c->theta;
		return k;
	}
	/* stage j uses rho_{j-1} (computed now from rho_{j-2}) and rho_{j-2} */
	const double rho_prev = c->rho_1;
	const double rho = 1.0 / (2.0 * c->sigma - rho_prev);
	k.mu = 1.0 + rho * rho_prev;
	k.nu = -rho * rho_prev;
	k.tau_mu = 2.0 * rho / c->delta;
	c->rho_2 = rho_prev;
	c->rho_1 = rho;
	return k;
}

double ss_chebyshev_factor(const struct ss_chebyshev *c, double lambda)
{
	/* T_s(x) by its recurrence: valid for any x */
	const double x = (c->theta - lambda) / c->delta;
	double t0 = 1.0, t1 = x, u0 = 1.0, u1 = c->sigma;
	for (int k = 1; k < c->s; k++) {
		const double t2 = 2.0 * x * t1 - t0, u2 = 2.0 * c->sigma * u1 - u0;
		t0 = t1;
		t1 = t2;
		u0 = u1;
		u1 = u2;
	}
	return t1 / u1;
}

double ss_chebyshev_slow_rate(const struct ss_chebyshev *c, double ratio)
{
	if (!(ratio < c->tau))
		return 0.0;
	/* p_s falls from 1 at lambda = 0 to 0 at the first zero of T_s, where
	 * (theta - lambda) / delta = cos(pi / 2s); (1 - p_s) / lambda falls
	 * with it from tau: bisect there, in log lambda */
	const double zero = c->theta - c->delta * cos(M_PI / (2.0 * c->s));
	if (!(ratio > 1.0 / zero))
		return 1.0 / ratio;   /* beyond the first zero: 1 - p_s is about 1 */
	double lo = 1e-12 * zero, hi = zero;
	for (int k = 0; k < 100 && hi > lo * (1.0 + 1e-6); k++) {
		const double mid = sqrt(lo * hi);
		if ((1.0 - ss_chebyshev_factor(c, mid)) / mid > ratio)
			lo = mid;
		else
			hi = mid;
	}
	return sqrt(lo * hi);
}
