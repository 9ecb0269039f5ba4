/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit.c - `sandslide fit` (fit.h): forward runs through the library, the
 * cost functionals, the search (a coarse grid, then NLopt's BOBYQA), the
 * uncertainty (the noise and the forward model's own error) and the
 * identifiability verdicts, the comparison of the closures.  doc/fit.md
 * gives the equations this file computes (F0-F10).
 *
 * Every parameter is searched in a unit coordinate u in [0, 1]:
 * value = lo + u (hi - lo), or lo (hi / lo)^u on a log scale, so that one
 * step, one tolerance and one covariance serve parameters of any unit.
 */
#include "sandslide/fit.h"

#include <errno.h>
#include <math.h>
#include <nlopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/drive.h"
#include "app/fit_cost.h"
#include "app/fit_internal.h"
#include "base/strings.h"
#include "io/observations.h"
#include "io/output.h"
#include "model/setup.h"
#include "render/plot.h"
#include "sandslide/case.h"
#include "sandslide/closure.h"
#include "sandslide/material_table.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

/* ---- parameters ----------------------------------------------------------- */

/* The row of the model's table that parameter p frees (its case key is
 * "model." p->name; ss_fit_param_parse checked that one is fittable). */
static const struct ss_option *param_row(const struct ss_fit_param *p, size_t *offset)
{
	char key[48];
	snprintf(key, sizeof key, "model.%s", p->name);
	const struct ss_option *o = ss_option_find_key(&ss_case_option_table, key, offset);
	if (!o)
		SS_BUG("fit: no case key %s", key);
	return o;
}

/* Whether p is a class's parameter, "material NAME.KEY" (fit_options.c). */
static int is_material_param(const struct ss_fit_param *p)
{
	return !strncmp(p->name, "material ", strlen("material "));
}

/* Parameter p, a class's, set to value in table t (the case's [material
 * NAME]: the case parser made sure that it has one). */
static void set_material_param(const struct ss_fit_param *p, struct ss_material_table *t,
                               double value)
{
	const char *name = p->name + strlen("material "), *dot = strchr(name, '.');
	for (int k = 0; t && k < t->count; k++) {
		struct ss_material_spec *m = &t->item[k];
		if (strlen(m->name) == (size_t)(dot - name) && !strncmp(m->name, name, dot - name)) {
			*(!strcmp(dot + 1, "nu") ? &m->nu
			  : !strcmp(dot + 1, "static_angle") ? &m->static_deg : &m->angle_deg) = value;
			return;
		}
	}
	SS_BUG("fit: no [material %.*s] in the case", (int)(dot - name), name);
}

/* Whether closure kind takes parameter p: the closures of its row (a
 * class's parameter: every closure). */
static int param_applies(const struct ss_fit_param *p, enum ss_closure_kind kind)
{
	if (is_material_param(p))
		return 1;
	size_t offset;
	const struct ss_option *o = param_row(p, &offset);
	return !o->applies_to || (o->applies_to >> kind & 1);
}

/* "nu=0.13, repose_angle=33" of cf at u into buf, for messages. */
static void values_text(const struct fit *f, const struct closure_fit *cf, const double *u,
                        char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	buf[0] = '\0';
	for (int k = 0; k < cf->p; k++) {
		const struct ss_fit_param *p = &f->params[cf->param[k]];
		ss_strbuf_printf(&b, "%s%s=%s", k ? ", " : "", p->name, SS_REAL(fit_value_of(p, u[k])));
	}
}

/* The case of closure cf: the closure and each parameter set by override
 * (any value of its range: which keys an override drops does not depend
 * on it), parsed once; a forward run sets the values (make_stepper). */
static int parse_closure_case(const struct fit *f, struct closure_fit *cf)
{
	char text[SS_FIT_MAX_PARAMS + 1][96];
	const char *ov[SS_FIT_MAX_PARAMS + 1];
	int n = 0;
	snprintf(text[n], 96, "model.closure=%s", ss_closure_name(cf->kind));
	ov[n] = text[n];
	n++;
	for (int k = 0; k < cf->p; k++) {
		const struct ss_fit_param *p = &f->params[cf->param[k]];
		snprintf(text[n], 96, "%s%s=%s", is_material_param(p) ? "" : "model.", p->name,
		         SS_REAL(fit_value_of(p, 0.5)));
		ov[n] = text[n];
		n++;
	}
	return ss_case_parse(&cf->c, f->base.path, f->base.text, ov, n);
}

/* ---- the forward model ---------------------------------------------------- */

/* The interior heights of st, south row first, into out. */
static void copy_heights(const struct ss_stepper *st, double *out)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++) {
		const double *row = st->height + ss_grid_index(g, 0, j);
		memcpy(out + (size_t)j * g->nx, row, (size_t)g->nx * sizeof *out);
	}
}

/* The stepper of closure cf at u, prepared at t = 0: its case with each
 * parameter's value, nu derived again when the case derives it, and the
 * forward runs' RKL2 tolerance, or the reference's time stepping. */
static int make_stepper(const struct fit *f, const struct closure_fit *cf, const double *u,
                        enum stepping stepping, struct ss_stepper *st)
{
	struct ss_case c = cf->c;   /* a copy of the values: the set-up only reads */
	for (int k = 0; k < cf->p; k++) {
		const struct ss_fit_param *p = &f->params[cf->param[k]];
		if (is_material_param(p)) {
			/* the table is the closure's case's, set before each run */
			set_material_param(p, c.material_table, fit_value_of(p, u[k]));
			continue;
		}
		size_t offset;
		const struct ss_option *o = param_row(p, &offset);
		*(double *)((char *)&c + offset + o->offset) = fit_value_of(p, u[k]);
	}
	if (c.model.nu_from_layer) {
		c.model.nu = ss_model_nu_from_layer(&c.model);
		if (!(c.model.nu > 0.0) || !isfinite(c.model.nu)) {
			char at[256];
			values_text(f, cf, u, at, sizeof at);
			return ss_error_input("%s: [model] the physical parameters give nu = %g m^2/s "
			                      "at %s: expected a finite value > 0", c.path, c.model.nu, at);
		}
	}
	if (f->integrator == SS_INTEGRATOR_RKL2) {
		/* the forward runs' tolerance holds while a source pours too: a
		 * cost that jitters with the super-steps misleads the optimiser */
		c.model.rkl2_tol = stepping == STEP_REFERENCE ? fit_reference_rkl2_tol(f) : fit_rkl2_tol(f);
		c.model.rkl2_pouring_tol = c.model.rkl2_tol;
	}
	else if (stepping == STEP_REFERENCE)
		c.model.cfl *= 0.5;
	return ss_setup_stepper(&c, f->o->job.tile[0], f->o->job.tile[1], SS_KERNEL_FAST, st);
}

