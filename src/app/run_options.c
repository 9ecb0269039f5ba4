/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * run_options.c - run's options (run.h): the one table the command line,
 * the options set by name and the Python module read, continued by the
 * job's (job.h).  The case's own keys are the case file's table (case.h),
 * reached through --set and --unset.
 */
#include "sandslide/run.h"

#include <string.h>

/* The overrides' words, checked as they are collected (case.h applies
 * them, in order, --set and --unset alike). */
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
	 .offset = AT(job.output), .expected = "a path",
	 .help = "output file (default out/<case name>.h5; its folder\n"
	         "must exist unless it is the default out/); beside it\n"
	         "OUT.xmf (XDMF, for ParaView) and OUT.h5.aux.xml\n"
	         "(GDAL's georeferencing of an .h5 name)"},
	{.name = "restart", .value_name = "OUT.h5", .kind = SS_OPTION_TEXT, .offset = AT(restart),
	 .expected = "a path",
	 .help = "continue the run in OUT.h5 from its last snapshot,\n"
	         "appending to it, with the case stored in it (a\n"
	         "CASE.ini given too must be that case, and its\n"
	         "files are found beside it); the snapshots are\n"
	         "those of a run never interrupted"},
	{.name = "set", .alias = "-P", .value_name = "SECTION.KEY=VALUE", .kind = SS_OPTION_LIST,
	 .offset = AT(overrides), .parse = parse_set, .expected = "SECTION.KEY=VALUE, e.g. model.closure=casson",
	 .help = "override key KEY of section SECTION of the case, e.g.\n"
	         "--set model.closure=casson, --set 'source pour.rate=0.002';\n"
	         "a key of the case it makes redundant is dropped\n"
	         "(the summary says which)"},
	{.name = "unset", .value_name = "SECTION.KEY", .kind = SS_OPTION_LIST,
	 .offset = AT(overrides), .parse = parse_unset,
	 .expected = "SECTION.KEY, e.g. time.max_time, or a section such as 'source pour'",
	 .help = "drop a key of the case (its default applies), or a\n"
	         "wall, open or source section: --unset 'source pour'"},
	{.name = "reference-kernel", .kind = SS_OPTION_FLAG, .offset = AT(reference_kernel),
	 .expected = "1 or 0",
	 .help = "use the plain two-pass sweep the fast one is tested\n"
	         "against (same bits, several times slower)"},
	{.name = "deflate", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(deflate),
	 .default_value = "0", .lo = 0, .hi = 9, .expected = "0 to 9",
	 .help = "HDF5 deflate level of /height, 0 (off) to 9"},
};

static const struct ss_option_part parts[] = {
	{&ss_job_option_table, AT(job)}, {&ss_job_stepping_option_table, AT(job)},
};

const struct ss_option_table ss_run_option_table = {
	.command = "run", .options = options, .count = sizeof options / sizeof *options,
	.parts = parts, .part_count = 2, .size = sizeof(struct ss_run_options),
};

void ss_run_options_init(struct ss_run_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_run_option_table, o);
}
