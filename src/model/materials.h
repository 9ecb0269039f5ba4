/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * materials.h - a grid of materials for the stepper (ss_stepper_set_materials,
 * doc/model.md#materials) from what a user gives: a raster of repose angles
 * (relax --angle FILE, a case's [model] repose_angle = FILE).  The model's
 * closure, gamma and nu hold in every cell; each distinct angle is a
 * material.
 */
#ifndef SANDSLIDE_MODEL_MATERIALS_H
#define SANDSLIDE_MODEL_MATERIALS_H

#include "sandslide/dem.h"
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

#endif
