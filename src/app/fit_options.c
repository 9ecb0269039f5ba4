/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fit_options.c - fit's options (fit.h): the one table the command line,
 * the options set by name and the Python module read, continued by the
 * job's (job.h); --param's words; the report in a buffer for foreign
 * callers.
 */
#include "sandslide/fit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/model_options.h"
#include "sandslide/error.h"
#include "sandslide/material_table.h"

static int parse_cost(const char *value, void *field)
{
	static const char *const names[] = {"auto", "height", "support", "both"};
	for (int k = 0; k < 4; k++)
		if (!strcmp(value, names[k])) {
			*(enum ss_fit_cost *)field = (enum ss_fit_cost)k;
			return 0;
		}
	return -1;
}

/* --param's words: NAME=... as they are collected; ss_fit_param_parse
 * checks the rest when the command reads them, saying what is wrong. */
static int parse_param(const char *value, void *field)
{
	(void)field;
	const char *eq = strchr(value, '=');
	return eq && eq != value ? 0 : -1;
}

#define AT(m) offsetof(struct ss_fit_options, m)

static const struct ss_option options[] = {
	{.name = "case", .kind = SS_OPTION_TEXT, .offset = AT(case_path),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a path",
	 .help = "the case file (the command line's first argument)"},
	{.name = "observations", .kind = SS_OPTION_TEXT, .offset = AT(observations),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a path",
	 .help = "the observations (the command line's second argument)"},
	{.name = "param", .alias = "-p", .value_name = "NAME=LO:HI[:log]", .kind = SS_OPTION_LIST,
	 .offset = AT(params), .parse = parse_param,
	 .expected = "NAME=LO:HI or NAME=LO:HI:log, NAME a [model] key of the case, "
	             "e.g. nu=0.01:1:log",
	 .help = "free a [model] key of the case within LO..HI, searched\n"
	         "on a log scale with :log; give one --param per key\n"
	         "(the keys: doc/fit.md#parameters)"},
	{.name = "closures", .value_name = "LIST", .kind = SS_OPTION_TEXT, .offset = AT(closures),
	 .expected = "all, or a comma-separated list of coulomb, bingham, herschel-bulkley, casson",
	 .help = "fit each of these closures and compare them (default:\n"
	         "the case's closure)"},
	{.name = "cost", .value_name = "NAME", .kind = SS_OPTION_WORD, .offset = AT(cost),
	 .default_value = "auto", .parse = parse_cost,
	 .expected = "auto, height, support or both",
	 .help = "the cost functional (doc/fit.md#cost-functionals): height\n"
	         "misfit, support (the area between the supports and the\n"
	         "front's speed) or both; auto: height for heights,\n"
	         "support for a front"},
	{.name = "threshold", .value_name = "M", .kind = SS_OPTION_REAL, .offset = AT(threshold),
	 SS_OPTION_POSITIVE, .expected = "a length in m, > 0",
	 .help = "sand thicker than this is in the support, m (default:\n"
	         "2 % of the thickest sand; at least 3x the noise)"},
	{.name = "support-weight", .value_name = "W", .kind = SS_OPTION_REAL,
	 .offset = AT(support_weight), .default_value = "1", .lo = 0.0, .hi = INFINITY,
	 .expected = "a number >= 0",
	 .help = "the support cost's weight in --cost both"},
	{.name = "grid-points", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(grid_points),
	 .default_value = "0", .lo = 0, .hi = 50, .expected = "an integer from 0 to 50",
	 .help = "points per parameter of the coarse grid before the\n"
	         "search (0: 7, 4, 3 or 2 for 1 to 4 parameters)"},
	{.name = "max-runs", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(max_runs),
	 .default_value = "60", .lo = 1, .hi = 100000, .expected = "an integer from 1 to 100000",
	 .help = "forward runs of each BOBYQA search at most"},
	{.name = "profile-points", .value_name = "N", .kind = SS_OPTION_INT,
	 .offset = AT(profile_points), .default_value = "9", .lo = 2, .hi = 33,
	 .expected = "an integer from 2 to 33",
	 .help = "points of the cost along each parameter"},
	{.name = "rkl2-tol", .value_name = "T", .kind = SS_OPTION_REAL, .offset = AT(rkl2_tol),
	 .default_value = "0.01", SS_OPTION_POSITIVE, .expected = "a number > 0",
	 .help = "the forward runs' RKL2 tolerance when the case's is\n"
	         "larger (doc/fit.md#the-search: the cost must be\n"
	         "smooth in the parameters)"},
	{.name = "output", .alias = "-o", .value_name = "FIT.json", .kind = SS_OPTION_TEXT,
	 .offset = AT(job.output), .expected = "a path",
	 .help = "write the report there (JSON, doc/fit.md#the-report)"},
	{.name = "plot", .value_name = "FIT.png", .kind = SS_OPTION_TEXT, .offset = AT(plot),
	 .expected = "a path",
	 .help = "draw the observed and fitted fronts and the cost\n"
	         "along each parameter"},
};

