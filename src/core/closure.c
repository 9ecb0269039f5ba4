/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * closure.c - closure set-up, names and the tabulated CFL bound.
 * The point-wise formulas are static inline in closure.h.
 */
#include "sandslide/closure.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"

static const char *const closure_names[] = {
	[SS_CLOSURE_COULOMB] = "coulomb",
	[SS_CLOSURE_BINGHAM] = "bingham",
	[SS_CLOSURE_HERSCHEL_BULKLEY] = "herschel-bulkley",
	[SS_CLOSURE_CASSON] = "casson",
};

const char *ss_closure_name(enum ss_closure_kind kind)
{
	if ((unsigned)kind >= sizeof closure_names / sizeof *closure_names)
		SS_BUG("unknown closure kind %d", (int)kind);
	return closure_names[kind];
}

int ss_closure_parse(const char *name, enum ss_closure_kind *kind)
{
	const int k = ss_parse_name(name, closure_names,
	                            (int)(sizeof closure_names / sizeof *closure_names));
	if (k >= 0)
		*kind = (enum ss_closure_kind)k;
	return k < 0 ? -1 : 0;
}

int ss_closure_init(struct ss_closure *c, enum ss_closure_kind kind,
                    double repose_angle_deg, double gamma, double nu)
{
	if (!(repose_angle_deg > 0.0 && repose_angle_deg < 90.0))
		return ss_error_input("repose angle %g deg is outside (0, 90)",
		                      repose_angle_deg);
	if (!(gamma > 0.0) || !isfinite(gamma))
		return ss_error_input("gamma %g must be finite and > 0", gamma);
	if (!(nu > 0.0) || !isfinite(nu))
		return ss_error_input("nu %g m^2/s must be finite and > 0", nu);
	const double a = repose_angle_deg * (M_PI / 180.0);
	c->kind = kind;
	c->repose_angle_deg = repose_angle_deg;
	c->tan_cr = tan(a);
	c->sin_cr = sin(a);
	c->gamma = kind == SS_CLOSURE_HERSCHEL_BULKLEY ? gamma : 1.0;
	c->power = 1.0 + 1.0 / c->gamma;
	c->nu = nu;
	return SS_OK;
}

enum { SAMPLES_PER_INTERVAL = 16 };
#define CFL_TABLE_MARGIN 1e-6

void ss_cfl_bound_init(struct ss_cfl_bound *t, const struct ss_closure *c)
{
	const double dangle = (M_PI / 2.0) / SS_CFL_TABLE_SIZE;
	/* Coulomb's f' jumps from 0 to cos a_cr just above tan a_cr: that
	 * one-sided limit enters the entry the lookup picks for such a slope */
	const double s_cr = nextafter(c->tan_cr, INFINITY);
	const double k_cr = ceil(atan(s_cr) / dangle);
	const double lambda_cr = ss_closure_lambda(c, s_cr);
	double running = 0.0;
	t->tan_cr = c->tan_cr;
	t->lambda_max[0] = 0.0;
	for (int k = 1; k <= SS_CFL_TABLE_SIZE; k++) {
		/* samples in ((k-1) da, k da]; the last one stops short of
		 * 90 deg, where s is infinite and lambda tends to 0 */
		for (int m = 1; m <= SAMPLES_PER_INTERVAL; m++) {
			double a = ((k - 1) + (double)m / SAMPLES_PER_INTERVAL) * dangle;
			if (a >= M_PI / 2.0)
				a = M_PI / 2.0 - 1e-9;
			running = fmax(running, ss_closure_lambda(c, tan(a)));
		}
		if (k >= k_cr)
			running = fmax(running, lambda_cr);
		t->lambda_max[k] = running * (1.0 + CFL_TABLE_MARGIN);
	}
}

double ss_cfl_bound_lookup(const struct ss_cfl_bound *t, double s_max)
{
	if (!(s_max > t->tan_cr))
		return 0.0;
	const double dangle = (M_PI / 2.0) / SS_CFL_TABLE_SIZE;
	double k = ceil(atan(s_max) / dangle);
	if (k > SS_CFL_TABLE_SIZE)
		k = SS_CFL_TABLE_SIZE;
	return t->lambda_max[(int)k];
}

/* The entry of the table for slope s >= 0, unclamped from above. */
static double cfl_entry(double s)
{
	const double dangle = (M_PI / 2.0) / SS_CFL_TABLE_SIZE;
	const double k = ceil(atan(s) / dangle);
	return k > SS_CFL_TABLE_SIZE ? SS_CFL_TABLE_SIZE : k;
}

void ss_cfl_bound_thresholds(double bound[SS_CFL_TABLE_SIZE])
{
	/* non-negative doubles are ordered as their bits: bisect on them for
	 * the last s whose entry is <= k (the entry never falls as s grows) */
	for (int k = 0; k < SS_CFL_TABLE_SIZE; k++) {
		uint64_t lo = 0, hi = 0x7ff0000000000000u;     /* entry(0) = 0 <= k < entry(inf) */
		while (hi - lo > 1) {
			const uint64_t mid = lo + (hi - lo) / 2;
			double s;
			memcpy(&s, &mid, sizeof s);
			if (cfl_entry(s) <= k)
				lo = mid;
			else
				hi = mid;
		}
		memcpy(&bound[k], &lo, sizeof lo);
	}
}

void ss_cfl_bound_widen(struct ss_cfl_bound *t, const struct ss_closure *c, double nu_t)
{
	struct ss_cfl_bound u;
	ss_cfl_bound_init(&u, c);
	const double scale = c->nu / nu_t;
	t->tan_cr = fmin(t->tan_cr, u.tan_cr);
	for (int k = 0; k <= SS_CFL_TABLE_SIZE; k++)
		t->lambda_max[k] = fmax(t->lambda_max[k], scale * u.lambda_max[k]);
}
