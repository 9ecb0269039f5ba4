/*
 * rkl2.c - RKL2 coefficients from their closed formulas (rkl2.h).
 */
#include "sandslide/rkl2.h"

#include <math.h>

/* b_j of the recurrence: 1/3 for j <= 2, else (j^2 + j - 2) / (2 j (j + 1)) */
static double b_of(int j)
{
	if (j <= 2)
		return 1.0 / 3.0;
	const double jj = j;
	return (jj * jj + jj - 2.0) / (2.0 * jj * (jj + 1.0));
}

struct ss_rkl2_stage ss_rkl2_stage(int s, int j)
{
	const double ss = s;
	const double w1 = 4.0 / (ss * ss + ss - 2.0);
	struct ss_rkl2_stage c = {0.0, 0.0, w1 / 3.0, 0.0};
	if (j < 2)
		return c;
	const double jj = j;
	c.mu = (2.0 * jj - 1.0) / jj * b_of(j) / b_of(j - 1);
	c.nu = -(jj - 1.0) / jj * b_of(j) / b_of(j - 2);
	c.mu_tilde = w1 * c.mu;
	c.gamma_tilde = -(1.0 - b_of(j - 1)) * c.mu_tilde;
	return c;
}

double ss_rkl2_stable_ratio(int s)
{
	const double ss = s;
	return (ss * ss + ss - 2.0) / 4.0;
}

int ss_rkl2_stages_for(double ratio)
{
	if (!(ratio > 1.0))
		return 2;
	/* the positive root of s^2 + s - 2 - 4 ratio = 0, rounded up; then
	 * checked both ways against the ratio itself, since the root is
	 * rounded */
	int s = (int)ceil(0.5 * (-1.0 + sqrt(9.0 + 16.0 * ratio)));
	if (s < 2)
		s = 2;
	while (s > 2 && ss_rkl2_stable_ratio(s - 1) >= ratio)
		s--;
	while (ss_rkl2_stable_ratio(s) < ratio)
		s++;
	return s;
}
