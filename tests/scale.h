/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * scale.h - smaller test cases under slow instrumentation.
 *
 * SANDSLIDE_TEST_SCALE, a factor in (0, 1] (default 1), multiplies the
 * number of cells along each side of the longest-running cases of the C
 * tests; each test file says at its top which cases read it.  Every check
 * still runs, on the smaller grid.  `make SANITIZE=1 test` and `make race`
 * set it to 0.5: under AddressSanitizer or ThreadSanitizer those cases take
 * most of the time (their steps to a steady state grow like the cells
 * along a side squared, so half the side is about 16 times less work).
 */
#ifndef SANDSLIDE_TESTS_SCALE_H
#define SANDSLIDE_TESTS_SCALE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* The factor from the environment: 1 when unset; a value outside (0, 1]
 * is refused with a message and taken as 1. */
static inline double test_scale(void)
{
	const char *s = getenv("SANDSLIDE_TEST_SCALE");
	if (!s || !*s)
		return 1.0;
	char *end;
	const double v = strtod(s, &end);
	if (*end || !(v > 0.0 && v <= 1.0)) {
		fprintf(stderr, "SANDSLIDE_TEST_SCALE='%s' ignored: expected a number in (0, 1]\n",
		        s);
		return 1.0;
	}
	return v;
}

/* n cells scaled by test_scale(), rounded, at least min. */
static inline int test_scaled(int n, int min)
{
	const int m = (int)lround(n * test_scale());
	return m < min ? min : m;
}

#endif
