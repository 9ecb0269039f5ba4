/*
 * stepper.c - adaptive forward-Euler substeps, events and accounting (see
 * stepper.h for the rules).
 */
#include "sandslide/stepper.h"

#include <limits.h>
#include <math.h>
#include <string.h>

#include "sandslide/comm.h"
#include "sandslide/cpu.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/rkl2.h"

static void outflow_batch_release(struct ss_stepper *st);

static const char *const integrator_names[] = {
	[SS_INTEGRATOR_EULER] = "euler", [SS_INTEGRATOR_RKL2] = "rkl2",
	[SS_INTEGRATOR_AUTO] = "auto",
};

const char *ss_integrator_name(enum ss_integrator integrator)
{
	return integrator_names[integrator];
}

int ss_integrator_parse(const char *name, enum ss_integrator *out)
{
	for (int k = 0; k < 3; k++) {
		if (strcmp(name, integrator_names[k]) == 0) {
			*out = (enum ss_integrator)k;
			return 0;
		}
	}
	return -1;
}

enum ss_integrator ss_integrator_resolve(enum ss_integrator asked, int has_bedrock)
{
	if (asked != SS_INTEGRATOR_AUTO)
		return asked;
	return has_bedrock ? SS_INTEGRATOR_EULER : SS_INTEGRATOR_RKL2;
}

double ss_stepper_memory_bytes(const struct ss_grid *g, enum ss_integrator integrator)
{
	/* height and source_rate (doubles) and the packed types, and RKL2's
	 * Y_0, D_{j-1}, D_{j-2} and M(Y_0); the fast sweep's ring rows and
	 * buffers are below 2 % of that */
	const double doubles = integrator == SS_INTEGRATOR_RKL2 ? 6.0 : 2.0;
	return (double)ss_grid_storage_cells(g) * (doubles * sizeof(double) + 0.25);
}

void ss_stepper_slab_rows(const struct ss_grid *g, int tile_nx, int tile_ny, int rank,
                          int *first_row, int *rows)
{
	struct ss_tiling t;
	ss_tiling_init(&t, g, tile_nx, tile_ny);
	long long first = 0, count = t.tiles_y;
	if (ss_comm_size() > 1)
		ss_comm_split_of(t.tiles_y, rank, &first, &count);
	const long long j0 = first * t.tile_ny, j1 = (first + count) * t.tile_ny;
	*first_row = (int)(j0 < g->ny ? j0 : g->ny);
	*rows = (int)((j1 < g->ny ? j1 : g->ny) - *first_row);
}

int ss_stepper_init(struct ss_stepper *st, const struct ss_grid *g,
                    const struct ss_closure *c, const struct ss_boundary *b,
                    double cfl, int tile_nx, int tile_ny)
{
	memset(st, 0, sizeof *st);
	if (!(cfl > 0.0 && cfl <= 1.0))
		return ss_error_input("cfl %g is outside (0, 1]", cfl);
	/* the kernel path SANDSLIDE_CPU names (cpu.h), for a program of one
	 * process that did not check it first as the command line does (in a
	 * distributed run ss_cpu_init is collective: the program calls it) */
	int err = ss_comm_size() == 1 ? ss_cpu_init() : SS_OK;
	if (err)
		return err;
	err = ss_boundary_check(b);
	if (err)
		return err;

	/* the tiling of the whole grid, then this rank's run of tile rows */
	ss_tiling_init(&st->tiling, g, tile_nx, tile_ny);
	const long long tile_rows = st->tiling.tiles_y;
	if (ss_comm_size() > tile_rows)
		return ss_error_input("%d ranks for a grid of %lld tile rows (ny = %lld cells, "
		                      "tiles of %d rows): use at most %lld ranks", ss_comm_size(),
		                      tile_rows, g->global_ny, st->tiling.tile_ny, tile_rows);
	st->tiles_all = (double)st->tiling.tiles_x * (double)tile_rows;
	st->grid = *g;
	if (ss_comm_size() > 1) {
		int first_row, rows;
		ss_stepper_slab_rows(g, tile_nx, tile_ny, ss_comm_rank(), &first_row, &rows);
		ss_grid_take_rows(&st->grid, first_row, rows);
		st->tiling.tiles_y = (rows + st->tiling.tile_ny - 1) / st->tiling.tile_ny;
	}
	g = &st->grid;
	ss_boundary_neighbours(g, b, &st->rank_south, &st->rank_north);
	st->closure = *c;
	st->boundary = *b;
	st->cfl = cfl;
	st->rkl2_tau = INFINITY;
	ss_cfl_bound_init(&st->cfl_bound, c);
	ss_face_rule_init(&st->face_rule, c);

	const size_t n = ss_grid_storage_cells(g);
	st->height = ss_alloc(n, sizeof(double), "heights");
	st->cell_types = ss_alloc(ss_cell_types_bytes(n), 1, "cell types");
	st->row_scratch = ss_alloc((size_t)g->ny, sizeof(double), "row sums");
	st->edges_in = ss_alloc(2 * (size_t)st->tiling.tiles_x, 1, "tile flags");
	if (!st->height || !st->cell_types || !st->row_scratch || !st->edges_in) {
		ss_stepper_release(st);
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

void ss_stepper_release(struct ss_stepper *st)
{
	for (int k = 0; k < st->source_count; k++)
		ss_free(st->sources[k].cells);
	ss_free(st->sources);
	ss_free(st->open_faces);
	ss_free(st->open_flux);
	outflow_batch_release(st);
	ss_sweep_fast_release(&st->fast);
	ss_free(st->rkl2_m0);
	ss_free(st->rkl2_d2);
	ss_free(st->rkl2_d1);
	ss_free(st->rkl2_y0);
	ss_free(st->bedrock);
	ss_free(st->source_rate);
	ss_free(st->rate_field);
	ss_free(st->edges_in);
	ss_free(st->row_scratch);
	ss_free(st->flux_y);
	ss_free(st->flux_x);
	ss_free(st->cell_type_bytes);
	ss_free(st->cell_types);
	ss_free(st->height);
	memset(st, 0, sizeof *st);
}

int ss_stepper_add_source(struct ss_stepper *st, const uint8_t *mask,
                          double rate, double start, double stop)
{
	const struct ss_grid *g = &st->grid;
	if (st->source_count >= SS_MAX_SOURCES)
		return ss_error_input("at most %d sources are supported", SS_MAX_SOURCES);
	if (!st->sources) {
		st->sources = ss_alloc(SS_MAX_SOURCES, sizeof *st->sources, "sources");
		if (!st->sources)
			return SS_ERR_FAIL;
	}
	size_t count = 0;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			count += mask[(size_t)j * g->nx + i] &&
			         ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j)) ==
			         SS_CELL_FLOW;
	struct ss_source *s = &st->sources[st->source_count];
	double none = 0.0;
	s->cell_count_all = (double)count;
	ss_comm_reduce(&none, 0, &s->cell_count_all, 1);
	s->cells = ss_alloc(count ? count : 1, sizeof *s->cells, "source cells");
	if (!s->cells)
		return SS_ERR_FAIL;
	size_t n = 0;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (mask[(size_t)j * g->nx + i] &&
			    ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				s->cells[n++] = k;
		}
	}
	s->cell_count = n;
	s->rate = rate;
	s->start = start;
	s->stop = stop;
	st->source_count++;
	return SS_OK;
}

