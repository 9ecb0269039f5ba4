/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * watch.h - a run, relax or fit watched and stopped from another thread,
 * through flat functions (for callers that cannot lay out the options'
 * structs, such as Python's ctypes).
 *
 * A watch holds a stop flag and the last progress the library reported.
 * Attached to a command's job (ss_job_set_watch, job.h), it becomes its
 * stop_signal and progress callback: the thread running the call writes the progress after each
 * substep (each forward run of a fit), and any other thread may read it
 * with ss_watch_read or ask the call to stop with ss_watch_stop.  The call
 * then ends as a stop signal ends it: relax and run with the state of
 * that moment written (run's file ends at that last complete snapshot),
 * fit with the best so far and "interrupted" in its report.
 *
 * A watch serves one call (create one for each); it must outlive the call.
 */
#ifndef SANDSLIDE_WATCH_H
#define SANDSLIDE_WATCH_H

#include <signal.h>

#include "sandslide/job.h"
#include "sandslide/progress.h"

struct ss_watch;

/* A watch with the stop flag clear and no progress yet, or NULL (message
 * printed) when out of memory; destroy(NULL) does nothing. */
struct ss_watch *ss_watch_create(void);
void ss_watch_destroy(struct ss_watch *w);

/* Ask the watched call to stop: it does after its next substep (the
 * progress callback hands the request to the flag the call reads).  Safe
 * from any thread and from a signal handler (a lock-free atomic store). */
void ss_watch_stop(struct ss_watch *w);

/* The last progress reported, from any thread: *time (s, simulated),
 * *end (s; INFINITY: until steady), *steps (substeps since t = 0),
 * *fraction (of the work done, 0..1; NaN when it cannot be told: a relax
 * before its first substep; until steady an estimate, at most 0.99),
 * *runs (a fit's forward runs so far, else 0).
 * Any pointer may be NULL.  Returns the number of reports so far (0: none
 * yet, the values are then 0 and NaN). */
long long ss_watch_read(const struct ss_watch *w, double *time, double *end, long long *steps,
                        double *fraction, long long *runs);

/* Attach watch w to a command's job (job.h): its stop flag becomes the
 * job's stop_signal and its callback the progress, replacing any set; w
 * NULL detaches (no stop signal, no progress).  w must outlive the
 * command's call. */
void ss_job_set_watch(struct ss_job *job, struct ss_watch *w);

/* What ss_job_set_watch installs: the stop flag, and the callback
 * (context: the watch), which must both be installed: the callback sets
 * the flag on a request.  A progress with its fit part set is a fit's. */
const volatile sig_atomic_t *ss_watch_stop_flag(const struct ss_watch *w);
void ss_watch_progress(void *context, const struct ss_progress *p);

#endif
