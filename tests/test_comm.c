/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_comm.c - the ranks of a distributed run (comm.h) and the halo fill
 * of a slab (boundary.h, grid.h), with any number of ranks:
 *
 *   split        ss_comm_split covers 0 .. items - 1 contiguously in rank
 *                order, the first ranks taking one more (ranks may get none)
 *   take rows    ss_grid_take_rows keeps the global size, the stride and the
 *                coordinates of the rows it keeps
 *   neighbours   south/north ranks, -1 at the ends; periodic joins rank 0 and
 *                the last rank (with one rank: none)
 *   exchange     one row each way; a neighbour of -1 leaves its buffer alone
 *   halo         the slab of this rank (13 x 11 cells, rows split unevenly;
 *                and 6 x (ranks + 1), slabs of one row) filled by
 *                ss_boundary_fill_heights and ss_boundary_fill_types gives,
 *                ghost by ghost, corners included, the one-rank fill of the
 *                whole grid, computed here from the rule of boundary.h: x
 *                sides for the rows, then y sides for the full width (a
 *                corner takes the y side's rule applied to the x-ghost
 *                column); all wall, all open, mixed, periodic x, periodic y
 *                (across ranks: rank 0 and the last rank), periodic both;
 *                interior cells untouched; filled twice
 *   reduce       maxima (a NaN on one rank, first or last, is +inf on all;
 *                -inf stays), integer-valued sums exact (2^52 + ranks - 1),
 *                entries past n_max / n_sum untouched
 *   fold         the ordered fold over 22 values (1e16, 1, -1e16, 3.3 ...)
 *                split over the ranks (some ranks may hold none) has the
 *                bits of the serial left fold; the values are chosen so that
 *                adding per-rank partial sums would not
 *   fold many    the outflow batch's fold (ledger.c): 3000 folds of two
 *                sums in one call (6000 running values, 48 kB a message),
 *                each of 0 to 22 values split over the ranks, a third of
 *                them +0 or -0 and left out by the ranks: every total has
 *                the bits (the sign of a zero included) of its own serial
 *                left fold over every value, zeros included
 *   gather       rows of different lengths (one rank sends none) arrive on
 *                rank 0 in rank order; broadcast from the first and the last
 *                rank
 *   agree        all SS_OK -> SS_OK; one rank failing with SS_ERR_INPUT ->
 *                SS_ERR_INPUT on every rank; several failing -> the status
 *                of the first failing rank in rank order
 *
 * Run as a plain program (one rank: `make test`) or under mpirun -np N in the
 * MPI build (make MPI=1).  Only rank 0 prints "ok"/"FAIL" per test (a test
 * that made no check on any rank fails) and the closing "N passed, M
 * failed" (the totals of every rank); a failed check prints its rank.
 * Every rank exits with the agreed status.  Each test is collective: every
 * rank makes the same calls whatever its checks found.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "sandslide/boundary.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"

static int rank, ranks;

static int same_bits(double a, double b)
{
	return memcmp(&a, &b, sizeof a) == 0;
}

static void *zalloc(size_t bytes)
{
	void *p = calloc(bytes ? bytes : 1, 1);
	if (!p) {
		fprintf(stderr, "test_comm: out of memory (%zu bytes)\n", bytes);
		ss_comm_abort(1);
	}
	return p;
}

/* The counts of every rank, summed in place (exact: integers). */
static void sum_everywhere(int *counts, int n)
{
	double sum[3], unused = 0.0;
	for (int k = 0; k < n; k++)
		sum[k] = counts[k];
	ss_comm_reduce(&unused, 0, sum, n);
	for (int k = 0; k < n; k++)
		counts[k] = (int)sum[k];
}

/* RUN of check.h for every rank: the test's name carries the rank into the
 * FAIL lines, and rank 0 prints the verdict of all, judged on the checks
 * of every rank (a test may check on rank 0 alone what all sent it). */
