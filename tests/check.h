/*
 * check.h - a tiny test harness (git test-lib, redis testhelp).
 *
 *   CHECK(expr, fmt, ...)              fails with file:line, expr and message
 *   CHECK_NEAR(a, b, tol, fmt, ...)    |a - b| <= tol, prints both values
 *   CHECK_REL(a, b, rel, fmt, ...)     |a - b| <= rel * max(|a|, |b|)
 *   RUN(fn)                            runs a test function, names failures
 *   check_report()                     prints "N passed, M failed", exit code
 *
 * Each CHECK counts as one check; a test function may make many.
 */
#ifndef SANDSLIDE_TESTS_CHECK_H
#define SANDSLIDE_TESTS_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int check_passed, check_failed;
static const char *check_current = "";

#define CHECK(expr, ...)                                                      \
	do {                                                                  \
		if (expr) {                                                   \
			check_passed++;                                       \
		} else {                                                      \
			check_failed++;                                       \
			fprintf(stderr, "FAIL %s:%d in %s: %s: ", __FILE__,   \
			        __LINE__, check_current, #expr);              \
			fprintf(stderr, __VA_ARGS__);                         \
			fputc('\n', stderr);                                  \
		}                                                             \
	} while (0)

#define CHECK_NEAR(a, b, tol, ...)                                            \
	do {                                                                  \
		const double check_a_ = (a), check_b_ = (b);                  \
		if (fabs(check_a_ - check_b_) <= (tol)) {                     \
			check_passed++;                                       \
		} else {                                                      \
			check_failed++;                                       \
			fprintf(stderr, "FAIL %s:%d in %s: %s = %.17g, %s = %.17g, " \
			        "|diff| %.3g > %.3g: ", __FILE__, __LINE__,   \
			        check_current, #a, check_a_, #b, check_b_,    \
			        fabs(check_a_ - check_b_), (double)(tol));    \
			fprintf(stderr, __VA_ARGS__);                         \
			fputc('\n', stderr);                                  \
		}                                                             \
	} while (0)

#define CHECK_REL(a, b, rel, ...)                                             \
	CHECK_NEAR(a, b, (rel) * fmax(fabs(a), fabs(b)), __VA_ARGS__)

#define RUN(fn)                                                               \
	do {                                                                  \
		const int check_before_ = check_failed;                       \
		check_current = #fn;                                          \
		fn();                                                         \
		printf("%s %s\n", check_failed == check_before_ ? "ok  " : "FAIL", #fn); \
		fflush(stdout);                                               \
	} while (0)

static inline int check_report(void)
{
	printf("%d passed, %d failed\n", check_passed, check_failed);
	return check_failed ? 1 : 0;
}

#endif
