/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit.h - `sandslide fit`: which closure and which parameters reproduce
 * observations of a real or synthetic experiment, how sure that is, and
 * whether the data can tell at all.  The inverse problem the paper leaves
 * open (section 5); doc/fit.md gives the cost functionals, the search and
 * the uncertainty with their equations.
 *
 * A fit takes a case (geometry, walls, sources, initial state, as for
 * run), observations (a series of heights, or points on the front of the
 * sand-covered region) and the parameters to free, each within bounds.
 * For each closure asked for it searches the bounds (a coarse grid, then
 * NLopt's BOBYQA from the best points), runs forward through the library
 * (no files written), then estimates the uncertainty (a Gauss-Newton
 * covariance with the noise from the residuals and the forward model's
 * own error from a run with another time stepping, and the cost along
 * each parameter) and says which parameters the data identify (never one
 * whose best value is on a bound of its range).  The closures
 * are compared by cost and by Akaike's information criterion.  The report
 * is JSON.  The library prints nothing: progress goes to a callback.
 */
#ifndef SANDSLIDE_FIT_H
#define SANDSLIDE_FIT_H

#include <signal.h>
#include <stddef.h>

#include "sandslide/job.h"
#include "sandslide/option.h"

/* A parameter freed by --param NAME=LO:HI[:log]: a [model] key of the case
 * (nu, repose_angle, gamma, delta, viscosity or consistency), searched in
 * [lo, hi], uniformly in log(value) when log is set. */
struct ss_fit_param {
	char name[32];
	double lo, hi;
	int log;
};

enum { SS_FIT_MAX_PARAMS = 4 };

/* What the cost compares (doc/fit.md#cost-functionals). */
enum ss_fit_cost {
	SS_FIT_COST_AUTO,       /* height for a height series, support for a front */
	SS_FIT_COST_HEIGHT,     /* mean squared height misfit over observed cells */
	SS_FIT_COST_SUPPORT,    /* area between the supports, and the front's speed */
	SS_FIT_COST_BOTH,       /* height / relief^2 + support_weight * support */
};

/* What a fit reports as it goes, the fit part of the job's progress
 * (progress.h): after each forward run, and after each substep of one. */
struct ss_fit_progress {
	const char *closure;    /* being fitted */
	const char *stage;      /* "grid", "search", "uncertainty", "profile", "front" */
	int closure_index, closure_count;
	long long runs;         /* forward runs so far, over every closure */
	double best_cost;       /* of this closure so far (INFINITY: none yet) */
};

struct ss_fit_options {
	const char *case_path;
	const char *observations;    /* OBS: .h5 heights, or a CSV */
	struct ss_job job;           /* output: FIT.json (NULL: the report is
	                              * only returned); force: replace FIT.json
	                              * and FIT.png; threads and tiles of each
	                              * forward run; the stop signal (when it
	                              * becomes non-zero the fit stops and
	                              * reports the best so far) and the
	                              * progress, after each forward run and
	                              * each substep of one, with its fit part
	                              * set (progress.h, job.h) */
	const char *plot;            /* FIT.png, or NULL */
	const char *closures;        /* "all", or a comma-separated list; NULL:
	                              * the case's closure */
	enum ss_fit_cost cost;
	double threshold;            /* m: sand thicker than this is in the
	                              * support; NaN: 2 % of the initial relief */
	double support_weight;       /* of the support cost in SS_FIT_COST_BOTH */
	int grid_points;             /* coarse grid points per parameter; 0: by
	                              * the parameter count (7, 4, 3, 2) */
	int max_runs;                /* forward runs of BOBYQA per start */
	int profile_points;          /* points of the cost along each parameter */
	double rkl2_tol;             /* the forward runs' RKL2 tolerance, when the
	                              * case's is larger: the search needs a
	                              * cost smooth in the parameters */
	struct ss_option_list params; /* --param's words, NAME=LO:HI[:log]
	                              * (ss_fit_param_parse), in order */
};

/* fit's options: name, kind, default, range, help (option.h). */
extern const struct ss_option_table ss_fit_option_table;

void ss_fit_options_init(struct ss_fit_options *o);

/* "nu=0.01:1:log" into *p: SS_ERR_INPUT naming what is wrong and what is
 * accepted (a known name, lo < hi, both > 0 on a log scale). */
int ss_fit_param_parse(const char *text, struct ss_fit_param *p);

/* Fit; *report is the report as JSON (free() it), also written to
 * o->output when it is set, whatever the end (done or interrupted), and
 * *summary (when summary is not NULL; free() it; NULL when no forward run
 * finished) a line per closure and one of the runs, for people.
 * SS_ERR_INPUT (message printed) for bad options, case or observations;
 * SS_ERR_FAIL for a failure while fitting.  An interrupted fit is SS_OK
 * with "interrupted": true in the report. */
int ss_fit_run(const struct ss_fit_options *o, char **report, char **summary);

/* ss_fit_run with the report copied into buf (size bytes): SS_ERR_INPUT
 * when it does not fit, saying how many bytes it needs. */
int ss_fit_run_json(const struct ss_fit_options *o, char *buf, size_t size);

#endif
