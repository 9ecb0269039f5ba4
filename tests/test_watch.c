/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_watch.c - a call watched and stopped from another thread (watch.h),
 * and each thread's own last message (error.c): what the Python module
 * relies on to stop a call on Ctrl-C and to run calls side by side.
 *
 * A relax of a rough random surface runs in a POSIX thread (not C11's
 * thrd_create, which ThreadSanitizer does not see); this thread
 * reads its progress (steps rising, fraction in 0..1) and stops it, and
 * the relax must then return SS_OK with "interrupted" as its end.  Two
 * threads set different bad options, interleaved: each reads back its own
 * message, and ss_error_adopt hands one to this thread.  The seed of the surface is printed.
 */
#include "check.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <sched.h>

#include "sandslide/error.h"
#include "sandslide/relax.h"
#include "sandslide/watch.h"

enum { NX = 256, NY = 256 };

struct job {
	struct ss_relax_options *o;
	double *h;
	char report[4096];
	int status;
};

static void *relax_job(void *arg)
{
	struct job *j = arg;
	j->status = ss_relax_heights(j->o, NX, NY, 1.0, 1.0, j->h, NULL, j->h, j->report,
	                             sizeof j->report);
	return NULL;
}

static void a_relax_is_watched_and_stopped_from_another_thread(void)
{
	unsigned seed = (unsigned)(getenv("SEED") ? atoi(getenv("SEED")) : 27);
	printf("seed = %u\n", seed);
	srand(seed);
	struct job j = {.o = ss_option_object_create(&ss_relax_option_table), .h = malloc(sizeof(double) * NX * NY)};
	struct ss_watch *w = ss_watch_create();
	CHECK(j.o && j.h && w, "create");
	if (!j.o || !j.h || !w)
		goto out;
	for (int m = 0; m < NX * NY; m++)
		j.h[m] = 50.0 * rand() / RAND_MAX;   /* far steeper than repose everywhere */
	double t, e, f;
	long long s, r;
	CHECK(ss_watch_read(w, &t, &e, &s, &f, &r) == 0 && isnan(f),
	      "a new watch has no report and an unknown fraction (%g)", f);
	CHECK(ss_option_object_set(j.o, "threads", "1") == SS_OK, "%s", ss_error_last_message());
	ss_job_set_watch(&j.o->job, w);

	pthread_t th;
	CHECK(pthread_create(&th, NULL, relax_job, &j) == 0, "thread");
	long long n = 0, steps_before = -1;
	int rising = 1;
	const double t0 = check_now();
	while (n < 20 && check_now() - t0 < 30.0) {
		n = ss_watch_read(w, &t, &e, &s, &f, &r);
		if (n > 0) {
			rising &= s >= steps_before;
			steps_before = s;
		}
		sched_yield();
	}
	CHECK(n >= 20, "the relax reported %lld substeps in 30 s, expected 20", n);
	CHECK(rising, "the steps read went down");
	CHECK(isinf(e) && f >= 0.0 && f <= 1.0 && r == 0,
	      "until steady: end %g (expected inf), fraction %g (expected 0..1), runs %lld", e,
	      f, r);
	const double stopped = check_now();
	ss_watch_stop(w);
	pthread_join(th, NULL);
	const double took = check_now() - stopped;
	CHECK(j.status == SS_OK, "the stopped relax returned %d: %s", j.status,
	      ss_error_last_message());
	CHECK(strstr(j.report, "\"end\": \"interrupted\"") != NULL,
	      "the report does not end \"interrupted\":\n%s", j.report);
	CHECK(took < 1.0, "the relax took %.3f s to stop, expected well under 1 s", took);
	long long s2;
	ss_watch_read(w, NULL, NULL, &s2, NULL, NULL);
	CHECK(s2 >= s, "the last steps read (%lld) are below an earlier read (%lld)", s2, s);
out:
	ss_watch_destroy(w);
	ss_watch_destroy(NULL);
	ss_option_object_destroy(j.o);
	free(j.h);
}

/* Two threads' messages, interleaved: A fails, B fails, A reads. */
static atomic_int turn;
static char read_back[2][256];   /* each thread's message, checked in main */

static void *fail_in_turn(void *arg)
{
	const int me = *(int *)arg;
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	while (atomic_load(&turn) != me)
		sched_yield();
	ss_option_object_set(o, "angle", me == 0 ? "95" : "-3");
	atomic_store(&turn, me + 1);
	while (atomic_load(&turn) != 2)
		sched_yield();
	snprintf(read_back[me], sizeof read_back[me], "%s", ss_error_last_message());
	ss_option_object_destroy(o);
	return NULL;
}

static void each_thread_reads_its_own_message(void)
{
	pthread_t a, b;
	int ia = 0, ib = 1;
	atomic_store(&turn, 0);
	pthread_create(&a, NULL, fail_in_turn, &ia);
	pthread_create(&b, NULL, fail_in_turn, &ib);
	pthread_join(a, NULL);
	pthread_join(b, NULL);
	CHECK(strstr(read_back[0], "'95'"), "thread 0 reads '%s', not its own message",
	      read_back[0]);
	CHECK(strstr(read_back[1], "'-3'"), "thread 1 reads '%s', not its own message",
	      read_back[1]);
	/* a worker's message handed to this thread (render's frames do so) */
	CHECK(!strstr(ss_error_last_message(), "'95'"), "this thread reads another's message");
	CHECK(ss_error_adopt(SS_ERR_INPUT, read_back[0]) == SS_ERR_INPUT &&
	      !strcmp(ss_error_last_message(), read_back[0]),
	      "adopted '%s', reads '%s'", read_back[0], ss_error_last_message());
}

int main(void)
{
	ss_error_set_quiet(1);
	RUN(a_relax_is_watched_and_stopped_from_another_thread);
	RUN(each_thread_reads_its_own_message);
	return check_report();
}
