/*
 * run_options.c - run's options (run.h): the one table the command line,
 * the options set by name and the Python module read, and the options
 * object for foreign callers.  The case's own keys are the case file's
 * table (case.h), reached through --set and --unset.
 */
#include "sandslide/run.h"

#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"

static int parse_tile(const char *value, void *field)
{
	return ss_parse_tile(value, field);
}

/* The overrides' words, checked as they are collected (case.h applies them). */
static int parse_set(const char *value, void *field)
{
	(void)field;
	const char *eq = strchr(value, '=');
	return eq && eq != value ? 0 : -1;
}

static int parse_unset(const char *value, void *field)
{
	(void)field;
	return *value && !strchr(value, '=') ? 0 : -1;
}

#define AT(m) offsetof(struct ss_run_options, m)

static const struct ss_option options[] = {
	{.name = "case", .kind = SS_OPTION_TEXT, .offset = AT(case_path),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a path",
	 .help = "the case file (the command line's argument)"},
	{.name = "output", .alias = "-o", .value_name = "OUT.h5", .kind = SS_OPTION_TEXT,
	 .offset = AT(output), .expected = "a path",
	 .help = "output file (default out/<case name>.h5; its folder\n"
	         "must exist unless it is the default out/)"},
	{.name = "force", .kind = SS_OPTION_FLAG, .offset = AT(force), .expected = "1 or 0",
	 .help = "replace OUT.h5 if it exists (else refused)"},
	{.name = "restart", .value_name = "OUT.h5", .kind = SS_OPTION_TEXT, .offset = AT(restart),
	 .expected = "a path",
	 .help = "continue the run in OUT.h5 from its last snapshot,\n"
	         "appending to it, with the case stored in it (a\n"
	         "CASE.ini given too must be that case, and its\n"
	         "files are found beside it); the snapshots are\n"
	         "those of a run never interrupted"},
	{.name = "threads", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(threads),
	 .lo = 1, .hi = 4096, .expected = "an integer from 1 to 4096",
	 .help = "OpenMP threads (default: OMP_NUM_THREADS, else\n"
	         "the processors this process may run on)"},
	{.name = "set", .alias = "-P", .value_name = "SECTION.KEY=VALUE", .kind = SS_OPTION_LIST,
	 .parse = parse_set, .expected = "SECTION.KEY=VALUE, e.g. model.closure=casson",
	 .help = "override key KEY of section SECTION of the case, e.g.\n"
	         "--set model.closure=casson, --set 'source pour.rate=0.002';\n"
	         "a key of the case it makes redundant is dropped\n"
	         "(the summary says which)"},
	{.name = "unset", .value_name = "SECTION.KEY", .kind = SS_OPTION_LIST,
	 .parse = parse_unset,
	 .expected = "SECTION.KEY, e.g. time.max_time, or a section such as 'source pour'",
	 .help = "drop a key of the case (its default applies), or a\n"
	         "wall, open or source section: --unset 'source pour'"},
	{.name = "tile", .value_name = "NXxNY", .kind = SS_OPTION_WORD, .offset = AT(tile),
	 .parse = parse_tile, .expected = "NXxNY, e.g. 256x64",
	 .help = "cells per tile of the sweep (default 256x128, smaller\n"
	         "on small grids); results are the same bits for any\n"
	         "tile size and thread count"},
	{.name = "reference-kernel", .kind = SS_OPTION_FLAG, .offset = AT(reference_kernel),
	 .expected = "1 or 0",
	 .help = "use the plain two-pass sweep the fast one is tested\n"
	         "against (same bits, several times slower)"},
	{.name = "deflate", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(deflate),
	 .default_value = "0", .lo = 0, .hi = 9, .expected = "0 to 9",
	 .help = "HDF5 deflate level of /height, 0 (off) to 9"},
	{.name = "history", .kind = SS_OPTION_TEXT, .offset = AT(history),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a text",
	 .help = "the output's history attribute (the command line)"},
};

const struct ss_option_table ss_run_option_table = {
	.command = "run", .options = options, .count = sizeof options / sizeof *options,
};

void ss_run_options_init(struct ss_run_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_run_option_table, o);
}

/* A heap options object: the options first (the caller's pointer is to
 * them), the copies of the texts and of the overrides set by name. */
struct owned_options {
	struct ss_run_options o;
	struct ss_option_texts texts;
	char **overrides;            /* o.overrides points here */
	int room;                    /* entries allocated at overrides */
};

struct ss_run_options *ss_run_options_create(void)
{
	struct owned_options *w = ss_alloc(1, sizeof *w, "run options");
	if (w)
		ss_run_options_init(&w->o);
	return w ? &w->o : NULL;
}

void ss_run_options_destroy(struct ss_run_options *o)
{
	if (!o)
		return;
	struct owned_options *w = (struct owned_options *)o;
	ss_option_texts_release(&w->texts);
	for (int k = 0; k < o->override_count; k++)
		ss_free(w->overrides[k]);
	ss_free(w->overrides);
	ss_free(w);
}

/* One more override (--set or --unset) after those before, as the
 * command line keeps them. */
static int append_override(struct owned_options *w, const char *value)
{
	struct ss_run_options *o = &w->o;
	if (o->override_count == w->room) {
		const int room = w->room ? 2 * w->room : 8;
		char **grown = ss_alloc((size_t)room, sizeof *grown, "the case's overrides");
		if (!grown)
			return SS_ERR_FAIL;
		if (o->override_count)
			memcpy(grown, w->overrides, (size_t)o->override_count * sizeof *grown);
		ss_free(w->overrides);
		w->overrides = grown;
		w->room = room;
	}
	const size_t n = strlen(value) + 1;
	char *copy = ss_alloc(n, 1, "an override");
	if (!copy)
		return SS_ERR_FAIL;
	memcpy(copy, value, n);
	w->overrides[o->override_count++] = copy;
	o->overrides = (const char *const *)w->overrides;
	return SS_OK;
}

int ss_run_options_set(struct ss_run_options *o, const char *key, const char *value)
{
	struct owned_options *w = (struct owned_options *)o;
	const struct ss_option *opt = ss_option_find(&ss_run_option_table, key, NULL);
	if (!opt || opt->kind != SS_OPTION_LIST)
		return ss_option_set(&ss_run_option_table, o, key, value, &w->texts);
	if (!value || opt->parse(value, NULL))
		return ss_error_input("%s '%s': expected %s", key, value ? value : "", opt->expected);
	return append_override(w, value);
}