static char current[160];
#define RUN_ALL(fn)                                                               \
	do {                                                                      \
		snprintf(current, sizeof current, "%s (rank %d of %d)", #fn, rank, ranks); \
		const struct check_mark mark_ = check_begin(current);             \
		fn();                                                             \
		fflush(stderr);                                                   \
		int made_[3] = {check_passed + check_failed - mark_.passed - mark_.failed, \
		                check_failed - mark_.failed, check_skipped - mark_.skipped}; \
		sum_everywhere(made_, 3);                                         \
		if (rank == 0) {                                                  \
			printf("%s %s\n", check_verdict(made_[0], made_[1], made_[2]), #fn); \
			fflush(stdout);                                           \
		}                                                                 \
	} while (0)

/* ---- split, rows, neighbours --------------------------------------------- */

static void test_split(void)
{
	static const long long items[] = {0, 1, 2, 3, 5, 6, 7, 11, 13, 48, 1000003};
	for (size_t n = 0; n < sizeof items / sizeof *items; n++) {
		const long long N = items[n];
		long long first = -1, count = -1;
		ss_comm_split(N, &first, &count);
		/* every rank's part on rank 0, in rank order */
		long long mine[2] = {first, count};
		long long *all = rank == 0 ? zalloc((size_t)ranks * sizeof mine) : NULL;
		ss_comm_gather_rows(mine, sizeof mine, all);
		if (rank == 0) {
			long long next = 0;
			for (int r = 0; r < ranks; r++) {
				const long long f = all[2 * r], c = all[2 * r + 1];
				const long long want = N / ranks + (r < N % ranks ? 1 : 0);
				CHECK(f == next, "%lld items, %d ranks: rank %d starts at %lld, "
				      "not at %lld (the end of the rank before)", N, ranks, r, f,
				      next);
				CHECK(c == want, "%lld items, %d ranks: rank %d gets %lld, not "
				      "%lld (the first ranks take one more)", N, ranks, r, c, want);
				next = f + c;
			}
			CHECK(next == N, "%lld items, %d ranks: the parts end at %lld", N,
			      ranks, next);
		}
		free(all);
	}
}

static void test_take_rows(void)
{
	struct ss_grid whole, g;
	CHECK(ss_grid_init(&whole, 13, 11, 0.5, 0.25, -3.0, 7.0) == SS_OK, "grid refused");
	long long first, count;
	ss_comm_split(whole.global_ny, &first, &count);
	g = whole;
	ss_grid_take_rows(&g, first, (int)count);
	CHECK(g.ny == count && g.offset_j == first, "rows [%lld, +%lld): ny %d, offset_j %lld",
	      first, count, g.ny, g.offset_j);
	CHECK(g.nx == 13 && g.offset_i == 0 && g.stride == whole.stride,
	      "the columns changed: nx %d, offset_i %lld, stride %td (was %td)", g.nx,
	      g.offset_i, g.stride, whole.stride);
	CHECK(g.global_nx == 13 && g.global_ny == 11, "global size %lld x %lld, not 13 x 11",
	      g.global_nx, g.global_ny);
	CHECK(ss_grid_storage_cells(&g) == (size_t)whole.stride * (size_t)(count + 2),
	      "storage %zu elements for %lld rows", ss_grid_storage_cells(&g), count);
	for (int j = 0; j < g.ny; j++)
		CHECK(same_bits(ss_grid_y(&g, j), ss_grid_y(&whole, (int)first + j)),
		      "row %d of the slab is at y = %.17g, row %lld of the grid at %.17g", j,
		      ss_grid_y(&g, j), first + j, ss_grid_y(&whole, (int)first + j));
	CHECK(same_bits(ss_grid_x(&g, 4), ss_grid_x(&whole, 4)), "x of column 4 moved");
	CHECK(ss_grid_is_whole(&g) == (ranks == 1), "ss_grid_is_whole says %d with %d ranks",
	      ss_grid_is_whole(&g), ranks);
}

static void test_neighbours(void)
{
	int s, n;
	ss_comm_neighbours(0, &s, &n);
	CHECK(s == (rank > 0 ? rank - 1 : -1), "not periodic: south %d", s);
	CHECK(n == (rank + 1 < ranks ? rank + 1 : -1), "not periodic: north %d", n);
	ss_comm_neighbours(1, &s, &n);
	if (ranks == 1) {
		CHECK(s == -1 && n == -1, "one rank, periodic: neighbours %d, %d, not none", s, n);
	} else {
		CHECK(s == (rank + ranks - 1) % ranks, "periodic: south %d", s);
		CHECK(n == (rank + 1) % ranks, "periodic: north %d", n);
	}
}

static void test_exchange(void)
{
	enum { LEN = 5 };
	for (int periodic = 0; periodic <= 1; periodic++) {
		int s, n;
		ss_comm_neighbours(periodic, &s, &n);
		double send_s[LEN], send_n[LEN], recv_s[LEN], recv_n[LEN];
		for (int k = 0; k < LEN; k++) {
			send_s[k] = 1000.0 * rank + k;          /* travels south */
			send_n[k] = -1000.0 * rank - k - 0.5;   /* travels north */
			recv_s[k] = recv_n[k] = 4242.0;
		}
		ss_comm_exchange(s, n, send_s, recv_s, send_n, recv_n, sizeof send_s);
		for (int k = 0; k < LEN; k++) {
			/* from the south comes what the south rank sent north */
			const double want_s = s < 0 ? 4242.0 : -1000.0 * s - k - 0.5;
			const double want_n = n < 0 ? 4242.0 : 1000.0 * n + k;
			CHECK(same_bits(recv_s[k], want_s), "periodic %d: from the south "
			      "(rank %d) element %d is %.17g, not %.17g", periodic, s, k,
			      recv_s[k], want_s);
			CHECK(same_bits(recv_n[k], want_n), "periodic %d: from the north "
			      "(rank %d) element %d is %.17g, not %.17g", periodic, n, k,
			      recv_n[k], want_n);
		}
	}
}

/* ---- the halo of a slab against the one-rank rule --------------------------- */

struct sides_case {
	const char *name;
	enum ss_side_kind w, e, s, n;
};

static const struct sides_case side_cases[] = {
	{"all wall", SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL},
	{"all open", SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN},
	{"mixed (open west and north)", SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_OPEN},
	{"mixed (open east and south)", SS_SIDE_WALL, SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_WALL},
	{"periodic x", SS_SIDE_PERIODIC, SS_SIDE_PERIODIC, SS_SIDE_OPEN, SS_SIDE_WALL},
	{"periodic y", SS_SIDE_WALL, SS_SIDE_OPEN, SS_SIDE_PERIODIC, SS_SIDE_PERIODIC},
	{"periodic both", SS_SIDE_PERIODIC, SS_SIDE_PERIODIC, SS_SIDE_PERIODIC,
	 SS_SIDE_PERIODIC},
};
#define N_SIDE_CASES ((int)(sizeof side_cases / sizeof *side_cases))

#define OPEN_LEVEL 0.125
#define SENTINEL (-999.0)
#define TYPE_SENTINEL 3u   /* no cell type: 2 bits that no fill writes */

/* Interior values of the global grid: exact, distinct from 0, the open
 * level and the sentinel; `generation` changes them for the second fill. */
static double height_at(long long gi, long long gj, int generation)
{
	return 1.0 + (double)gi + 100.0 * (double)gj + 0.5 * generation;
}

static unsigned type_at(long long gi, long long gj)
{
	return (unsigned)((gi + 2 * gj) % 3);   /* flow, wall, open */
}

/*
 * The one-rank fill of the whole NX x NY grid at global (gi, gj), -1 <= gi
 * <= NX, -1 <= gj <= NY (boundary.h): rows first (the x sides), then the y
 * sides across the full width, so a y ghost of a periodic side copies the
 * filled cell (x ghost included) of the opposite edge row.
 */
static double expected_height(const struct sides_case *c, long long NX, long long NY,
                              long long gi, long long gj, int generation)
{
	if (gj >= 0 && gj < NY) {
		if (gi >= 0 && gi < NX)
			return height_at(gi, gj, generation);
		const enum ss_side_kind k = gi < 0 ? c->w : c->e;
		if (k == SS_SIDE_PERIODIC)
			return height_at(gi < 0 ? NX - 1 : 0, gj, generation);
		return k == SS_SIDE_WALL ? 0.0 : OPEN_LEVEL;
	}
	const enum ss_side_kind k = gj < 0 ? c->s : c->n;
	if (k == SS_SIDE_PERIODIC)
		return expected_height(c, NX, NY, gi, gj < 0 ? NY - 1 : 0, generation);
	return k == SS_SIDE_WALL ? 0.0 : OPEN_LEVEL;
}

static unsigned expected_type(const struct sides_case *c, long long NX, long long NY,
                              long long gi, long long gj)
{
	if (gj >= 0 && gj < NY) {
		if (gi >= 0 && gi < NX)
			return type_at(gi, gj);
		const enum ss_side_kind k = gi < 0 ? c->w : c->e;
		if (k == SS_SIDE_PERIODIC)
			return type_at(gi < 0 ? NX - 1 : 0, gj);
		return k == SS_SIDE_WALL ? SS_CELL_WALL : SS_CELL_OPEN;
	}
	const enum ss_side_kind k = gj < 0 ? c->s : c->n;
	if (k == SS_SIDE_PERIODIC)
		return expected_type(c, NX, NY, gi, gj < 0 ? NY - 1 : 0);
	return k == SS_SIDE_WALL ? SS_CELL_WALL : SS_CELL_OPEN;
}

static const char *where(const struct ss_grid *g, int i, int j)
{
	const int gx = i < 0 || i >= g->nx, gy = j < 0 || j >= g->ny;
	return gx && gy ? "corner" : gx ? "x ghost" : gy ? "y ghost" : "interior";
}

/* One global grid of NX x NY cells, this rank's slab of it, one set of
 * sides: heights (filled twice) and types. */
static void halo_case(int NX, int NY, const struct sides_case *c)
{
	struct ss_grid g;
	CHECK(ss_grid_init(&g, NX, NY, 0.1, 0.1, 0.0, 0.0) == SS_OK, "grid refused");
	long long first, count;
	ss_comm_split(NY, &first, &count);
	ss_grid_take_rows(&g, first, (int)count);
	const struct ss_boundary b = {{c->w, c->e, c->s, c->n}, OPEN_LEVEL};
	const size_t cells = ss_grid_storage_cells(&g);
	double *h = zalloc(cells * sizeof *h);
	uint8_t *t = zalloc(ss_cell_types_bytes(cells));
	int bad = 0;   /* mismatches: the first 8 are printed, then counted */

	for (int generation = 0; generation < 2; generation++) {
		for (size_t k = 0; k < cells; k++)
			h[k] = SENTINEL;
		for (int j = 0; j < g.ny; j++)
			for (int i = 0; i < g.nx; i++)
				h[ss_grid_index(&g, i, j)] =
					height_at(i, g.offset_j + j, generation);
		ss_boundary_fill_heights(&g, &b, h);
		for (int j = -1; j <= g.ny; j++) {
			for (int i = -1; i <= g.nx; i++) {
				const long long gj = g.offset_j + j;
				const double want =
					expected_height(c, NX, NY, i, gj, generation);
				const double got = h[ss_grid_index(&g, i, j)];
				bad += !same_bits(got, want);
				CHECK(same_bits(got, want) || bad > 8,
				      "%d x %d, %s, fill %d: height of the %s (%d, %lld) "
				      "(slab row %d of rows %lld..%lld) is %.17g, not %.17g",
				      NX, NY, c->name, generation + 1, where(&g, i, j), i, gj, j,
				      first, first + count - 1, got, want);
			}
		}
	}

	memset(t, 0xff, ss_cell_types_bytes(cells));   /* every cell TYPE_SENTINEL */
	for (int j = 0; j < g.ny; j++)
		for (int i = 0; i < g.nx; i++)
			ss_cell_type_set(t, ss_grid_index(&g, i, j),
			                 (enum ss_cell_type)type_at(i, g.offset_j + j));
	ss_boundary_fill_types(&g, &b, t);
	for (int j = -1; j <= g.ny; j++) {
		for (int i = -1; i <= g.nx; i++) {
			const long long gj = g.offset_j + j;
			const unsigned want = expected_type(c, NX, NY, i, gj);
			const unsigned got = ss_cell_type_get(t, ss_grid_index(&g, i, j));
			bad += got != want;
			CHECK(got == want || bad > 8,
			      "%d x %d, %s: type of the %s (%d, %lld) (slab row %d of rows "
			      "%lld..%lld) is %u, not %u%s", NX, NY, c->name, where(&g, i, j), i,
			      gj, j, first, first + count - 1, got, want,
			      got == TYPE_SENTINEL ? " (never filled)" : "");
		}
	}
	CHECK(bad == 0, "%d x %d, %s: %d cells differ from the one-rank fill", NX, NY,
	      c->name, bad);
	free(h);
	free(t);
}

static void test_halo(void)
{
	/* 13 x 11: rows split unevenly for 2, 3, 4 ranks; 6 x (ranks + 1):
	 * slabs of one row (rows 0 and ny - 1 the same), stride 8 */
	const int sizes[2][2] = {{13, ranks > 11 ? ranks : 11}, {6, ranks + 1}};
	for (int s = 0; s < 2; s++)
		for (int c = 0; c < N_SIDE_CASES; c++)
			halo_case(sizes[s][0], sizes[s][1], &side_cases[c]);
}

/* ---- reductions ------------------------------------------------------------ */

static void test_reduce(void)
{
	const double P = ranks;
	for (int nan_rank = 0; nan_rank < 2; nan_rank++) {
		const int holder = nan_rank ? ranks - 1 : 0;   /* the first, then the last */
		double max[SS_COMM_REDUCE_MAX] = {
			1.5 * rank - 7.0,
			-(double)(rank + 1),
			rank == holder ? NAN : 1e300,
			-INFINITY,
		};
		double sum[SS_COMM_REDUCE_MAX] = {
			rank + 1.0,
			rank == 0 ? 0x1p52 : 1.0,
			-3.0 * (rank + 1),
			0.0,
		};
		ss_comm_reduce(max, SS_COMM_REDUCE_MAX, sum, SS_COMM_REDUCE_MAX);
		CHECK(same_bits(max[0], 1.5 * (P - 1) - 7.0), "max[0] = %.17g, not %.17g", max[0],
		      1.5 * (P - 1) - 7.0);
		CHECK(same_bits(max[1], -1.0), "max[1] = %.17g, not -1", max[1]);
		CHECK(max[2] == INFINITY, "a NaN on rank %d: max[2] = %.17g on rank %d, not +inf",
		      holder, max[2], rank);
		CHECK(max[3] == -INFINITY, "-inf everywhere: max[3] = %.17g", max[3]);
		CHECK(same_bits(sum[0], P * (P + 1) / 2), "sum[0] = %.17g, not %.17g", sum[0],
		      P * (P + 1) / 2);
		CHECK(same_bits(sum[1], 0x1p52 + (P - 1)), "sum[1] = %.17g, not 2^52 + %g exactly",
		      sum[1], P - 1);
		CHECK(same_bits(sum[2], -1.5 * P * (P + 1)), "sum[2] = %.17g, not %.17g", sum[2],
		      -1.5 * P * (P + 1));
		CHECK(same_bits(sum[3], 0.0), "sum[3] = %.17g, not +0", sum[3]);
	}

	/* fewer entries: the rest untouched; a NaN where the max is one */
	double max[SS_COMM_REDUCE_MAX] = {rank == ranks - 1 ? NAN : (double)rank, 11.0, 12.0,
	                                  13.0};
	double sum[SS_COMM_REDUCE_MAX] = {2.0, 21.0, 22.0, 23.0};
	ss_comm_reduce(max, 1, sum, 1);
	CHECK(max[0] == INFINITY, "a NaN on the last rank: max[0] = %.17g, not +inf", max[0]);
	CHECK(same_bits(sum[0], 2.0 * P), "sum[0] = %.17g, not %.17g", sum[0], 2.0 * P);
	CHECK(max[1] == 11.0 && max[2] == 12.0 && max[3] == 13.0 && sum[1] == 21.0 &&
	      sum[2] == 22.0 && sum[3] == 23.0,
	      "entries past n_max = n_sum = 1 changed: max %g %g %g, sum %g %g %g", max[1],
	      max[2], max[3], sum[1], sum[2], sum[3]);

	/* maxima only, sums only */
	double m2[2] = {5.0 - rank, (double)(rank % 2)}, s0[1] = {99.0};
	ss_comm_reduce(m2, 2, s0, 0);
	CHECK(m2[0] == 5.0 && m2[1] == (ranks > 1 ? 1.0 : 0.0) && s0[0] == 99.0,
	      "maxima only: %g %g, the sum %g untouched", m2[0], m2[1], s0[0]);
	double m0[1] = {NAN}, s2[2] = {1.0, (double)rank};
	ss_comm_reduce(m0, 0, s2, 2);
	CHECK(isnan(m0[0]) && s2[0] == P && s2[1] == P * (P - 1) / 2,
	      "sums only: %g %g, the NaN of n_max = 0 untouched (%g)", s2[0], s2[1], m0[0]);
}

/* ---- the ordered fold -------------------------------------------------------- */

#define N_VALUES 22

static double value(int k)
{
	/* large terms that cancel and small ones that they swallow: every
	 * order of additions differs (checked below) */
	static const double base[] = {1e16, 1.0, -1e16, 3.3, 1.0, 1e16, 2.5e-7,
	                              -1e16, 0.1, 7.0, -3.3, 1e-3, 1.0};
	return base[k % (int)(sizeof base / sizeof *base)];
}

/* The fold each rank continues: a sum, and a decaying sum (also order
 * dependent, so a second running value is carried too). */
static void fold_over(double running[2], int k0, int k1)
{
	for (int k = k0; k < k1; k++) {
		running[0] += value(k);
		running[1] = 0.75 * running[1] + value(k);
	}
}

static void test_fold(void)
{
	/* the serial left fold, and the sum of per-rank partial sums it must
	 * not be confused with */
	double serial[2] = {0.0, 0.5};
	fold_over(serial, 0, N_VALUES);
	if (ranks > 1) {
		double partials = 0.0;
		for (int r = 0; r < ranks; r++) {
			const long long base = N_VALUES / ranks, extra = N_VALUES % ranks;
			const long long f = r * base + (r < extra ? r : extra);
			const long long c = base + (r < extra ? 1 : 0);
			double part[2] = {0.0, 0.0};
			fold_over(part, (int)f, (int)(f + c));
			partials += part[0];
		}
		CHECK(!same_bits(partials, serial[0]),
		      "test set-up: with %d ranks the partial sums give the serial bits too "
		      "(%.17g): the values do not test the order", ranks, partials);
	}

	/* no values at all, fewer values than ranks (with 3 or 4 ranks some
	 * hold none), an uneven split, all of them */
	static const int counts[] = {0, 2, 10, N_VALUES};
	for (size_t m = 0; m < sizeof counts / sizeof *counts; m++) {
		const int n = counts[m];
		double want[2] = {0.0, 0.5};
		fold_over(want, 0, n);
		long long first, count;
		ss_comm_split(n, &first, &count);
		/* rank 0 sets the start; the others' running values must be
		 * replaced by what the ranks south of them reached */
		double running[2] = {rank == 0 ? 0.0 : NAN, rank == 0 ? 0.5 : -7.0};
		ss_comm_fold_start(running, 2);
		fold_over(running, (int)first, (int)(first + count));
		ss_comm_fold_finish(running, 2);
		CHECK(same_bits(running[0], want[0]), "%d values: the fold's sum is %.17g, the "
		      "serial left fold %.17g", n, running[0], want[0]);
		CHECK(same_bits(running[1], want[1]), "%d values: the second running value is "
		      "%.17g, the serial fold %.17g", n, running[1], want[1]);
	}

	/* two folds in a row do not mix */
	double a[1] = {rank == 0 ? 1.0 : NAN}, b[1] = {rank == 0 ? 1000.0 : NAN};
	ss_comm_fold_start(a, 1);
	a[0] += 1.0;
	ss_comm_fold_finish(a, 1);
	ss_comm_fold_start(b, 1);
	b[0] -= 1.0;
	ss_comm_fold_finish(b, 1);
	CHECK(a[0] == 1.0 + ranks && b[0] == 1000.0 - ranks,
	      "back-to-back folds: %.17g and %.17g, not %d and %d", a[0], b[0], 1 + ranks,
	      1000 - ranks);
}

/* Value k of fold e of test_fold_many, of sum `which` (0, 1): value()'s
 * cancelling terms, a third of them replaced by +0 or -0. */
static double many_value(int e, int k, int which)
{
	const int m = e * 7 + k * 3 + which;
	if (m % 3 == 0)
		return m % 2 ? -0.0 : 0.0;
	return value(e + k + 5 * which);
}

#define N_FOLDS 3000

static void test_fold_many(void)
{
	double *run = zalloc(2 * N_FOLDS * sizeof *run);
	for (int k = 0; k < 2 * N_FOLDS; k++)
		run[k] = rank == 0 ? 0.0 : NAN;
	ss_comm_fold_start(run, 2 * N_FOLDS);
	for (int e = 0; e < N_FOLDS; e++) {
		long long first, count;
		ss_comm_split(e % 23, &first, &count);
		for (int which = 0; which < 2; which++) {
			double sum = run[2 * e + which];
			for (long long k = first; k < first + count; k++) {
				const double t = many_value(e, (int)k, which);
				if (t != 0.0)   /* as the batch keeps them */
					sum += t;
			}
			run[2 * e + which] = sum;
		}
	}
	ss_comm_fold_finish(run, 2 * N_FOLDS);
	int bad = 0, zeros = 0;
	for (int e = 0; e < N_FOLDS; e++) {
		for (int which = 0; which < 2; which++) {
			double want = 0.0;
			for (int k = 0; k < e % 23; k++)
				want += many_value(e, k, which);
			zeros += want == 0.0;
			if (!same_bits(run[2 * e + which], want) && bad++ < 3)
				CHECK(0, "fold %d, sum %d: %.17g, the serial left fold %.17g", e, which,
				      run[2 * e + which], want);
		}
	}
	CHECK(bad == 0, "%d of %d batched folds differ from the serial ones", bad, 2 * N_FOLDS);
	CHECK(zeros > 0, "test set-up: no fold ends at zero (the sign of a zero is not tested)");
	free(run);
}

/* ---- gather, broadcast --------------------------------------------------------- */

static void test_gather_and_broadcast(void)
{
	/* rank r sends r + 1 values, except rank 1, which sends none */
	const int mine_n = rank == 1 ? 0 : rank + 1;
	double *mine = zalloc((size_t)(ranks + 1) * sizeof *mine);
	for (int k = 0; k < mine_n; k++)
		mine[k] = 100.0 * rank + k + 0.25;
	int total = 0;
	for (int r = 0; r < ranks; r++)
		total += r == 1 ? 0 : r + 1;
	double *all = rank == 0 ? zalloc((size_t)total * sizeof *all) : NULL;
	ss_comm_gather_rows(mine, (size_t)mine_n * sizeof *mine, all);
	if (rank == 0) {
		int at = 0, bad = 0;
		for (int r = 0; r < ranks; r++)
			for (int k = 0; k < (r == 1 ? 0 : r + 1); k++, at++) {
				const int same = same_bits(all[at], 100.0 * r + k + 0.25);
				bad += !same;
				CHECK(same || bad > 4, "gathered value %d is %.17g, not value %d "
				      "of rank %d (%.17g)", at, all[at], k, r,
				      100.0 * r + k + 0.25);
			}
		CHECK(bad == 0, "%d gathered values out of place", bad);
	}
	free(all);
	free(mine);

	for (int root = 0; root < 2; root++) {
		const int from = root ? ranks - 1 : 0;
		double buf[5];
		for (int k = 0; k < 5; k++)
			buf[k] = rank == from ? -1.5 * k + from : NAN;
		ss_comm_broadcast(buf, sizeof buf, from);
		for (int k = 0; k < 5; k++)
			CHECK(same_bits(buf[k], -1.5 * k + from), "broadcast from rank %d: element "
			      "%d is %.17g", from, k, buf[k]);
	}
	ss_comm_barrier();
}

/* ---- agreeing on a failure ------------------------------------------------------- */

static void test_agree(void)
{
	int got = ss_comm_agree(SS_OK);
	CHECK(got == SS_OK, "every rank SS_OK: agreed %d", got);

	/* the last rank fails with bad input (one rank: rank 0 itself) */
	got = ss_comm_agree(rank == ranks - 1 ? SS_ERR_INPUT : SS_OK);
	CHECK(got == SS_ERR_INPUT, "rank %d failed with SS_ERR_INPUT: agreed %d", ranks - 1,
	      got);

	/* rank 0 fails: its status, on every rank */
	got = ss_comm_agree(rank == 0 ? SS_ERR_FAIL : SS_OK);
	CHECK(got == SS_ERR_FAIL, "rank 0 failed with SS_ERR_FAIL: agreed %d", got);

	/* every rank but 0 fails, with alternating statuses: the first in
	 * rank order (rank 1) wins */
	if (ranks > 1) {
		got = ss_comm_agree(rank == 0 ? SS_OK : rank % 2 ? SS_ERR_INPUT : SS_ERR_FAIL);
		CHECK(got == SS_ERR_INPUT, "ranks 1.. failed, rank 1 with SS_ERR_INPUT: agreed %d",
		      got);
	}

	/* and agreement afterwards is SS_OK again */
	got = ss_comm_agree(SS_OK);
	CHECK(got == SS_OK, "after the failures, every rank SS_OK: agreed %d", got);
}

int main(int argc, char **argv)
{
	ss_comm_init(&argc, &argv);
	/* a FAIL line (several fprintf calls in check.h) leaves in one write,
	 * not interleaved with another rank's */
	static char err_buf[8192];
	setvbuf(stderr, err_buf, _IOLBF, sizeof err_buf);
	rank = ss_comm_rank();
	ranks = ss_comm_size();
	if (rank == 0) {
		printf("test_comm: %d rank%s\n", ranks, ranks == 1 ? "" : "s");
		fflush(stdout);
	}
	RUN_ALL(test_split);
	RUN_ALL(test_take_rows);
	RUN_ALL(test_neighbours);
	RUN_ALL(test_exchange);
	RUN_ALL(test_halo);
	RUN_ALL(test_reduce);
	RUN_ALL(test_fold);
	RUN_ALL(test_fold_many);
	RUN_ALL(test_gather_and_broadcast);
	RUN_ALL(test_agree);

	/* the totals of every rank, printed once, and one exit status */
	int totals[3] = {check_passed, check_failed, check_skipped};
	sum_everywhere(totals, 3);
	check_passed = totals[0];
	check_failed = totals[1];
	check_skipped = totals[2];
	int status = 0;
	if (rank == 0)
		status = check_report();
	else
		status = check_failed ? 1 : 0;
	ss_comm_finalize();
	return status;
}
