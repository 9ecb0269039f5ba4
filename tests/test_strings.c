/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_strings.c - numbers as text (src/base/strings.h): ss_real_text, the
 * shortest text that reads back as the same double, for the numbers people
 * read that must be exact (coordinates, cell sizes, tolerances), and
 * ss_strbuf_json_number, which writes the JSON of relax's report and run's
 * summary with it.
 */
#include "check.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"

/* The significant digits of a %g text ("5479330.25" 9, "1e-09" 1). */
static int digits_of(const char *s)
{
	int n = 0, leading = 1;
	for (; *s && *s != 'e'; s++) {
		if (*s < '0' || *s > '9')
			continue;
		if (*s == '0' && leading)
			continue;
		leading = 0;
		n++;
	}
	/* trailing zeros of an integer part are not significant to %g either */
	return n;
}

static void test_examples(void)
{
	static const struct {
		double x;
		const char *text;
	} cases[] = {
		{1e-9, "1e-09"},                /* not 1.0000000000000001e-09 */
		{1e-6, "1e-06"},
		{0.1, "0.1"},
		{0.3, "0.3"},
		{0.1 + 0.2, "0.30000000000000004"},
		{5479330.25, "5479330.25"},     /* %g: 5.47933e+06, 2 m off */
		{263811.0, "263811"},
		{4100000.25, "4100000.25"},
		{-0.5, "-0.5"},
		{0.0, "0"},
		{1.0 / 3.0, "0.3333333333333333"},
		{7557.1059765279342, "7557.105976527934"},
		{DBL_MAX, "1.7976931348623157e+308"},
		{5e-324, "4.94065645841247e-324"},   /* the smallest subnormal */
	};
	for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
		char buf[SS_REAL_TEXT_SIZE];
		ss_real_text(cases[k].x, buf);
		CHECK(!strcmp(buf, cases[k].text), "%.17g printed as '%s', expected '%s'", cases[k].x,
		      buf, cases[k].text);
	}
	char line[128];
	snprintf(line, sizeof line, "(%s, %s) m", SS_REAL(263811.5), SS_REAL(5479330.25));
	CHECK(!strcmp(line, "(263811.5, 5479330.25) m"), "SS_REAL twice in one call: '%s'", line);
	CHECK(!strcmp(SS_REAL(NAN), "nan") && !strcmp(SS_REAL(INFINITY), "inf") &&
	      !strcmp(SS_REAL(-INFINITY), "-inf"), "non-finite: %s %s %s", SS_REAL(NAN),
	      SS_REAL(INFINITY), SS_REAL(-INFINITY));
}

/* Random doubles of every magnitude read back exactly, and no text of
 * fewer digits in 15..17 would have. */
static void test_round_trip(void)
{
	const uint64_t seed = 2311;
	struct rng r = {seed};
	int bad = 0, longer = 0;
	for (int k = 0; k < 100000; k++) {
		double x;
		uint64_t bits = rng_next(&r);
		memcpy(&x, &bits, sizeof x);
		if (!isfinite(x))
			continue;
		char buf[SS_REAL_TEXT_SIZE], shorter[320];   /* %g's worst case, for the compiler */
		ss_real_text(x, buf);
		if (strtod(buf, NULL) != x) {
			if (!bad++)
				fprintf(stderr, "  seed %llu: %a printed as '%s' reads back as %a\n",
				        (unsigned long long)seed, x, buf, strtod(buf, NULL));
			continue;
		}
		const int d = digits_of(buf);
		if (d > 15) {
			snprintf(shorter, sizeof shorter, "%.*g", d - 1, x);
			if (strtod(shorter, NULL) == x && !longer++)
				fprintf(stderr, "  seed %llu: '%s' for %a, where '%s' reads back too\n",
				        (unsigned long long)seed, buf, x, shorter);
		}
	}
	CHECK(bad == 0, "%d of 100000 random doubles did not read back (seed %llu)", bad,
	      (unsigned long long)seed);
	CHECK(longer == 0, "%d texts longer than needed (seed %llu)", longer,
	      (unsigned long long)seed);
}

static const char *json(double x, int digits, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	ss_strbuf_json_number(&b, x, digits);
	return buf;
}

static void test_json_numbers(void)
{
	char buf[64];
	CHECK(!strcmp(json(1e-9, 17, buf, sizeof buf), "1e-09"), "tol: %s", buf);
	CHECK(!strcmp(json(9.9999999999999995e-07, 17, buf, sizeof buf), "1e-06"),
	      "slope_tol: %s", buf);
	CHECK(!strcmp(json(246980.00000000081, 17, buf, sizeof buf), "246980.00000000081"),
	      "a volume that needs 17 digits: %s", buf);
	CHECK(strtod(json(246980.00000000081, 17, buf, sizeof buf), NULL) == 246980.00000000081,
	      "17 digits read back: %s", buf);
	/* fewer digits asked: that many, as %g gives them (seconds) */
	CHECK(!strcmp(json(41.376743719, 6, buf, sizeof buf), "41.3767"), "6 digits: %s", buf);
	CHECK(!strcmp(json(0.5, 6, buf, sizeof buf), "0.5"), "6 digits of 0.5: %s", buf);
	CHECK(!strcmp(json(NAN, 17, buf, sizeof buf), "null") &&
	      !strcmp(json(-INFINITY, 6, buf, sizeof buf), "null"), "non-finite: null");
}

/* The one way messages name a cell: index from the south-west, centre in
 * the raster's units to 15 digits (a centre 0 + 14.5 * 0.1 reads 1.45). */
static void test_cell_names(void)
{
	const char *a = SS_CELL(2, 14, 2.5 * 0.1, 14.5 * 0.1);
	CHECK(!strcmp(a, "cell (2, 14) at x = 0.25 m, y = 1.45 m"), "%s", a);
	const char *b = SS_CELL(0, 3, 263811.5, 5479330.25);
	CHECK(!strcmp(b, "cell (0, 3) at x = 263811.5 m, y = 5479330.25 m"), "%s", b);
	const char *c = SS_CELL(7, 1, NAN, 1.5);
	CHECK(!strcmp(c, "cell (7, 1)"), "without coordinates: %s", c);
}

int main(void)
{
	RUN(test_examples);
	RUN(test_round_trip);
	RUN(test_json_numbers);
	RUN(test_cell_names);
	return check_report();
}
