/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit_internal.h - what fit.c (the search, the forward runs, the
 * uncertainty) and fit_report.c (the report, the summary and the figure)
 * share: one fit's state.  doc/fit.md gives the equations (F0-F10).
 */
#ifndef SANDSLIDE_APP_FIT_INTERNAL_H
#define SANDSLIDE_APP_FIT_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "io/observations.h"
#include "sandslide/case.h"
#include "sandslide/fit.h"
#include "sandslide/integrator.h"

enum { PROFILE_MAX = 33, CLOSURES = 4, FRONT_SAMPLES = 4, TRACE_TIMES = 40 };

/* A best value within this of a bound, in u, is on it (F9a): ten times
 * the search's stopping step (1e-4). */
#define FIT_BOUND_TOL 1e-3

/* How a forward run ended. */
enum { RUN_DONE, RUN_CUT, RUN_STOPPED };

/* The time stepping of a forward run: the fit's (the case's, with the
 * RKL2 tolerance at most --rkl2-tol), or the reference that the forward
 * model's own error is measured against (F7a). */
enum stepping { STEP_FIT, STEP_REFERENCE };

/* One closure's fit. */
struct closure_fit {
	enum ss_closure_kind kind;
	struct ss_case c;               /* the case with this closure and the
	                                 * parameters set by override (which keys
	                                 * they drop: case.h); a forward run
	                                 * copies it and sets their values */
	int param[SS_FIT_MAX_PARAMS];   /* indices into the options' params */
	int p;                          /* how many apply to this closure */
	double u[SS_FIT_MAX_PARAMS];    /* the best point so far */
	double cost;                    /* its cost (INFINITY: none yet) */
	long long runs, cut_short;
	int searched;                   /* the search finished (not stopped) */
	int assessed;                   /* uncertainty and profiles done */
	double std_u[SS_FIT_MAX_PARAMS]; /* Gauss-Newton standard deviation in u
	                                  * (INFINITY: J^T J singular) */
	double noise;                   /* cost of pure noise used, s^2 (F7) */
	double std_noise_u[SS_FIT_MAX_PARAMS]; /* the noise's part of std_u */
	double shift_u[SS_FIT_MAX_PARAMS]; /* du: how far the forward model's own
	                                    * error moves the best point (F7a) */
	double model_cost;              /* J_m: the cost of that error (F7a) */
	int profile_n;
	double profile_u[SS_FIT_MAX_PARAMS][PROFILE_MAX];
	double profile_cost[SS_FIT_MAX_PARAMS][PROFILE_MAX];
	int identifiable[SS_FIT_MAX_PARAMS];
	char why[SS_FIT_MAX_PARAMS][200];
	double aic;
	double trace_radius[TRACE_TIMES]; /* the front's equivalent radius, m */
	int traced;
};

struct fit {
	const struct ss_fit_options *o;
	struct ss_fit_param params[SS_FIT_MAX_PARAMS];   /* --param's, parsed */
	int param_count;
	struct ss_case base;            /* the case as given */
	struct ss_observations obs;
	enum ss_fit_cost cost;
	int nx, ny;
	size_t cells;
	double dx, dy, origin_x, origin_y;
	uint8_t *flow;                  /* [cells] 1 on the case's flow cells */
	double *floor;                  /* [cells] m: thickness = height - floor */
	double relief;                  /* m: the thickest sand observed or initial */
	double threshold;               /* m, theta of F2 */
	double *chi_obs;                /* [times][cells] observed support (F2, F3) */
	uint8_t *support_seen;          /* [times][cells] where chi_obs is known */
	double *radius_obs;             /* [times] equivalent radius, m (F4) */
	double *area_obs;               /* [times] support area, m^2 */
	double speed_scale;             /* m/s: the fastest observed front */
	long long height_count;         /* observed heights on flow cells */
	long long area_count, speed_count;
	long long residual_count;       /* M */
	double cost_floor;              /* the least noise a cost is read with (F7) */
	double *sim;                    /* [cells] a forward run's heights */
	double *thickness, *chi_sim;    /* [cells] its thickness and support */
	double *residuals;              /* [M] */
	double *model_delta;            /* [M] the reference run's residuals (F7a) */
	double *jacobian;               /* [M][p] */
	double trace_time[TRACE_TIMES];
	enum ss_integrator integrator;  /* the case's, resolved */
	long long runs;
	double run_seconds;
	int interrupted;
	int failed;                     /* a forward run failed: the status */
	struct closure_fit fits[CLOSURES];
	int fit_count;
	int current;                    /* the closure being fitted */
	const char *stage;
	double started;
	double seconds;                 /* the whole fit, when it reports: once,
	                                 * for the measuring and the writing pass
	                                 * of text_of to agree */
};

/* ---- parameters ----------------------------------------------------------- */

/* A parameter's value at unit coordinate u (F0). */
static inline double fit_value_of(const struct ss_fit_param *p, double u)
{
	return p->log ? p->lo * pow(p->hi / p->lo, u) : p->lo + u * (p->hi - p->lo);
}

/* Whether u is on a bound of the range searched (F9a): -1 the lower, +1
 * the upper, 0 neither. */
static inline int fit_bound_side(double u)
{
	return u <= FIT_BOUND_TOL ? -1 : u >= 1.0 - FIT_BOUND_TOL ? 1 : 0;
}

static inline const char *fit_bound_name(int side)
{
	return side < 0 ? "lower" : "upper";
}

/* The forward runs' RKL2 tolerance: the case's, at most --rkl2-tol. */
static inline double fit_rkl2_tol(const struct fit *f)
{
	return fmin(f->base.model.rkl2_tol, f->o->rkl2_tol);
}

/*
 * The time stepping that the forward model's own error is measured
 * against (F7a): another solution of the same case.  With RKL2 the
 * case's own tolerance when the fit tightened it (the case as `run`
 * solves it: the fit's tighter tolerance only smooths the cost for the
 * search), else one ten times tighter; with forward Euler half the CFL
 * number (covariance() doubles that difference: Euler is first order).
 */
static inline double fit_reference_rkl2_tol(const struct fit *f)
{
	return f->base.model.rkl2_tol > f->o->rkl2_tol ? f->base.model.rkl2_tol
	                                               : 0.1 * f->base.model.rkl2_tol;
}

/* ---- fit_report.c ---------------------------------------------------------- */

/* The report (JSON) of the fit into *report and, when summary is not NULL
 * and a closure was fitted (best >= 0), the summary for people into
 * *summary (free() both); SS_ERR_FAIL out of memory. */
int ss_fit_report_text(const struct fit *f, int best, char **report, char **summary);

/* FIT.png (the front over time, the cost along each parameter). */
int ss_fit_plot(const struct fit *f, int best, const char *path);

#endif
