/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * ledger.h - the stepper's volume ledger (doc/model.md#conservation): the
 * volume poured in (inflow), gone out through open cells (outflow) and put
 * in or taken out from outside by writing heights (external), each a
 * compensated sum, so that
 *
 *   volume = initial + inflow - outflow + external
 *
 * holds to round-off however many substeps are added up.  The outflow is
 * metered on the open faces, the faces from a flow cell to an open cell,
 * which the ledger lists (the sweeper writes their fluxes, sweeper.h).
 *
 * What an evaluation's outflow rate r (m^3/s) adds, an entry of the
 * ledger: forward Euler adds dt r; RKL2's stage j combines it as the
 * heights are combined (rkl2.h),
 *
 *   O_j = (mu O_{j-1} + nu O_{j-2}) + (tau mu~ r_j + tau gamma~ r_1),
 *
 * from O_0 = O_{-1} = 0, and the last stage adds O_s.
 *
 * The outflow on several ranks: the outflow of an evaluation is a sum over
 * the open faces in list order, and the list of the whole grid is the
 * ranks' lists in rank order, so each rank's part continues the sum the
 * rank before it ended with: summed each evaluation that is a chain of
 * P - 1 messages.  Instead, with more than one rank and open faces, each
 * rank keeps its faces' non-zero fluxes of each evaluation in a batch of
 * batch_bytes and room for one more evaluation's (8 B an open face of the
 * rank), and the ranks fold the batch in one pass (P - 1 messages for the
 * whole batch) when ss_stepper_advance returns, when ss_stepper_diagnostics
 * is called and when the batch is full, then add each evaluation to the
 * ledger as one rank would have: the same bits (ledger.c says how).  So
 * the outflow is that of the current state between calls to
 * ss_stepper_advance; inside its progress callback it may lag (several
 * ranks only).  One rank adds each evaluation at once.
 *
 * Every function that sums over the ranks is collective (comm.h).
 */
#ifndef SANDSLIDE_CORE_LEDGER_H
#define SANDSLIDE_CORE_LEDGER_H

#include <stddef.h>
#include <stdint.h>

#include "core/sweep.h"
#include "sandslide/diagnostics.h"
#include "sandslide/grid.h"

/* The outflow batch's bytes a rank unless batch_bytes says otherwise. */
#define SS_LEDGER_BATCH_BYTES ((size_t)4 << 20)

/* What an evaluation is to the ledger: kind, and an RKL2 stage's weights. */
enum {
	SS_LEDGER_EULER = 0,    /* a forward-Euler step */
	SS_LEDGER_STAGE = 1,    /* an RKL2 stage, */
	SS_LEDGER_FIRST = 2,    /*   the first of its super-step */
	SS_LEDGER_LAST = 4,     /*   the last: O_s is added */
};

struct ss_ledger_entry {
	double mu, nu, tau_mu, tau_gamma;   /* the stage's (ss_sweep_stage);
	                                     * Euler: dt in tau_mu */
	int kind;
};

struct ss_outflow_batch;

struct ss_ledger {
	struct ss_volume_sum inflow;   /* m^3 */
	struct ss_volume_sum outflow;  /* (on several ranks: as of the last fold) */
	struct ss_volume_sum external;
	double *row_volume;               /* a row each: the volume of the state
	                                   * by rows (ss_stepper_diagnostics) */
	struct ss_open_face *open_faces;  /* this rank's, in row order */
	size_t open_face_count;           /* on this rank */
	double open_face_count_all;       /* on every rank */
	double *open_flux;                /* m^2/s through each open face, as the
	                                   * last pass left it (sweeper.h) */
	double stage_1, stage_2, stage_m0; /* RKL2: O_{j-1}, O_{j-2} and r_1 of
	                                    * the super-step so far */
	size_t batch_bytes;               /* set before ss_stepper_prepare; 0:
	                                   * SS_LEDGER_BATCH_BYTES (a test hook
	                                   * sets it, tests/hooks/batch_step.c) */
	struct ss_outflow_batch *batch;   /* several ranks with open faces, else
	                                   * NULL: ledger.c */
};

/* A zeroed ledger on the heap, for a block of `rows` rows (NULL and
 * SS_ERR_FAIL if it cannot be). */
int ss_ledger_create(struct ss_ledger **out, int rows);
void ss_ledger_destroy(struct ss_ledger *l);

/* The total of a compensated sum, m^3. */
static inline double ss_volume_sum_total(const struct ss_volume_sum *v)
{
	return v->sum + v->carry;
}

/*
 * Once the cell types are final (halo included): list this rank's open
 * faces and their fluxes, then (collective, after every rank's lists are
 * made and agreed on) ss_ledger_prepare_batch, whose allocation the caller
 * agrees on too, then ss_ledger_agree_batch.  Each allocates or sums as
 * its name says; SS_ERR_FAIL when an allocation fails.
 */
int ss_ledger_list_open_faces(struct ss_ledger *l, const struct ss_grid *g,
                              const uint8_t *cell_types);
int ss_ledger_prepare_batch(struct ss_ledger *l);
void ss_ledger_agree_batch(struct ss_ledger *l);

/* Volume poured in (m^3) and put in from outside (m^3, signed). */
void ss_ledger_add_inflow(struct ss_ledger *l, double volume);
void ss_ledger_add_external(struct ss_ledger *l, double volume);

/* The outflow of the open fluxes the sweeper just wrote, as entry e: added
 * at once, or kept in the batch (perhaps after folding it: collective). */
void ss_ledger_add_outflow(struct ss_ledger *l, const struct ss_grid *g,
                           const struct ss_ledger_entry *e);

/* Fold the batch over the ranks and add its entries (collective; nothing
 * when it is empty, which every rank knows alike). */
void ss_ledger_flush(struct ss_ledger *l, const struct ss_grid *g);

/*
 * The batch's room, for the reduction that ends each step (stepper.c):
 * the evaluations that surely fit in this rank's terms now, and, once the
 * minimum over the ranks is known, that minimum.  Only with a batch.
 */
double ss_ledger_room_here(const struct ss_ledger *l);
void ss_ledger_room_agreed(struct ss_ledger *l, double least);

#endif