int ss_stepper_set_bedrock(struct ss_stepper *st, const double *bedrock)
{
	const struct ss_grid *g = &st->grid;
	if (!st->bedrock) {
		st->bedrock = ss_alloc(ss_grid_storage_cells(g), sizeof(double), "bedrock");
		if (!st->bedrock)
			return SS_ERR_FAIL;
	}
	for (size_t k = 0; k < ss_grid_storage_cells(g); k++)
		st->bedrock[k] = -INFINITY;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const double b = bedrock[(size_t)j * g->nx + i];
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (!isfinite(b))
				return ss_error_input("bedrock of cell (%lld, %lld) at x = %g m, y = %g m "
				                      "is %g: it must be finite", g->offset_i + i,
				                      g->offset_j + j, ss_grid_x(g, i), ss_grid_y(g, j), b);
			if (ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				st->bedrock[k] = b;
		}
	}
	return SS_OK;
}

/* Neumaier's compensated sum: *sum + *carry holds the total of every term
 * to about one rounding, however many substeps are added up. */
static void add_compensated(double *sum, double *carry, double term)
{
	const double t = *sum + term;
	if (fabs(*sum) >= fabs(term))
		*carry += (*sum - t) + term;
	else
		*carry += (term - t) + *sum;
	*sum = t;
}

/* Volume leaving through open faces per second with the current fluxes,
 * on one rank (or none open anywhere); summed in list order, so the same
 * bits for any thread count and kernel. */
static double outflow_rate(const struct ss_stepper *st)
{
	if (st->open_face_count_all == 0.0)
		return 0.0;
	/* two sums in registers: sum[f->axis] would go through memory */
	double sum_x = 0.0, sum_y = 0.0;   /* x-faces, y-faces */
	for (size_t m = 0; m < st->open_face_count; m++) {
		const struct ss_open_face *f = &st->open_faces[m];
		const double flux = st->kernel == SS_KERNEL_FAST ? st->open_flux[m]
		                  : f->axis == 0 ? st->flux_x[f->index] : st->flux_y[f->index];
		if (f->axis == 0)
			sum_x += f->sign * flux;
		else
			sum_y += f->sign * flux;
	}
	return sum_x * st->grid.dy + sum_y * st->grid.dx;
}

/*
 * The outflow ledger and, on several ranks, its batch (stepper.h).
 *
 * What an evaluation's outflow rate r (m^3/s) does to outflow_sum and
 * outflow_carry, an entry of the ledger: forward Euler adds dt r; RKL2's
 * stage j combines it as the heights are combined (rkl2_superstep),
 *
 *   O_j = (mu O_{j-1} + nu O_{j-2}) + (tau mu~ r_j + tau gamma~ r_1),
 *
 * from O_0 = O_{-1} = 0, and the last stage adds O_s.
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
 * evaluation, and the reduction that ends each step (step_end) sets it to
 * min over ranks of (terms_max - terms_used) / open_face_count.  When it
 * runs out between those (an RKL2 super-step's stages), one reduction asks
 * the same, and only if that says no the batch is folded.
 */
enum {
	OUTFLOW_EULER = 0,      /* a forward-Euler step */
	OUTFLOW_STAGE = 1,      /* an RKL2 stage, */
	OUTFLOW_FIRST = 2,      /*   the first of its super-step */
	OUTFLOW_LAST = 4,       /*   the last: O_s is added */
};

struct outflow_entry {
	double mu, nu, tau_mu, tau_gamma;   /* the stage's (ss_sweep_stage);
	                                     * Euler: dt in tau_mu */
	int kind;
};

struct ss_outflow_batch {
	double out_1, out_2, out_m0;  /* RKL2: O_{j-1}, O_{j-2}, r_1 so far */
	int on;                       /* several ranks, open faces: batched */
	int entries_max, count;       /* evaluations: room, kept (every rank) */
	double fits, fits_empty;      /* evaluations that surely fit now, and
	                               * after a flush (every rank) */
	int fits_measured;            /* fits is the room measured, not a
	                               * count down since */
	size_t terms_max, terms_used; /* this rank's */
	struct outflow_entry *entries;
	size_t *ends;                 /* 2 a evaluation: the end of its x-face
	                               * terms, then of its y-face terms */
	double *running;              /* 2 a evaluation: sum_x, sum_y */
	double *terms;
};

/* Bytes of the batch a kept evaluation takes besides its terms. */
#define OUTFLOW_ENTRY_BYTES \
	(sizeof(struct outflow_entry) + 2 * sizeof(size_t) + 2 * sizeof(double))

static void outflow_batch_release(struct ss_stepper *st)
{
	struct ss_outflow_batch *b = st->outflow_batch;
	if (!b)
		return;
	ss_free(b->terms);
	ss_free(b->running);
	ss_free(b->ends);
	ss_free(b->entries);
	ss_free(b);
	st->outflow_batch = NULL;
}

/* Evaluations that surely fit in this rank's terms now. */
static double outflow_fits_here(const struct ss_stepper *st)
{
	const struct ss_outflow_batch *b = st->outflow_batch;
	if (st->open_face_count == 0)
		return INFINITY;
	return floor((double)(b->terms_max - b->terms_used) / (double)st->open_face_count);
}

/* The ledger and, on several ranks with open faces, the batch: a quarter
 * of outflow_batch_bytes for the evaluations, the rest for the terms, and
 * one more evaluation's terms (8 B a face of this rank).  Allocates (the
 * caller agrees on failure). */
