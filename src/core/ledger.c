/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * ledger.c - the stepper's volume ledger and, on several ranks, its
 * outflow batch (see ledger.h).
 *
 * One rank applies each entry at once.  On several ranks with open faces
 * r = sum_x dy + sum_y dx, with sum_x the left fold ((+0 + t_1) + t_2) + ...
 * of the x-faces' signed fluxes t in the order of the whole grid's list
 * (sum_y likewise), which is the ranks' lists in rank order: rank q's part
 * continues the sum rank q - 1 ended with.  Each rank keeps, per
 * evaluation, its own non-zero terms in list order (x-faces, then
 * y-faces), and every rank the entry (the same on all).  A flush starts
 * 2 K running sums at +0 for the K evaluations kept, carries them from
 * rank to rank once (ss_comm_fold_start/finish: P - 1 messages of 16 K
 * bytes, then a broadcast), each rank continuing each with its terms, and
 * applies the K entries in order with the totals: the operations of one
 * rank on the same values, so the same bits.
 *
 * Zero terms are left out: a running sum that starts at +0 is never -0
 * (an IEEE sum is -0 only when both operands are, an exact cancellation
 * gives +0), and s + (+0) = s + (-0) = s for every s but -0.  NaN terms are
 * kept (NaN != 0).
 *
 * The batch holds entries_max evaluations (same on every rank) and this
 * rank terms_max terms; the flush comes before an evaluation that might
 * not fit.  Whether it fits must be the same answer on every rank:
 * `fits` is how many more evaluations surely fit on every rank, each
 * taking at most its open_face_count terms there; it counts down each
 * evaluation, and the reduction that ends each step (stepper.c) sets it to
 * min over ranks of (terms_max - terms_used) / open_face_count.  When it
 * runs out between those (an RKL2 super-step's stages), one reduction asks
 * the same, and only if that says no the batch is folded.
 */
#include "core/ledger.h"

#include <limits.h>
#include <math.h>
#include <string.h>

#include "sandslide/comm.h"
#include "sandslide/error.h"

struct ss_outflow_batch {
	int entries_max, count;       /* evaluations: room, kept (every rank) */
	double fits, fits_empty;      /* evaluations that surely fit now, and
	                               * after a flush (every rank) */
	int fits_measured;            /* fits is the room measured, not a
	                               * count down since */
	size_t terms_max, terms_used; /* this rank's */
	struct ss_ledger_entry *entries;
	size_t *ends;                 /* 2 a evaluation: the end of its x-face
	                               * terms, then of its y-face terms */
	double *running;              /* 2 a evaluation: sum_x, sum_y */
	double *terms;
};

/* Bytes of the batch a kept evaluation takes besides its terms. */
#define ENTRY_BYTES \
	(sizeof(struct ss_ledger_entry) + 2 * sizeof(size_t) + 2 * sizeof(double))

int ss_ledger_create(struct ss_ledger **out, int rows)
{
	struct ss_ledger *l = ss_alloc(1, sizeof *l, "volume ledger");
	*out = l;
	if (!l)
		return SS_ERR_FAIL;
	memset(l, 0, sizeof *l);
	l->row_volume = ss_alloc((size_t)rows, sizeof(double), "row sums");
	return l->row_volume ? SS_OK : SS_ERR_FAIL;
}

static void batch_destroy(struct ss_outflow_batch *b)
{
	if (!b)
		return;
	ss_free(b->terms);
	ss_free(b->running);
	ss_free(b->ends);
	ss_free(b->entries);
	ss_free(b);
}

void ss_ledger_destroy(struct ss_ledger *l)
{
	if (!l)
		return;
	batch_destroy(l->batch);
	ss_free(l->open_flux);
	ss_free(l->open_faces);
	ss_free(l->row_volume);
	ss_free(l);
}

/* Neumaier's compensated sum: v->sum + v->carry holds the total of every
 * term to about one rounding, however many substeps are added up. */
static void add_compensated(struct ss_volume_sum *v, double term)
{
	const double t = v->sum + term;
	if (fabs(v->sum) >= fabs(term))
		v->carry += (v->sum - t) + term;
	else
		v->carry += (term - t) + v->sum;
	v->sum = t;
}

void ss_ledger_add_inflow(struct ss_ledger *l, double volume)
{
	add_compensated(&l->inflow, volume);
}

void ss_ledger_add_external(struct ss_ledger *l, double volume)
{
	add_compensated(&l->external, volume);
}

int ss_ledger_list_open_faces(struct ss_ledger *l, const struct ss_grid *g,
                              const uint8_t *cell_types)
{
	const uint8_t *t = cell_types;
	const ptrdiff_t stride = g->stride;
	/* two passes: count, then fill (axis, neighbour offset, sign) */
	for (int pass = 0; pass < 2; pass++) {
		size_t n = 0;
		for (int j = 0; j < g->ny; j++) {
			for (int i = 0; i < g->nx; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(t, k) != SS_CELL_FLOW)
					continue;
				/* west, east, south, north faces of flow cell k */
				const struct ss_open_face f[4] = {
					{k, 0, -1}, {k + 1, 0, +1},
					{k, 1, -1}, {k + stride, 1, +1},
				};
				const ptrdiff_t nb[4] = {k - 1, k + 1, k - stride, k + stride};
				for (int m = 0; m < 4; m++) {
					if (ss_cell_type_get(t, nb[m]) != SS_CELL_OPEN)
						continue;
					if (pass == 1)
						l->open_faces[n] = f[m];
					n++;
				}
			}
		}
		if (pass == 0) {
			l->open_face_count = n;
			l->open_faces = ss_alloc(n ? n : 1, sizeof *l->open_faces,
			                         "open face list");
			if (!l->open_faces)
				return SS_ERR_FAIL;
		}
	}
	l->open_flux = ss_alloc(l->open_face_count ? l->open_face_count : 1, sizeof(double),
	                        "open-face fluxes");
	return l->open_flux ? SS_OK : SS_ERR_FAIL;
}

