/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_options.c - the option tables (sandslide/option.h): one table per
 * command, and the model's options the same wherever they are given.
 *
 * Each table's defaults are values of their own options; names and case
 * keys are unique; every option says what it accepts; the model's options
 * have the same default, the same range and the same message as relax's
 * command-line options and as case-file keys; open and closed ends of a
 * range are honoured; each table describes itself as JSON.
 */
#include "check.h"

#include <math.h>
#include <string.h>

#include "sandslide/bench.h"
#include "sandslide/case.h"
#include "sandslide/error.h"
#include "sandslide/fit.h"
#include "sandslide/job.h"
#include "sandslide/model_options.h"
#include "sandslide/option.h"
#include "sandslide/relax.h"
#include "sandslide/render.h"
#include "sandslide/run.h"

static const struct ss_option_table *const tables[] = {
	&ss_relax_option_table, &ss_run_option_table, &ss_fit_option_table,
	&ss_render_option_table, &ss_render_look_option_table, &ss_bench_option_table,
	&ss_model_option_table, &ss_job_option_table, &ss_case_option_table,
};
enum { TABLES = sizeof tables / sizeof *tables };

/* The smallest case, with overrides. */
static int parse_case(struct ss_case *c, const char *const *sets, int count)
{
	static const char text[] = "[grid]\nnx = 4\nny = 3\ndx = 1\n[model]\nrepose_angle = 35\n"
	                           "nu = 1\n[time]\nend = 1\noutput_every = 1\n";
	return ss_case_parse(c, "test.ini", text, sets, count);
}

static void every_table_is_consistent(void)
{
	for (int t = 0; t < TABLES; t++) {
		const struct ss_option_table *table = tables[t];
		const struct ss_option *option[SS_OPTION_MAX];
		size_t at[SS_OPTION_MAX];
		const int n = ss_option_flatten(table, option, at);
		for (int k = 0; k < n; k++) {
			const struct ss_option *o = option[k];
			if (!o->name && !o->case_key)
				continue;   /* a heading */
			const char *id = o->name ? o->name : o->case_key;
			CHECK(o->expected || o->kind == SS_OPTION_FLAG ||
			      o->kind == SS_OPTION_OPTIONAL_INT,
			      "%s: '%s' says nothing of what it accepts", table->command, id);
			CHECK(o->kind != SS_OPTION_WORD || o->parse,
			      "%s: the word option '%s' has no parser", table->command, id);
			size_t offset;
			if (o->name)
				CHECK(ss_option_find(table, o->name, &offset) == o && offset == at[k],
				      "%s: two options are named '%s'", table->command, o->name);
			if (o->case_key)
				CHECK(ss_option_find_key(table, o->case_key, &offset) == o &&
				      offset == at[k], "%s: two options are the case key '%s'",
				      table->command, o->case_key);
		}
	}
}

/* Every default is a value of its option (ss_option_defaults would stop
 * the program otherwise), and every table describes itself as JSON. */
static void defaults_parse_and_tables_describe_themselves(void)
{
	static char json[1 << 16];
	for (int t = 0; t < TABLES; t++) {
		const struct ss_option_table *table = tables[t];
		CHECK(ss_option_table_json(table, json, sizeof json) == SS_OK, "%s: %s",
		      table->command, ss_error_last_message());
		CHECK(json[0] == '[' && strstr(json, "\"default\""), "%s: %.80s", table->command, json);
		const struct ss_option *option[SS_OPTION_MAX];
		size_t at[SS_OPTION_MAX];
		const int n = ss_option_flatten(table, option, at);
		for (int k = 0; k < n; k++) {
			const struct ss_option *o = option[k];
			if (o->name && !(o->flags & SS_OPTION_CLI_ONLY)) {
				char quoted[80];
				snprintf(quoted, sizeof quoted, "\"name\": \"%s\"", o->name);
				CHECK(strstr(json, quoted), "%s: '%s' missing from its JSON",
				      table->command, o->name);
			}
		}
		CHECK(ss_option_table_json(table, json, 16) == SS_ERR_INPUT &&
		      strstr(ss_error_last_message(), "bytes"), "%s: a short buffer: %s",
		      table->command, ss_error_last_message());
	}
	struct ss_relax_options r;
	ss_relax_options_init(&r);
	CHECK(r.model.angle_deg == 35.0 && r.model.closure == SS_CLOSURE_COULOMB &&
	      r.model.gamma == 1.0 && r.model.cfl == 0.9 && r.model.steady_tol == 1e-9 &&
	      r.model.integrator == SS_INTEGRATOR_AUTO && isnan(r.model.max_time) &&
	      r.sides == SS_SIDE_WALL && r.nodata_type == SS_CELL_WALL && isnan(r.open_level),
	      "relax's defaults are the table's");
	struct ss_bench_options b;
	ss_bench_options_init(&b);
	CHECK(b.nx == 8192 && b.ny == 8192 && b.repeats == 5 && b.thread_count == 2 &&
	      b.closure_count == 5, "bench's defaults: %d x %d, %d repeats, %d thread counts, "
	      "%d closures", b.nx, b.ny, b.repeats, b.thread_count, b.closure_count);
}