static int outflow_batch_init(struct ss_stepper *st)
{
	struct ss_outflow_batch *b = ss_alloc(1, sizeof *b, "outflow ledger");
	if (!b)
		return SS_ERR_FAIL;
	memset(b, 0, sizeof *b);
	st->outflow_batch = b;
	b->on = ss_comm_size() > 1 && st->open_face_count_all > 0.0;
	if (!b->on)
		return SS_OK;
	const size_t bytes = st->outflow_batch_bytes ? st->outflow_batch_bytes
	                                             : SS_OUTFLOW_BATCH_BYTES;
	size_t entries = bytes / 4 / OUTFLOW_ENTRY_BYTES;
	entries = entries < 1 ? 1 : entries > (size_t)INT_MAX / 2 ? (size_t)INT_MAX / 2 : entries;
	const size_t left = bytes > entries * OUTFLOW_ENTRY_BYTES
	                  ? bytes - entries * OUTFLOW_ENTRY_BYTES : 0;
	/* and room for one more evaluation's, every face, so that the batch
	 * is folded only when the terms kept (not the faces) pass the bytes;
	 * no more than every face of every evaluation */
	const size_t faces = st->open_face_count;
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

/* After outflow_batch_init on every rank: the room every rank has
 * (collective). */
static void outflow_batch_agree(struct ss_stepper *st)
{
	struct ss_outflow_batch *b = st->outflow_batch;
	if (!b->on)
		return;
	/* minima as maxima of the negatives: whole numbers, exact */
	double least[2] = {-outflow_fits_here(st), -(double)b->entries_max};
	ss_comm_reduce(least, 2, NULL, 0);
	b->fits = b->fits_empty = -least[0];
	b->fits_measured = 1;
	b->entries_max = (int)-least[1];
}

/* Apply an entry of the ledger with the evaluation's rate r, m^3/s. */
static void ledger_apply(struct ss_stepper *st, const struct outflow_entry *e, double r)
{
	struct ss_outflow_batch *b = st->outflow_batch;
	if (e->kind == OUTFLOW_EULER) {
		add_compensated(&st->outflow_sum, &st->outflow_carry, e->tau_mu * r);
		return;
	}
	const struct ss_sweep_stage stage = {
		.mu = e->mu, .nu = e->nu, .tau_mu = e->tau_mu, .tau_gamma = e->tau_gamma,
	};
	const int first = e->kind & OUTFLOW_FIRST;
	if (first) {
		b->out_1 = b->out_2 = 0.0;
		b->out_m0 = r;
	}
	const double out_j = ss_sweep_stage_delta(&stage, b->out_1, b->out_2, r, b->out_m0);
	b->out_2 = first ? 0.0 : b->out_1;
	b->out_1 = out_j;
	if (e->kind & OUTFLOW_LAST)
		add_compensated(&st->outflow_sum, &st->outflow_carry, b->out_1);
}

/* Fold the batch over the ranks and apply its entries (collective; nothing
 * when it is empty, which every rank knows alike). */
static void outflow_flush(struct ss_stepper *st)
{
	struct ss_outflow_batch *b = st->outflow_batch;
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
		ledger_apply(st, &b->entries[k], run[2 * k] * st->grid.dy + run[2 * k + 1] * st->grid.dx);
	b->count = 0;
	b->terms_used = 0;
	b->fits = b->fits_empty;
	b->fits_measured = 1;
	st->outflow = st->outflow_sum + st->outflow_carry;
}

/* This rank's non-zero signed fluxes of one axis, in list order, from the
 * fluxes the sweep just wrote, appended at *used. */
static void outflow_keep_axis(const struct ss_stepper *st, int axis, double *terms,
                              size_t *used)
{
	size_t n = *used;
	for (size_t m = 0; m < st->open_face_count; m++) {
		const struct ss_open_face *f = &st->open_faces[m];
		if (f->axis != axis)
			continue;
		const double flux = st->kernel == SS_KERNEL_FAST ? st->open_flux[m]
		                  : axis == 0 ? st->flux_x[f->index] : st->flux_y[f->index];
		const double t = f->sign * flux;
		if (t != 0.0)
			terms[n++] = t;
	}
	*used = n;
}

/* The outflow of the fluxes the sweep just wrote, into the ledger with
 * entry e: at once, or kept in the batch. */
static void outflow_account(struct ss_stepper *st, const struct outflow_entry *e)
{
	struct ss_outflow_batch *b = st->outflow_batch;
	if (!b->on) {
		ledger_apply(st, e, outflow_rate(st));
		return;
	}
	if (b->fits < 1.0 && !b->fits_measured && b->count < b->entries_max) {
		/* the guess ran out (RKL2 stages: no reduction between them):
		 * ask every rank, one reduction, before folding */
		double least = -outflow_fits_here(st);
		ss_comm_reduce(&least, 1, NULL, 0);
		b->fits = -least;
	}
	if (b->count == b->entries_max || b->fits < 1.0)
		outflow_flush(st);
	const int k = b->count;
	outflow_keep_axis(st, 0, b->terms, &b->terms_used);
	b->ends[2 * k] = b->terms_used;
	outflow_keep_axis(st, 1, b->terms, &b->terms_used);
	b->ends[2 * k + 1] = b->terms_used;
	b->entries[k] = *e;
	b->count++;
	b->fits -= 1.0;
	b->fits_measured = 0;
}

static int open_faces_build(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const uint8_t *t = st->cell_types;
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
						st->open_faces[n] = f[m];
					n++;
				}
			}
		}
		if (pass == 0) {
			st->open_face_count = n;
			st->open_faces = ss_alloc(n ? n : 1, sizeof *st->open_faces,
			                          "open face list");
			if (!st->open_faces)
				return SS_ERR_FAIL;
		}
	}
	return SS_OK;
}

/* Forward Euler's step for every slope the closure has (stepper.h): the
 * unit of RKL2's super-steps, s. */
static double rkl2_dt_all(const struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	return st->cfl / (2.0 * st->closure.nu *
	                  ss_cfl_bound_lookup(&st->cfl_bound, HUGE_VAL) * inv_d2);
}

/* The first super-steps are at most RKL2_START_STAGES stages long, and the
 * limit grows from there by at most 2x a super-step (rkl2_control): a run
 * starts with no measure of how fast its state changes. */
#define RKL2_START_STAGES 4