/* Volume leaving through open faces per second with the current fluxes,
 * on one rank (or none open anywhere); summed in list order, so the same
 * bits for any thread count and kernel. */
static double outflow_rate(const struct ss_ledger *l, const struct ss_grid *g)
{
	if (l->open_face_count_all == 0.0)
		return 0.0;
	/* two sums in registers: sum[f->axis] would go through memory */
	double sum_x = 0.0, sum_y = 0.0;   /* x-faces, y-faces */
	for (size_t m = 0; m < l->open_face_count; m++) {
		const struct ss_open_face *f = &l->open_faces[m];
		const double flux = l->open_flux[m];
		if (f->axis == 0)
			sum_x += f->sign * flux;
		else
			sum_y += f->sign * flux;
	}
	return sum_x * g->dy + sum_y * g->dx;
}

double ss_ledger_room_here(const struct ss_ledger *l)
{
	const struct ss_outflow_batch *b = l->batch;
	if (l->open_face_count == 0)
		return INFINITY;
	return floor((double)(b->terms_max - b->terms_used) / (double)l->open_face_count);
}

void ss_ledger_room_agreed(struct ss_ledger *l, double least)
{
	l->batch->fits = least;
	l->batch->fits_measured = 1;
}

/* With several ranks and open faces anywhere (counted here: collective),
 * the batch: a quarter of batch_bytes for the evaluations, the rest for
 * the terms, and one more evaluation's terms (8 B a face of this rank). */
int ss_ledger_prepare_batch(struct ss_ledger *l)
{
	double none = 0.0;
	l->open_face_count_all = (double)l->open_face_count;
	ss_comm_reduce(&none, 0, &l->open_face_count_all, 1);
	if (!(ss_comm_size() > 1 && l->open_face_count_all > 0.0))
		return SS_OK;
	struct ss_outflow_batch *b = ss_alloc(1, sizeof *b, "outflow batch");
	if (!b)
		return SS_ERR_FAIL;
	memset(b, 0, sizeof *b);
	l->batch = b;
	const size_t bytes = l->batch_bytes ? l->batch_bytes : SS_LEDGER_BATCH_BYTES;
	size_t entries = bytes / 4 / ENTRY_BYTES;
	entries = entries < 1 ? 1 : entries > (size_t)INT_MAX / 2 ? (size_t)INT_MAX / 2 : entries;
	const size_t left = bytes > entries * ENTRY_BYTES ? bytes - entries * ENTRY_BYTES : 0;
	/* and room for one more evaluation's, every face, so that the batch
	 * is folded only when the terms kept (not the faces) pass the bytes;
	 * no more than every face of every evaluation */
	const size_t faces = l->open_face_count;
	size_t terms = left / sizeof(double) + faces;
	terms = terms > entries * faces ? entries * faces : terms;
	b->entries_max = (int)entries;
	b->terms_max = terms;
	b->entries = ss_alloc(entries, sizeof *b->entries, "outflow batch");
	b->ends = ss_alloc(2 * entries, sizeof *b->ends, "outflow batch");
	b->running = ss_alloc(2 * entries, sizeof *b->running, "outflow batch");
	b->terms = ss_alloc(terms ? terms : 1, sizeof *b->terms, "outflow batch");
	if (!b->entries || !b->ends || !b->running || !b->terms)
		return SS_ERR_FAIL;
	return SS_OK;
}

