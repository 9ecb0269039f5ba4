/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * progress.h - what `run`, `relax` and `fit` report as they go (a job's
 * progress, job.h): after each substep, and for a fit after each forward
 * run too.  The library calls back; the command line decides whether and
 * how to show it (on a terminal, at most twice a second).
 */
#ifndef SANDSLIDE_PROGRESS_H
#define SANDSLIDE_PROGRESS_H

struct ss_fit_progress;   /* fit.h */

struct ss_progress {
	double time;            /* simulated time now, s */
	double time_start;      /* where this process started (a restart: > 0), s */
	double end;             /* s; INFINITY: until steady */
	double steady_tol;      /* m/s: steady when max |dh/dt| falls below it */
	long long steps;        /* substeps since t = 0 */
	long long steps_here;   /* substeps taken by this process */
	double rate_max;        /* max |dh/dt| of the last substep, m/s */
	double cells;           /* cells of the grid */
	double wall_seconds;    /* since the command started, s */
	/* a fit's: the closure, stage and forward runs (fit.h); the fields
	 * above are then zero.  NULL for run and relax. */
	const struct ss_fit_progress *fit;
};

typedef void ss_progress_fn(void *context, const struct ss_progress *p);

#endif
