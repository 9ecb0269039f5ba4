/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * pause_step.c - the test hook of the interrupt (SIGINT, SIGTERM: the stop
 * flag of src/cli/main.c), linked into a third sandslide,
 * build/tests/sandslide-pause, and never into the real one.
 *
 * A test that signals a running sandslide races it: on a fast machine the
 * run may end before the signal arrives.  This program takes the race
 * away.  It is linked with -Wl,--wrap=ss_stepper_advance, as nan_step.c
 * is, so every call the library's time loop makes to the stepper comes
 * here first.  With SANDSLIDE_TEST_PAUSE_STEP=N in the environment it
 * stops right after substep N (in the progress callback, chained after the
 * caller's) and
 *
 *   - creates the file SANDSLIDE_TEST_PAUSE_FILE (when set), holding
 *     "paused after step N", for the test to wait for;
 *   - waits, polling every millisecond, until a stop signal was caught
 *     (*o->stop, the flag the CLI's handler sets), or for
 *     SANDSLIDE_TEST_PAUSE_SECONDS (default 60; then it says so on stderr
 *     and goes on, so a test that never signals cannot hang; with
 *     SANDSLIDE_TEST_PAUSE_SILENT=1 it goes on without a word: a test that
 *     only needs a run to last that long, whatever the machine's speed).
 *
 * The stepper reads the flag at the end of each substep, before the
 * progress callback, so a signal sent during the pause stops the run after
 * substep N + 1, every time: the interrupt's snapshot is after step N + 1.
 * A restart continues the step count, so N counts from the start of the
 * original run.
 *
 * The progress callback also comes between the stages of a super-step
 * (src/core/stages.h), with the steps before it: with
 * SANDSLIDE_TEST_PAUSE_CALL=k it pauses at the k-th report that sees step
 * N (default 1, the end of step N; k > 1, after stage k - 1 of step N +
 * 1).  Once it goes on after a stop signal it counts the reports that
 * still come, one per evaluation of the stencil, and says on stderr
 * "pause hook: K evaluations after the stop signal": how long a stop
 * request waits.  Under MPI every rank pauses after step N until its own
 * handler ran (mpirun passes the signal on to each), and the ranks agree
 * to stop after step N + 1 (stepper.c, step_end); each writes the same
 * file.  A signal that comes before step N stops the run earlier, as in
 * sandslide; SIGKILL needs no flag.  Without SANDSLIDE_TEST_PAUSE_STEP the
 * program is sandslide.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "sandslide/stepper.h"

enum ss_advance_end __real_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o);
enum ss_advance_end __wrap_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o);

struct hook {
	long long pause_step;
	double seconds;                       /* the longest wait */
	int silent;                           /* no word when it ends */
	const char *marker;                   /* NULL: none */
	long long pause_call;                 /* the report at step N to pause at */
	long long calls;                      /* reports seen at step N */
	int stopped;                          /* went on after a stop signal */
	long long after;                      /* reports since */
	const struct ss_advance_options *caller;
};

/* The marker, written under a name of this process and renamed, so that a
 * test that sees the file sees its whole text. */
static void mark(const char *path, long long step)
{
	char tmp[4200];
	snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
	FILE *f = fopen(tmp, "w");
	int bad = !f;
	if (f) {
		bad = fprintf(f, "paused after step %lld\n", step) < 0;
		bad |= fclose(f) != 0;
	}
	if (bad || rename(tmp, path) != 0)
		perror(path);
}

static double now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void pause_here(void *context, const struct ss_stepper *seen)
{
	struct hook *h = context;
	if (h->caller->progress)
		h->caller->progress(h->caller->context, seen);
	if (h->stopped)
		h->after++;
	if (seen->steps != h->pause_step || ++h->calls != h->pause_call)
		return;
	const volatile sig_atomic_t *stop = h->caller->stop;
	if (!stop) {
		fprintf(stderr, "pause hook: no stop flag to wait for: not paused\n");
		return;
	}
	if (h->marker)
		mark(h->marker, seen->steps);
	/* 1 ms at a time; a signal cuts a sleep short (EINTR), then the flag
	 * is read at once */
	const struct timespec ms = {0, 1000000};
	const double until = now() + h->seconds;
	while (!*stop) {
		if (now() > until) {
			if (h->silent)
				return;
			fprintf(stderr, "pause hook: no stop signal within %g s of step %lld: "
			        "going on\n", h->seconds, seen->steps);
			return;
		}
		nanosleep(&ms, NULL);
	}
	h->stopped = 1;
}

enum ss_advance_end __wrap_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o)
{
	const char *env = getenv("SANDSLIDE_TEST_PAUSE_STEP");
	if (!env || !*env)
		return __real_ss_stepper_advance(st, t_target, o);
	const char *file = getenv("SANDSLIDE_TEST_PAUSE_FILE");
	const char *secs = getenv("SANDSLIDE_TEST_PAUSE_SECONDS");
	const char *silent = getenv("SANDSLIDE_TEST_PAUSE_SILENT");
	const char *call = getenv("SANDSLIDE_TEST_PAUSE_CALL");
	/* the reports at step N seen by earlier calls of this one run */
	static long long calls;
	struct hook h = {atoll(env), secs && *secs ? atof(secs) : 60.0,
	                 silent && !strcmp(silent, "1"), file && *file ? file : NULL,
	                 call && *call ? atoll(call) : 1, calls, 0, 0, o};
	struct ss_advance_options hooked = *o;
	hooked.progress = pause_here;
	hooked.context = &h;
	const enum ss_advance_end e = __real_ss_stepper_advance(st, t_target, &hooked);
	calls = h.calls;
	if (h.stopped)
		fprintf(stderr, "pause hook: %lld evaluations after the stop signal\n", h.after);
	return e;
}