/* The simulated support of heights h into f->chi_sim: per cell for a
 * height series (compared cell by cell with the observed heights'), as a
 * front sees it for a front (F3). */
static void simulated_support(const struct fit *f, const double *h)
{
	if (f->obs.kind == SS_OBSERVED_HEIGHTS) {
		for (size_t c = 0; c < f->cells; c++)
			f->chi_sim[c] = f->flow[c] ? ss_fit_support_indicator(h[c] - f->floor[c],
			                                                      f->threshold) : 0.0;
		return;
	}
	for (size_t c = 0; c < f->cells; c++)
		f->thickness[c] = f->flow[c] ? h[c] - f->floor[c] : 0.0;
	ss_fit_support_fraction(f->thickness, f->nx, f->ny, f->threshold, FRONT_SAMPLES,
	                        f->chi_sim);
	for (size_t c = 0; c < f->cells; c++)
		f->chi_sim[c] *= f->flow[c];
}

/* The area of f->chi_sim, m^2 (F4). */
static double support_area(const struct fit *f)
{
	double area = 0.0;
	for (size_t c = 0; c < f->cells; c++)
		area += f->chi_sim[c];
	return area * f->dx * f->dy;
}

/*
 * The residuals of time k for heights h, appended at r (when not NULL);
 * returns their sum of squares.  *radius_prev carries the simulated
 * front's equivalent radius from time k - 1 for the speed term.
 *
 *   height   r = (h - h_obs) w_h            over observed flow cells       (F1)
 *   support  r = |S_sim (+) S_obs| / A_obs w_a   at each time               (F3)
 *            r = (v_sim - v_obs) / v_max w_v     between consecutive times (F4)
 *
 * with the weights that make the cost a mean of each block (F5).
 */
static double residuals_at(const struct fit *f, long long k, const double *h, double *r,
                           long long *at, double *radius_prev)
{
	double sum = 0.0;
	const int heights = f->cost == SS_FIT_COST_HEIGHT || f->cost == SS_FIT_COST_BOTH;
	const int support = f->cost == SS_FIT_COST_SUPPORT || f->cost == SS_FIT_COST_BOTH;
	const double block = f->cost == SS_FIT_COST_BOTH ? f->o->support_weight : 1.0;
	if (heights) {
		const double w = (f->cost == SS_FIT_COST_BOTH ? 1.0 / f->relief : 1.0) /
		                 sqrt((double)f->height_count);
		const double *obs = f->obs.height + (size_t)k * f->cells;
		for (size_t c = 0; c < f->cells; c++)
			if (f->flow[c] && isfinite(obs[c])) {
				const double e = (h[c] - obs[c]) * w;
				sum += e * e;
				if (r)
					r[(*at)++] = e;
			}
	}
	if (support) {
		const double *chi = f->chi_obs + (size_t)k * f->cells;
		const uint8_t *seen = f->support_seen + (size_t)k * f->cells;
		simulated_support(f, h);
		double mismatch = 0.0;
		for (size_t c = 0; c < f->cells; c++)
			if (seen[c])
				mismatch += fabs(f->chi_sim[c] - chi[c]);
		mismatch *= f->dx * f->dy;
		if (f->area_obs[k] > 0.0) {
			const double e = mismatch / f->area_obs[k] * sqrt(block / (double)f->area_count);
			sum += e * e;
			if (r)
				r[(*at)++] = e;
		}
		const double radius = sqrt(support_area(f) / M_PI);
		if (k > 0 && f->speed_count > 0) {
			const double dt = f->obs.time[k] - f->obs.time[k - 1];
			const double v_sim = (radius - *radius_prev) / dt;
			const double v_obs = (f->radius_obs[k] - f->radius_obs[k - 1]) / dt;
			const double e = (v_sim - v_obs) / f->speed_scale *
			                 sqrt(block / (double)f->speed_count);
			sum += e * e;
			if (r)
				r[(*at)++] = e;
		}
		*radius_prev = radius;
	}
	return sum;
}

/* The fit's progress as it stands, fitting closure cf, to the job's. */
static void report_progress(const struct fit *f, const struct closure_fit *cf)
{
	const struct ss_job *job = &f->o->job;
	if (!job->progress)
		return;
	const struct ss_fit_progress fit = {
		ss_closure_name(cf->kind), f->stage, f->current, f->fit_count, f->runs, cf->cost,
	};
	const struct ss_progress p = {.fit = &fit};
	job->progress(job->progress_context, &p);
}

/* What a forward run's substeps report. */
struct run_context {
	const struct fit *f;
	const struct closure_fit *cf;
};

/* After each substep of a forward run, the progress again: a caller that
 * watches from another thread (watch.h) hands its stop request over in the
 * callback, so a fit stops within a substep, not a whole run. */
static void substep_progress(void *context, const struct ss_stepper *st)
{
	(void)st;
	const struct run_context *c = context;
	report_progress(c->f, c->cf);
}

/* How a forward run that did not reach a time ended. */
struct run_end {
	enum ss_advance_end end;        /* SS_ADVANCE_REACHED: it reached them all */
	double time;                    /* where it stopped, s */
	long long k;                    /* the time it did not reach */
};

/*
 * A forward run of closure cf at u through the times t[0..n-1]: at each the
 * heights are copied to f->sim and at_time(f, k, context) called, which
 * returns non-zero to stop the run there (*how RUN_CUT).  *how is RUN_DONE
 * or RUN_STOPPED (the stop signal); *e says how the stepper ended when it
 * did not reach a time (the caller says what that means).  The cost and
 * the front's trace are both such runs.
 */
