/*
 * diagnostics.h - the per-snapshot record of a run (SPEC section 5): what the
 * stepper measures and the snapshot writer stores, shared by both without
 * either knowing the other.
 */
#ifndef SANDSLIDE_DIAGNOSTICS_H
#define SANDSLIDE_DIAGNOSTICS_H

struct ss_diagnostics {
	double volume;          /* sand on flow cells, sum h dx dy, m^3 */
	double inflow;          /* cumulative volume added by sources, m^3 */
	double outflow;         /* cumulative volume that left through open cells, m^3 */
	double max_height;      /* highest flow cell, m */
	double max_slope_deg;   /* steepest face that can carry flux, degrees */
	double steps;           /* cumulative substeps */
	double active_fraction; /* tiles swept / tiles, over the last interval */
	double wall_seconds;    /* wall time since the run started, s */
};

#endif
