/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax_options.c - relax's options (relax.h): the one table the command
 * line, the options set by name and the Python module read, continued by
 * the model's and the job's.
 */
#include "sandslide/relax.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>


int ss_relax_sides_parse(const char *word, enum ss_side_kind *sides)
{
	enum ss_side_kind kind;
	if (ss_side_kind_parse(word, &kind) || kind == SS_SIDE_PERIODIC)
		return -1;
	*sides = kind;
	return 0;
}

int ss_relax_nodata_parse(const char *word, enum ss_cell_type *type)
{
	if (strcmp(word, "wall") && strcmp(word, "open"))
		return -1;
	*type = !strcmp(word, "wall") ? SS_CELL_WALL : SS_CELL_OPEN;
	return 0;
}

static int parse_sides(const char *value, void *field)
{
	return ss_relax_sides_parse(value, field);
}

static int parse_nodata(const char *value, void *field)
{
	return ss_relax_nodata_parse(value, field);
}

/* rect=X0,Y0,X1,Y1 or disk=X,Y,R into a shape (shape.h checks the numbers) */
static int parse_sand_shape(const char *value, void *field)
{
	struct ss_shape *shape = field, s;
	memset(&s, 0, sizeof s);
	const enum ss_shape_kind kind = !strncmp(value, "rect=", 5) ? SS_SHAPE_RECT
	                              : !strncmp(value, "disk=", 5) ? SS_SHAPE_DISK
	                              : SS_SHAPE_NONE;
	if (kind == SS_SHAPE_NONE || ss_shape_parse_numbers(kind, value + 5, &s))
		return -1;
	snprintf(s.where, sizeof s.where, "--add-sand");
	*shape = s;
	return 0;
}

#define AT(m) offsetof(struct ss_relax_options, m)

static const struct ss_option options[] = {
	{.name = "dem", .kind = SS_OPTION_TEXT, .offset = AT(dem), .flags = SS_OPTION_NAMED_ONLY,
	 .expected = "a path", .help = "the DEM (the command line's argument)"},
	{.name = "output", .alias = "-o", .value_name = "OUT", .kind = SS_OPTION_TEXT,
	 .offset = AT(job.output), .expected = "a path",
	 .help = ".asc, .png, .tif: the relaxed raster; .h5: the whole\n"
	         "series with diagnostics, and beside it OUT.xmf and\n"
	         "OUT.h5.aux.xml as run writes (default\n"
	         "out/<DEM>-relaxed with the input's extension)"},
	{.name = "sides", .value_name = "wall|open", .kind = SS_OPTION_WORD, .offset = AT(sides),
	 .default_value = "wall", .parse = parse_sides, .expected = "wall or open",
	 .help = "the four sides of the DEM"},
	{.name = "nodata", .value_name = "wall|open", .kind = SS_OPTION_WORD,
	 .offset = AT(nodata_type), .default_value = "wall", .parse = parse_nodata,
	 .expected = "wall or open",
	 .help = "cells without data (wall: no sand enters them;\n"
	         "open: sand leaves there, at --open-level)"},
	{.name = "open-level", .value_name = "M", .kind = SS_OPTION_REAL, .offset = AT(open_level),
	 .lo = -INFINITY, .hi = INFINITY, .expected = "a height in m",
	 .help = "height held on open sides and open nodata cells\n"
	         "(default: the lowest height of the DEM)"},
	{.name = "bedrock", .value_name = "FILE", .kind = SS_OPTION_TEXT, .offset = AT(bedrock),
	 .expected = "a path",
	 .help = "non-erodible base, a raster of the DEM's size: only\n"
	         "the sand above it moves"},
	{.name = "material-table", .value_name = "FILE", .kind = SS_OPTION_TEXT,
	 .offset = AT(material_table), .expected = "a path",
	 .help = "the [material NAME] sections of --materials'\n"
	         "classes (doc/model.md#materials)"},
	{.name = "add-sand", .value_name = "SHAPE", .kind = SS_OPTION_WORD,
	 .offset = AT(sand_shape), .parse = parse_sand_shape,
	 .expected = "rect=X0,Y0,X1,Y1 (X0 < X1, Y0 < Y1) or disk=X,Y,R (R > 0), in m",
	 .help = "pour sand on rect=X0,Y0,X1,Y1 or disk=X,Y,R (m)"},
	{.name = "sand-rate", .value_name = "R", .kind = SS_OPTION_REAL, .offset = AT(sand_rate),
	 SS_OPTION_POSITIVE, .expected = "m/s > 0", .help = "at R m/s (needed with --add-sand)"},
	{.name = "sand-duration", .value_name = "S", .kind = SS_OPTION_REAL,
	 .offset = AT(sand_duration), SS_OPTION_POSITIVE, .expected = "s > 0",
	 .help = "for S seconds from t = 0 (needed with --add-sand)"},
	{.name = "dx", .value_name = "M", .kind = SS_OPTION_REAL, .offset = AT(read.cellsize),
	 SS_OPTION_POSITIVE, .expected = "m > 0", .help = "cell size, for files that do not give one"},
	{.name = "zscale", .value_name = "Z", .kind = SS_OPTION_REAL, .offset = AT(read.zscale),
	 SS_OPTION_POSITIVE, .expected = "m per grey level > 0",
	 .help = "PNG: m per grey level (default: the file's range)"},
	{.name = "zoffset", .value_name = "Z0", .kind = SS_OPTION_REAL,
	 .offset = AT(read.zoffset), .lo = -INFINITY, .hi = INFINITY, .expected = "m",
	 .help = "PNG: height of grey 0, m (default 0; needs --zscale)"},
	{.name = "output-every", .value_name = "T", .kind = SS_OPTION_REAL,
	 .offset = AT(output_every), SS_OPTION_POSITIVE, .expected = "s > 0",
	 .help = ".h5 output: a snapshot every T s (default: 20 over\n"
	         "--max-time, else the first and the last)"},
	{.name = "report", .value_name = "FILE.json", .kind = SS_OPTION_TEXT, .offset = AT(report),
	 .expected = "a path", .help = "write the diagnostics for scripts"},
};

static const struct ss_option_part parts[] = {
	{&ss_job_option_table, AT(job)}, {&ss_job_stepping_option_table, AT(job)},
	{&ss_model_option_table, AT(model)},
};

static void init(void *o)
{
	ss_relax_options_init(o);
}

const struct ss_option_table ss_relax_option_table = {
	.command = "relax", .options = options, .count = sizeof options / sizeof *options,
	.parts = parts, .part_count = 3, .size = sizeof(struct ss_relax_options), .init = init,
};

void ss_relax_options_init(struct ss_relax_options *o)
{
	memset(o, 0, sizeof *o);
	ss_dem_read_options_init(&o->read);
	ss_option_defaults(&ss_relax_option_table, o);
}