static int run_through(struct fit *f, const struct closure_fit *cf, const double *u,
                       enum stepping stepping, const double *t, long long n,
                       int (*at_time)(struct fit *f, long long k, void *context), void *context,
                       int *how, struct run_end *e)
{
	struct ss_stepper st;
	*how = RUN_DONE;
	e->end = SS_ADVANCE_REACHED;
	int err = make_stepper(f, cf, u, stepping, &st);
	if (err)
		return err;
	const struct run_context rc = {f, cf};
	struct ss_advance_options adv = {.stop = f->o->job.stop_signal,
	                                 .progress = f->o->job.progress ? substep_progress : NULL,
	                                 .context = (void *)&rc};
	for (long long k = 0; k < n; k++) {
		e->end = t[k] > st.time ? ss_stepper_advance(&st, t[k], &adv) : SS_ADVANCE_REACHED;
		e->time = st.time;
		e->k = k;
		if (e->end == SS_ADVANCE_INTERRUPTED)
			*how = RUN_STOPPED;
		if (e->end != SS_ADVANCE_REACHED)
			break;
		copy_heights(&st, f->sim);
		if (at_time(f, k, context)) {
			*how = RUN_CUT;
			break;
		}
	}
	ss_stepper_release(&st);
	return SS_OK;
}

/* The cost of a forward run so far: the residuals of each observation
 * time (residuals_at) added up, until it passes cut. */
struct cost_sum {
	double cut, cost;
	double *r;                      /* the residuals, or NULL */
	long long at;                   /* residuals written so far */
	double radius_prev;             /* the front's radius at the time before */
};

static int add_residuals(struct fit *f, long long k, void *context)
{
	struct cost_sum *c = context;
	c->cost += residuals_at(f, k, f->sim, c->r, &c->at, &c->radius_prev);
	return c->cost > c->cut;
}

/*
 * One forward run of closure cf at u through every observation time: the
 * cost (F5) into *cost and, with r, the residuals.  With a finite cut the
 * run stops as soon as the sum so far passes it (*how RUN_CUT, *cost that
 * lower bound): safe where only "is it better than the best?" is asked,
 * since every time adds a non-negative term.  RUN_STOPPED: the stop signal.
 */
static int forward_stepped(struct fit *f, struct closure_fit *cf, const double *u,
                           enum stepping stepping, double cut, double *r, double *cost,
                           int *how)
{
	const double t0 = ss_parallel_wall_seconds();
	struct cost_sum sum = {.cut = cut, .r = r};
	struct run_end e;
	int err = run_through(f, cf, u, stepping, f->obs.time, f->obs.times, add_residuals, &sum,
	                      how, &e);
	*cost = sum.cost;
	if (err)
		return err;   /* no run: the set-up failed */
	if (e.end != SS_ADVANCE_REACHED && e.end != SS_ADVANCE_INTERRUPTED) {
		char at[512];
		values_text(f, cf, u, at, sizeof at);
		err = ss_error_fail("the forward run of %s at %s stopped at t = %g s before the "
		                    "observation at %g s: %s", ss_closure_name(cf->kind), at, e.time,
		                    f->obs.time[e.k],
		                    e.end == SS_ADVANCE_NONFINITE ? "a height became non-finite"
		                                                  : "its time step vanished");
	}
	f->runs++;
	cf->runs++;
	cf->cut_short += *how == RUN_CUT;
	f->run_seconds += ss_parallel_wall_seconds() - t0;
	if (*how == RUN_STOPPED)
		f->interrupted = 1;
	report_progress(f, cf);
	return err;
}

/* forward_stepped with the fit's time stepping. */
static int forward(struct fit *f, struct closure_fit *cf, const double *u, double cut,
                   double *r, double *cost, int *how)
{
	return forward_stepped(f, cf, u, STEP_FIT, cut, r, cost, how);
}

/* A forward run that keeps the best point: the cost, or INFINITY once the
 * fit is stopped or failed. */
static double evaluate(struct fit *f, struct closure_fit *cf, const double *u, double cut)
{
	if (f->interrupted || f->failed)
		return INFINITY;
	double cost;
	int how;
	const int err = forward(f, cf, u, cut, NULL, &cost, &how);
	if (err) {
		f->failed = err;
		return INFINITY;
	}
	if (how != RUN_DONE)
		return how == RUN_CUT ? cost : INFINITY;
	if (cost < cf->cost) {
		cf->cost = cost;
		memcpy(cf->u, u, (size_t)cf->p * sizeof *u);
	}
	return cost;
}

/* ---- the search ----------------------------------------------------------- */

struct search {
	struct fit *f;
	struct closure_fit *cf;
	nlopt_opt opt;
};

static double objective(unsigned n, const double *u, double *gradient, void *data)
{
	(void)n;
	(void)gradient;   /* BOBYQA asks for none */
	struct search *s = data;
	const double cost = evaluate(s->f, s->cf, u, INFINITY);
	if (s->f->interrupted || s->f->failed)
		nlopt_force_stop(s->opt);
	return cost;
}

/* The coarse grid's points per parameter (F6). */
static int grid_points(const struct fit *f, int p)
{
	static const int by_count[SS_FIT_MAX_PARAMS + 1] = {1, 7, 4, 3, 2};
	return f->o->grid_points > 0 ? f->o->grid_points : by_count[p];
}

/* The coarse grid (runs cut at the best so far: only the ranking counts),
 * then BOBYQA from its best point and, with two or more parameters, from
 * the best point that is not next to it. */