/* RKL2's arrays: Y_0 = the heights, D = 0 and M(Y_0) = 0 everywhere, as
 * after a super-step in which nothing moved (the fast sweep relies on it
 * for the tiles it skips). */
static int rkl2_prepare(struct ss_stepper *st)
{
	if (st->bedrock)
		return ss_error_input("the rkl2 integrator cannot be used with a bedrock: its "
		                      "stages cannot keep the sand above the rock; use euler");
	if (st->rkl2_max_stages < 2 || !(st->rkl2_tol > 0.0))
		SS_BUG("rkl2_max_stages %d, rkl2_tol %g: set them before ss_stepper_prepare, "
		       "in the model options' range (model_options.h)", st->rkl2_max_stages,
		       st->rkl2_tol);
	const size_t n = ss_grid_storage_cells(&st->grid);
	st->rkl2_y0 = ss_alloc(n, sizeof(double), "RKL2 Y_0");
	st->rkl2_d1 = ss_alloc(n, sizeof(double), "RKL2 D_{j-1}");
	st->rkl2_d2 = ss_alloc(n, sizeof(double), "RKL2 D_{j-2}");
	st->rkl2_m0 = ss_alloc(n, sizeof(double), "RKL2 M(Y_0)");
	if (!st->rkl2_y0 || !st->rkl2_d1 || !st->rkl2_d2 || !st->rkl2_m0)
		return SS_ERR_FAIL;
	memcpy(st->rkl2_y0, st->height, n * sizeof(double));
	memset(st->rkl2_d1, 0, n * sizeof(double));
	memset(st->rkl2_d2, 0, n * sizeof(double));
	memset(st->rkl2_m0, 0, n * sizeof(double));
	st->rkl2_tau = rkl2_dt_all(st) * ss_rkl2_stable_ratio(RKL2_START_STAGES);
	return SS_OK;
}

/* The checks of ss_stepper_prepare on this rank's cells (the messages name
 * a cell by its index in the whole grid). */
static int check_cells(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const enum ss_cell_type type = ss_cell_type_get(st->cell_types, k);
			if (type == SS_CELL_OPEN)
				st->height[k] = st->boundary.open_level;
			else if (type == SS_CELL_WALL)
				st->height[k] = 0.0;
			else if (st->height[k] == 0.0)
				st->height[k] = 0.0;   /* no -0: h + 0 then keeps every bit */
			if (!isfinite(st->height[k]))
				return ss_error_input("initial height of cell (%lld, %lld) at x = %g m, "
				                      "y = %g m is %g: heights must be finite",
				                      g->offset_i + i, g->offset_j + j, ss_grid_x(g, i),
				                      ss_grid_y(g, j), st->height[k]);
			if (st->bedrock && type == SS_CELL_FLOW && st->bedrock[k] > st->height[k])
				return ss_error_input("bedrock of cell (%lld, %lld) at x = %g m, y = %g m "
				                      "is %.17g m, above the surface %.17g m: the "
				                      "surface must be at or above the bedrock",
				                      g->offset_i + i, g->offset_j + j, ss_grid_x(g, i),
				                      ss_grid_y(g, j), st->bedrock[k], st->height[k]);
		}
	}
	return SS_OK;
}

/* The parts of prepare that allocate (each rank's own failure; the caller
 * agrees on it before the next collective call). */
static int prepare_arrays(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (st->source_count > 0) {
		st->source_rate = ss_alloc(ss_grid_storage_cells(g), sizeof(double),
		                           "source rates");
		if (!st->source_rate)
			return SS_ERR_FAIL;
	}
	int err = open_faces_build(st);
	if (err)
		return err;
	if (st->integrator == SS_INTEGRATOR_RKL2 && (err = rkl2_prepare(st)))
		return err;
	if (st->kernel == SS_KERNEL_REFERENCE) {
		/* the reference sweep reads one type byte per cell */
		const size_t n = ss_grid_storage_cells(g);
		st->flux_x = ss_alloc(n, sizeof(double), "x-face fluxes");
		st->flux_y = ss_alloc(n, sizeof(double), "y-face fluxes");
		st->cell_type_bytes = ss_alloc(n, 1, "cell types");
		if (!st->flux_x || !st->flux_y || !st->cell_type_bytes)
			return SS_ERR_FAIL;
		ss_cell_types_unpack(st->cell_types, 0, n, st->cell_type_bytes);
		return SS_OK;
	}
	st->open_flux = ss_alloc(st->open_face_count ? st->open_face_count : 1,
	                         sizeof(double), "open-face fluxes");
	if (!st->open_flux)
		return SS_ERR_FAIL;
	/* periodic y across ranks is the ranks' business (comm.h) */
	return ss_sweep_fast_init(&st->fast, g, &st->tiling, ss_parallel_max_threads(),
	                          st->boundary.side[SS_WEST] == SS_SIDE_PERIODIC,
	                          st->boundary.side[SS_SOUTH] == SS_SIDE_PERIODIC &&
	                          ss_grid_is_whole(g),
	                          st->cell_types, st->open_faces, st->open_face_count);
}

int ss_stepper_prepare(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_types(g, &st->boundary, st->cell_types);
	int err = ss_comm_agree(check_cells(st));
	if (err)
		return err;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	if (st->bedrock)
		/* bedrock ghosts: a periodic side copies the cell it wraps to;
		 * elsewhere no sand lies outside the grid (-infinity: no limit) */
		ss_boundary_fill_field(g, &st->boundary, st->bedrock, -INFINITY, -INFINITY);
	if ((err = ss_comm_agree(prepare_arrays(st))))
		return err;
	double none = 0.0;
	st->open_face_count_all = (double)st->open_face_count;
	ss_comm_reduce(&none, 0, &st->open_face_count_all, 1);
	if ((err = ss_comm_agree(outflow_batch_init(st))))
		return err;
	outflow_batch_agree(st);
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_wake_all(&st->fast, g, st->height, st->cell_types);
	return SS_OK;
}

void ss_stepper_heights_changed(struct ss_stepper *st)
{
	ss_boundary_fill_heights(&st->grid, &st->boundary, st->height);
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_wake_all(&st->fast, &st->grid, st->height, st->cell_types);
}

double ss_stepper_next_source_event(const struct ss_stepper *st, double t)
{
	double next = INFINITY;
	for (int k = 0; k < st->source_count; k++) {
		const struct ss_source *s = &st->sources[k];
		if (s->start > t && s->start < next)
			next = s->start;
		if (s->stop > t && s->stop < next)
			next = s->stop;
	}
	return next;
}