/* After ss_ledger_prepare_batch on every rank: the room every rank has. */
void ss_ledger_agree_batch(struct ss_ledger *l)
{
	struct ss_outflow_batch *b = l->batch;
	if (!b)
		return;
	/* minima as maxima of the negatives: whole numbers, exact */
	double least[2] = {-ss_ledger_room_here(l), -(double)b->entries_max};
	ss_comm_reduce(least, 2, NULL, 0);
	b->fits = b->fits_empty = -least[0];
	b->fits_measured = 1;
	b->entries_max = (int)-least[1];
}

/* Apply an entry of the ledger with the evaluation's rate r, m^3/s. */
static void apply(struct ss_ledger *l, const struct ss_ledger_entry *e, double r)
{
	if (e->kind == SS_LEDGER_EULER) {
		add_compensated(&l->outflow, e->tau_mu * r);
		return;
	}
	const struct ss_sweep_stage stage = {
		.mu = e->mu, .nu = e->nu, .tau_mu = e->tau_mu, .tau_gamma = e->tau_gamma,
	};
	const int first = e->kind & SS_LEDGER_FIRST;
	if (first) {
		l->stage_1 = l->stage_2 = 0.0;
		l->stage_m0 = r;
	}
	const double out_j = ss_sweep_stage_delta(&stage, l->stage_1, l->stage_2, r, l->stage_m0);
	l->stage_2 = first ? 0.0 : l->stage_1;
	l->stage_1 = out_j;
	if (e->kind & SS_LEDGER_LAST)
		add_compensated(&l->outflow, l->stage_1);
}

void ss_ledger_flush(struct ss_ledger *l, const struct ss_grid *g)
{
	struct ss_outflow_batch *b = l->batch;
	if (!b || b->count == 0)
		return;
	const int n = 2 * b->count;
	double *run = b->running;
	for (int k = 0; k < n; k++)
		run[k] = 0.0;
	ss_comm_fold_start(run, n);
	size_t m = 0;
	for (int k = 0; k < b->count; k++) {
		double sum_x = run[2 * k], sum_y = run[2 * k + 1];
		for (; m < b->ends[2 * k]; m++)
			sum_x += b->terms[m];
		for (; m < b->ends[2 * k + 1]; m++)
			sum_y += b->terms[m];
		run[2 * k] = sum_x;
		run[2 * k + 1] = sum_y;
	}
	ss_comm_fold_finish(run, n);
	for (int k = 0; k < b->count; k++)
		apply(l, &b->entries[k], run[2 * k] * g->dy + run[2 * k + 1] * g->dx);
	b->count = 0;
	b->terms_used = 0;
	b->fits = b->fits_empty;
	b->fits_measured = 1;
}

/* This rank's non-zero signed fluxes of one axis, in list order, appended
 * at *used. */
static void keep_axis(const struct ss_ledger *l, int axis, double *terms, size_t *used)
{
	size_t n = *used;
	for (size_t m = 0; m < l->open_face_count; m++) {
		const struct ss_open_face *f = &l->open_faces[m];
		if (f->axis != axis)
			continue;
		const double t = f->sign * l->open_flux[m];
		if (t != 0.0)
			terms[n++] = t;
	}
	*used = n;
}

void ss_ledger_add_outflow(struct ss_ledger *l, const struct ss_grid *g,
                           const struct ss_ledger_entry *e)
{
	struct ss_outflow_batch *b = l->batch;
	if (!b) {
		apply(l, e, outflow_rate(l, g));
		return;
	}
	if (b->fits < 1.0 && !b->fits_measured && b->count < b->entries_max) {
		/* the guess ran out (RKL2 stages: no reduction between them):
		 * ask every rank, one reduction, before folding */
		double least = -ss_ledger_room_here(l);
		ss_comm_reduce(&least, 1, NULL, 0);
		b->fits = -least;
	}
	if (b->count == b->entries_max || b->fits < 1.0)
		ss_ledger_flush(l, g);
	const int k = b->count;
	keep_axis(l, 0, b->terms, &b->terms_used);
	b->ends[2 * k] = b->terms_used;
	keep_axis(l, 1, b->terms, &b->terms_used);
	b->ends[2 * k + 1] = b->terms_used;
	b->entries[k] = *e;
	b->count++;
	b->fits -= 1.0;
	b->fits_measured = 0;
}