static int search(struct fit *f, struct closure_fit *cf)
{
	const int p = cf->p, g = grid_points(f, p);
	long long total = 1;
	for (int k = 0; k < p; k++)
		total *= g;
	double best = INFINITY, second = INFINITY;
	long long best_at = -1, second_at = -1;
	f->stage = "grid";
	for (long long m = 0; m < total && !f->interrupted && !f->failed; m++) {
		double u[SS_FIT_MAX_PARAMS];
		for (long long k = 0, rest = m; k < p; k++, rest /= g)
			u[k] = (rest % g + 0.5) / g;
		const double cost = evaluate(f, cf, u, best);
		if (cost < best) {
			second = best;
			second_at = best_at;
			best = cost;
			best_at = m;
		} else if (cost < second) {
			second = cost;
			second_at = m;
		}
	}
	(void)second;
	/* a second start only where it is not the first's neighbour */
	long long starts[2] = {best_at, -1};
	if (p >= 2 && second_at >= 0) {
		int far = 0;
		for (long long k = 0, a = best_at, b = second_at; k < p; k++, a /= g, b /= g)
			far |= llabs(a % g - b % g) > 1;
		if (far)
			starts[1] = second_at;
	}
	f->stage = "search";
	for (int s = 0; s < 2 && starts[s] >= 0 && !f->interrupted && !f->failed; s++) {
		double u[SS_FIT_MAX_PARAMS], lo[SS_FIT_MAX_PARAMS], hi[SS_FIT_MAX_PARAMS],
		       step[SS_FIT_MAX_PARAMS], found;
		for (long long k = 0, rest = starts[s]; k < p; k++, rest /= g) {
			u[k] = (rest % g + 0.5) / g;
			lo[k] = 0.0;
			hi[k] = 1.0;
			step[k] = 0.5 / g;
		}
		nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, (unsigned)p);
		if (!opt)
			return ss_error_fail("out of memory");
		struct search data = {f, cf, opt};
		nlopt_set_lower_bounds(opt, lo);
		nlopt_set_upper_bounds(opt, hi);
		nlopt_set_min_objective(opt, objective, &data);
		nlopt_set_initial_step(opt, step);
		nlopt_set_xtol_abs1(opt, 1e-4);
		nlopt_set_ftol_rel(opt, 1e-10);
		nlopt_set_maxeval(opt, f->o->max_runs);
		const nlopt_result res = nlopt_optimize(opt, u, &found);
		nlopt_destroy(opt);
		if (res < 0 && res != NLOPT_FORCED_STOP && res != NLOPT_ROUNDOFF_LIMITED)
			return ss_error_fail("NLopt's BOBYQA failed for %s (NLopt status %d)",
			                     ss_closure_name(cf->kind), (int)res);
	}
	if (f->failed)
		return f->failed;
	cf->searched = !f->interrupted;
	return SS_OK;
}

/* ---- how sure ------------------------------------------------------------- */

/* Solve the p x p symmetric system a x = b in place by Gaussian elimination
 * with partial pivoting; -1 when a pivot falls below tiny times the
 * largest diagonal (singular for these data). */
static int invert(int p, double a[SS_FIT_MAX_PARAMS][SS_FIT_MAX_PARAMS],
                  double inv[SS_FIT_MAX_PARAMS][SS_FIT_MAX_PARAMS])
{
	double scale = 0.0;
	for (int i = 0; i < p; i++) {
		scale = fmax(scale, fabs(a[i][i]));
		for (int j = 0; j < p; j++)
			inv[i][j] = i == j;
	}
	if (!(scale > 0.0))
		return -1;
	for (int c = 0; c < p; c++) {
		int piv = c;
		for (int i = c + 1; i < p; i++)
			if (fabs(a[i][c]) > fabs(a[piv][c]))
				piv = i;
		if (fabs(a[piv][c]) < 1e-12 * scale)
			return -1;
		for (int j = 0; j < p; j++) {
			double t = a[c][j];
			a[c][j] = a[piv][j];
			a[piv][j] = t;
			t = inv[c][j];
			inv[c][j] = inv[piv][j];
			inv[piv][j] = t;
		}
		for (int i = 0; i < p; i++) {
			if (i == c)
				continue;
			const double m = a[i][c] / a[c][c];
			for (int j = 0; j < p; j++) {
				a[i][j] -= m * a[c][j];
				inv[i][j] -= m * inv[c][j];
			}
		}
	}
	for (int i = 0; i < p; i++)
		for (int j = 0; j < p; j++)
			inv[i][j] /= a[i][i];
	return 0;
}

/* The residuals at u into r (a full run with the time stepping given);
 * -1 when stopped or failed. */
static int residuals(struct fit *f, struct closure_fit *cf, const double *u,
                     enum stepping stepping, double *r)
{
	double cost;
	int how;
	const int err = forward_stepped(f, cf, u, stepping, INFINITY, r, &cost, &how);
	if (err)
		f->failed = err;
	return err || how != RUN_DONE ? -1 : 0;
}

/*
 * The Gauss-Newton covariance of the best point (F7) with the forward
 * model's own error (F7a): J_r by central differences of the residuals in
 * u (one-sided at a bound), the noise s^2 = max(J, J_floor) / (M - p) from
 * the residuals, and d = c (r_fit(u*) - r_ref(u*)), the change of the
 * residuals when the reference's time stepping replaces the fit's (c = 1
 * for RKL2, 2 for Euler).
 *
 * Linearised about the truth u_t, the residuals are r(u) = e + d +
 * J_r (u - u_t), e the noise (independent, variance s^2 each) and d the
 * model's error (the same in every run); least squares gives
 * u* - u_t = -(J_r^T J_r)^-1 J_r^T (e + d), so with Sigma = s^2 I + d d^T
 * the residuals' covariance,
 *
 *   C_u = (J_r^T J_r)^-1 J_r^T Sigma J_r (J_r^T J_r)^-1
 *       = s^2 (J_r^T J_r)^-1 + du du^T,   du = (J_r^T J_r)^-1 J_r^T d
 *
 * Added to s^2 as if it were noise, the model's cost J_m = |d|^2 would be
 * spread over the M residuals and averaged away, by up to sqrt(M): it
 * does not average, every residual carries it the same way in every run.
 */
