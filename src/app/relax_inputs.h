/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax_inputs.h - what relax reads and the stepper it sets up from it: one
 * input path for `relax` (relax.c) and the BMI's DEM configs (bmi.c), so
 * that a DEM relaxed either way is read, checked and set up alike.
 */
#ifndef SANDSLIDE_APP_RELAX_INPUTS_H
#define SANDSLIDE_APP_RELAX_INPUTS_H

#include "sandslide/dem.h"
#include "sandslide/material_table.h"
#include "sandslide/relax.h"
#include "sandslide/stepper.h"

struct ss_pour_cover;   /* model/setup.h */

struct ss_relax_inputs {
	struct ss_raster dem;       /* this rank's rows (a window, dem.h): the
	                             * initial surface, later the output's */
	struct ss_raster bedrock;   /* the same rows, when o->bedrock */
	struct ss_raster angles;    /* the same rows, when o->model.angle_file,
	                             * or the classes of o->model.materials_file */
	struct ss_material_table *table;  /* o->material_table, or NULL */
};

/* The DEM (o->dem, or a copy of o->input_raster) and the bedrock, this
 * rank's rows as the stepper will split the grid with o->job.tile, and
 * the options that go together (a pour's shape, rate and duration; a PNG's
 * zoffset and zscale) checked.  Collective: a failure of one rank is every
 * rank's.  Release in either way. */
int ss_relax_inputs_read(const struct ss_relax_options *o, struct ss_relax_inputs *in);
void ss_relax_inputs_release(struct ss_relax_inputs *in);

/* st prepared at t = 0 from the inputs and the options (model/setup.h):
 * what relax starts from, and what its guard rebuilds; steady: it will
 * be stepped until steady (relax; not the BMI, which drives it); *cover
 * (NULL: not wanted) where --add-sand's sand lands. */
int ss_relax_setup_stepper(const struct ss_relax_options *o, const struct ss_relax_inputs *in,
                           int steady, struct ss_stepper *st, struct ss_pour_cover *cover);

#endif