/* Rebuild the source field when the set of active sources changes or the
 * rate field was set; sources are summed in file order and the rate field
 * last, so the field has the same bits every run. */
static void sources_update(struct ss_stepper *st)
{
	uint64_t on = 0;
	for (int k = 0; k < st->source_count; k++) {
		const struct ss_source *s = &st->sources[k];
		if (s->start <= st->time && st->time < s->stop && s->cell_count_all > 0)
			on |= UINT64_C(1) << k;
	}
	if (on == st->sources_on && !st->source_field_stale)
		return;
	st->sources_on = on;
	st->source_field_stale = 0;
	st->source_field_on = on || st->rate_field_on;
	st->source_rate_max = 0.0;
	st->source_volume_rate = 0.0;
	if (!st->source_field_on) {
		if (st->kernel == SS_KERNEL_FAST)
			ss_sweep_fast_mark_sources(&st->fast, &st->grid, NULL);
		return;
	}
	const size_t n = ss_grid_storage_cells(&st->grid);
	memset(st->source_rate, 0, n * sizeof(double));
	for (int k = 0; k < st->source_count; k++) {
		if (!(on >> k & 1))
			continue;
		const struct ss_source *s = &st->sources[k];
		for (size_t m = 0; m < s->cell_count; m++)
			st->source_rate[s->cells[m]] += s->rate;
	}
	if (st->rate_field_on)
		for (size_t k = 0; k < n; k++)
			st->source_rate[k] += st->rate_field[k];
	/* the volume rate in storage order, deterministic: on several ranks
	 * one fold carried from rank to rank (the ghost rows between add
	 * zeros, which change no bit of a sum that starts at +0) */
	double rate_max = 0.0, volume_rate = 0.0;
	ss_comm_fold_start(&volume_rate, 1);
	for (size_t k = 0; k < n; k++) {
		volume_rate += st->source_rate[k];
		rate_max = fmax(rate_max, fabs(st->source_rate[k]));
	}
	ss_comm_fold_finish(&volume_rate, 1);
	ss_comm_reduce(&rate_max, 1, NULL, 0);
	st->source_rate_max = rate_max;
	st->source_volume_rate = volume_rate * st->grid.dx * st->grid.dy;
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_mark_sources(&st->fast, &st->grid, st->source_rate);
}

int ss_stepper_set_rate_field(struct ss_stepper *st, const double *rate)
{
	const struct ss_grid *g = &st->grid;
	const size_t n = ss_grid_storage_cells(g);
	int any = 0;
	if (rate) {
		/* every value checked before any is kept */
		for (int j = 0; j < g->ny; j++)
			for (int i = 0; i < g->nx; i++) {
				const double r = rate[(size_t)j * g->nx + i];
				const size_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW)
					continue;
				if (!isfinite(r))
					return ss_error_input("rate field: cell (%d, %d) is %g m/s: "
					                      "expected a finite rate", i, j, r);
				if (r < 0.0 && st->bedrock)
					return ss_error_input("rate field: cell (%d, %d) is %g m/s: a "
					                      "negative rate (erosion) needs a model "
					                      "without a bedrock", i, j, r);
				any |= r != 0.0;
			}
		if (!st->source_rate &&
		    !(st->source_rate = ss_alloc(n, sizeof(double), "source rates")))
			return SS_ERR_FAIL;
		if (!st->rate_field &&
		    !(st->rate_field = ss_alloc(n, sizeof(double), "the rate field")))
			return SS_ERR_FAIL;
		memset(st->rate_field, 0, n * sizeof(double));
		for (int j = 0; j < g->ny; j++)
			for (int i = 0; i < g->nx; i++) {
				const size_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
					st->rate_field[k] = rate[(size_t)j * g->nx + i];
			}
	}
	st->rate_field_on = any;
	st->source_field_stale = 1;
	return SS_OK;
}

void ss_stepper_book_external(struct ss_stepper *st, double volume_m3)
{
	add_compensated(&st->external_sum, &st->external_carry, volume_m3);
	st->external = st->external_sum + st->external_carry;
}

/* The tiles the coming pass sweeps on this rank (the reference sweep:
 * all). */
static double tiles_to_sweep(const struct ss_stepper *st)
{
	return st->kernel == SS_KERNEL_FAST
		? ss_sweep_fast_awake(&st->fast) : (double)st->tiling.tiles_x * st->tiling.tiles_y;
}

/* The halo, then the largest face slope S of the state over every rank
 * (the fast sweep also saves its ring rows; the reference sweep computes
 * the fluxes), and the tiles the coming pass sweeps into st->tiles_awake. */
static double measure(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double t0 = ss_parallel_wall_seconds();
	double s_max = st->kernel == SS_KERNEL_FAST
		? ss_sweep_fast_begin(&st->fast, g, st->height, st->cell_types)
		: ss_sweep_fluxes(g, &st->tiling, &st->face_rule, st->height,
		                  st->cell_type_bytes, st->flux_x, st->flux_y);
	st->seconds_measure += ss_parallel_wall_seconds() - t0;
	st->tiles_awake = st->tiles_awake_here = tiles_to_sweep(st);
	ss_comm_reduce(&s_max, 1, &st->tiles_awake, 1);
	return isinf(s_max) ? NAN : s_max;
}

/* The start of an RKL2 stage after the first: the halo and what the sweep
 * reads besides the heights (the fast sweep's ring rows, the reference
 * sweep's fluxes), but no slope and nothing summed over the ranks: the
 * super-step's length is fixed, and a NaN shows in the stage's change.
 * Returns the tiles this rank sweeps. */
static double measure_stage(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double t0 = ss_parallel_wall_seconds();
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_save_rings(&st->fast, g, st->height);
	else
		ss_sweep_fluxes(g, &st->tiling, &st->face_rule, st->height, st->cell_type_bytes,
		                st->flux_x, st->flux_y);
	st->seconds_measure += ss_parallel_wall_seconds() - t0;
	return tiles_to_sweep(st);
}

/* After a pass of the fast sweep that planned the next: the tiles here
 * that changed edges of the ranks beside wake (sweep.h). */
