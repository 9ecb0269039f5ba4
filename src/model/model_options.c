/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * model_options.c - the options run and relax share (model_options.h):
 * one table, one default and one range each.
 */
#include "sandslide/model_options.h"

#include <math.h>
#include <stddef.h>

static int parse_closure(const char *value, void *field)
{
	return ss_closure_parse(value, field);
}

static int parse_integrator(const char *value, void *field)
{
	return ss_integrator_parse(value, field);
}

static int parse_rest(const char *value, void *field)
{
	return ss_rest_mode_parse(value, field);
}

#define AT(m) offsetof(struct ss_model_options, m)
/* the closures a key applies to (applies_to) */
#define FOR(k) (1u << SS_CLOSURE_##k)

static const struct ss_option options[] = {
	{.help = "The model and its time stepping (also the case file's [model] and\n"
	         "[time] keys: doc/model.md):\n"},
	/* the sliding layer nu derives from: a case's keys (doc/model.md) */
	{.case_key = "model.delta", .kind = SS_OPTION_REAL, .offset = AT(layer.delta),
	 .lo = 0.0, .hi = INFINITY, .flags = SS_OPTION_LO_OPEN | SS_OPTION_FITTABLE,
	 .applies_to = FOR(BINGHAM) | FOR(HERSCHEL_BULKLEY) | FOR(CASSON),
	 .expected = "a finite number > 0", .help = "sliding layer thickness, m"},
	{.case_key = "model.density", .kind = SS_OPTION_REAL, .offset = AT(layer.density),
	 SS_OPTION_POSITIVE, .applies_to = FOR(BINGHAM) | FOR(HERSCHEL_BULKLEY) | FOR(CASSON),
	 .expected = "a finite number > 0", .help = "kg/m^3"},
	{.case_key = "model.gravity", .kind = SS_OPTION_REAL, .offset = AT(layer.gravity),
	 .default_value = "9.81", SS_OPTION_POSITIVE,
	 .applies_to = FOR(BINGHAM) | FOR(HERSCHEL_BULKLEY) | FOR(CASSON),
	 .expected = "a finite number > 0", .help = "m/s^2"},
	{.case_key = "model.viscosity", .kind = SS_OPTION_REAL, .offset = AT(layer.viscosity),
	 .lo = 0.0, .hi = INFINITY, .flags = SS_OPTION_LO_OPEN | SS_OPTION_FITTABLE,
	 .applies_to = FOR(BINGHAM) | FOR(CASSON), .expected = "a finite number > 0",
	 .help = "mu, Pa s (bingham, casson)"},
	{.case_key = "model.consistency", .kind = SS_OPTION_REAL, .offset = AT(layer.consistency),
	 .lo = 0.0, .hi = INFINITY, .flags = SS_OPTION_LO_OPEN | SS_OPTION_FITTABLE,
	 .applies_to = FOR(HERSCHEL_BULKLEY), .expected = "a finite number > 0",
	 .help = "k, Pa s^gamma (herschel-bulkley)"},
	{.name = "closure", .case_key = "model.closure", .value_name = "NAME",
	 .kind = SS_OPTION_WORD, .offset = AT(closure), .default_value = "coulomb",
	 .parse = parse_closure, .expected = SS_CLOSURE_NAMES,
	 .help = "the sliding law f_sl: coulomb, bingham,\n"
	         "herschel-bulkley or casson"},
	{.name = "angle", .case_key = "model.repose_angle", .value_name = "DEG|FILE",
	 .kind = SS_OPTION_REAL, .offset = AT(angle_deg), .default_value = "35", .lo = 0.0,
	 .hi = 90.0, .flags = SS_OPTION_LO_OPEN | SS_OPTION_HI_OPEN | SS_OPTION_CASE_REQUIRED |
	                      SS_OPTION_FITTABLE | SS_OPTION_OR_FILE,
	 .value_offset = AT(angle_file),
	 .expected = "degrees in (0, 90), or a raster of them",
	 .help = "repose angle a_cr, or a raster of each cell's"},
	{.name = "materials", .case_key = "model.materials", .value_name = "FILE",
	 .kind = SS_OPTION_TEXT, .offset = AT(materials_file), .expected = "a file name",
	 .help = "a raster of material classes, each the law of\n"
	         "its [material NAME] (relax: of --material-table;\n"
	         "doc/model.md#materials)"},
	{.name = "static-angle", .case_key = "model.static_angle", .value_name = "DEG",
	 .kind = SS_OPTION_REAL, .offset = AT(static_angle_deg), .lo = 0.0, .hi = 90.0,
	 .flags = SS_OPTION_LO_OPEN | SS_OPTION_HI_OPEN | SS_OPTION_FITTABLE,
	 .expected = "degrees in (0, 90)",
	 .help = "hysteresis: the angle where sand at rest starts\n"
	         "to slide, at least the repose angle, where moving\n"
	         "sand stops (default: the repose angle, no\n"
	         "hysteresis; doc/model.md#hysteresis)"},
	{.name = "gamma", .case_key = "model.gamma", .value_name = "G", .kind = SS_OPTION_REAL,
	 .offset = AT(gamma), .default_value = "1", .lo = 0.0, .hi = INFINITY,
	 .flags = SS_OPTION_LO_OPEN | SS_OPTION_FITTABLE, .applies_to = FOR(HERSCHEL_BULKLEY),
	 .expected = "a number > 0", .help = "herschel-bulkley exponent (1: bingham's law)"},
	{.name = "nu", .case_key = "model.nu", .value_name = "V", .kind = SS_OPTION_REAL,
	 .offset = AT(nu), .default_value = "1", .lo = 0.0, .hi = INFINITY,
	 .flags = SS_OPTION_LO_OPEN | SS_OPTION_FITTABLE, .expected = "m^2/s > 0",
	 .help = "m^2/s: sets the time scale only (a case gives it,\n"
	         "or the sliding layer it derives from)"},
	{.name = "tol", .case_key = "time.steady_tol", .value_name = "X", .kind = SS_OPTION_REAL,
	 .offset = AT(steady_tol), .default_value = "1e-9", SS_OPTION_POSITIVE, .expected = "m/s > 0",
	 .help = "steady when max |dh/dt| < X m/s"},
	{.name = "slope-tol", .case_key = "time.steady_slope_tol", .value_name = "E",
	 .kind = SS_OPTION_REAL, .offset = AT(steady_slope_tol), .default_value = "1e-6",
	 SS_OPTION_POSITIVE, .expected = "a number > 0",
	 .help = "and no sand face steeper than tan(angle) + E\n"
	         "(other closures: the same flux)"},
	{.name = "integrator", .case_key = "time.integrator", .value_name = "NAME",
	 .kind = SS_OPTION_WORD, .offset = AT(integrator), .default_value = "auto",
	 .parse = parse_integrator, .expected = SS_INTEGRATOR_NAMES,
	 .help = "euler, rkl2 (super-steps) or auto: euler to\n"
	         "relax a DEM (then the approach to rest), euler\n"
	         "with a bedrock (rkl2 cannot keep sand above\n"
	         "it), else rkl2"},
	{.name = "rest", .case_key = "time.rest", .value_name = "NAME", .kind = SS_OPTION_WORD,
	 .offset = AT(rest), .default_value = "chebyshev", .parse = parse_rest,
	 .expected = SS_REST_NAMES,
	 .help = "the approach to rest of a run until steady:\n"
	         "chebyshev super-steps once the motion is slow\n"
	         "(not with a bedrock), or off: the integrator's\n"
	         "own steps to the end (doc/model.md)"},
	{.name = "rkl2-max-stages", .case_key = "time.rkl2_max_stages", .value_name = "S",
	 .kind = SS_OPTION_INT, .offset = AT(rkl2_max_stages),
	 .default_value = "2048", .lo = 2, .hi = 100000,
	 .expected = "an integer from 2 to 100000", .help = "rkl2: at most S stages a super-step"},
	{.name = "rkl2-tol", .case_key = "time.rkl2_tol", .value_name = "E", .kind = SS_OPTION_REAL,
	 .offset = AT(rkl2_tol), .default_value = "0.1", SS_OPTION_POSITIVE,
	 .expected = "a number > 0",
	 .help = "rkl2: error estimate of a super-step at most\n"
	         "E tan(angle) min(dx, dy)"},
	{.name = "rkl2-pouring-tol", .case_key = "time.rkl2_pouring_tol", .value_name = "E",
	 .kind = SS_OPTION_REAL, .offset = AT(rkl2_pouring_tol), .default_value = "1",
	 SS_OPTION_POSITIVE, .expected = "a number > 0",
	 .help = "rkl2: the same while a source of the case\n"
	         "pours (doc/model.md#accuracy-rule)"},
	{.name = "max-time", .case_key = "time.max_time", .value_name = "T", .kind = SS_OPTION_REAL,
	 .offset = AT(max_time), SS_OPTION_POSITIVE, .expected = "s > 0",
	 .help = "stop at T s even if not steady (default: no limit;\n"
	         "a case: with end = steady)"},
	{.name = "cfl", .case_key = "time.cfl", .value_name = "C", .kind = SS_OPTION_REAL,
	 .offset = AT(cfl), .default_value = "0.9", .lo = 0.0, .hi = 1.0,
	 .flags = SS_OPTION_LO_OPEN, .expected = "a number in (0, 1]",
	 .help = "fraction of the stable forward-Euler step"},
};