/* Relax's model options and a case's model keys: the same defaults (a case
 * that gives only what it must has relax's), the same values accepted and
 * the same words refused, with the same "expected ...". */
static void model_options_are_case_keys_with_the_same_rules(void)
{
	struct ss_case c;
	struct ss_relax_options r;
	ss_relax_options_init(&r);
	const int err = parse_case(&c, NULL, 0);
	CHECK(err == SS_OK, "the minimal case: %s", ss_error_last_message());
	if (!err) {
		const struct ss_model_options *a = &c.model, *b = &r.model;
		CHECK(a->closure == b->closure && a->gamma == b->gamma && a->cfl == b->cfl &&
		      a->steady_tol == b->steady_tol && a->steady_slope_tol == b->steady_slope_tol &&
		      isnan(a->max_time) && isnan(b->max_time) && a->integrator == b->integrator &&
		      a->rkl2_max_stages == b->rkl2_max_stages && a->rkl2_tol == b->rkl2_tol,
		      "a case's model defaults differ from relax's");
	}
	ss_case_release(&c);

	const struct ss_option_table *m = &ss_model_option_table;
	for (int k = 0; k < m->count; k++) {
		const struct ss_option *o = &m->options[k];
		if (!o->case_key || !o->name)
			continue;   /* a heading, or a case's key only (the sliding layer) */
		if (o->kind == SS_OPTION_TEXT)
			continue;   /* a file (materials): any name is one; test_materials.py */
		/* a value relax takes, as a case key (an override of the
		 * minimal case: it gives repose_angle and nu itself; max_time
		 * belongs to end = steady) */
		const char *good = o->default_value ? o->default_value : "7";
		char set[128];
		const char *sets[2] = {"time.end=steady", set};
		snprintf(set, sizeof set, "%s=%s", o->case_key, good);
		struct ss_relax_options *ro = ss_option_object_create(&ss_relax_option_table);
		CHECK(ss_option_object_set(ro, o->name, good) == SS_OK, "relax --%s %s: %s", o->name,
		      good, ss_error_last_message());
		CHECK(parse_case(&c, sets, 2) == SS_OK, "--set %s: %s", set, ss_error_last_message());
		ss_case_release(&c);

		/* a word neither takes, refused with the same words (a number
		 * or a file: a mistyped number) */
		const char *bad = (o->flags & SS_OPTION_OR_FILE) ? "1x" : "x1";
		CHECK(ss_option_object_set(ro, o->name, bad) == SS_ERR_INPUT, "relax --%s %s",
		      o->name, bad);
		char relax_message[512];
		snprintf(relax_message, sizeof relax_message, "%s", ss_error_last_message());
		snprintf(set, sizeof set, "%s=%s", o->case_key, bad);
		CHECK(parse_case(&c, sets, 2) == SS_ERR_INPUT, "--set %s", set);
		char want[256];
		snprintf(want, sizeof want, "expected %s", o->expected);
		CHECK(strstr(relax_message, want) && strstr(ss_error_last_message(), want),
		      "%s: relax says '%s', the case '%s'", o->case_key, relax_message,
		      ss_error_last_message());
		ss_case_release(&c);
		ss_option_object_destroy(ro);
	}
}

/* (0, 90) and (0, 1]: the ends as the ranges say. */
static void open_and_closed_ends(void)
{
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	CHECK(ss_option_object_set(o, "angle", "0") == SS_ERR_INPUT, "angle 0 refused");
	CHECK(ss_option_object_set(o, "angle", "90") == SS_ERR_INPUT, "angle 90 refused");
	CHECK(ss_option_object_set(o, "angle", "1e-6") == SS_OK, "angle 1e-6 taken");
	CHECK(ss_option_object_set(o, "cfl", "1") == SS_OK, "cfl 1 taken");
	CHECK(ss_option_object_set(o, "cfl", "0") == SS_ERR_INPUT, "cfl 0 refused");
	CHECK(ss_option_object_set(o, "nu", "inf") == SS_ERR_INPUT, "nu inf refused");
	CHECK(ss_option_object_set(o, "open-level", "-5") == SS_OK && o->open_level == -5.0,
	      "a negative open level taken");
	ss_option_object_destroy(o);
}

int main(void)
{
	ss_error_set_quiet(1);
	RUN(every_table_is_consistent);
	RUN(defaults_parse_and_tables_describe_themselves);
	RUN(model_options_are_case_keys_with_the_same_rules);
	RUN(open_and_closed_ends);
	return check_report();
}