static void wake_across(struct ss_stepper *st)
{
	if (st->kernel != SS_KERNEL_FAST || ss_grid_is_whole(&st->grid))
		return;
	const size_t n = (size_t)st->tiling.tiles_x;
	uint8_t *from_south = st->edges_in, *from_north = st->edges_in + n;
	ss_comm_exchange(st->rank_south, st->rank_north, st->fast.edges_out_south, from_south,
	                 st->fast.edges_out_north, from_north, n);
	ss_sweep_fast_wake_across(&st->fast, st->rank_south >= 0 ? from_south : NULL,
	                          st->rank_north >= 0 ? from_north : NULL);
}

/* What every step starts from: the sources of this time, the next event,
 * and the measure. */
struct step_start {
	double next_event;      /* the next target or source switch, s */
	int may_be_steady;      /* a steady stop is asked for, no source to come */
	double s_max;           /* NaN if a height is not finite */
};

static struct step_start step_begin(struct ss_stepper *st, double t_target,
                                    const struct ss_advance_options *o)
{
	struct step_start b;
	sources_update(st);
	const double next_switch = ss_stepper_next_source_event(st, st->time);
	/* a state is steady only if no source will switch on later */
	b.may_be_steady = o->steady_tol > 0.0 && isinf(next_switch);
	b.next_event = fmin(next_switch, t_target);
	b.s_max = measure(st);
	return b;
}

/*
 * The slope part of the steady test (stepper.h): the steepest face in sand
 * carries no more sliding flux than a Coulomb face steeper than the repose
 * angle by slope_tol.  s_max is the state's largest face slope (exact above
 * the critical slope); with a bedrock, bare rock may stay steep for ever,
 * so the faces in sand are measured again.
 */
static int slopes_settled(struct ss_stepper *st, double s_max, double slope_tol)
{
	const struct ss_closure *c = &st->closure;
	const double t = c->tan_cr + slope_tol;
	const double flux_tol = slope_tol / sqrt(1.0 + t * t);   /* f_coulomb(t) */
	if (st->bedrock) {
		const struct ss_grid *g = &st->grid;
		/* a film of sand thinner than round-off of the heights is rock */
		const double bare = 1e-9 * fmax(g->dx, g->dy);
		s_max = ss_sweep_max_sand_slope(g, st->height, st->cell_types, st->bedrock, bare);
		ss_comm_reduce(&s_max, 1, NULL, 0);
	}
	return !(s_max > c->tan_cr) || ss_closure_eval(c, s_max) <= flux_tol;
}

/* After a step: the totals, the counters, progress, and why to stop (or
 * -1 to go on).  *steady_candidate: the rate is below steady_tol, so the
 * next step's start checks the slopes. */
static int step_end(struct ss_stepper *st, const struct ss_advance_options *o,
                    const struct step_start *b, int *steady_candidate)
{
	st->outflow = st->outflow_sum + st->outflow_carry;   /* batched: as of the last flush */
	st->inflow = st->inflow_sum + st->inflow_carry;
	st->tile_slots += st->tiles_all;
	/* every rank decides on the same values: a signal reaches the ranks
	 * at different times; and the outflow batch's room on every rank
	 * (a minimum, as the maximum of the negatives) */
	struct ss_outflow_batch *ob = st->outflow_batch;
	double agree[3] = {st->rate_max, o->stop && *o->stop ? 1.0 : 0.0,
	                   ob->on ? -outflow_fits_here(st) : 0.0};
	ss_comm_reduce(agree, ob->on ? 3 : 2, NULL, 0);
	st->rate_max = agree[0];
	if (ob->on) {
		ob->fits = -agree[2];
		ob->fits_measured = 1;
	}
	if (o->progress)
		o->progress(o->context, st);
	if (!isfinite(st->rate_max))
		return SS_ADVANCE_NONFINITE;
	*steady_candidate = b->may_be_steady && st->rate_max < o->steady_tol;
	if (agree[1] != 0.0)
		return SS_ADVANCE_INTERRUPTED;
	return -1;
}

/* One forward-Euler substep of dt seconds from the state step_begin
 * measured. */
static void euler_step(struct ss_stepper *st, double dt)
{
	const struct ss_grid *g = &st->grid;
	const double t0 = ss_parallel_wall_seconds();
	st->tile_sweeps += st->tiles_awake;
	if (st->kernel == SS_KERNEL_FAST) {
		st->rate_max = ss_sweep_fast_step(&st->fast, g, &st->face_rule, dt,
		                                  st->source_field_on ? st->source_rate : NULL,
		                                  st->bedrock, st->cell_types, st->height,
		                                  st->open_flux);
	} else {
		if (st->bedrock)
			ss_sweep_limit(g, &st->tiling, dt, st->height, st->bedrock,
			               st->flux_x, st->flux_y);
		st->rate_max = ss_sweep_update(g, &st->tiling, dt, st->flux_x, st->flux_y,
		                               st->source_field_on ? st->source_rate : NULL,
		                               st->cell_type_bytes, st->height);
	}
	st->seconds_sweep += ss_parallel_wall_seconds() - t0;
	wake_across(st);
	const struct outflow_entry e = {.kind = OUTFLOW_EULER, .tau_mu = dt};
	outflow_account(st, &e);
	add_compensated(&st->inflow_sum, &st->inflow_carry, dt * st->source_volume_rate);
	st->evaluations++;
}

/* One pass of the stencil for an RKL2 stage (or the estimate after the
 * last), from the halo (unless `measured`: step_begin measured the state
 * for stage 1).  Returns what the sweep returns on this rank; the tiles it
 * swept here are added to *awake. */
static double rkl2_pass(struct ss_stepper *st, const struct ss_sweep_stage *stage, int last,
                        int measured, double *awake)
{
	const struct ss_grid *g = &st->grid;
	const double *src = st->source_field_on ? st->source_rate : NULL;
	*awake += measured ? st->tiles_awake_here : measure_stage(st);
	const double t1 = ss_parallel_wall_seconds();
	double change;
	if (st->kernel == SS_KERNEL_FAST) {
		change = ss_sweep_fast_stage(&st->fast, g, &st->face_rule, stage, last, src,
		                             st->cell_types, st->height, st->open_flux);
	} else {
		change = ss_sweep_stage_update(g, &st->tiling, stage, st->flux_x, st->flux_y, src,
		                               st->cell_type_bytes, st->height);
	}
	st->seconds_sweep += ss_parallel_wall_seconds() - t1;
	if (!stage->estimate_only)
		wake_across(st);
	st->evaluations++;
	return change;
}

