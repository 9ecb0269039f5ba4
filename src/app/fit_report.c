/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit_report.c - what `sandslide fit` reports (fit_internal.h): the JSON
 * report (doc/fit.md#the-report), the summary for people, and the figure
 * FIT.png.
 */
#include "app/fit_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "render/plot.h"
#include "sandslide/closure.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

/* The reference's time stepping in words, for the report:
 * "rkl2_tol 0.1 (the case's)", "rkl2_tol 0.001", "euler, cfl 0.45". */
static void reference_text(const struct fit *f, char *buf, size_t size)
{
	if (f->integrator == SS_INTEGRATOR_RKL2)
		snprintf(buf, size, "rkl2_tol %s%s", SS_REAL(fit_reference_rkl2_tol(f)),
		         f->base.model.rkl2_tol > f->o->rkl2_tol ? " (the case's)" : "");
	else
		snprintf(buf, size, "%s, cfl %s", ss_integrator_name(f->integrator),
		         SS_REAL(0.5 * f->base.model.cfl));
}

/* ---- the figure ----------------------------------------------------------- */

/*
 * FIT.png: the front's equivalent radius over time, observed (markers) and
 * of each closure's best run (lines); then for each parameter the cost
 * along it (F8), one line per closure that takes it, and a vertical line
 * at the best closure's value.
 */
int ss_fit_plot(const struct fit *f, int best, const char *path)
{
	const int panels = 1 + f->param_count;
	const int columns = panels < 3 ? panels : 3, rows = (panels + columns - 1) / columns;
	struct ss_plot *fig = NULL;
	int err = ss_plot_create(&fig, columns, rows, 480, 360);
	if (!err)
		err = ss_plot_panel(fig, 0, "front: equivalent radius", "time (s)", "radius (m)", 0);
	if (!err && f->radius_obs)
		err = ss_plot_add(fig, 0, f->obs.time, f->radius_obs, f->obs.times, SS_PLOT_MARKERS,
		                  0, "observed");
	for (int c = 0; c < f->fit_count && !err; c++) {
		const struct closure_fit *cf = &f->fits[c];
		if (cf->traced)
			err = ss_plot_add(fig, 0, f->trace_time, cf->trace_radius, cf->traced,
			                  SS_PLOT_LINE, c + 1, ss_closure_name(cf->kind));
	}
	for (int k = 0; k < f->param_count && !err; k++) {
		const struct ss_fit_param *p = &f->params[k];
		char title[96];
		snprintf(title, sizeof title, "cost along %s", p->name);
		err = ss_plot_panel(fig, 1 + k, title, p->name, "cost", p->log);
		for (int c = 0; c < f->fit_count && !err; c++) {
			const struct closure_fit *cf = &f->fits[c];
			for (int m = 0; m < cf->p && !err; m++) {
				if (cf->param[m] != k || !cf->assessed)
					continue;
				double x[PROFILE_MAX];
				for (int i = 0; i < cf->profile_n; i++)
					x[i] = fit_value_of(p, cf->profile_u[m][i]);
				err = ss_plot_add(fig, 1 + k, x, cf->profile_cost[m], cf->profile_n,
				                  SS_PLOT_LINE_MARKERS, c + 1, ss_closure_name(cf->kind));
				if (!err && c == best)
					err = ss_plot_vline(fig, 1 + k, fit_value_of(p, cf->u[m]), c + 1);
			}
		}
	}
	if (!err)
		err = ss_plot_write_png(fig, path);
	ss_plot_destroy(fig);
	return err;
}

/* ---- the report ----------------------------------------------------------- */

static const char *cost_name(enum ss_fit_cost c)
{
	return c == SS_FIT_COST_HEIGHT ? "height" : c == SS_FIT_COST_SUPPORT ? "support" : "both";
}

static void json_value(struct ss_strbuf *b, const struct ss_fit_param *p, double u)
{
	ss_strbuf_json_number(b, fit_value_of(p, u), 10);
}

static void json_closure(struct ss_strbuf *b, const struct fit *f, const struct closure_fit *cf,
                         double best_aic)
{
	const struct ss_fit_param *params = f->params;
	ss_strbuf_printf(b, "    {\"closure\": \"%s\", \"params\": {", ss_closure_name(cf->kind));
	for (int k = 0; k < cf->p; k++) {
		ss_strbuf_printf(b, "%s\"%s\": ", k ? ", " : "", params[cf->param[k]].name);
		json_value(b, &params[cf->param[k]], cf->u[k]);
	}
	ss_strbuf_printf(b, "},\n     \"cost\": ");
	ss_strbuf_json_number(b, cf->cost, 10);
	ss_strbuf_printf(b, ", \"aic\": ");
	ss_strbuf_json_number(b, cf->aic, 10);
	ss_strbuf_printf(b, ", \"delta_aic\": ");
	ss_strbuf_json_number(b, cf->aic - best_aic, 6);
	ss_strbuf_printf(b, ", \"evaluations\": %lld, \"cut_short\": %lld, \"searched\": %s",
	                 cf->runs, cf->cut_short, cf->searched ? "true" : "false");
	ss_strbuf_printf(b, ",\n     \"uncertainty\": {");
	for (int k = 0; cf->assessed && k < cf->p; k++) {
		const struct ss_fit_param *p = &params[cf->param[k]];
		const double lo_u = fmax(cf->u[k] - 1.96 * cf->std_u[k], 0.0),
		             hi_u = fmin(cf->u[k] + 1.96 * cf->std_u[k], 1.0);
		const double v = fit_value_of(p, cf->u[k]);
		/* dvalue/du: (hi - lo), or value ln(hi / lo) on a log scale */
		const double slope = p->log ? v * log(p->hi / p->lo) : p->hi - p->lo;
		ss_strbuf_printf(b, "%s\"%s\": {\"std\": ", k ? ", " : "", p->name);
		ss_strbuf_json_number(b, isfinite(cf->std_u[k]) ? cf->std_u[k] * slope : NAN, 6);
		ss_strbuf_printf(b, ", \"low\": ");
		ss_strbuf_json_number(b, isfinite(cf->std_u[k]) ? fit_value_of(p, lo_u) : p->lo, 10);
		ss_strbuf_printf(b, ", \"high\": ");
		ss_strbuf_json_number(b, isfinite(cf->std_u[k]) ? fit_value_of(p, hi_u) : p->hi, 10);
		ss_strbuf_printf(b, ", \"method\": \"gauss-newton, 95 %%\", \"std_noise\": ");
		ss_strbuf_json_number(b, isfinite(cf->std_noise_u[k]) ? cf->std_noise_u[k] * slope
		                                                      : NAN, 6);
		ss_strbuf_printf(b, ", \"std_model\": ");
		ss_strbuf_json_number(b, isfinite(cf->shift_u[k]) ? fabs(cf->shift_u[k]) * slope
		                                                  : NAN, 6);
		ss_strbuf_printf(b, "}");
	}
	ss_strbuf_printf(b, "},\n     \"model_error\": ");
	if (cf->assessed) {
		char reference[96];
		reference_text(f, reference, sizeof reference);
		ss_strbuf_printf(b, "{\"cost\": ");
		ss_strbuf_json_number(b, cf->model_cost, 6);
		ss_strbuf_printf(b, ", \"noise_cost\": ");
		ss_strbuf_json_number(b, cf->noise, 6);
		ss_strbuf_printf(b, ", \"reference\": ");
		ss_strbuf_json_string(b, reference);
		ss_strbuf_printf(b, "}");
	} else {
		ss_strbuf_printf(b, "null");
	}
	ss_strbuf_printf(b, ",\n     \"at_bound\": {");
	for (int k = 0, first = 1; k < cf->p; k++)
		if (fit_bound_side(cf->u[k])) {
			ss_strbuf_printf(b, "%s\"%s\": \"%s\"", first ? "" : ", ",
			                 params[cf->param[k]].name, fit_bound_side(cf->u[k]) < 0 ? "lo" : "hi");
			first = 0;
		}
	ss_strbuf_printf(b, "},\n     \"identifiable\": {");
	for (int k = 0; cf->assessed && k < cf->p; k++)
		ss_strbuf_printf(b, "%s\"%s\": %s", k ? ", " : "", params[cf->param[k]].name,
		                 cf->identifiable[k] ? "true" : "false");
	ss_strbuf_printf(b, "}, \"why\": {");
	for (int k = 0, first = 1; cf->assessed && k < cf->p; k++)
		if (!cf->identifiable[k]) {
			ss_strbuf_printf(b, "%s\"%s\": ", first ? "" : ", ", params[cf->param[k]].name);
			ss_strbuf_json_string(b, cf->why[k]);
			first = 0;
		}
	ss_strbuf_printf(b, "},\n     \"profile\": {");
	for (int k = 0; cf->assessed && k < cf->p; k++) {
		const struct ss_fit_param *p = &params[cf->param[k]];
		ss_strbuf_printf(b, "%s\"%s\": {\"values\": [", k ? ", " : "", p->name);
		for (int i = 0; i < cf->profile_n; i++) {
			ss_strbuf_printf(b, i ? ", " : "");
			json_value(b, p, cf->profile_u[k][i]);
		}
		ss_strbuf_printf(b, "], \"costs\": [");
		for (int i = 0; i < cf->profile_n; i++) {
			ss_strbuf_printf(b, i ? ", " : "");
			ss_strbuf_json_number(b, cf->profile_cost[k][i], 8);
		}
		ss_strbuf_printf(b, "]}");
	}
	ss_strbuf_printf(b, "}}");
}

/* The closures within 2 of the least AIC cannot be told apart (F10). */
static void format_report(struct ss_strbuf *b, const struct fit *f, int best)
{
	const struct ss_fit_options *o = f->o;
	const struct closure_fit *top = best >= 0 ? &f->fits[best] : NULL;
	ss_strbuf_printf(b, "{\n  \"case\": ");
	ss_strbuf_json_string(b, f->base.path);
	ss_strbuf_printf(b, ",\n  \"observations\": {\"path\": ");
	ss_strbuf_json_string(b, f->obs.path);
	ss_strbuf_printf(b, ", \"kind\": \"%s\", \"times\": %lld, \"first_time\": ",
	                 f->obs.kind == SS_OBSERVED_FRONT ? "front" : "heights", f->obs.times);
	ss_strbuf_json_number(b, f->obs.time[0], 17);
	ss_strbuf_printf(b, ", \"last_time\": ");
	ss_strbuf_json_number(b, f->obs.time[f->obs.times - 1], 17);
	if (f->obs.kind == SS_OBSERVED_FRONT)
		ss_strbuf_printf(b, ", \"points\": %lld}", f->obs.points);
	else
		ss_strbuf_printf(b, ", \"observed_values\": %lld}", f->obs.observed);
	ss_strbuf_printf(b, ",\n  \"cost_functional\": {\"name\": \"%s\", \"residuals\": %lld, "
	                 "\"threshold_m\": ", cost_name(f->cost), f->residual_count);
	ss_strbuf_json_number(b, f->threshold, 10);
	ss_strbuf_printf(b, ", \"relief_m\": ");
	ss_strbuf_json_number(b, f->relief, 10);
	ss_strbuf_printf(b, ", \"support_weight\": ");
	ss_strbuf_json_number(b, f->cost == SS_FIT_COST_BOTH ? o->support_weight : NAN, 10);
	ss_strbuf_printf(b, ", \"noise_floor\": ");
	ss_strbuf_json_number(b, f->cost_floor, 6);
	ss_strbuf_printf(b, ", \"doc\": \"doc/fit.md#cost-functionals\"}");
	ss_strbuf_printf(b, ",\n  \"best\": ");
	if (top) {
		ss_strbuf_printf(b, "{\"closure\": \"%s\", \"params\": {", ss_closure_name(top->kind));
		for (int k = 0; k < top->p; k++) {
			ss_strbuf_printf(b, "%s\"%s\": ", k ? ", " : "", f->params[top->param[k]].name);
			json_value(b, &f->params[top->param[k]], top->u[k]);
		}
		ss_strbuf_printf(b, "}, \"cost\": ");
		ss_strbuf_json_number(b, top->cost, 10);
		ss_strbuf_printf(b, "}");
	} else {
		ss_strbuf_printf(b, "null");
	}
	ss_strbuf_printf(b, ",\n  \"closures\": [\n");
	int listed = 0;
	for (int c = 0; c < f->fit_count; c++) {
		if (!isfinite(f->fits[c].cost))
			continue;
		ss_strbuf_printf(b, listed ? ",\n" : "");
		json_closure(b, f, &f->fits[c], top ? top->aic : NAN);
		listed++;
	}
	ss_strbuf_printf(b, "\n  ],\n  \"indistinguishable\": [");
	int ties = 0;
	for (int c = 0; top && c < f->fit_count; c++)
		if (isfinite(f->fits[c].cost) && f->fits[c].aic - top->aic < 2.0)
			ss_strbuf_printf(b, "%s\"%s\"", ties++ ? ", " : "", ss_closure_name(f->fits[c].kind));
	ss_strbuf_printf(b, "],\n  \"verdict\": ");
	char verdict[2048];   /* 4 closures x 4 parameters of notes at most */
	struct ss_strbuf v = {verdict, sizeof verdict, 0};
	if (!top)
		ss_strbuf_printf(&v, "no forward run finished");
	else if (ties > 1)
		ss_strbuf_printf(&v, "these data cannot tell the closures apart: %d are within 2 of "
		                 "the least AIC (%s best)", ties, ss_closure_name(top->kind));
	else
		ss_strbuf_printf(&v, "%s fits best%s", ss_closure_name(top->kind),
		                 f->fit_count > 1 ? ", by more than 2 in AIC" : "");
	for (int c = 0; c < f->fit_count; c++) {
		const struct closure_fit *cf = &f->fits[c];
		for (int k = 0; cf->assessed && k < cf->p; k++) {
			const struct ss_fit_param *p = &f->params[cf->param[k]];
			if (!cf->identifiable[k])
				ss_strbuf_printf(&v, "; %s: %s not identifiable", ss_closure_name(cf->kind),
				                 p->name);
			if (!cf->identifiable[k] && fit_bound_side(cf->u[k]))
				ss_strbuf_printf(&v, ", on the %s bound of its range: widen it",
				                 fit_bound_name(fit_bound_side(cf->u[k])));
			/* Herschel-Bulkley with gamma = 1 is Bingham exactly (closure.h) */
			if (cf->kind == SS_CLOSURE_HERSCHEL_BULKLEY && !strcmp(p->name, "gamma") &&
			    fabs(fit_value_of(p, cf->u[k]) - 1.0) <
			    1.96 * cf->std_u[k] * (p->log ? log(p->hi / p->lo) : p->hi - p->lo))
				ss_strbuf_printf(&v, "; herschel-bulkley's gamma is 1 within its "
				                 "uncertainty: it is bingham");
		}
	}
	ss_strbuf_json_string(b, verdict);
	ss_strbuf_printf(b, ",\n  \"integrator\": \"%s\", \"rkl2_tol\": ",
	                 ss_integrator_name(f->integrator));
	ss_strbuf_json_number(b, f->integrator == SS_INTEGRATOR_RKL2
	                         ? fit_rkl2_tol(f) : NAN, 10);
	ss_strbuf_printf(b, ", \"forward_runs\": %lld, \"seconds\": ", f->runs);
	ss_strbuf_json_number(b, f->seconds, 4);
	ss_strbuf_printf(b, ", \"seconds_per_run\": ");
	ss_strbuf_json_number(b, f->runs ? f->run_seconds / (double)f->runs : NAN, 4);
	ss_strbuf_printf(b, ", \"threads\": %d, \"interrupted\": %s\n}\n", ss_parallel_max_threads(),
	                 f->interrupted ? "true" : "false");
}

/* What the command line prints: a line per closure, the verdict. */
static void format_summary(struct ss_strbuf *b, const struct fit *f, int best)
{
	for (int c = 0; c < f->fit_count; c++) {
		const struct closure_fit *cf = &f->fits[c];
		if (!isfinite(cf->cost))
			continue;
		ss_strbuf_printf(b, "%-16s", ss_closure_name(cf->kind));
		for (int k = 0; k < cf->p; k++) {
			const struct ss_fit_param *p = &f->params[cf->param[k]];
			ss_strbuf_printf(b, " %s = %.4g", p->name, fit_value_of(p, cf->u[k]));
			if (cf->assessed && isfinite(cf->std_u[k]))
				ss_strbuf_printf(b, " (%.4g .. %.4g)",
				                 fit_value_of(p, fmax(cf->u[k] - 1.96 * cf->std_u[k], 0.0)),
				                 fit_value_of(p, fmin(cf->u[k] + 1.96 * cf->std_u[k], 1.0)));
			if (cf->assessed && fit_bound_side(cf->u[k]))
				ss_strbuf_printf(b, " on the %s bound: widen the range,",
				                 fit_bound_name(fit_bound_side(cf->u[k])));
			if (cf->assessed && !cf->identifiable[k])
				ss_strbuf_printf(b, " not identifiable");
		}
		ss_strbuf_printf(b, ", cost %.4g, AIC %+.1f%s, %lld runs\n", cf->cost,
		                 cf->aic - f->fits[best].aic, c == best ? " (best)" : "", cf->runs);
	}
	ss_strbuf_printf(b, "%lld forward runs, %.3g s each, %.1f s in all%s\n", f->runs,
	                 f->runs ? f->run_seconds / (double)f->runs : 0.0,
	                 f->seconds,
	                 f->interrupted ? "; interrupted: the best so far" : "");
}

/* A formatter's text, measured first, then written. */
static int text_of(void (*format)(struct ss_strbuf *, const struct fit *, int),
                   const struct fit *f, int best, char **out)
{
	struct ss_strbuf b = {NULL, 0, 0};
	format(&b, f, best);
	char *text = malloc(b.len + 1);
	if (!text)
		return ss_error_fail("out of memory");
	const size_t len = b.len;
	b = (struct ss_strbuf){text, len + 1, 0};
	format(&b, f, best);
	if (b.len != len)   /* a formatter must print the same text twice */
		SS_BUG("the fit's text was %zu bytes, then %zu", len, b.len);
	*out = text;
	return SS_OK;
}

int ss_fit_report_text(const struct fit *f, int best, char **report, char **summary)
{
	int err = text_of(format_report, f, best, report);
	if (!err && summary && best >= 0)
		err = text_of(format_summary, f, best, summary);
	return err;
}
