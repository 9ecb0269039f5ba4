/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * hysteresis.h - each flow cell at rest or moving (doc/model.md#hysteresis;
 * ss_stepper_set_hysteresis, stepper.h).
 */
#ifndef SANDSLIDE_CORE_HYSTERESIS_H
#define SANDSLIDE_CORE_HYSTERESIS_H

#include "sandslide/stepper.h"

/* Every cell at rest, the halo's too (the start of a run from its initial
 * state); the first ss_hysteresis_update sets moving what is steeper than
 * tan a_s. */
void ss_hysteresis_start(struct ss_stepper *st);

/* The states from the heights (hysteresis.c), the halo's too, and
 * st->flowing_cells; every tile woken when a state changed.  slope_tol:
 * the steady rule's (stepper.h), below which moving sand stops.  Returns
 * the cells that changed, all ranks.  Collective. */
long long ss_hysteresis_update(struct ss_stepper *st, double slope_tol);

/* The states of a snapshot (ss_stepper_restore): moving, this rank's
 * cells (nx x ny, south row first), nonzero where sand moves; NULL: every
 * cell at rest.  Collective. */
void ss_hysteresis_restore(struct ss_stepper *st, const uint8_t *moving);

#endif
