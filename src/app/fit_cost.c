/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit_cost.c - the support as a front sees it, and the observed support of
 * a front (fit_cost.h).
 */
#include "app/fit_cost.h"

#include <stdlib.h>

struct angled {
	double angle, x, y;
};

static int by_angle(const void *a, const void *b)
{
	const struct angled *p = a, *q = b;
	return (p->angle > q->angle) - (p->angle < q->angle);
}

/* Even-odd rule: is (x, y) inside the closed polygon p[0..n-1]? */
static int inside(const struct angled *p, long long n, double x, double y)
{
	int in = 0;
	for (long long a = 0, b = n - 1; a < n; b = a++)
		if ((p[a].y > y) != (p[b].y > y) &&
		    x < p[b].x + (y - p[b].y) * (p[a].x - p[b].x) / (p[a].y - p[b].y))
			in = !in;
	return in;
}

double ss_fit_front_support(const double *x, const double *y, long long n, int nx, int ny,
                            double origin_x, double origin_y, double dx, double dy,
                            int samples, double *chi)
{
	struct angled *p = malloc((size_t)n * sizeof *p);
	if (!p)
		return -1.0;
	double cx = 0.0, cy = 0.0;
	for (long long k = 0; k < n; k++) {
		cx += x[k];
		cy += y[k];
	}
	cx /= (double)n;
	cy /= (double)n;
	for (long long k = 0; k < n; k++)
		p[k] = (struct angled){atan2(y[k] - cy, x[k] - cx), x[k], y[k]};
	qsort(p, (size_t)n, sizeof *p, by_angle);
	/* the shoelace formula */
	double area = 0.0;
	for (long long a = 0, b = n - 1; a < n; b = a++)
		area += p[b].x * p[a].y - p[a].x * p[b].y;
	area = 0.5 * fabs(area);
	/* the polygon's bounding box limits the cells sampled */
	double x0 = p[0].x, x1 = p[0].x, y0 = p[0].y, y1 = p[0].y;
	for (long long k = 1; k < n; k++) {
		x0 = fmin(x0, p[k].x);
		x1 = fmax(x1, p[k].x);
		y0 = fmin(y0, p[k].y);
		y1 = fmax(y1, p[k].y);
	}
	const double per_sample = 1.0 / ((double)samples * samples);
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++) {
			const double cell_x = origin_x + i * dx, cell_y = origin_y + j * dy;
			int hits = 0;
			if (cell_x + dx >= x0 && cell_x <= x1 && cell_y + dy >= y0 && cell_y <= y1)
				for (int b = 0; b < samples; b++)
					for (int a = 0; a < samples; a++)
						hits += inside(p, n, cell_x + (a + 0.5) * dx / samples,
						               cell_y + (b + 0.5) * dy / samples);
			chi[(size_t)j * nx + i] = hits * per_sample;
		}
	free(p);
	return area;
}

void ss_fit_support_fraction(const double *d, int nx, int ny, double theta, int samples,
                             double *chi)
{
	const double per_sample = 1.0 / ((double)samples * samples);
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++) {
			double sum = 0.0;
			for (int b = 0; b < samples; b++) {
				/* the sample's position in centre coordinates: cell (i, j)
				 * spans i - 1/2 .. i + 1/2 */
				const double y = fmin(fmax(j - 0.5 + (b + 0.5) / samples, 0.0), ny - 1.0);
				const int j0 = y < ny - 1 ? (int)y : ny - 1 > 0 ? ny - 2 : 0;
				const double fy = ny > 1 ? y - j0 : 0.0;
				const int j1 = ny > 1 ? j0 + 1 : j0;
				for (int a = 0; a < samples; a++) {
					const double x = fmin(fmax(i - 0.5 + (a + 0.5) / samples, 0.0), nx - 1.0);
					const int i0 = x < nx - 1 ? (int)x : nx - 1 > 0 ? nx - 2 : 0;
					const double fx = nx > 1 ? x - i0 : 0.0;
					const int i1 = nx > 1 ? i0 + 1 : i0;
					const double *r0 = d + (size_t)j0 * nx, *r1 = d + (size_t)j1 * nx;
					const double v = (1 - fy) * ((1 - fx) * r0[i0] + fx * r0[i1]) +
					                 fy * ((1 - fx) * r1[i0] + fx * r1[i1]);
					sum += ss_fit_support_indicator(v, theta);
				}
			}
			chi[(size_t)j * nx + i] = sum * per_sample;
		}
}