const struct ss_option_table ss_model_option_table = {
	.command = "model", .options = options, .count = sizeof options / sizeof *options,
};

void ss_model_options_init(struct ss_model_options *m)
{
	ss_option_defaults(&ss_model_option_table, m);
}

double ss_model_time_limit(const struct ss_model_options *m)
{
	return isnan(m->max_time) ? INFINITY : m->max_time;
}

int ss_model_option_is_layer(const struct ss_option *o)
{
	return o->offset >= AT(layer) && o->offset < AT(layer) + sizeof(struct ss_sliding_layer);
}

int ss_model_closure(const struct ss_model_options *m, struct ss_closure *c)
{
	return ss_closure_init(c, m->closure, m->angle_deg, m->gamma, m->nu);
}

double ss_model_nu_from_layer(const struct ss_model_options *m)
{
	const struct ss_sliding_layer *l = &m->layer;
	/* tau = rho g delta sin a_cr; doc/model.md, [Paper] eqs. 8 and 12 */
	const double tau = l->density * l->gravity * l->delta * sin(m->angle_deg * M_PI / 180.0);
	const double d2 = l->delta * l->delta;
	switch (m->closure) {
	case SS_CLOSURE_BINGHAM:
		return tau * d2 / (6.0 * l->viscosity);
	case SS_CLOSURE_CASSON:
		return tau * d2 / (30.0 * l->viscosity);
	case SS_CLOSURE_HERSCHEL_BULKLEY: {
		const double g = m->gamma;
		return pow(tau / l->consistency, 1.0 / g) * g / ((1.0 + g) * (1.0 + 2.0 * g)) * d2;
	}
	case SS_CLOSURE_COULOMB:
		break;
	}
	return NAN;   /* the coulomb closure takes nu directly */
}
