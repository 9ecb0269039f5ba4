/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_fit.c - the numerics of fit's cost functionals (app/fit_cost.h,
 * doc/fit.md F2-F3) and the words of --param (fit.h).  The fits themselves
 * are twin experiments driven through the command line:
 * tests/cli/test_fit.py.
 */
#include "check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app/fit_cost.h"
#include "sandslide/error.h"
#include "sandslide/fit.h"

/* F2: 0 below theta/2, 1 above 3 theta/2, linear and continuous between. */
static void test_indicator(void)
{
	const double theta = 0.02;
	CHECK(ss_fit_support_indicator(0.0, theta) == 0.0, "bare floor is in the support");
	CHECK(ss_fit_support_indicator(0.01, theta) == 0.0, "theta/2 is in the support");
	CHECK(ss_fit_support_indicator(0.0301, theta) == 1.0, "above 3 theta/2 is not wholly in it");
	CHECK(ss_fit_support_indicator(1.0, theta) == 1.0, "thick sand is not wholly in it");
	CHECK_NEAR(ss_fit_support_indicator(0.02, theta), 0.5, 1e-15, "theta itself");
	CHECK(ss_fit_support_indicator(-1.0, theta) == 0.0, "a hole is in the support");
	/* continuous: no jump anywhere on a fine scan */
	double prev = ss_fit_support_indicator(0.0, theta), jump = 0.0;
	for (int k = 1; k <= 40000; k++) {
		const double v = ss_fit_support_indicator(0.04 * k / 40000.0, theta);
		jump = fmax(jump, fabs(v - prev));
		prev = v;
	}
	CHECK(jump <= 0.04 / 40000.0 / theta * 1.0001, "chi jumps by %g in a step of %g m",
	      jump, 0.04 / 40000.0);
}

/* The support a front sees of a thickness that falls linearly from a
 * line: the thickness d = s (x0 - x) crosses theta at x = x0 - theta / s,
 * and the support's area is the area west of it, whatever the ramp. */
static void test_fraction_of_a_ramp(void)
{
	enum { NX = 40, NY = 6 };
	const double theta = 0.02, slope = 0.013;   /* m per cell */
	double d[NX * NY], chi[NX * NY];
	for (int x0i = 0; x0i < 5; x0i++) {
		const double x0 = 20.0 + 0.23 * x0i;  /* in cells, centre of cell 0 at 0 */
		for (int j = 0; j < NY; j++)
			for (int i = 0; i < NX; i++)
				d[j * NX + i] = fmax(slope * (x0 - i), 0.0);
		ss_fit_support_fraction(d, NX, NY, theta, 4, chi);
		double area = 0.0;
		for (int i = 0; i < NX * NY; i++)
			area += chi[i];
		/* cell i spans i - 1/2 .. i + 1/2: the area west of the contour */
		const double want = (x0 - theta / slope + 0.5) * NY;
		CHECK_NEAR(area, want, 0.02 * NY, "front at %g cells: area %g cells, the contour "
		           "gives %g", x0, area, want);
	}
	/* a single thick cell: its support spreads no further than a cell on
	 * each side, and is symmetric */
	memset(d, 0, sizeof d);
	d[3 * NX + 10] = 1.0;
	ss_fit_support_fraction(d, NX, NY, theta, 4, chi);
	CHECK(chi[3 * NX + 10] == 1.0, "the thick cell is not wholly in its support");
	CHECK(chi[3 * NX + 8] == 0.0 && chi[3 * NX + 12] == 0.0 && chi[1 * NX + 10] == 0.0,
	      "the support reaches two cells away");
	CHECK_NEAR(chi[3 * NX + 9], chi[3 * NX + 11], 1e-15, "west and east neighbours differ");
	CHECK_NEAR(chi[2 * NX + 10], chi[4 * NX + 10], 1e-15, "south and north neighbours differ");
}

/* A front of points on a circle: the polygon's area is the inscribed
 * n-gon's, and the cells inside it are 1, outside 0, its edge partly. */
static void test_front_support(void)
{
	enum { NX = 50, NY = 40, N = 180 };
	const double dx = 0.1, dy = 0.1, ox = -2.5, oy = -2.0, r = 1.3, cx = 0.07, cy = -0.11;
	double x[N], y[N], chi[NX * NY];
	/* given in a scrambled order: the polygon joins them by angle */
	for (int k = 0; k < N; k++) {
		const int m = (k * 37) % N;
		x[k] = cx + r * cos(2 * M_PI * m / N);
		y[k] = cy + r * sin(2 * M_PI * m / N);
	}
	const double area = ss_fit_front_support(x, y, N, NX, NY, ox, oy, dx, dy, 4, chi);
	const double polygon = 0.5 * N * r * r * sin(2 * M_PI / N);
	CHECK_REL(area, polygon, 1e-12, "polygon area %g, the inscribed %d-gon's %g", area, N,
	          polygon);
	double sum = 0.0;
	int wrong = 0;
	for (int j = 0; j < NY; j++)
		for (int i = 0; i < NX; i++) {
			const double v = chi[j * NX + i];
			sum += v * dx * dy;
			const double px = ox + (i + 0.5) * dx - cx, py = oy + (j + 0.5) * dy - cy;
			const double dist = hypot(px, py);
			wrong += (dist < r - dx && v != 1.0) || (dist > r + dx && v != 0.0) ||
			         v < 0.0 || v > 1.0;
		}
	CHECK(wrong == 0, "%d cells well inside or outside the front have the wrong fraction",
	      wrong);
	CHECK_REL(sum, polygon, 0.01, "the cells' support %g m^2, the polygon's %g m^2", sum,
	          polygon);
	CHECK(ss_fit_front_support(x, y, N, NX, NY, ox, oy, dx, dy, 4, chi) == area,
	      "the same front twice gives another area");
}

static void test_param_words(void)
{
	struct ss_fit_param p;
	CHECK(ss_fit_param_parse("nu=0.01:1:log", &p) == SS_OK && !strcmp(p.name, "nu") &&
	      p.lo == 0.01 && p.hi == 1.0 && p.log == 1, "nu=0.01:1:log");
	CHECK(ss_fit_param_parse("repose_angle=30:40", &p) == SS_OK &&
	      !strcmp(p.name, "repose_angle") && p.lo == 30.0 && p.hi == 40.0 && !p.log,
	      "repose_angle=30:40");
	CHECK(ss_fit_param_parse("gamma=0.2:5:log", &p) == SS_OK, "gamma=0.2:5:log");
	static const char *const bad[] = {
		"nu", "nu=", "nu=1", "nu=1:", "nu=:1", "nu=2:1", "nu=1:1", "nu=0:1:log",
		"nu=-1:1:log", "nu=0.1:1:lin", "nu=0.1:1:log:x", "angle=30:40", "nux=1:2",
		"nu=a:1", "nu=1:nan", "=1:2", "nu=0.1:inf",
	};
	ss_error_set_quiet(1);
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		const int err = ss_fit_param_parse(bad[k], &p);
		CHECK(err == SS_ERR_INPUT, "--param '%s' is accepted", bad[k]);
		CHECK(err != SS_ERR_INPUT || strstr(ss_error_last_message(), bad[k]),
		      "the message for '%s' does not name it: %s", bad[k], ss_error_last_message());
	}
	ss_error_set_quiet(0);
}

int main(void)
{
	RUN(test_indicator);
	RUN(test_fraction_of_a_ramp);
	RUN(test_front_support);
	RUN(test_param_words);
	return check_report();
}
