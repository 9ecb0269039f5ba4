/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * job.c - the options the commands share (job.h): two tables, and the job
 * in an options struct (its parts).
 */
#include "sandslide/job.h"

#include <stddef.h>

#include "base/strings.h"

static int parse_tile(const char *value, void *field)
{
	return ss_parse_tile(value, field);
}

static int parse_device(const char *value, void *field)
{
	return ss_device_parse(value, field);
}

#define AT(m) offsetof(struct ss_job, m)

static const struct ss_option options[] = {
	{.name = "force", .kind = SS_OPTION_FLAG, .offset = AT(force), .expected = "1 or 0",
	 .help = "replace the output if it exists (else refused)"},
	{.name = "threads", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(threads),
	 .lo = 1, .hi = 4096, .expected = "an integer from 1 to 4096",
	 .help = "OpenMP threads (default: OMP_NUM_THREADS, else\n"
	         "the processors this process may run on, fewer on\n"
	         "a small grid)"},
};

const struct ss_option_table ss_job_option_table = {
	.command = "job", .options = options, .count = sizeof options / sizeof *options,
	.size = sizeof(struct ss_job),
};

static const struct ss_option stepping[] = {
	{.name = "tile", .value_name = "NXxNY", .kind = SS_OPTION_WORD, .offset = AT(tile),
	 .parse = parse_tile, .expected = "NXxNY, e.g. 256x64",
	 .help = "cells per tile of the sweep (default 256x128, smaller\n"
	         "on small grids); results are the same bits for any\n"
	         "tile size and thread count"},
	{.name = "device", .value_name = "cpu|cuda[:N]", .kind = SS_OPTION_WORD,
	 .offset = AT(device), .parse = parse_device, .default_value = "cpu",
	 .expected = "cpu, cuda or cuda:N (N from 0 to 63)",
	 .help = "where to compute: the CPU, or GPU N of a build\n"
	         "with CUDA (make CUDA=1; doc/gpu.md)"},
	{.name = "history", .kind = SS_OPTION_TEXT, .offset = AT(history),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a text",
	 .help = "the output's history attribute (the command line)"},
};

const struct ss_option_table ss_job_stepping_option_table = {
	.command = "job", .options = stepping, .count = sizeof stepping / sizeof *stepping,
	.size = sizeof(struct ss_job),
};

struct ss_job *ss_job_of(const struct ss_option_table *t, void *base)
{
	for (int p = 0; p < t->part_count; p++) {
		char *part = (char *)base + t->parts[p].offset;
		if (t->parts[p].table == &ss_job_option_table)
			return (struct ss_job *)part;
		struct ss_job *job = ss_job_of(t->parts[p].table, part);
		if (job)
			return job;
	}
	return NULL;
}
