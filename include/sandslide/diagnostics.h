/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * diagnostics.h - the per-snapshot record of a run (doc/output.md) and the
 * counters a restart needs: what the stepper measures and the snapshot
 * writer stores, shared by both without either knowing the other.
 */
#ifndef SANDSLIDE_DIAGNOSTICS_H
#define SANDSLIDE_DIAGNOSTICS_H

struct ss_diagnostics {
	double volume;          /* sand on flow cells, sum h dx dy, m^3 */
	double inflow;          /* cumulative volume added by sources, m^3 */
	double outflow;         /* cumulative volume that left through open cells, m^3 */
	double external;        /* cumulative volume put in (or taken out, < 0)
	                         * by writing heights from outside (the BMI's
	                         * set_value), m^3; 0 in a run */
	double max_height;      /* highest flow cell, m */
	double max_slope_deg;   /* steepest face in sand, degrees: bare bedrock
	                         * does not count (ss_stepper_max_sand_slope) */
	double steps;           /* cumulative substeps (RKL2: super-steps) */
	double evaluations;     /* cumulative stencil evaluations */
	double active_fraction; /* tiles swept / tiles, over the last interval */
	double wall_seconds;    /* wall time since the run started, s */
};

/* A cumulative volume as a compensated sum (Neumaier [Neumaier1974],
 * doc/model.md#conservation): sum + carry is the total of every term added,
 * to about one rounding however many there were. */
struct ss_volume_sum {
	double sum, carry;                  /* m^3 */
};

/* What a restart needs beyond the heights and the time to continue with the
 * same bits: the counters, RKL2's next super-step limit (stepper.h) and the
 * volume ledger's inflow and outflow (src/core/ledger.h; its external
 * volume, which only a coupled model puts in, bmi.h, is not kept), stored
 * with every snapshot (root attributes restart_state_even and _odd,
 * snapshot.h). */
struct ss_restart_state {
	long long steps;
	long long evaluations;
	double rkl2_tau;                    /* s; INFINITY: no limit */
	int rest_stages;                    /* the approach to rest's next
	                                     * super-step (0: not begun) */
	struct ss_volume_sum inflow, outflow;
};

#endif
