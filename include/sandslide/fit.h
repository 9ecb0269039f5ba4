/*
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
 * covariance with the noise from the residuals, and the cost along each
 * parameter) and says which parameters the data identify.  The closures
 * are compared by cost and by Akaike's information criterion.  The report
 * is JSON.  The library prints nothing: progress goes to a callback.
 */
#ifndef SANDSLIDE_FIT_H
#define SANDSLIDE_FIT_H

#include <signal.h>
#include <stddef.h>

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

/* What a fit reports as it goes (ss_fit_options.progress): after each
 * forward run, and after each substep of one. */
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
	const char *output;          /* FIT.json; NULL: the report is only returned */
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
	int threads;                 /* <= 0: OMP_NUM_THREADS, else all */
	int force;                   /* replace FIT.json and FIT.png */
	struct ss_fit_param params[SS_FIT_MAX_PARAMS];
	int param_count;
	const volatile sig_atomic_t *stop_signal; /* when it becomes non-zero the
	                              * fit stops and reports the best so far */
	void (*progress)(void *context, const struct ss_fit_progress *p);
	void *progress_context;
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

/* For foreign callers (Python's ctypes): options on the heap set by name
 * ("case", "observations", "output", "plot", "closures", "cost",
 * "threshold", "support-weight", "grid-points", "max-runs",
 * "profile-points", "threads", "force", and "param" NAME=LO:HI[:log], one
 * more each time), checked as the command line checks them. */
struct ss_fit_options *ss_fit_options_create(void);
void ss_fit_options_destroy(struct ss_fit_options *o);
int ss_fit_options_set(struct ss_fit_options *o, const char *key, const char *value);

/* Attach watch w (watch.h) to options o: its stop flag becomes their
 * stop_signal and its callback their progress, replacing any set; w NULL
 * detaches (no stop signal, no progress).  w must outlive the call. */
struct ss_watch;
void ss_fit_options_set_watch(struct ss_fit_options *o, struct ss_watch *w);

/* ss_fit_run with the report copied into buf (size bytes): SS_ERR_INPUT
 * when it does not fit, saying how many bytes it needs. */
int ss_fit_run_json(const struct ss_fit_options *o, char *buf, size_t size);

#endif