/*
 * One RKL2 super-step of tau seconds in s stages (rkl2.h, sweep.h); stage 1
 * starts from the state step_begin measured.  The outflow of the stages is
 * combined with the stage weights, O_j = mu O_{j-1} + nu O_{j-2} +
 * tau (mu~ out(M(Y_{j-1})) + gamma~ out(M(Y_0))), as the heights are, so
 * that it is the outflow of the super-step's change (ledger_apply; on
 * several ranks perhaps later, from the batch); the source is
 * constant over it, so the inflow is tau times its rate.  The ranks agree
 * once a super-step, after the estimate (the stages need nothing summed
 * over them but the outflow).  Returns max |Y_s - Y_0| (as max |D_s|), m
 * (INFINITY on NaN), and the error estimate (sweep.h) in *estimate.
 */
static double rkl2_superstep(struct ss_stepper *st, double tau, int s, double *estimate)
{
	double change = 0.0, awake = 0.0;
	for (int j = 1; j <= s; j++) {
		const struct ss_rkl2_stage k = ss_rkl2_stage(s, j);
		const struct ss_sweep_stage stage = {
			.first = j == 1, .mu = k.mu, .nu = k.nu,
			.tau_mu = tau * k.mu_tilde, .tau_gamma = tau * k.gamma_tilde,
			.y0 = st->rkl2_y0, .d1 = st->rkl2_d1, .d2 = st->rkl2_d2, .m0 = st->rkl2_m0,
		};
		change = rkl2_pass(st, &stage, j == s, j == 1, &awake);
		const struct outflow_entry e = {
			.mu = stage.mu, .nu = stage.nu, .tau_mu = stage.tau_mu,
			.tau_gamma = stage.tau_gamma,
			.kind = OUTFLOW_STAGE | (j == 1 ? OUTFLOW_FIRST : 0) | (j == s ? OUTFLOW_LAST : 0),
		};
		outflow_account(st, &e);
	}
	add_compensated(&st->inflow_sum, &st->inflow_carry, tau * st->source_volume_rate);
	/* the error estimate: one more evaluation, at Y_s, that writes nothing;
	 * the next super-step's first stage evaluates there again, but the
	 * estimate is then known before the next super-step is sized, and a
	 * restart from Y_s needs nothing a snapshot does not hold */
	const struct ss_sweep_stage est = {
		.estimate_only = 1, .estimate_tau = tau, .estimate = estimate,
		.y0 = st->rkl2_y0, .d1 = st->rkl2_d1, .d2 = st->rkl2_d2, .m0 = st->rkl2_m0,
	};
	rkl2_pass(st, &est, 0, 0, &awake);
	/* the tile counts are whole numbers: their sum has the same bits for
	 * any rank count */
	double max[2] = {change, *estimate};
	ss_comm_reduce(max, 2, &awake, 1);
	*estimate = max[1];
	st->tile_sweeps += awake / (s + 1);
	return isfinite(max[0]) ? max[0] : INFINITY;
}

/*
 * The accuracy rule (stepper.h) after a super-step of tau with error
 * estimate est: the limit becomes tau 0.9 sqrt(tol / est), at most twice
 * the limit it had; a limit above the stage cap is none.
 */
static void rkl2_control(struct ss_stepper *st, double tau, double estimate,
                         double tol, double tau_stages)
{
	const double factor = estimate > 0.0 ? fmin(0.9 * sqrt(tol / estimate), 2.0) : 2.0;
	const double limit = isfinite(st->rkl2_tau) ? st->rkl2_tau : tau_stages;
	st->rkl2_tau = fmin(tau * factor, 2.0 * limit);
	if (st->rkl2_tau >= tau_stages)
		st->rkl2_tau = INFINITY;
}

static enum ss_advance_end advance(struct ss_stepper *st, double t_target,
                                   const struct ss_advance_options *o)
{
	const struct ss_grid *g = &st->grid;
	const struct ss_closure *c = &st->closure;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	const double source_rise = st->cfl * c->tan_cr * fmin(g->dx, g->dy);
	const double slope_tol = o->steady_slope_tol > 0.0 ? o->steady_slope_tol : 1e-6;
	const int rkl2 = st->integrator == SS_INTEGRATOR_RKL2;
	/* RKL2: forward Euler's step for every slope, the longest super-step
	 * its stage cap allows, and the error tolerance in m */
	const double dt_all = rkl2_dt_all(st);
	const double tau_stages = dt_all * ss_rkl2_stable_ratio(st->rkl2_max_stages);
	const double tol = st->rkl2_tol * c->tan_cr * fmin(g->dx, g->dy);

	long long steps_left = o->max_steps > 0 ? o->max_steps : -1;
	int steady_candidate = 0;
	/* polishing near rest (stepper.h): the forward-Euler steps left in the
	 * burst, the stages of this call's last super-step (a burst's length),
	 * and whether a burst just ended (the next step is a super-step) */
	long long polish_left = 0;
	int stages = 0, burst_ended = 0;
	while (st->time < t_target) {
		if (steps_left == 0)
			return SS_ADVANCE_STEPS;
		const struct step_start b = step_begin(st, t_target, o);
		if (!isfinite(b.s_max)) {
			st->rate_max = NAN;
			return SS_ADVANCE_NONFINITE;
		}
		if (steady_candidate) {
			if (slopes_settled(st, b.s_max, slope_tol))
				return SS_ADVANCE_STEADY;
			/* RKL2 near rest: a burst of forward-Euler steps, as
			 * many as the last super-step had stages (stepper.h) */
			if (rkl2 && polish_left == 0 && !burst_ended)
				polish_left = stages > 0 ? stages : 1;
		}
		const int polish = polish_left > 0;

		const double lambda = c->nu * ss_cfl_bound_lookup(&st->cfl_bound, b.s_max);
		double dt = lambda > 0.0 ? st->cfl / (2.0 * lambda * inv_d2) : INFINITY;
		/* RKL2: stable for every state its stages can reach, also when
		 * a source is about to raise a flat state past the onset */
		if (rkl2 && !polish && (lambda > 0.0 || st->source_field_on))
			dt = fmin(tau_stages, st->rkl2_tau);
		if (st->source_field_on && source_rise / st->source_rate_max < dt)
			dt = source_rise / st->source_rate_max;

		if (isinf(dt)) {
			/* nothing slides and nothing is poured: the state is
			 * stationary until the next event */
			st->rate_max = 0.0;
			if (b.may_be_steady)
				return SS_ADVANCE_STEADY;
			st->time = b.next_event;
			continue;
		}

		const int lands = st->time + dt >= b.next_event;
		if (lands)
			dt = b.next_event - st->time;
		else if (st->time + dt == st->time)
			return SS_ADVANCE_STALLED;

		if (rkl2 && !polish) {
			int s = ss_rkl2_stages_for(dt / dt_all);
			s = s < st->rkl2_max_stages ? s : st->rkl2_max_stages;
			double estimate = 0.0;
			const double change = rkl2_superstep(st, dt, s, &estimate);
			rkl2_control(st, dt, estimate, tol, tau_stages);
			st->last_stages = stages = s;
			st->rate_max = change / dt;
			burst_ended = 0;
		} else {
			euler_step(st, dt);
			if (polish && --polish_left == 0)
				burst_ended = 1;
		}
		st->time = lands ? b.next_event : st->time + dt;
		st->steps++;
		steps_left--;
		const int end = step_end(st, o, &b, &steady_candidate);
		if (end >= 0)
			return (enum ss_advance_end)end;
	}
	/* on a target: the slopes are measured here, not by the next step */
	if (steady_candidate) {
		ss_boundary_fill_heights(g, &st->boundary, st->height);
		double s_max = ss_sweep_max_slope(g, st->height, st->cell_types);
		ss_comm_reduce(&s_max, 1, NULL, 0);
		if (slopes_settled(st, s_max, slope_tol))
			return SS_ADVANCE_STEADY;
	}
	return SS_ADVANCE_REACHED;
}

