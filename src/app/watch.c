/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * watch.c - a call's stop flag and progress, shared between the thread
 * running it and any other (see watch.h).
 *
 * The progress is a seqlock (Boehm, "Can seqlocks get along with
 * programming language memory models?", 2012): the one writer makes the
 * sequence odd, stores the fields, makes it even again; a reader retries
 * until it read the same even sequence before and after the fields.  Every
 * field is a C11 atomic accessed relaxed, so there is no data race, and the
 * fences order them against the sequence: a reader gets the fields of one
 * report, never half of two.  The writer is the library's own thread and
 * never waits on a reader.
 *
 * The stop flag the options point at is a volatile sig_atomic_t, as the
 * CLI's signal flag is, read by the stepper after each substep.  Another
 * thread must not write it (a data race: ThreadSanitizer says so), so
 * ss_watch_stop sets a C11 atomic request instead, and the progress
 * callbacks, which run in the thread of the call after each substep,
 * copy the request into the flag: the stepper sees it one substep later.
 */
#include "sandslide/watch.h"

#include <math.h>
#include <stdatomic.h>

#include "sandslide/error.h"
#include "sandslide/fit.h"

struct ss_watch {
	atomic_int stop_request;          /* 1: asked, from any thread */
	volatile sig_atomic_t stop;       /* 1: stop after this substep; written
	                                   * only in the thread of the call */
	atomic_ullong seq;                /* odd while the writer stores */
	_Atomic double time, end;         /* s */
	_Atomic double fraction;          /* 0..1, NaN: unknown */
	atomic_llong steps, runs, reports;
	/* the writer's own, for a relax's fraction: the first max |dh/dt|
	 * and the largest fraction so far (the rate does not fall evenly) */
	double rate_first, fraction_max;
};

struct ss_watch *ss_watch_create(void)
{
	struct ss_watch *w = ss_alloc(1, sizeof *w, "a watch");
	if (!w)
		return NULL;
	atomic_init(&w->stop_request, 0);
	w->stop = 0;
	atomic_init(&w->seq, 0);
	atomic_init(&w->time, 0.0);
	atomic_init(&w->end, NAN);
	atomic_init(&w->fraction, NAN);
	atomic_init(&w->steps, 0);
	atomic_init(&w->runs, 0);
	atomic_init(&w->reports, 0);
	w->rate_first = NAN;
	w->fraction_max = 0.0;
	return w;
}

void ss_watch_destroy(struct ss_watch *w)
{
	ss_free(w);
}

void ss_watch_stop(struct ss_watch *w)
{
	/* lock-free, so also safe in a signal handler (C11 7.14.1.1) */
	atomic_store_explicit(&w->stop_request, 1, memory_order_relaxed);
}

/* In the thread of the call: the request becomes the flag it reads. */
static void hand_over_stop(struct ss_watch *w)
{
	if (!w->stop && atomic_load_explicit(&w->stop_request, memory_order_relaxed))
		w->stop = 1;
}

const volatile sig_atomic_t *ss_watch_stop_flag(const struct ss_watch *w)
{
	return &w->stop;
}

static void publish(struct ss_watch *w, double time, double end, long long steps,
                    double fraction, long long runs)
{
	const unsigned long long s = atomic_load_explicit(&w->seq, memory_order_relaxed);
	atomic_store_explicit(&w->seq, s + 1, memory_order_relaxed);
	atomic_thread_fence(memory_order_release);
	atomic_store_explicit(&w->time, time, memory_order_relaxed);
	atomic_store_explicit(&w->end, end, memory_order_relaxed);
	atomic_store_explicit(&w->steps, steps, memory_order_relaxed);
	atomic_store_explicit(&w->fraction, fraction, memory_order_relaxed);
	atomic_store_explicit(&w->runs, runs, memory_order_relaxed);
	atomic_store_explicit(&w->reports,
	                      atomic_load_explicit(&w->reports, memory_order_relaxed) + 1,
	                      memory_order_relaxed);
	atomic_store_explicit(&w->seq, s + 2, memory_order_release);
}

/* A fit's fraction: of the closures to fit. */
static void fit_progress(struct ss_watch *w, const struct ss_fit_progress *p)
{
	const double f = p->closure_count > 0 ? (double)p->closure_index / p->closure_count : NAN;
	publish(w, NAN, NAN, 0, f, p->runs);
	hand_over_stop(w);
}

/* The fraction done: a fit's (above); of the time to the end when there
 * is one; until steady, how far max |dh/dt| has fallen from the first
 * substep's towards the steady tolerance on a log scale (the decay is
 * roughly exponential), never going back; 1 only from the caller, when
 * the call has returned. */
void ss_watch_progress(void *context, const struct ss_progress *p)
{
	struct ss_watch *w = context;
	if (p->fit) {
		fit_progress(w, p->fit);
		return;
	}
	double f = NAN;
	if (isfinite(p->end) && p->end > p->time_start) {
		f = (p->time - p->time_start) / (p->end - p->time_start);
	} else if (p->steady_tol > 0.0 && p->rate_max > 0.0 && isfinite(p->rate_max)) {
		if (isnan(w->rate_first))
			w->rate_first = p->rate_max;
		const double span = log(w->rate_first / p->steady_tol);
		/* at most 0.99: below the tolerance the steady rule may still wait
		 * for the last faces to come down to the repose angle */
		f = fmin(span > 0.0 ? log(w->rate_first / p->rate_max) / span : 1.0, 0.99);
	} else if (p->steady_tol > 0.0 && p->rate_max == 0.0) {
		f = 0.99;
	}
	if (!isnan(f)) {
		f = fmin(fmax(f, w->fraction_max), 1.0);
		w->fraction_max = f;
	}
	publish(w, p->time, p->end, p->steps, f, 0);
	hand_over_stop(w);
}

void ss_job_set_watch(struct ss_job *job, struct ss_watch *w)
{
	job->stop_signal = w ? ss_watch_stop_flag(w) : NULL;
	job->progress = w ? ss_watch_progress : NULL;
	job->progress_context = w;
}

long long ss_watch_read(const struct ss_watch *w, double *time, double *end, long long *steps,
                        double *fraction, long long *runs)
{
	/* the const is the caller's promise not to change the watch; the
	 * atomics' loads take non-const pointers in some C libraries */
	struct ss_watch *m = (struct ss_watch *)w;
	double t, e, f;
	long long s, r, n;
	for (;;) {
		const unsigned long long s0 = atomic_load_explicit(&m->seq, memory_order_acquire);
		if (s0 & 1)
			continue;   /* a store of a few words: spin */
		t = atomic_load_explicit(&m->time, memory_order_relaxed);
		e = atomic_load_explicit(&m->end, memory_order_relaxed);
		s = atomic_load_explicit(&m->steps, memory_order_relaxed);
		f = atomic_load_explicit(&m->fraction, memory_order_relaxed);
		r = atomic_load_explicit(&m->runs, memory_order_relaxed);
		n = atomic_load_explicit(&m->reports, memory_order_relaxed);
		atomic_thread_fence(memory_order_acquire);
		if (atomic_load_explicit(&m->seq, memory_order_relaxed) == s0)
			break;
	}
	if (time)
		*time = t;
	if (end)
		*end = e;
	if (steps)
		*steps = s;
	if (fraction)
		*fraction = f;
	if (runs)
		*runs = r;
	return n;
}