static int covariance(struct fit *f, struct closure_fit *cf)
{
	const int p = cf->p;
	const long long m = f->residual_count;
	const double h = 0.02;
	f->stage = "uncertainty";
	for (int k = 0; k < p; k++) {
		double up[SS_FIT_MAX_PARAMS], down[SS_FIT_MAX_PARAMS];
		memcpy(up, cf->u, sizeof up);
		memcpy(down, cf->u, sizeof down);
		up[k] = fmin(cf->u[k] + h, 1.0);
		down[k] = fmax(cf->u[k] - h, 0.0);
		double *col = f->jacobian + (size_t)k * m;
		if (residuals(f, cf, up, STEP_FIT, col) ||
		    residuals(f, cf, down, STEP_FIT, f->residuals))
			return -1;
		for (long long i = 0; i < m; i++)
			col[i] = (col[i] - f->residuals[i]) / (up[k] - down[k]);
	}
	double jtj[SS_FIT_MAX_PARAMS][SS_FIT_MAX_PARAMS], inv[SS_FIT_MAX_PARAMS][SS_FIT_MAX_PARAMS];
	for (int a = 0; a < p; a++)
		for (int b = 0; b < p; b++) {
			double s = 0.0;
			const double *ja = f->jacobian + (size_t)a * m, *jb = f->jacobian + (size_t)b * m;
			for (long long i = 0; i < m; i++)
				s += ja[i] * jb[i];
			jtj[a][b] = s;
		}
	/* d = r_fit - r_ref at the best point (twice that for Euler),
	 * J_m = sum d_i^2, J_r^T d (F7a) */
	if (residuals(f, cf, cf->u, STEP_FIT, f->residuals) ||
	    residuals(f, cf, cf->u, STEP_REFERENCE, f->model_delta))
		return -1;
	/* forward Euler is first order in its step: h(dt) - h(dt/2) is half
	 * the error of h(dt) (Richardson); RKL2's tolerance sets no such rate */
	const double richardson = f->integrator == SS_INTEGRATOR_RKL2 ? 1.0 : 2.0;
	double jtd[SS_FIT_MAX_PARAMS] = {0.0};
	cf->model_cost = 0.0;
	for (long long i = 0; i < m; i++) {
		const double d = richardson * (f->residuals[i] - f->model_delta[i]);
		cf->model_cost += d * d;
		for (int a = 0; a < p; a++)
			jtd[a] += f->jacobian[(size_t)a * m + i] * d;
	}
	cf->noise = fmax(cf->cost, f->cost_floor);
	const double s2 = cf->noise / (double)(m > p ? m - p : 1);
	if (invert(p, jtj, inv)) {
		for (int k = 0; k < p; k++)
			cf->std_u[k] = cf->std_noise_u[k] = cf->shift_u[k] = INFINITY;
		return 0;
	}
	/* C_u = s^2 (J_r^T J_r)^-1 + du du^T,  du = (J_r^T J_r)^-1 J_r^T d  (F7) */
	for (int k = 0; k < p; k++) {
		double du = 0.0;
		for (int b = 0; b < p; b++)
			du += inv[k][b] * jtd[b];
		cf->shift_u[k] = du;
		cf->std_noise_u[k] = inv[k][k] > 0.0 ? sqrt(s2 * inv[k][k]) : INFINITY;
		cf->std_u[k] = sqrt(cf->std_noise_u[k] * cf->std_noise_u[k] + du * du);
	}
	return 0;
}

/*
 * The cost along each parameter, the others at the best point (F8), and
 * the verdicts (F9): a parameter is identified when its 95 % interval
 * covers less than half the range searched and the cost along it rises
 * above the noise: by chi^2_1(0.95) = 3.84 in units of s^2 / (M - p).
 */
static int profiles(struct fit *f, struct closure_fit *cf)
{
	const int n = f->o->profile_points;
	f->stage = "profile";
	cf->profile_n = n;
	for (int k = 0; k < cf->p; k++)
		for (int i = 0; i < n; i++) {
			double u[SS_FIT_MAX_PARAMS];
			memcpy(u, cf->u, sizeof u);
			u[k] = n > 1 ? (double)i / (n - 1) : 0.5;
			cf->profile_u[k][i] = u[k];
			double cost;
			int how;
			const int err = forward(f, cf, u, INFINITY, NULL, &cost, &how);
			if (err) {
				f->failed = err;
				return -1;
			}
			if (how != RUN_DONE)
				return -1;
			cf->profile_cost[k][i] = cost;
		}
	const long long m = f->residual_count;
	const double s2 = cf->noise / (double)(m > cf->p ? m - cf->p : 1);
	for (int k = 0; k < cf->p; k++) {
		const struct ss_fit_param *p = &f->params[cf->param[k]];
		double rise = 0.0;
		for (int i = 0; i < n; i++)
			rise = fmax(rise, cf->profile_cost[k][i] - cf->cost);
		const double width = 2.0 * 1.96 * cf->std_u[k];
		const int side = fit_bound_side(cf->u[k]);
		if (side) {
			/* the least cost may lie beyond the range: neither the rise
			 * nor the interval says where the minimum is (F9a) */
			cf->identifiable[k] = 0;
			snprintf(cf->why[k], sizeof cf->why[k],
			         "the best value %s is on the %s bound of the range searched "
			         "(%s .. %s): the cost may fall further beyond it; widen the range "
			         "(--param %s=LO:HI) and fit again", SS_REAL(fit_value_of(p, cf->u[k])),
			         fit_bound_name(side), SS_REAL(p->lo), SS_REAL(p->hi), p->name);
		} else if (!(rise > 3.84 * s2)) {
			cf->identifiable[k] = 0;
			snprintf(cf->why[k], sizeof cf->why[k],
			         "the cost changes by less than the noise over the whole range of %s: "
			         "these observations do not see it", p->name);
		} else if (!(width < 0.5)) {
			cf->identifiable[k] = 0;
			snprintf(cf->why[k], sizeof cf->why[k],
			         "its 95 %% interval spans %s of the range searched",
			         isfinite(width) ? "more than half" : "all");
		} else {
			cf->identifiable[k] = 1;
			cf->why[k][0] = '\0';
		}
	}
	return 0;
}

/* ---- set-up --------------------------------------------------------------- */

