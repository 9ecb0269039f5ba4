/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * setup.h - the initial state of a run, prepared for stepping: from a case
 * (run) or from a raster (relax), through the same steps: grid, integrator
 * (ss_integrator_resolve), memory check, closure, stepper, cell types,
 * heights, bedrock, sources.
 */
#ifndef SANDSLIDE_SETUP_H
#define SANDSLIDE_SETUP_H

#include "sandslide/case.h"
#include "sandslide/dem.h"
#include "sandslide/material_table.h"
#include "sandslide/model_options.h"
#include "sandslide/shape.h"
#include "sandslide/stepper.h"

/* Initialise st for case c with tiles of tile_nx x tile_ny cells (<= 0:
 * defaults), the given kernel and the case's integrator: cell types from
 * the wall and open regions (in file order, a later region overriding an
 * earlier one), initial heights, bedrock, sources.  SS_ERR_INPUT names the
 * key at fault (a region that covers no cell, an initial file of the wrong
 * size, too little memory, rkl2 with a bedrock).  On error st is
 * released. */
int ss_setup_stepper(const struct ss_case *c, int tile_nx, int tile_ny,
                     enum ss_kernel kernel, struct ss_stepper *st);

/* Where poured sand lands: the cells a pour's shape covers, of them those
 * without data (walls or open cells, where nothing is poured), and the
 * extent of the centres of the others (poured on). */
struct ss_pour_cover {
	long long cells;                  /* cell centres the shape covers */
	long long nodata;                 /*   of them without data */
	double x_min, x_max;              /* m: the centres poured on (NaN */
	double y_min, y_max;              /*   when none is) */
};

/* What relax builds its stepper from: a raster and the model. */
struct ss_raster_setup {
	const struct ss_model_options *model;
	const char *name;                 /* the raster, for messages */
	const struct ss_raster *heights;  /* this rank's rows at least (a
	                                   * window, dem.h, or the whole) */
	double dx;                        /* m; NaN: the raster's cell size */
	enum ss_side_kind sides;          /* all four sides */
	enum ss_cell_type nodata_type;    /* cells without data: wall or open */
	double open_level;                /* m; NaN: the lowest height of the
	                                   * raster (where an open side or cell
	                                   * lets sand leave) */
	const struct ss_raster *bedrock;  /* the same size and rows, or NULL */
	const struct ss_raster *angles;   /* each cell's repose angle, degrees
	                                   * (model/materials.h), the same size
	                                   * and rows, or NULL: the model's */
	const struct ss_material_table *classes;  /* not NULL: `angles` holds
	                                   * classes, each the law of its
	                                   * material here */
	const char *angles_what;          /*   the file, for messages */
	int steady;                       /* the run goes on until steady (relax;
	                                   * not the BMI, which drives it): the
	                                   * approach to rest (stepper.h) */
	int tile_nx, tile_ny;             /* cells per tile; <= 0: relax's
	                                   * defaults */
	const struct ss_shape *pour;      /* sand poured from t = 0, or NULL: */
	double pour_rate;                 /*   m/s */
	double pour_duration;             /*   s */
	struct ss_pour_cover *pour_cover; /* out: where it lands (NULL: not
	                                   * wanted); a pour on no cell with
	                                   * data is refused */
};

/* This rank's rows of the raster spec (its window, dem.h) as the stepper
 * splits a grid of the raster's size in tiles of tile_nx x tile_ny cells
 * (<= 0: the defaults) over the ranks (ss_stepper_slab_rows), found from
 * the header first when there are other ranks: no rank holds the whole
 * raster.  One rank reads it whole.  Release r either way. */
int ss_setup_read_window(const char *spec, const char *context,
                         struct ss_dem_read_options opt, int tile_nx, int tile_ny,
                         struct ss_raster *r);

/* The approach to rest a stepper of model m takes: for a run until steady,
 * not with a bedrock (its stages have negative weights, as RKL2's). */
enum ss_rest_mode ss_setup_rest_mode(const struct ss_model_options *m, int steady,
                                     int has_bedrock);

/* The bytes a stepper of g's size with this integrator and approach needs
 * on this node: this rank's share of the grid times the ranks on the node
 * (dx, dy and the origin do not matter). */
double ss_setup_node_bytes(const struct ss_grid *g, enum ss_integrator integrator,
                           enum ss_rest_mode rest);

/* SS_ERR_INPUT "NAME: NX x NY cells need X of memory; this machine has Y
 * available" when `rasters` whole rasters of nx x ny cells (values and
 * nodata flags) and the stepper of model m (with a bedrock or not) need
 * more than the machine has: checked from a raster's header, before a
 * command reads the raster or does any work. */
int ss_setup_check_raster_memory(const char *name, int nx, int ny, int rasters,
                                 const struct ss_model_options *m, int has_bedrock);

/* st for the raster set-up s, as ss_setup_stepper (the fast kernel, the
 * default tiles, auto as relax resolves it).  On error st is released. */
int ss_setup_stepper_from_raster(const struct ss_raster_setup *s, struct ss_stepper *st);

#endif
