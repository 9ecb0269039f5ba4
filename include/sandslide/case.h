/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * case.h - the case file (doc/case-file.md): an INI file parsed with inih,
 * plus the command line's overrides, "SECTION.KEY=VALUE" (--set) and
 * "SECTION.KEY" or "SECTION" (--unset).
 *
 *   [grid]      nx, ny, dx, dy (default dx), origin = X Y
 *   [model]     closure, repose_angle (deg), nu (m^2/s) or the physical
 *               parameters delta, density, gravity, viscosity | consistency;
 *               gamma (herschel-bulkley)
 *   [time]      end (s) | end = steady, output_every (s), cfl, steady_tol,
 *               steady_slope_tol, max_time (s, with end = steady),
 *               integrator = auto|euler|rkl2, rkl2_max_stages, rkl2_tol
 *   [boundary]  west, east, south, north = wall|open|periodic; open_level (m)
 *   [initial]   type = flat|cone|file; height; center, radius, angle; file
 *   [wall NAME] [open NAME] [source NAME]
 *               rect = X0 Y0 X1 Y1 | disk = X Y R | polygon = X Y X Y ... |
 *               mask = PNG; sources also rate (m/s), start, stop (s)
 *
 * The keys are one table (ss_case_option_table), which continues in the
 * model's (model_options.h): [model] closure, repose_angle, nu, gamma and
 * [time] cfl, steady_tol, ... are the options relax takes as --closure,
 * --angle, ..., with the same defaults and ranges.  cases/reference.ini
 * documents every key with units and defaults.  Every error names file:line
 * (or the --set / --unset argument) and what is accepted.
 *
 * An override wins over the file: a key of the file that an override makes
 * redundant (max_time once --set time.end gives a time, nu once --set
 * model.delta gives the sliding layer, a cone's keys once --set
 * initial.type=flat, ...) is dropped, and a note says so (c->notes), where
 * the same conflict inside the file, or between two overrides, is an error.
 */
#ifndef SANDSLIDE_CASE_H
#define SANDSLIDE_CASE_H

#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/material_table.h"
#include "sandslide/model_options.h"
#include "sandslide/shape.h"
#include "sandslide/stepper.h"


enum { SS_CASE_MAX_NOTES = 16, SS_CASE_NOTE_SIZE = 512 };

enum ss_region_role { SS_REGION_WALL, SS_REGION_OPEN, SS_REGION_SOURCE };

struct ss_region {
	enum ss_region_role role;
	char name[64];
	char where[SS_CASE_WHERE_SIZE];        /* "file:line" of the section header */
	struct ss_shape shape;
	double rate;            /* source: m/s */
	double start, stop;     /* source: s (stop INFINITY = never) */
	char rate_where[SS_CASE_WHERE_SIZE];  /* where rate, start, stop were set */
	char start_where[SS_CASE_WHERE_SIZE]; /* ("" when not set) */
	char stop_where[SS_CASE_WHERE_SIZE];
};

enum ss_initial_type { SS_INITIAL_FLAT, SS_INITIAL_CONE, SS_INITIAL_FILE };

struct ss_case {
	char *path;             /* as given */
	char *text;             /* the whole file */

	/* [grid] */
	char grid_where[SS_CASE_WHERE_SIZE]; /* where nx was set, for messages */
	int nx, ny;
	double dx, dy;          /* m */
	double origin_x, origin_y; /* lower-left corner, m */

	/* [model] closure, repose_angle, nu (given or derived), gamma (1
	 * but for herschel-bulkley), the sliding layer nu may be derived from
	 * (model.layer: delta, density, gravity, viscosity, consistency), and
	 * [time] cfl, steady_tol, steady_slope_tol, max_time, integrator,
	 * rkl2_max_stages, rkl2_tol */
	struct ss_model_options model;

	/* [time] */
	double end;             /* s; INFINITY when steady */
	int steady;             /* end = steady */
	double output_every;    /* s */

	/* [boundary] */
	struct ss_boundary boundary;

	/* [initial] */
	enum ss_initial_type initial;
	double initial_height;  /* m: flat level, or the floor under a cone */
	double cone_x, cone_y, cone_radius; /* m */
	double cone_angle_deg;
	char *initial_file;     /* resolved against the case file's folder */
	char initial_where[SS_CASE_WHERE_SIZE];
	char *bedrock_file;     /* non-erodible base (raster), or NULL */
	char bedrock_where[SS_CASE_WHERE_SIZE];

	/* [model] repose_angle = FILE: resolved, owned; model.angle_file is it */
	char *angle_file;
	char angle_where[SS_CASE_WHERE_SIZE];
	/* [model] materials = FILE (model.materials_file, resolved, owned) and
	 * its [material NAME] sections (NULL: none) */
	char materials_where[SS_CASE_WHERE_SIZE];
	struct ss_material_table *material_table;

	struct ss_region *regions; /* in file order */
	int region_count;

	/* What the overrides made of the file: the keys they dropped, one
	 * sentence each ("[time] max_time (cases/cone.ini:31) dropped: ..."),
	 * for the run's summary. */
	char notes[SS_CASE_MAX_NOTES][SS_CASE_NOTE_SIZE];
	int note_count;
};

/*
 * Read and validate the case file at path, then apply the overrides in
 * order: "SECTION.KEY=VALUE" sets a key ("model.closure=casson",
 * "source pour.rate=0.002"), "SECTION.KEY" without '=' unsets one (as if
 * the file did not give it: its default, or missing), and "SECTION" alone
 * removes a wall, open or source section ("source pour").  Returns SS_OK, SS_ERR_INPUT (message names the
 * file:line or override) or SS_ERR_FAIL.  Release with ss_case_release()
 * whatever the result.
 */
int ss_case_load(struct ss_case *c, const char *path,
                 const char *const *overrides, int override_count);
void ss_case_release(struct ss_case *c);

/* Parse a whole case from text (path is only used in messages and to
 * resolve relative file names). */
int ss_case_parse(struct ss_case *c, const char *path, const char *text,
                  const char *const *overrides, int override_count);

/* The case file's keys ([grid], [model], [time], [boundary], [initial]),
 * continued by the model's options (model_options.h) at c->model. */
extern const struct ss_option_table ss_case_option_table;

#endif