static int parse_closures(struct fit *f)
{
	const char *list = f->o->closures;
	if (!list || !*list) {
		f->fits[f->fit_count++].kind = f->base.model.closure;
		return SS_OK;
	}
	if (!strcmp(list, "all")) {
		for (int k = 0; k < CLOSURES; k++)
			f->fits[f->fit_count++].kind = (enum ss_closure_kind)k;
		return SS_OK;
	}
	char word[64];
	for (const char *s = list; *s;) {
		const size_t len = strcspn(s, ",");
		snprintf(word, sizeof word, "%.*s", (int)len, s);
		enum ss_closure_kind kind;
		if (len >= sizeof word || ss_closure_parse(word, &kind))
			return ss_error_input("--closures '%s': '%s' is not a closure: expected all, or "
			                      "a comma-separated list of %s", list, word,
			                      SS_CLOSURE_NAMES);
		for (int k = 0; k < f->fit_count; k++)
			if (f->fits[k].kind == kind)
				return ss_error_input("--closures '%s': %s is named twice", list, word);
		f->fits[f->fit_count++].kind = kind;
		s += len + (s[len] == ',');
	}
	return SS_OK;
}

/* --param's words parsed, then each closure's parameters: those it takes.
 * A closure that takes none, nu and delta together, or a name given twice
 * is refused. */
static int assign_params(struct fit *f)
{
	const struct ss_fit_options *o = f->o;
	if (o->params.count > SS_FIT_MAX_PARAMS)
		return ss_error_input("at most %d --param", SS_FIT_MAX_PARAMS);
	for (int k = 0; k < o->params.count; k++) {
		int err = ss_fit_param_parse(o->params.items[k], &f->params[k]);
		if (err)
			return err;
		f->param_count++;
	}
	if (f->param_count < 1)
		return ss_error_input("fit needs at least one --param NAME=LO:HI[:log], e.g. "
		                      "--param nu=0.01:1:log");
	int nu = 0, derived = 0;
	for (int k = 0; k < f->param_count; k++) {
		for (int m = 0; m < k; m++)
			if (!strcmp(f->params[k].name, f->params[m].name))
				return ss_error_input("--param %s is given twice", f->params[k].name);
		size_t offset;
		nu |= !strcmp(f->params[k].name, "nu");
		derived |= !is_material_param(&f->params[k]) &&
		           ss_model_option_is_layer(param_row(&f->params[k], &offset));
	}
	if (nu && derived)
		return ss_error_input("--param nu and the sliding layer's parameters (delta, "
		                      "viscosity, consistency) exclude each other: nu is derived "
		                      "from them (doc/model.md#nu-from-the-sliding-layer)");
	for (int c = 0; c < f->fit_count; c++) {
		struct closure_fit *cf = &f->fits[c];
		cf->cost = INFINITY;
		for (int k = 0; k < f->param_count; k++)
			if (param_applies(&f->params[k], cf->kind))
				cf->param[cf->p++] = k;
		if (cf->p == 0)
			return ss_error_input("%s takes none of the parameters given (%s%s): it takes "
			                      "nu and repose_angle%s", ss_closure_name(cf->kind),
			                      f->params[0].name, f->param_count > 1 ? ", ..." : "",
			                      cf->kind == SS_CLOSURE_COULOMB ? ""
			                      : ", and the sliding layer's parameters");
	}
	return SS_OK;
}

/* The observations against the case's grid. */
static int check_grid(const struct fit *f)
{
	const struct ss_observations *b = &f->obs;
	const struct ss_case *c = &f->base;
	if (b->kind != SS_OBSERVED_HEIGHTS)
		return SS_OK;
	if (b->nx != c->nx || b->ny != c->ny)
		return ss_error_input("'%s' has %d x %d cells: the case's grid is %d x %d (%s)",
		                      b->path, b->nx, b->ny, c->nx, c->ny, c->path);
	if ((isfinite(b->dx) && fabs(b->dx - c->dx) > 1e-6 * c->dx) ||
	    (isfinite(b->dy) && fabs(b->dy - c->dy) > 1e-6 * c->dy))
		return ss_error_input("'%s' has cells of %g x %g m: the case's are %g x %g m (%s)",
		                      b->path, b->dx, b->dy, c->dx, c->dy, c->path);
	if ((isfinite(b->origin_x) && fabs(b->origin_x - c->origin_x) > 1e-3 * c->dx) ||
	    (isfinite(b->origin_y) && fabs(b->origin_y - c->origin_y) > 1e-3 * c->dy))
		return ss_error_input("'%s' has its lower-left corner at (%g, %g) m: the case's is "
		                      "at (%g, %g) m (%s)", b->path, b->origin_x, b->origin_y,
		                      c->origin_x, c->origin_y, c->path);
	return SS_OK;
}

/* The case's flow cells, the floor that thickness is measured from (the
 * bedrock, or the initial state's lowest height), the relief. */
static int measure_initial(struct fit *f)
{
	struct ss_stepper st;
	int err = ss_setup_stepper(&f->base, f->o->job.tile[0], f->o->job.tile[1], SS_KERNEL_FAST,
	                           &st);
	if (err)
		return err;
	const struct ss_grid *g = &st.grid;
	double lowest = INFINITY, thickest = 0.0;
	copy_heights(&st, f->sim);
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t at = ss_grid_index(g, i, j);
			const size_t c = (size_t)j * g->nx + i;
			f->flow[c] = ss_cell_type_get(st.cell_types, at) == SS_CELL_FLOW;
			if (f->flow[c])
				lowest = fmin(lowest, f->sim[c]);
		}
	for (size_t c = 0; c < f->cells; c++) {
		const ptrdiff_t at = ss_grid_index(g, (int)(c % g->nx), (int)(c / g->nx));
		f->floor[c] = st.bedrock && isfinite(st.bedrock[at]) ? st.bedrock[at] : lowest;
		if (f->flow[c])
			thickest = fmax(thickest, f->sim[c] - f->floor[c]);
	}
	f->integrator = st.integrator;
	ss_stepper_release(&st);
	if (!isfinite(lowest))
		return ss_error_input("%s has no flow cell: nothing to fit", f->base.path);
	if (f->obs.kind == SS_OBSERVED_HEIGHTS)
		for (long long k = 0; k < f->obs.times; k++)
			for (size_t c = 0; c < f->cells; c++) {
				const double h = f->obs.height[(size_t)k * f->cells + c];
				if (f->flow[c] && isfinite(h))
					thickest = fmax(thickest, h - f->floor[c]);
			}
	f->relief = thickest;
	return SS_OK;
}

