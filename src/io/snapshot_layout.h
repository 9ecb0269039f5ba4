/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * snapshot_layout.h - what the HDF5 writer (h5_write.c) and reader
 * (h5_read.c) share of the file layout of doc/output.md, without
 * any HDF5 type: the diagnostic series and the constants of the
 * definition of a sandslide file.  Not installed; snapshot.h is the
 * public interface.
 */
#ifndef SANDSLIDE_SNAPSHOT_LAYOUT_H
#define SANDSLIDE_SNAPSHOT_LAYOUT_H

#include "sandslide/diagnostics.h"

/* Root attribute `source` starts with this ("sandslide 0.1.0"). */
#define SS_SNAPSHOT_SOURCE "sandslide"

/* Root attribute `boundary`: the kinds of the grid's four sides as the
 * case file's [boundary] names them, "west=wall east=open south=open
 * north=open" (the renderer draws wall sides).  Files written before it
 * have none. */
#define SS_SNAPSHOT_BOUNDARY "boundary"

/* /height chunks are 1 x 256 x 256 (fewer rows or columns on small grids):
 * readers take whole chunks of rows at a time. */
#define SS_SNAPSHOT_CHUNK_SIDE 256

/* A side longer than this is not a grid sandslide writes (int indices). */
#define SS_SNAPSHOT_MAX_SIDE (1 << 30)

/* Root attributes restart_state_even and restart_state_odd: the restart
 * state of the last snapshot of even and of odd index (steps, inflow sum
 * and carry, outflow sum and carry, stencil evaluations, RKL2's next
 * super-step limit (s, or infinity), the approach to rest's next
 * super-step in stages (0: not begun); diagnostics.h, struct
 * ss_restart_state).  Files written before the two hold one
 * restart_state, of the last snapshot; those written before RKL2 have
 * its first 5 values, those before the approach to rest its first 7. */
#define SS_SNAPSHOT_RESTART_VALUES 8
#define SS_SNAPSHOT_RESTART_VALUES_RKL2 7
#define SS_SNAPSHOT_RESTART_VALUES_OLD 5

static inline const char *ss_snapshot_restart_attribute(long long snapshot)
{
	return snapshot % 2 ? "restart_state_odd" : "restart_state_even";
}

/* The float64 (time) series beside /time; stencil_evaluations
 * (SS_SNAPSHOT_DIAG_EVALUATIONS) is missing from files written before RKL2,
 * and read as steps. */
enum { SS_SNAPSHOT_DIAG_COUNT = 9, SS_SNAPSHOT_DIAG_EVALUATIONS = 8 };

static inline const char *ss_snapshot_diag_name(int k)
{
	static const char *const names[SS_SNAPSHOT_DIAG_COUNT] = {
		"volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
		"active_fraction", "wall_seconds", "stencil_evaluations",
	};
	return names[k];
}

static inline const char *ss_snapshot_diag_units(int k)
{
	static const char *const units[SS_SNAPSHOT_DIAG_COUNT] = {
		"m3", "m3", "m3", "m", "degree", "1", "1", "s", "1",
	};
	return units[k];
}

static inline const char *ss_snapshot_diag_long_name(int k)
{
	static const char *const long_names[SS_SNAPSHOT_DIAG_COUNT] = {
		"volume of sand on flow cells",
		"cumulative volume added by sources",
		"cumulative volume that left through open cells",
		"highest sand surface on flow cells",
		"steepest slope of the faces in sand (bare bedrock not counted)",
		"cumulative substeps (forward Euler) or super-steps (RKL2)",
		"fraction of tiles swept since the previous snapshot",
		"wall-clock time since the run started",
		"cumulative evaluations of the stencil (one per Euler substep, s + 1 per RKL2 super-step)",
	};
	return long_names[k];
}

/* The field of d that series k holds, in the order of the names. */
static inline double *ss_snapshot_diag_field(struct ss_diagnostics *d, int k)
{
	double *const f[SS_SNAPSHOT_DIAG_COUNT] = {
		&d->volume, &d->inflow, &d->outflow, &d->max_height, &d->max_slope_deg,
		&d->steps, &d->active_fraction, &d->wall_seconds, &d->evaluations,
	};
	return f[k];
}

#endif