static const struct ss_option_part parts[] = {
	{&ss_job_option_table, AT(job)}, {&ss_job_stepping_option_table, AT(job)},
};

const struct ss_option_table ss_fit_option_table = {
	.command = "fit", .options = options, .count = sizeof options / sizeof *options,
	.parts = parts, .part_count = 2, .size = sizeof(struct ss_fit_options),
};

void ss_fit_options_init(struct ss_fit_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_fit_option_table, o);
}

/* The names --param takes: the case keys of the model's rows flagged
 * SS_OPTION_FITTABLE, without "model.", into buf ("nu, repose_angle, ..."). */
static void fittable_names(char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	int n = 0;
	buf[0] = '\0';
	for (int k = 0; k < ss_model_option_table.count; k++) {
		const struct ss_option *o = &ss_model_option_table.options[k];
		if (o->flags & SS_OPTION_FITTABLE)
			ss_strbuf_printf(&b, "%s%s", n++ ? ", " : "", strchr(o->case_key, '.') + 1);
	}
}

/* Whether name (len bytes) is "material NAME.repose_angle",
 * "material NAME.static_angle" or "material NAME.nu": a class's angle,
 * static angle or nu (doc/fit.md#parameters). */
static int fittable_material(const char *name, size_t len)
{
	char section[96];
	const char *dot = memchr(name, '.', len);
	if (!dot || (size_t)(dot - name) >= sizeof section)
		return 0;
	snprintf(section, sizeof section, "%.*s", (int)(dot - name), name);
	const size_t key = len - (size_t)(dot + 1 - name);
	static const char *const keys[] = {"repose_angle", "static_angle", "nu"};
	int known = 0;
	for (size_t k = 0; k < sizeof keys / sizeof *keys; k++)
		known |= key == strlen(keys[k]) && !strncmp(dot + 1, keys[k], key);
	return ss_material_section(section) && known;
}

/* Whether name (len bytes) is a key --param takes. */
static int fittable(const char *name, size_t len)
{
	if (fittable_material(name, len))
		return 1;
	for (int k = 0; k < ss_model_option_table.count; k++) {
		const struct ss_option *o = &ss_model_option_table.options[k];
		const char *key = o->case_key ? strchr(o->case_key, '.') + 1 : NULL;
		if ((o->flags & SS_OPTION_FITTABLE) && strlen(key) == len && !strncmp(name, key, len))
			return 1;
	}
	return 0;
}

int ss_fit_param_parse(const char *text, struct ss_fit_param *p)
{
	char names[256], expected[512];
	fittable_names(names, sizeof names);
	snprintf(expected, sizeof expected, "NAME=LO:HI or NAME=LO:HI:log with NAME one of %s, or "
	         "'material NAME.KEY' with KEY repose_angle, static_angle or nu, and LO < HI, e.g. "
	         "nu=0.01:1:log", names);
	memset(p, 0, sizeof *p);
	const char *eq = strchr(text, '=');
	const size_t len = eq ? (size_t)(eq - text) : 0;
	if (!eq || len >= sizeof p->name || !fittable(text, len))
		return ss_error_input("--param '%s': %s", text, expected);
	memcpy(p->name, text, len);
	char lo[64], hi[64], scale[16] = "";
	const char *rest = eq + 1, *c1 = strchr(rest, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
	if (!c1 || (size_t)(c1 - rest) >= sizeof lo ||
	    (size_t)((c2 ? c2 : c1 + 1 + strlen(c1 + 1)) - (c1 + 1)) >= sizeof hi ||
	    (c2 && strlen(c2 + 1) >= sizeof scale))
		return ss_error_input("--param '%s': %s", text, expected);
	snprintf(lo, sizeof lo, "%.*s", (int)(c1 - rest), rest);
	snprintf(hi, sizeof hi, "%.*s", (int)((c2 ? c2 : c1 + 1 + strlen(c1 + 1)) - (c1 + 1)),
	         c1 + 1);
	if (c2)
		snprintf(scale, sizeof scale, "%s", c2 + 1);
	if (ss_parse_real(lo, -INFINITY, INFINITY, &p->lo) ||
	    ss_parse_real(hi, -INFINITY, INFINITY, &p->hi) || (c2 && strcmp(scale, "log")) ||
	    !(p->lo < p->hi))
		return ss_error_input("--param '%s': %s", text, expected);
	p->log = c2 != NULL;
	if (p->log && !(p->lo > 0.0))
		return ss_error_input("--param '%s': a log scale needs LO > 0", text);
	return SS_OK;
}

int ss_fit_run_json(const struct ss_fit_options *o, char *buf, size_t size)
{
	char *report = NULL;
	const int err = ss_fit_run(o, &report, NULL);
	if (err)
		return err;
	const size_t n = strlen(report) + 1;
	if (n > size) {
		free(report);
		return ss_error_input("the fit's report needs %zu bytes, more than the %zu given",
		                      n, size);
	}
	memcpy(buf, report, n);
	free(report);
	return SS_OK;
}
