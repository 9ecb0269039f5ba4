/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * check.h - a tiny test harness (git test-lib, redis testhelp).
 *
 *   CHECK(expr, fmt, ...)              fails with file:line, expr and message
 *   CHECK_NEAR(a, b, tol, fmt, ...)    |a - b| <= tol, prints both values
 *   CHECK_REL(a, b, rel, fmt, ...)     |a - b| <= rel * max(|a|, |b|)
 *   CHECK_SKIP(fmt, ...)               says why what follows is not checked
 *                                      in this build ("  skipped: WHY" on a
 *                                      line of its own) and counts a skip;
 *                                      the caller then returns, or goes on
 *                                      with what it can check
 *   RUN(fn)                            runs a test function, prints its
 *                                      verdict: "ok   fn", "FAIL fn" or
 *                                      "skip fn" (it only skipped)
 *   check_begin(name), check_end(mark) what RUN does around fn, for a
 *                                      test's own RUN (timed, every rank)
 *   check_report()                     prints "N passed, M failed" (with
 *                                      ", K skipped" when K > 0), exit code
 *   CHECK_OPENMP                       1 if the tests (and the library) are
 *                                      built with OpenMP: without, a run
 *                                      "on 2 threads" runs on 1, and a test
 *                                      comparing thread counts says so with
 *                                      CHECK_SKIP
 *   check_now()                        monotonic clock, s (for timings)
 *   struct rng, rng_next/uniform/int   splitmix64: reproducible random states
 *   check_scratch_make(name)           a mkdtemp folder /tmp/NAME.XXXXXX for files
 *   check_scratch(), check_file(name)  its path, and a file's path in it
 *   check_scratch_remove()             remove it and the files in it
 *   check_write_file(path, text)       text into a new file (exits 2 if it cannot)
 *
 * Each CHECK counts as one check; a test function may make many.  Nothing
 * passes by testing nothing: a test function that made no check and
 * skipped nothing fails (one failure, "made no check"), and so does a
 * program that made no check at all, whatever it skipped.
 */
#ifndef SANDSLIDE_TESTS_CHECK_H
#define SANDSLIDE_TESTS_CHECK_H

#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* The scratch folder of a test program (one per program). */
static inline char *check_scratch(void)
{
	static char dir[64];
	return dir;
}

/* Make it, /tmp/NAME.XXXXXX; 0, or -1 after perror. */
static inline int check_scratch_make(const char *name)
{
	snprintf(check_scratch(), 64, "/tmp/%s.XXXXXX", name);
	if (mkdtemp(check_scratch()))
		return 0;
	perror("mkdtemp");
	return -1;
}

/* scratch/name into a static buffer (two in turn, enough for one call) */
static inline const char *check_file(const char *name)
{
	static char buf[2][512];
	static int k;
	k ^= 1;
	snprintf(buf[k], sizeof buf[k], "%s/%s", check_scratch(), name);
	return buf[k];
}

/* Remove the scratch folder and the files in it (not folders in it). */
static inline void check_scratch_remove(void)
{
	DIR *d = opendir(check_scratch());
	for (struct dirent *e; d && (e = readdir(d));) {
		if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
			unlink(check_file(e->d_name));
	}
	if (d)
		closedir(d);
	rmdir(check_scratch());
}

static inline void check_write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "wb");
	if (!f || fputs(text, f) == EOF || fclose(f)) {
		perror(path);
		exit(2);
	}
}

static inline double check_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* splitmix64: a small reproducible generator, seeded by s */
struct rng {
	uint64_t s;
};

static inline uint64_t rng_next(struct rng *r)
{
	uint64_t z = (r->s += UINT64_C(0x9e3779b97f4a7c15));
	z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
	z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
	return z ^ (z >> 31);
}

/* uniform in [0, 1) */
static inline double rng_uniform(struct rng *r)
{
	return (double)(rng_next(r) >> 11) * 0x1.0p-53;
}

/* uniform integer in [0, n) */
static inline int rng_int(struct rng *r, int n)
{
	return (int)(rng_next(r) % (uint64_t)n);
}

/* The tests are compiled with the library's flags, -fopenmp or not. */
#ifdef _OPENMP
enum { CHECK_OPENMP = 1 };
#else
enum { CHECK_OPENMP = 0 };
#endif

static int check_passed, check_failed, check_skipped;
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

/* A skip: what follows is not checked in this build, and why (what is
 * missing, e.g. "this build has no GDAL").  Printed at once, indented as
 * the tests' own notes are, before the verdict of its function. */
#define CHECK_SKIP(...)                                                       \
	do {                                                                  \
		check_skipped++;                                              \
		fputs("  skipped: ", stdout);                                 \
		printf(__VA_ARGS__);                                          \
		fputc('\n', stdout);                                          \
		fflush(stdout);                                               \
	} while (0)

/* The counts before a test function (check_begin), to judge it by what it
 * added (check_end). */
struct check_mark {
	int passed, failed, skipped;
};

static inline struct check_mark check_begin(const char *name)
{
	check_current = name;
	return (struct check_mark){check_passed, check_failed, check_skipped};
}

/* The verdict on a test function (check_current) that made `checks`
 * checks, `failed` of them failed, and `skipped` skips: "FAIL", "skip"
 * (no check, only skips: its skip lines say why) or "ok  ".  A function
 * that made no check and skipped nothing tested nothing: that is one
 * failure, with a message. */
static inline const char *check_verdict(int checks, int failed, int skipped)
{
	if (failed)
		return "FAIL";
	if (checks == 0 && skipped == 0) {
		check_failed++;
		fprintf(stderr, "FAIL %s: made no check and skipped nothing (a test that "
		        "tests nothing)\n", check_current);
		return "FAIL";
	}
	return checks == 0 ? "skip" : "ok  ";
}

static inline const char *check_end(struct check_mark m)
{
	return check_verdict(check_passed + check_failed - m.passed - m.failed,
	                     check_failed - m.failed, check_skipped - m.skipped);
}

#define RUN(fn)                                                               \
	do {                                                                  \
		const struct check_mark check_mark_ = check_begin(#fn);       \
		fn();                                                         \
		printf("%s %s\n", check_end(check_mark_), #fn);               \
		fflush(stdout);                                               \
	} while (0)

/* The closing line, "N passed, M failed" (", K skipped" added when K > 0:
 * tools may read the two-count form), and the exit status: 1 if a check
 * failed, or if the program made no check at all (counted as a failure:
 * a program that checked nothing has not passed). */
static inline int check_report(void)
{
	if (check_passed + check_failed == 0) {
		check_failed++;
		fprintf(stderr, "FAIL: this program made no check%s\n",
		        check_skipped ? " (everything was skipped)" : "");
	}
	if (check_skipped)
		printf("%d passed, %d failed, %d skipped\n", check_passed, check_failed,
		       check_skipped);
	else
		printf("%d passed, %d failed\n", check_passed, check_failed);
	return check_failed ? 1 : 0;
}

#endif