enum ss_advance_end ss_stepper_advance(struct ss_stepper *st, double t_target,
                                       const struct ss_advance_options *o)
{
	const enum ss_advance_end end = advance(st, t_target, o);
	/* every rank returns after the same substep: the outflow batch is
	 * folded here, so that the ledger is current between calls */
	outflow_flush(st);
	return end;
}

/* ss_stepper_max_sand_slope on this rank's faces (the halo filled). */
static double max_sand_slope_here(const struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (!st->bedrock)
		return ss_sweep_max_slope(g, st->height, st->cell_types);
	return ss_sweep_max_sand_slope(g, st->height, st->cell_types, st->bedrock,
	                               1e-6 * fmin(g->dx, g->dy));
}

double ss_stepper_max_sand_slope(struct ss_stepper *st)
{
	ss_boundary_fill_heights(&st->grid, &st->boundary, st->height);
	double s = max_sand_slope_here(st);
	ss_comm_reduce(&s, 1, NULL, 0);
	return s;
}

void ss_stepper_diagnostics(struct ss_stepper *st, struct ss_diagnostics *d)
{
	const struct ss_grid *g = &st->grid;
	double *row_volume = st->row_scratch, max_height = -INFINITY;
	outflow_flush(st);   /* empty after ss_stepper_advance; collective */

	/* rows summed in parallel, then the row sums in order: the same bits
	 * for any thread count */
	#pragma omp parallel for schedule(static) reduction(max:max_height)
	for (int j = 0; j < g->ny; j++) {
		double row = 0.0, top = -INFINITY;
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW)
				continue;
			const double h = st->height[k];
			row += h;
			top = h > top || h != h ? (h != h ? INFINITY : h) : top;
		}
		row_volume[j] = row;
		if (top > max_height)
			max_height = top;
	}
	/* the row sums in row order, carried from rank to rank */
	double volume = 0.0;
	ss_comm_fold_start(&volume, 1);
	for (int j = 0; j < g->ny; j++)
		volume += row_volume[j];
	ss_comm_fold_finish(&volume, 1);

	ss_boundary_fill_heights(g, &st->boundary, st->height);
	double max[2] = {max_sand_slope_here(st), max_height};
	ss_comm_reduce(max, 2, NULL, 0);
	const double s_max = max[0];
	max_height = max[1];
	d->volume = volume * g->dx * g->dy;
	d->inflow = st->inflow;
	d->outflow = st->outflow;
	d->external = st->external;
	d->max_height = max_height;
	d->max_slope_deg = atan(s_max) * (180.0 / M_PI);
	d->steps = (double)st->steps;
	d->evaluations = (double)st->evaluations;
	d->active_fraction = st->tile_slots > 0.0 ? st->tile_sweeps / st->tile_slots : 0.0;
	st->tile_sweeps = st->tile_slots = 0.0;
}

void ss_stepper_restart_state(const struct ss_stepper *st, struct ss_restart_state *s)
{
	s->steps = st->steps;
	s->inflow_sum = st->inflow_sum;
	s->inflow_carry = st->inflow_carry;
	s->outflow_sum = st->outflow_sum;
	s->outflow_carry = st->outflow_carry;
	s->evaluations = st->evaluations;
	s->rkl2_tau = st->rkl2_tau;
}

void ss_stepper_restore(struct ss_stepper *st, double t, const double *height,
                        const struct ss_restart_state *s)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++)
		memcpy(st->height + ss_grid_index(g, 0, j), height + (size_t)j * g->nx,
		       (size_t)g->nx * sizeof(double));
	st->time = t;
	st->steps = s->steps;
	st->inflow_sum = s->inflow_sum;
	st->inflow_carry = s->inflow_carry;
	st->outflow_sum = s->outflow_sum;
	st->outflow_carry = s->outflow_carry;
	st->evaluations = s->evaluations;
	st->rkl2_tau = s->rkl2_tau;
	/* the totals as ss_stepper_advance forms them after every substep */
	st->inflow = st->inflow_sum + st->inflow_carry;
	st->outflow = st->outflow_sum + st->outflow_carry;
	ss_stepper_heights_changed(st);
}

int ss_stepper_first_nonfinite(const struct ss_stepper *st, int *i, int *j)
{
	const struct ss_grid *g = &st->grid;
	/* the first in global row order: the largest of minus its index */
	double first = -INFINITY;
	for (int jj = 0; jj < g->ny && first == -INFINITY; jj++)
		for (int ii = 0; ii < g->nx; ii++)
			if (!isfinite(st->height[ss_grid_index(g, ii, jj)])) {
				first = -((double)(g->offset_j + jj) * (double)g->global_nx +
				          (double)(g->offset_i + ii));
				break;
			}
	ss_comm_reduce(&first, 1, NULL, 0);
	if (first == -INFINITY)
		return 0;
	*j = (int)(-first / (double)g->global_nx);
	*i = (int)(-first - (double)*j * (double)g->global_nx);
	return 1;
}
