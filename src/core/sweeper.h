/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sweeper.h - the kernel a stepper drives, behind one call per pass: the
 * fast sweep (sweep_fast.c, the default) or the reference sweep (sweep.c),
 * chosen by st->kernel; the face rule and the CFL table of its closure;
 * the tiles across rank edges woken after each pass; the kernel's timers
 * and the tile counts of the active fraction.  Both sweeps give the same
 * bits (sweep.h).
 *
 * Each pass also leaves the fluxes of the ledger's open faces in
 * ledger->open_flux (the fast sweep writes them; the reference sweep's
 * are copied from its flux arrays), from which the ledger meters the
 * outflow (ledger.h).
 *
 * The functions take the stepper, whose grid, boundary, heights, cell
 * types, bedrock and sources they sweep.  Those that sum over the ranks
 * (measuring) or trade tile edges with them (every pass that writes) are
 * collective (comm.h).
 */
#ifndef SANDSLIDE_CORE_SWEEPER_H
#define SANDSLIDE_CORE_SWEEPER_H

#include <stdint.h>

#include "core/face.h"
#include "core/sweep.h"
#include "sandslide/closure.h"
#include "sandslide/stepper.h"

struct ss_sweeper {
	struct ss_tiling tiling;        /* this rank's tiles */
	struct ss_face_rule face_rule;
	struct ss_face_table materials; /* several materials: their rules */
	struct ss_cfl_bound cfl_bound;  /* Lambda(S) of the closure (of
	                                 * materials: their largest, per nu of
	                                 * st->closure) */
	struct ss_sweep_fast fast;      /* fast kernel */
	uint8_t *cell_type_bytes;       /* reference kernel: the cell types,
	                                 * one byte per cell */
	double *flux_x, *flux_y;        /* reference kernel: m^2/s per face */

	/* a distributed grid (comm.h): the grid is this rank's slab of whole
	 * tile rows, the tiling its tiles */
	int rank_south, rank_north;     /* ranks beside, -1: none */
	uint8_t *edges_in;              /* 2 tiles_x: the changed edges of the
	                                 * tile rows beside (sweep.h) */
	double tiles_all;               /* tiles of the whole grid */
	double tiles_awake;             /* tiles the coming pass sweeps, all ranks */
	double tiles_awake_here;        /*   of them on this rank */

	double tile_sweeps, tile_slots; /* for active_fraction, since the last
	                                 * ss_stepper_diagnostics */
	double tiles_evaluated;         /* tiles each stencil evaluation swept,
	                                 * all ranks, summed since create */
	double tile_evaluation_slots;   /*   and tiles_all per evaluation: the
	                                 * cell-update rate counts only the
	                                 * cells of swept tiles */
	double seconds_measure;         /* kernel wall time, s: measuring S */
	double seconds_sweep;           /*   and sweeping */
};

/* For st's grid (this rank's), closure and boundary, covered by `tiling`;
 * tiles_all: the whole grid's tiles.  NULL and SS_ERR_FAIL if an
 * allocation fails. */
int ss_sweeper_create(struct ss_sweeper **out, const struct ss_stepper *st,
                      const struct ss_tiling *tiling, double tiles_all);
void ss_sweeper_destroy(struct ss_sweeper *w);

/* The face rule and the CFL table of st->closure, or of st's materials
 * (their rules for the face loops, each cell's material, a CFL table that
 * bounds every one): set by ss_stepper_set_materials after the sweeper was
 * created.  Before anything reads the CFL table (RKL2's and the approach
 * to rest's set-up). */
int ss_sweeper_rules(struct ss_stepper *st);

/* ss_sweeper_rules again for st's new materials, after the sweeper was
 * prepared (ss_stepper_change_materials): on failure (SS_ERR_FAIL) the
 * rules are as they were. */
int ss_sweeper_change_rules(struct ss_stepper *st);

/* The arrays of the kernel st->kernel, once the cell types are final and
 * the ledger lists the open faces (each rank's failure: the caller agrees
 * on it).  The fast sweep starts with every tile awake. */
int ss_sweeper_prepare(struct ss_stepper *st);

/* The heights changed from outside, their halo filled: every tile is
 * swept and measured again (fast sweep). */
void ss_sweeper_wake_all(struct ss_stepper *st);

/* The sources' field changed (sources.h): the fast sweep marks the tiles
 * it pours on. */
void ss_sweeper_mark_sources(struct ss_stepper *st);

/* The start of a step: the halo, then the largest face slope S of the
 * state over every rank (NaN if a height is not finite; the fast sweep
 * also saves its ring rows, the reference sweep computes the fluxes), and
 * the tiles the coming pass sweeps. */
double ss_sweeper_measure(struct ss_stepper *st);

/* A forward-Euler pass of dt seconds from the state measured, with the
 * sources' field and the bedrock.  Returns max |dh/dt| over the flow
 * cells of this rank, m/s (INFINITY on NaN). */
double ss_sweeper_euler(struct ss_stepper *st, double dt);

/* The tile counts of a super-step of `evaluations` passes that swept
 * `awake` tiles in all (summed over the ranks): its share of the active
 * fraction (the mean over its passes) and of the swept cells' rate. */
void ss_sweeper_count_superstep(struct ss_sweeper *w, double awake, int evaluations);

/* A pass of an RKL2 stage (or the estimate after the last: sweep.h), from
 * the halo and the ring rows it fills first unless `measured` (stage 1:
 * ss_sweeper_measure did).  Returns what the sweep returns on this rank;
 * the tiles it swept here are added to *awake. */
double ss_sweeper_stage(struct ss_stepper *st, const struct ss_sweep_stage *stage, int last,
                        int measured, double *awake);

#endif
