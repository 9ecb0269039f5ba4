/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * stepper.h - time integration of the DPSM on one block (doc/model.md#forward-euler).
 *
 * Each substep: fill the halo -> the largest face slope S of the current
 * state -> dt from the CFL bound -> clip dt to the next event (target time,
 * a source switching on or off) -> the sweep -> account inflow and outflow.
 * The fast sweep (default) measures S as a by-product of the previous sweep
 * and updates in place over the active tiles; the reference sweep computes
 * every flux into two arrays, then updates (src/core/sweep.h).  Both give
 * the same bits.  The step is forward Euler with
 *
 *   dt = cfl / (2 nu Lambda(S) (1/dx^2 + 1/dy^2))    doc/model.md eq. (11)
 *
 * where Lambda(S) >= max(f_sl', f_sl/s) over [0, S] (closure.h).  While a
 * source is on, dt is also limited so that it raises a cell by at most
 * cfl tan(a_cr) min(dx, dy): the step then cannot jump over the onset of
 * sliding.  A state with no face above the critical slope and no source
 * does not change, so the stepper jumps straight to the next event.
 *
 * RKL2 (integrator = SS_INTEGRATOR_RKL2) advances the same stencil by
 * super-steps of s stages instead (doc/model.md#rkl2-super-steps; the
 * state between super-steps and their rules: src/core/rkl2.h).  Its rules:
 *
 *   stability  tau <= dt_all (s^2 + s - 2) / 4 with dt_all forward Euler's
 *              step above for Lambda(infinity), the bound of every slope
 *              (for Coulomb max f' = f'(tan a_cr+) = cos a_cr whatever the
 *              state), so no state a stage can reach is unstable;
 *   accuracy   s <= rkl2_max_stages, and the embedded error estimate of
 *              RKC and SUNDIALS at most rkl2_tol tan(a_cr) min(dx, dy) in
 *              the max norm (rkl2_pouring_tol in its place for a
 *              super-step in which a source of ss_stepper_add_source
 *              pours, not the rate field).  One more evaluation
 *              after the last stage, at Y_s, writing nothing, makes the
 *              estimate of a super-step,
 *              which sets the limit of the next, tau 0.9 sqrt(tol / est),
 *              growing by at most 2x a super-step, from 4 stages at the
 *              start.  The limit is known when a super-step ends and is
 *              saved with each snapshot (restart state), so a restart from
 *              a snapshot takes the same super-steps.  The estimate, not
 *              the size of the change, bounds the super-steps as a state
 *              comes to rest, where RKL2 damps the stiff remainder only by
 *              its a_s ~ 1/2 a super-step;
 *   events     super-steps end on target times and source switches, so a
 *              source is constant over a super-step (its value at every
 *              stage time), and the source rule above holds for tau;
 *   ledger     the outflow of each stage is combined with the stage
 *              weights, as the heights are, so volume balances to
 *              round-off.
 *
 *   rest       a run that asks for steady hands the last of its motion
 *              to the approach to rest (rest, src/core/rest.h), with
 *              either integrator.
 *
 * Bedrock is not supported by RKL2 (its stages have negative weights, so
 * the per-face limit of doc/model.md#bedrock cannot keep sand above the
 * rock): a stepper with a bedrock refuses it at ss_stepper_prepare.
 *
 * Steady means: no source to switch on, max |dh/dt| < steady_tol (for RKL2
 * the mean rate |Y_s - Y_0| / tau of the super-step), and no face in sand
 * carries more sliding flux than a Coulomb face steeper than the repose
 * angle by steady_slope_tol would (for Coulomb: no sand face steeper than
 * tan a_cr + steady_slope_tol).  The rate alone is not enough: a long slope
 * just above the angle barely changes height, the more so the larger the
 * cells.
 *
 * The stepper owns its arrays; it knows nothing of files.  Its parts sit
 * behind pointers, each in a file of src/core/ (src/README.md): the kernel
 * it drives (sweeper.c), the sources (sources.c), the volume ledger
 * (ledger.c) and RKL2's state (rkl2.c); stepper.c holds the rest.
 */
#ifndef SANDSLIDE_STEPPER_H
#define SANDSLIDE_STEPPER_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/diagnostics.h"
#include "sandslide/grid.h"
#include "sandslide/integrator.h"

enum ss_kernel {
	SS_KERNEL_FAST,         /* in place, active tiles (sweep_fast.c) */
	SS_KERNEL_REFERENCE,    /* two passes, two flux arrays (sweep.c) */
};

/* The parts of a stepper, each defined in src/core/ beside its file. */
struct ss_sweeper;
struct ss_sources;
struct ss_ledger;
struct ss_rkl2;
struct ss_rest;

struct ss_stepper {
	/* set by ss_stepper_init */
	struct ss_grid grid;          /* this rank's block (below) */
	struct ss_closure closure;
	struct ss_boundary boundary;
	double cfl;                   /* in (0, 1] */

	/* set by the caller before ss_stepper_prepare (init zeroes them) */
	enum ss_kernel kernel;
	enum ss_integrator integrator; /* euler or rkl2 */
	enum ss_rest_mode rest;       /* the approach to rest when steady is
	                               * asked for (src/core/rest.h; not with
	                               * a bedrock) */
	int rkl2_max_stages;          /* RKL2 and the approach to rest: s <= it,
	                               * >= 2 */
	double rkl2_tol;              /* RKL2: error estimate per super-step, in
	                               * units of tan(a_cr) min(dx, dy), > 0
	                               * (both: the model options' table,
	                               * model_options.h, has the defaults and
	                               * checks the ranges) */
	double rkl2_pouring_tol;      /* RKL2: the same while a source added by
	                               * ss_stepper_add_source pours (not the
	                               * rate field); 0: rkl2_tol */

	/* the state */
	double *height;               /* m, cells with halo (ss_grid_index) */
	uint8_t *cell_types;          /* enum ss_cell_type with halo, packed
	                               * (ss_cell_type_get, grid.h) */
	double *bedrock;              /* m, with halo; NULL without bedrock
	                               * (-infinity where no sand lies: walls,
	                               * open cells, open and wall ghosts) */
	/* several materials (doc/model.md#materials), set by
	 * ss_stepper_set_materials; NULL: `closure` everywhere */
	struct ss_closure *materials; /* material_count closures; `closure` is
	                               * then the one of the smallest angle */
	int material_count;
	uint16_t *material;           /* each cell's material, with halo */
	int hysteresis;               /* ss_stepper_set_hysteresis: materials
	                               * 2n (material n's sand at rest, a_s) and
	                               * 2n + 1 (moving, a_d); the low bit of
	                               * `material` is then each cell's state
	                               * (doc/model.md#hysteresis) */
	long long flowing_cells;      /*   flow cells moving, all ranks */
	double time;                  /* s */
	long long steps;              /* substeps (RKL2: super-steps) taken */
	long long evaluations;        /* stencil evaluations: Euler one a step,
	                               * RKL2 s + 1 a super-step (the stages and
	                               * the error estimate) */
	double rate_max;              /* max |dh/dt| of the last substep, m/s */

	/* the parts: their structs are src/core's (read by its files, by
	 * bench's kernel timing and by the white-box tests) */
	struct ss_sweeper *sweeper;   /* the kernel: fast or reference sweep,
	                               * face rule, CFL table, timers, tiles */
	struct ss_sources *sources;   /* the sources and the rate field */
	struct ss_ledger *ledger;     /* inflow, outflow, external volume; the
	                               * open faces; the outflow batch */
	struct ss_rkl2 *rkl2;         /* RKL2's arrays and step control; NULL
	                               * before ss_stepper_prepare and for euler */
	struct ss_rest *rest_state;   /* the approach to rest; NULL before
	                               * ss_stepper_prepare, when off, and with
	                               * a bedrock */
};

/* Allocate the arrays for grid g (zero heights, all flow cells).  Returns
 * SS_ERR_INPUT for a bad cfl or boundary, SS_ERR_FAIL when an allocation
 * fails (callers that know the case check ss_stepper_memory_bytes first).
 * A default thread count of the calling thread is lowered to what this
 * rank's cells and tile rows can use (ss_parallel_threads_for); a count
 * asked for is kept.
 *
 * In a run of several ranks (comm.h) g is the whole grid and st->grid
 * becomes this rank's slab: the tiling of the whole grid (the tile sizes
 * given, or the defaults of the whole grid) split into runs of whole tile
 * rows, one per rank in rank order from the south, so that every rank
 * count sweeps the same tiles and gives the same bits.  More ranks than
 * tile rows is SS_ERR_INPUT.  Every function below then works on the slab
 * (masks, bedrock and heights are the slab's rows) and is collective:
 * every rank calls it, in the same order. */
int ss_stepper_init(struct ss_stepper *st, const struct ss_grid *g,
                    const struct ss_closure *c, const struct ss_boundary *b,
                    double cfl, int tile_nx, int tile_ny);
void ss_stepper_release(struct ss_stepper *st);

/* The rows first_row .. first_row + rows - 1 (from the south) of the whole
 * grid g that rank `rank`'s slab holds, as ss_stepper_init splits it (the
 * tile sizes as there); rows 0 for a rank that would get no tile row.
 * What a rank reads of a raster before its stepper exists (dem.h's
 * windows), and what the rank that writes a raster receives from each. */
void ss_stepper_slab_rows(const struct ss_grid *g, int tile_nx, int tile_ny, int rank,
                          int *first_row, int *rows);

/* The cells per tile of st's sweep: the sizes ss_stepper_init was given,
 * or the defaults they resolved to (what ss_stepper_slab_rows needs to
 * split another grid as st's was). */
void ss_stepper_tile_size(const struct ss_stepper *st, int *tile_nx, int *tile_ny);

/* Bytes the stepper allocates for grid g with the fast kernel, that
 * integrator and approach to rest (for the memory check). */
double ss_stepper_memory_bytes(const struct ss_grid *g, enum ss_integrator integrator,
                               enum ss_rest_mode rest);
/* The bytes of st's arrays on this rank: ss_stepper_memory_bytes and each
 * cell's material (2 B, with several materials). */
double ss_stepper_bytes(const struct ss_stepper *st);
/* The smallest and largest repose angle of st's materials (degrees): the
 * closure's twice without materials. */
void ss_stepper_repose_range(const struct ss_stepper *st, double *min_deg, double *max_deg);

/* Add a source of rate m/s on the cells where mask (nx * ny, row-major,
 * south row first) is non-zero; call after the cell types are final.
 * Cells that are not flow cells are ignored. */
int ss_stepper_add_source(struct ss_stepper *st, const uint8_t *mask,
                          double rate, double start, double stop);

/*
 * A source field set from outside (the BMI's deposition rate): rate (nx *
 * ny values, m/s, row-major, south row first) is added to dh/dt of every
 * flow cell from now on, with the case's sources, until set again (NULL:
 * none).  Other cells are ignored.  Its volume counts as inflow; the time
 * step keeps the source rule (stepper.h's top) with the largest |rate|.
 * A negative rate erodes: refused (SS_ERR_INPUT) on a stepper with a
 * bedrock, which has no rule to stop erosion at the rock; also refused: a
 * rate that is not finite.  Nothing is changed when it is refused.  Call
 * after ss_stepper_prepare, between calls of ss_stepper_advance.
 */
int ss_stepper_set_rate_field(struct ss_stepper *st, const double *rate);

/* Book volume_m3 (signed) put on the grid from outside, by writing heights
 * between calls of ss_stepper_advance, as the ledger's external volume
 * (compensated, as the inflow is), so that volume = initial + inflow -
 * outflow + external (ss_stepper_diagnostics). */
void ss_stepper_book_external(struct ss_stepper *st, double volume_m3);

/* The ledger's cumulative volumes, m^3, as ss_stepper_diagnostics reports
 * them (without its sums over the grid): poured in by the sources and the
 * rate field, and gone out through open cells.  Between calls of
 * ss_stepper_advance they are those of the current state; inside its
 * progress callback the outflow may lag on several ranks (src/core/ledger.h:
 * the outflow batch). */
double ss_stepper_inflow(const struct ss_stepper *st);
double ss_stepper_outflow(const struct ss_stepper *st);

/* What the approach to rest took of the steps and evaluations since
 * ss_stepper_prepare (0 when it did not begin; src/core/rest.h). */
void ss_stepper_rest_counts(const struct ss_stepper *st, long long *steps,
                            long long *evaluations);

/* Of the tiles of the grid, the fraction each stencil evaluation since
 * ss_stepper_init swept, on average (the fast sweep skips sleeping tiles;
 * the reference sweep sweeps all: 1); 0 before the first evaluation. */
double ss_stepper_swept_fraction(const struct ss_stepper *st);

/* The kernel's wall time since ss_stepper_init, s: measuring the slopes
 * (and the reference sweep's fluxes) and sweeping. */
void ss_stepper_kernel_seconds(const struct ss_stepper *st, double *measure, double *sweep);

/*
 * Several materials (doc/model.md#materials): closures[m] holds in the
 * cells with material_of_cell[j nx + i] == m (this rank's rows, nx x ny).
 * A face takes the closure of the larger angle of its two cells.  The
 * CFL bound is the largest of the materials'; `closure` becomes the one of
 * the smallest angle (the accuracy and source rules' scale).  One material,
 * or several equal ones, is `closure` everywhere: the bits of a run without
 * materials.  Before ss_stepper_prepare; SS_ERR_INPUT names a material
 * number out of range.
 */
int ss_stepper_set_materials(struct ss_stepper *st, const struct ss_closure *closures,
                             int count, const uint16_t *material_of_cell);

/*
 * The same after ss_stepper_prepare, between steps (the BMI's angle
 * field): the kernel's rules and CFL table follow the new materials, RKL2
 * and the approach to rest size their steps from them as at the start,
 * and every tile is swept again.  Materials equal to st's change nothing,
 * not a bit.  On an error st is as it was.  Not with hysteresis.
 */
int ss_stepper_change_materials(struct ss_stepper *st, const struct ss_closure *closures,
                                int count, const uint16_t *material_of_cell);

/*
 * Hysteresis (doc/model.md#hysteresis): sand at rest starts to slide only
 * where a face of its cell is steeper than tan a_s (static_deg, the angle
 * of maximum stability), and moving sand stops once every face of its cell
 * is at most tan a_d (the closure's repose angle).  Each flow cell carries
 * its state (`material`: 0 at rest, 1 moving), updated between steps (and
 * RKL2's super-steps) from the heights; a face takes the larger angle of
 * its two cells' states (materials, face.h).  static_deg must be at least
 * the repose angle; equal, it is the model without hysteresis, the same
 * bits.  Before ss_stepper_prepare; not with ss_stepper_set_materials.
 */
int ss_stepper_set_hysteresis(struct ss_stepper *st, double static_deg);

/*
 * Several materials with hysteresis: ss_stepper_set_materials where
 * material m of the given also has its static angle static_deg[m] (at
 * least its repose angle).  Each flow cell then carries its material and
 * its state, `material` = 2 n + state (n the material's number by angle,
 * state 1 moving): a face takes the larger material of its two cells and,
 * of one material, the moving state.  Static angles equal to the repose
 * angles are ss_stepper_set_materials, the same bits; one material is
 * ss_stepper_set_hysteresis.  Before ss_stepper_prepare.
 */
int ss_stepper_set_hysteresis_materials(struct ss_stepper *st,
                                        const struct ss_closure *closures,
                                        const double *static_deg, int count,
                                        const uint16_t *material_of_cell);

/* A non-erodible bedrock (nx * ny values, m, row-major, south row first):
 * only the sand above it moves, each face limited by the thickness of the
 * cell it leaves (doc/model.md#bedrock).  Call after the cell types are final and before
 * ss_stepper_prepare, which refuses a bedrock above the surface. */
int ss_stepper_set_bedrock(struct ss_stepper *st, const double *bedrock);

/* Call once heights and interior cell types are set: fills the halo types,
 * holds open cells at the open level, lists the outflow faces, sets up the
 * kernel chosen in st->kernel and the integrator in st->integrator (for
 * rkl2 with the settings above: SS_BUG without them).  Returns
 * SS_ERR_INPUT naming the first non-finite height, the first cell whose
 * bedrock is above the surface, or rkl2 with a bedrock. */
int ss_stepper_prepare(struct ss_stepper *st);

/* How ss_stepper_advance ended.  Steady: see the top of this file. */
enum ss_advance_end {
	SS_ADVANCE_REACHED,     /* time == t_target (samples: time >= t_target) */
	SS_ADVANCE_STEADY,      /* steady (when requested) */
	SS_ADVANCE_NONFINITE,   /* a rate or height became NaN or infinite */
	SS_ADVANCE_STALLED,     /* dt fell below the resolution of the clock */
	SS_ADVANCE_STEPS,       /* took max_steps substeps */
	SS_ADVANCE_INTERRUPTED, /* *stop became non-zero (after a whole substep) */
};

struct ss_advance_options {
	double steady_tol;      /* m/s; steady needs max |dh/dt| < it; <= 0: never */
	double steady_slope_tol; /* and no sand face steeper than the repose
	                          * angle by more (see above); <= 0: 1e-6 */
	long long max_steps;    /* > 0: stop after this many substeps */
	void (*progress)(void *context, const struct ss_stepper *st);
	void *context;          /* passed to progress, called after each substep */
	const volatile sig_atomic_t *stop; /* NULL, or checked after each substep
	                                    * (set by a signal handler) */
	int samples;            /* t_target is where the caller samples the
	                         * state, not an event: no step is shortened to
	                         * end on it, and the call returns after the
	                         * step that reaches or passes it (relax: its
	                         * steps do not depend on when snapshots are
	                         * taken) */
};

enum ss_advance_end ss_stepper_advance(struct ss_stepper *st, double t_target,
                                       const struct ss_advance_options *o);

/* Volume, maxima and counters of the current state; wall_seconds is left to
 * the caller.  Resets the active_fraction counters.  max_slope_deg is
 * ss_stepper_max_sand_slope as an angle. */
void ss_stepper_diagnostics(struct ss_stepper *st, struct ss_diagnostics *d);

/*
 * The steepest face of the sand, s = |grad h| over every rank (fills the
 * halo): the faces that can carry flux whose stencil lies in sand at least
 * 1e-6 min(dx, dy) thick (src/core/sweep.h); without a bedrock every
 * such face.  Bare rock may stay steeper than the repose angle for ever,
 * and a cell at the top of a rock cliff drains geometrically (a quarter of
 * its sand per face and step, doc/model.md#bedrock), so it never quite
 * reaches 0.  What
 * relax reports and run's /max_slope_deg are.  The time step and the
 * steady rule measure slopes their own way (stepper.c).
 */
double ss_stepper_max_sand_slope(struct ss_stepper *st);

/* Tell the stepper that heights were changed from outside (every tile is
 * swept and measured again). */
void ss_stepper_heights_changed(struct ss_stepper *st);

/* Time of the next source switch after t (INFINITY if none). */
double ss_stepper_next_source_event(const struct ss_stepper *st, double t);

/* What a restart needs of the current state besides its heights and time:
 * the counters and the ledger's sums (diagnostics.h). */
void ss_stepper_restart_state(const struct ss_stepper *st, struct ss_restart_state *s);

/* Put a prepared stepper in a saved state: time t (s), the heights of
 * every cell of st->grid as a snapshot stores them (nx * ny, row-major,
 * south row first), with hysteresis which cells move (the same layout,
 * nonzero: moving; NULL: none), and the state s that
 * ss_stepper_restart_state gave.  Stepping on from it gives the same bits
 * as the run that saved it.  Collective. */
void ss_stepper_restore(struct ss_stepper *st, double t, const double *height,
                        const uint8_t *moving, const struct ss_restart_state *s);

/* The first cell (in row order, of every rank) whose height is not
 * finite: 1 and its global (i, j), or 0 when every height is finite. */
int ss_stepper_first_nonfinite(const struct ss_stepper *st, int *i, int *j);

#endif
