/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit_cost.h - the pieces of fit's cost functionals that are plain
 * numerics on arrays (doc/fit.md#cost-functionals): the support indicator
 * and the observed support of a front.  No files, no stepper.
 */
#ifndef SANDSLIDE_APP_FIT_COST_H
#define SANDSLIDE_APP_FIT_COST_H

#include <math.h>

/*
 * The support indicator chi(d) of sand of thickness d, m, for the
 * threshold theta, m (doc/fit.md eq. F2):
 *
 *   chi = 0 for d <= theta/2,  1 for d >= 3 theta/2,  (d - theta/2) / theta between.
 *
 * Its area sum(chi) dx dy is the support's (the cells thicker than theta)
 * to within the cells of the ramp, and it is continuous in d, so that the
 * support cost is continuous in the parameters: a 0/1 indicator makes it a
 * staircase that a search by quadratic models cannot follow.
 */
static inline double ss_fit_support_indicator(double d, double theta)
{
	const double x = (d - 0.5 * theta) / theta;
	return x <= 0.0 ? 0.0 : x >= 1.0 ? 1.0 : x;
}

/* The support of a surface as a front sees it: the thickness d[ny * nx]
 * (m, south row first, at cell centres) interpolated bilinearly between
 * the centres (held at the nearest centre outside them), chi of F2 at
 * samples x samples points per cell, their mean per cell into chi.  A
 * front traced on a surface is a contour of a continuous surface, not of
 * cell values: this is the support it traces (doc/fit.md eq. F3). */
void ss_fit_support_fraction(const double *d, int nx, int ny, double theta, int samples,
                             double *chi);

/* The observed support of a front at one time: points x[k], y[k] (m, n >= 3)
 * on the boundary of the sand-covered region, joined in the order of their
 * angle about their centroid (the region must be star-shaped about it, as a
 * spreading pile's is), as the fraction of each cell of an nx x ny grid
 * (south row first; lower-left corner origin_x, origin_y, cells dx x dy, m)
 * inside that polygon, from samples x samples points per cell, into
 * chi[ny * nx].  Returns the polygon's area, m^2, or -1 when out of
 * memory (n entries of scratch). */
double ss_fit_front_support(const double *x, const double *y, long long n, int nx, int ny,
                            double origin_x, double origin_y, double dx, double dy,
                            int samples, double *chi);

#endif
