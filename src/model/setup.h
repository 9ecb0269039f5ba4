/*
 * setup.h - build the initial state of a run from a case: grid, closure,
 * cell types from the wall and open regions (in file order, a later region
 * overriding an earlier one), initial heights, sources.
 */
#ifndef SANDSLIDE_SETUP_H
#define SANDSLIDE_SETUP_H

#include "sandslide/case.h"
#include "sandslide/stepper.h"

/* Initialise st for case c with tiles of tile_nx x tile_ny cells (<= 0:
 * defaults), the given kernel and the case's integrator.  SS_ERR_INPUT
 * names the key at fault (a region that covers no cell, an initial file
 * of the wrong size, too little memory, rkl2 with a bedrock).  On error st
 * is released. */
int ss_setup_stepper(const struct ss_case *c, int tile_nx, int tile_ny,
                     enum ss_kernel kernel, struct ss_stepper *st);

#endif
