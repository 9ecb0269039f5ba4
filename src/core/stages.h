/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * stages.h - what the super-steps (rkl2.c, rest.c) share between their
 * stages: the caller hears of the progress and may stop a super-step
 * after any of its stages, which then is taken back to where it began, so
 * that a stop request is answered within one evaluation of the stencil and
 * leaves a state the run could have stopped in.
 */
#ifndef SANDSLIDE_CORE_STAGES_H
#define SANDSLIDE_CORE_STAGES_H

#include "sandslide/stepper.h"

/* After a stage (not the last): the progress callback, then whether the
 * stop flag asks to stop, agreed by every rank (collective). */
int ss_stages_stop(struct ss_stepper *st, const struct ss_advance_options *o);

/*
 * Back to the heights Y_0 of the super-step being taken (its stage arrays
 * hold them wherever a stage swept: sweep.h), and the kernel's plan to a
 * fresh start; the evaluations and tile counts the caller restores.  The
 * ledger needs nothing: a super-step books its outflow with its last
 * stage, and the inflow after it.
 */
void ss_stages_take_back(struct ss_stepper *st, const double *y0);

/* The four arrays of a super-step's stages for st's grid, y0 .. m0 (Y_0,
 * D_{j-1}, D_{j-2} and M(Y_0), sweep.h), as after a super-step in which
 * nothing moved: Y_0 the heights, the others zero; names[k] names the
 * k-th in the message of a failed allocation (SS_ERR_FAIL; those made are
 * the caller's to free). */
int ss_stages_arrays_create(const struct ss_stepper *st, const char *const names[4],
                            double **y0, double **d1, double **d2, double **m0);

#endif