/* The observed support at every time (F2, F3), its area and equivalent
 * radius, the front's speed scale. */
static int observe_support(struct fit *f)
{
	const struct ss_observations *b = &f->obs;
	for (long long k = 0; k < b->times; k++) {
		double *chi = f->chi_obs + (size_t)k * f->cells;
		uint8_t *seen = f->support_seen + (size_t)k * f->cells;
		if (b->kind == SS_OBSERVED_HEIGHTS) {
			const double *h = b->height + (size_t)k * f->cells;
			for (size_t c = 0; c < f->cells; c++) {
				seen[c] = f->flow[c] && isfinite(h[c]);
				chi[c] = seen[c] ? ss_fit_support_indicator(h[c] - f->floor[c], f->threshold)
				                 : 0.0;
			}
		} else {
			const long long first = b->first_point[k];
			if (ss_fit_front_support(b->point_x + first, b->point_y + first,
			                         b->first_point[k + 1] - first, f->nx, f->ny,
			                         f->origin_x, f->origin_y, f->dx, f->dy, FRONT_SAMPLES,
			                         chi) < 0.0)
				return ss_error_fail("out of memory");
			for (size_t c = 0; c < f->cells; c++)
				seen[c] = f->flow[c];
		}
		double area = 0.0;
		for (size_t c = 0; c < f->cells; c++)
			area += seen[c] ? chi[c] : 0.0;
		f->area_obs[k] = area * f->dx * f->dy;
		f->radius_obs[k] = sqrt(f->area_obs[k] / M_PI);
		f->area_count += f->area_obs[k] > 0.0;
	}
	f->speed_scale = 0.0;
	for (long long k = 1; k < b->times; k++)
		f->speed_scale = fmax(f->speed_scale, fabs(f->radius_obs[k] - f->radius_obs[k - 1]) /
		                                      (b->time[k] - b->time[k - 1]));
	f->speed_count = f->speed_scale > 0.0 ? b->times - 1 : 0;
	if (f->area_count == 0 && f->cost != SS_FIT_COST_HEIGHT)
		return ss_error_input("'%s': no sand thicker than the threshold %g m at any time: "
		                      "the support cost has nothing to compare (give a smaller "
		                      "--threshold)", b->path, f->threshold);
	return SS_OK;
}

static int prepare(struct fit *f)
{
	const struct ss_fit_options *o = f->o;
	int err;
	if (!o->case_path || !o->observations)
		return ss_error_input("fit needs a case file and observations: sandslide fit "
		                      "CASE.ini OBS -o FIT.json");
	if ((err = ss_case_load(&f->base, o->case_path, NULL, 0)) || (err = parse_closures(f)) ||
	    (err = assign_params(f)))
		return err;
	/* before the observations are read: the case's grid, the stepper and
	 * fit's own arrays (flow flags, floor, simulated heights and
	 * thickness: about three rasters) must fit in memory */
	if ((err = ss_setup_check_raster_memory(f->base.path, f->base.nx, f->base.ny, 3,
	                                        &f->base.model, f->base.bedrock_file != NULL)))
		return err;
	if (o->job.output && ((err = ss_output_check_folder(o->job.output, 0)) ||
	                      (err = ss_output_check_absent(o->job.output, o->job.force, NULL))))
		return err;
	/* the figure's font too: its absence would end the fit at its end */
	if (o->plot && ((err = ss_output_check_folder(o->plot, 0)) ||
	                (err = ss_output_check_absent(o->plot, o->job.force, NULL)) ||
	                (err = ss_plot_check_font())))
		return err;
	if ((err = ss_observations_read(&f->obs, o->observations)) || (err = check_grid(f)))
		return err;
	f->nx = f->base.nx;
	f->ny = f->base.ny;
	f->cells = (size_t)f->nx * (size_t)f->ny;
	f->dx = f->base.dx;
	f->dy = f->base.dy;
	f->origin_x = f->base.origin_x;
	f->origin_y = f->base.origin_y;
	f->cost = o->cost != SS_FIT_COST_AUTO ? o->cost
	          : f->obs.kind == SS_OBSERVED_FRONT ? SS_FIT_COST_SUPPORT : SS_FIT_COST_HEIGHT;
	if (f->obs.kind == SS_OBSERVED_FRONT && f->cost != SS_FIT_COST_SUPPORT)
		return ss_error_input("'%s' holds a front, not heights: only --cost support "
		                      "compares it", f->obs.path);
	const size_t times = (size_t)f->obs.times;
	if (!(f->flow = ss_alloc(f->cells, 1, "flow cells")) ||
	    !(f->floor = ss_alloc(f->cells, sizeof *f->floor, "the floor")) ||
	    !(f->sim = ss_alloc(f->cells, sizeof *f->sim, "simulated heights")) ||
	    !(f->thickness = ss_alloc(f->cells, sizeof *f->thickness, "simulated heights")) ||
	    !(f->chi_sim = ss_alloc(f->cells, sizeof *f->chi_sim, "simulated support")))
		return SS_ERR_FAIL;
	if ((err = measure_initial(f)))
		return err;
	f->threshold = isnan(o->threshold) ? 0.02 * f->relief : o->threshold;
	if (f->cost != SS_FIT_COST_HEIGHT && !(f->threshold > 0.0))
		return ss_error_input("the support needs a threshold: the initial state and the "
		                      "observations hold no sand above the floor; give "
		                      "--threshold M");
	/* the observed support: the support cost's, and the plot's front */
	if (f->threshold > 0.0) {
		if (!(f->chi_obs = ss_alloc(times * f->cells, sizeof *f->chi_obs, "observed support")) ||
		    !(f->support_seen = ss_alloc(times * f->cells, 1, "observed support")) ||
		    !(f->area_obs = ss_alloc(times, sizeof *f->area_obs, "support areas")) ||
		    !(f->radius_obs = ss_alloc(times, sizeof *f->radius_obs, "support radii")))
			return SS_ERR_FAIL;
		if ((err = observe_support(f)))
			return err;
	}
	if (f->cost == SS_FIT_COST_HEIGHT || f->cost == SS_FIT_COST_BOTH) {
		for (size_t k = 0; k < times * f->cells; k++)
			f->height_count += f->flow[k % f->cells] && isfinite(f->obs.height[k]);
		if (f->height_count == 0)
			return ss_error_input("'%s' observes no flow cell of the case (%s)", f->obs.path,
			                      f->base.path);
		if (f->cost == SS_FIT_COST_BOTH && !(f->relief > 0.0))
			return ss_error_input("--cost both scales heights by the relief, and '%s' and "
			                      "the initial state hold no sand above the floor",
			                      f->obs.path);
	}
	f->residual_count = (f->cost != SS_FIT_COST_SUPPORT ? f->height_count : 0) +
	                    (f->cost != SS_FIT_COST_HEIGHT ? f->area_count + f->speed_count : 0);
	/* the least noise: 0.1 % of the relief in height, 0.1 % of the area */
	const double floor_h = 1e-3 * f->relief, floor_s = 1e-3;
	f->cost_floor = f->cost == SS_FIT_COST_HEIGHT ? floor_h * floor_h
	                : f->cost == SS_FIT_COST_SUPPORT ? floor_s * floor_s
	                : 1e-6 + o->support_weight * floor_s * floor_s;
	int most = 0;
	for (int c = 0; c < f->fit_count; c++)
		most = f->fits[c].p > most ? f->fits[c].p : most;
	if (!(f->residuals = ss_alloc((size_t)f->residual_count, sizeof *f->residuals,
	                              "residuals")) ||
	    !(f->model_delta = ss_alloc((size_t)f->residual_count, sizeof *f->model_delta,
	                                "the reference run's residuals")) ||
	    !(f->jacobian = ss_alloc((size_t)f->residual_count * (size_t)most,
	                             sizeof *f->jacobian, "the Jacobian")))
		return SS_ERR_FAIL;
	for (int k = 0; k < TRACE_TIMES; k++)
		f->trace_time[k] = f->obs.time[f->obs.times - 1] * k / (TRACE_TIMES - 1);
	for (int c = 0; c < f->fit_count; c++)
		if ((err = parse_closure_case(f, &f->fits[c])))
			return err;
	return SS_OK;
}

