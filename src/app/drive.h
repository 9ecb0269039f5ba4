/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * drive.h - the time loop that `run` and `relax` share.
 *
 * A prepared stepper is advanced through the target times k * output_every,
 * clipped to `end`, until the end, a steady state (max |dh/dt| < steady_tol
 * with no source still to switch on) or a stop signal.  At each target the
 * state is checked and, with a series, appended to the output as a snapshot
 * (which first checks that it fits, snapshot.h), unless the clock has not
 * moved since the last snapshot (steady or stopped before a step), so that
 * no two snapshots share a time.  The driver owns the
 * output: it claims it (io/output.h) before creating or appending to it and
 * holds the claim until ss_drive_finish.
 *
 * The guard of the explicit scheme: a height that becomes NaN or infinite
 * (which the CFL bound should prevent) stops the loop, and the driver keeps
 * the last good state, the one after the step before.  The sweep works in
 * place and keeps no copy, and a copy would cost 8 B per cell for a case
 * that should never arise; but a run is deterministic, so the driver takes
 * a fresh stepper from `rebuild`, puts it at the last snapshot (or leaves it
 * at t = 0 without a series), takes the same steps towards the same targets
 * again and stops one step short.  That costs at most one output_every of
 * computing (the whole run without a series), and only when it fires.
 *
 *   ss_drive_init        the loop's settings
 *   ss_drive_claim       claim the output (and make its default folder)
 *   ss_drive_create / ss_drive_append   the series: new with snapshot 0, or
 *                        continued (a restart)
 *   ss_drive_run         the loop, the guard
 *   ss_drive_finish      close the series, give the claim up
 */
#ifndef SANDSLIDE_APP_DRIVE_H
#define SANDSLIDE_APP_DRIVE_H

#include <signal.h>

#include "io/output.h"
#include "sandslide/job.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

enum ss_drive_end {
	SS_DRIVE_END,           /* reached `end` */
	SS_DRIVE_STEADY,        /* max |dh/dt| < steady_tol */
	SS_DRIVE_INTERRUPTED,   /* *stop_signal became non-zero */
	SS_DRIVE_NONFINITE,     /* the guard fired: see ss_drive_nonfinite_error */
};

/* Where a non-finite height appeared and where the last good state went. */
struct ss_drive_trouble {
	char cell[160];         /* "cell (i, j) at x = .. m, y = .. m" */
	long long step;         /* the substep after which it was seen */
	double time;            /* s */
	long long good_step;    /* the state kept is after this step; -1: none */
	double good_time;       /* s */
	long long good_snapshot; /* its index in the series; -1: not in one */
	long long snapshots;    /* in the series when the guard fired */
	double last_time;       /* of the last of them, s */
};

struct ss_drive {
	/* the loop (ss_drive_init sets these; the caller may change them) */
	struct ss_stepper *stepper;  /* prepared; the guard swaps in its replay */
	double output_every;    /* s between targets; INFINITY: only `end` */
	double end;             /* s; INFINITY: until steady */
	double steady_tol;      /* m/s; <= 0: never steady */
	double steady_slope_tol; /* stepper.h; <= 0: the default 1e-6 */
	double started;         /* wall clock when the command started, s */
	int samples;            /* the targets before `end` are where snapshots
	                           sample the state, not events: the steps pass
	                           them (stepper.h), and a snapshot is stamped
	                           with the time of the step that reached its
	                           target, so that the steps do not depend on
	                           output_every (relax) */
	const struct ss_job *job;   /* its stop signal, checked after every
	                           substep, and its progress after every
	                           substep (NULL: neither) */
	/* after every snapshot is written and flushed (NULL: none); a non-zero
	 * return (a status, message printed) stops the loop */
	int (*on_snapshot)(void *context, const char *path, long long index, double time);
	void *snapshot_context;
	/* a fresh stepper in the state of t = 0, prepared: the guard's replay */
	int (*rebuild)(void *context, struct ss_stepper *st);
	void *rebuild_context;

	/* the driver's own */
	char output[4096];
	struct ss_output_claim *claim;  /* rank 0's (comm.h) */
	int claimed;                    /* the claim is held, on every rank */
	struct ss_snapshot *snapshot;   /* the series; NULL: none */
	double seconds_output;          /* writing snapshots, s */
	double time_start;              /* of the loop, s */
	long long steps_start;
	long long evaluations_start;  /* st->evaluations when ss_drive_run started */
	struct ss_drive_trouble trouble;
};

void ss_drive_init(struct ss_drive *d, struct ss_stepper *st, double started);

/* Use `threads` OpenMP threads, or for 0 ss_parallel_default_threads:
 * OMP_NUM_THREADS, else the processors this process may run on divided
 * among the node's ranks (comm.h), at least one, which the stepper then
 * lowers for a small grid (ss_parallel_threads_for). */
void ss_drive_set_threads(int threads);

/* SS_OK when `command` (run, relax, fit, the BMI) can compute on device d
 * here: the CPU; else the reason (no CUDA in this build, no such GPU, or
 * that the command's loop is not on the GPU yet) as bad input, after
 * `what`, the setting that named d (NULL: "--device NAME"). */
int ss_drive_check_device(const struct ss_device *d, const char *what, const char *command);

/* Claim `output` for this run (unless it already holds the claim): make
 * its folder first when make_folder (a default output's out/), then refuse
 * an output that exists unless force or appending (SS_ERR_INPUT, the
 * message ends with hint). */
int ss_drive_claim(struct ss_drive *d, const char *output, int make_folder, int force,
                   int appending, const char *hint);

/* Create the series in the claimed output and write snapshot 0. */
int ss_drive_create(struct ss_drive *d, const struct ss_snapshot_meta *meta);

/* Continue the series of the claimed output (a restart). */
int ss_drive_append(struct ss_drive *d);

/* The loop.  SS_OK with *end set (SS_DRIVE_NONFINITE: nothing printed
 * yet, d->trouble says what happened and the stepper holds the last good
 * state when good_step >= 0), or SS_ERR_FAIL (printed). */
int ss_drive_run(struct ss_drive *d, enum ss_drive_end *end);

/* Print what the guard found, saying where the last good state is (in the
 * series, or in `kept_in`, a file the caller wrote it to; NULL: nowhere);
 * returns SS_ERR_FAIL. */
int ss_drive_nonfinite_error(const struct ss_drive *d, const char *kept_in);

/* Snapshots in the series (0 without one). */
long long ss_drive_snapshots(const struct ss_drive *d);

/* Close the series and give the claim up; err is the status so far, and
 * the result is it or the failure of the final close. */
int ss_drive_finish(struct ss_drive *d, int err);

#endif
