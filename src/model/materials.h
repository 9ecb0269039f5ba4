/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * materials.h - a grid of materials for the stepper (ss_stepper_set_materials,
 * doc/model.md#materials) from what a user gives: a raster of repose angles
 * (relax --angle FILE, a case's [model] repose_angle = FILE: the model's
 * closure, gamma and nu in every cell, each distinct angle a material), or
 * a raster of classes and their table (relax --materials FILE
 * --material-table FILE, a case's [model] materials = FILE with its
 * [material NAME] sections).
 */
#ifndef SANDSLIDE_MODEL_MATERIALS_H
#define SANDSLIDE_MODEL_MATERIALS_H

#include "sandslide/dem.h"
#include "sandslide/material_table.h"
#include "sandslide/model_options.h"
#include "sandslide/stepper.h"

/*
 * The angles of r (degrees; this rank's rows at least, the grid's size) as
 * st's materials.  A flow cell without data, or an angle outside (0, 90),
 * is refused with a message that names `what` (the file and where it was
 * given), the cell and the value; cells without data that do not flow take
 * the smallest angle.  More than 65535 distinct angles are refused.
 * Collective: every rank numbers the angles of the whole grid alike.
 */
int ss_materials_from_angles(struct ss_stepper *st, const struct ss_model_options *m,
                             const struct ss_raster *r, const char *what);

/*
 * The classes of r (integers >= 0; this rank's rows at least, the grid's
 * size) as st's materials, each class the law of its [material NAME] of t
 * (material_table.h; what it leaves out, the model's).  A flow cell
 * without data, a value that is not an integer, or a class that t does
 * not have, is refused naming `what`, the cell and the value.
 * Collective.
 */
int ss_materials_from_classes(struct ss_stepper *st, const struct ss_model_options *m,
                              const struct ss_material_table *t, const struct ss_raster *r,
                              const char *what);

/*
 * The angles of st's cells become angle_deg (degrees, this rank's cells,
 * nx x ny, [y][x] south row first), after ss_stepper_prepare and between
 * steps (the BMI's angle field): each cell keeps its closure, gamma and nu
 * (its material's law) with the new angle (ss_stepper_change_materials).
 * A flow cell's angle outside (0, 90) is refused naming `what`, the item
 * (j nx + i), the cell and the value; a wall keeps its angle, and so does
 * an open cell given one outside (0, 90).  Not with hysteresis.
 * Collective.
 */
int ss_materials_change_angles(struct ss_stepper *st, const double *angle_deg,
                               const char *what);

#endif