static void release(struct fit *f)
{
	for (int c = 0; c < f->fit_count; c++)
		ss_case_release(&f->fits[c].c);
	ss_case_release(&f->base);
	ss_observations_release(&f->obs);
	ss_free(f->flow);
	ss_free(f->floor);
	ss_free(f->sim);
	ss_free(f->thickness);
	ss_free(f->chi_sim);
	ss_free(f->chi_obs);
	ss_free(f->support_seen);
	ss_free(f->area_obs);
	ss_free(f->radius_obs);
	ss_free(f->residuals);
	ss_free(f->model_delta);
	ss_free(f->jacobian);
}

/* ---- the front over time, for the plot ------------------------------------ */

/* The front's equivalent radius at trace time k of the run being traced. */
static int add_radius(struct fit *f, long long k, void *context)
{
	struct closure_fit *cf = context;
	simulated_support(f, f->sim);
	cf->trace_radius[k] = sqrt(support_area(f) / M_PI);
	cf->traced = (int)k + 1;
	return 0;
}

/* The equivalent radius of the best run of cf at the trace times (as far
 * as the run goes). */
static int trace(struct fit *f, struct closure_fit *cf)
{
	int how;
	struct run_end e;
	f->stage = "front";
	return run_through(f, cf, cf->u, STEP_FIT, f->trace_time, TRACE_TIMES, add_radius, cf,
	                   &how, &e);
}

/* ---- the fit -------------------------------------------------------------- */

static int fit_all(struct fit *f)
{
	int err = SS_OK;
	for (int c = 0; c < f->fit_count && !err && !f->interrupted; c++) {
		struct closure_fit *cf = &f->fits[c];
		f->current = c;
		if ((err = search(f, cf)) || !cf->searched)
			break;
		if (!covariance(f, cf) && !profiles(f, cf))
			cf->assessed = 1;
		if (f->failed)
			err = f->failed;
		if (!err && !f->interrupted && f->o->plot)
			err = trace(f, cf);
	}
	/* AIC = M ln(cost) + 2 (p + 1): the Gaussian likelihood with the noise
	 * unknown, one more parameter than the closure's (F10) */
	for (int c = 0; c < f->fit_count; c++) {
		struct closure_fit *cf = &f->fits[c];
		cf->aic = (double)f->residual_count * log(fmax(cf->cost, f->cost_floor)) +
		          2.0 * (cf->p + 1);
	}
	return err;
}

int ss_fit_run(const struct ss_fit_options *o, char **report, char **summary)
{
	*report = NULL;
	if (summary)
		*summary = NULL;
	if (ss_comm_size() > 1)
		return ss_error_input("fit runs on one rank: start it without mpirun");
	if (ss_drive_check_device(&o->job.device, NULL, "fit"))
		return SS_ERR_INPUT;
	struct fit f;
	memset(&f, 0, sizeof f);
	f.o = o;
	f.started = ss_parallel_wall_seconds();
	ss_drive_set_threads(o->job.threads);
	int err = prepare(&f);
	if (!err)
		err = fit_all(&f);
	int best = -1;
	for (int c = 0; c < f.fit_count; c++)
		if (isfinite(f.fits[c].cost) && (best < 0 || f.fits[c].aic < f.fits[best].aic))
			best = c;
	f.seconds = ss_parallel_wall_seconds() - f.started;
	if (!err)
		err = ss_fit_report_text(&f, best, report, summary);
	if (!err && o->job.output)
		err = ss_output_write_text(o->job.output, *report);
	if (!err && o->plot && best >= 0)
		err = ss_fit_plot(&f, best, o->plot);
	if (err) {
		free(*report);
		*report = NULL;
		if (summary) {
			free(*summary);
			*summary = NULL;
		}
	}
	release(&f);
	return err;
}
