/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * materials.c - a raster of repose angles as the stepper's materials (see
 * materials.h).
 *
 * The materials are numbered by angle, smallest first, over the whole grid:
 * each rank sorts its own distinct angles, rank 0 merges the ranks' lists
 * and every rank takes the merged one, so that the numbers in the halo rows
 * traded between ranks mean the same on both sides.
 */
#include "model/materials.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

enum { MAX_MATERIALS = UINT16_MAX };

static int compare_doubles(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* values[0 .. n) sorted, each once; returns how many. */
static size_t sort_distinct(double *values, size_t n)
{
	qsort(values, n, sizeof *values, compare_doubles);
	size_t d = 0;
	for (size_t k = 0; k < n; k++)
		if (d == 0 || values[k] != values[d - 1])
			values[d++] = values[k];
	return d;
}

/* The distinct angles of the whole grid into *all (sorted, owned), from
 * this rank's `mine` (sorted, distinct, NaN-free); collective. */
static int merge_ranks(const double *mine, size_t n, double **all, size_t *count)
{
	const int ranks = ss_comm_size();
	double longest = (double)n;
	ss_comm_reduce(&longest, 1, NULL, 0);
	const size_t k = (size_t)longest;
	/* every rank sends k values, its own then NaN */
	double *padded = ss_alloc(k ? k : 1, sizeof *padded, "repose angles");
	double *gathered = ss_alloc((k ? k : 1) * (size_t)ranks, sizeof *gathered,
	                            "repose angles");
	int err = padded && gathered ? SS_OK : SS_ERR_FAIL;
	if ((err = ss_comm_agree(err))) {
		ss_free(padded);
		ss_free(gathered);
		return err;
	}
	for (size_t m = 0; m < k; m++)
		padded[m] = m < n ? mine[m] : NAN;
	ss_comm_gather_rows(padded, k * sizeof *padded, gathered);
	double total = 0.0;
	if (ss_comm_rank() == 0) {
		size_t kept = 0;
		for (size_t m = 0; m < k * (size_t)ranks; m++)
			if (gathered[m] == gathered[m])
				gathered[kept++] = gathered[m];
		total = (double)sort_distinct(gathered, kept);
	}
	ss_comm_broadcast(&total, sizeof total, 0);
	ss_comm_broadcast(gathered, (size_t)total * sizeof *gathered, 0);
	ss_free(padded);
	*all = gathered;
	*count = (size_t)total;
	return SS_OK;
}

/* The first cell of this rank that lacks data and flows, or an angle out
 * of range: its message.  Also this rank's distinct angles. */
static int check_angles(const struct ss_stepper *st, const struct ss_raster *r,
                        const char *what, double *distinct, size_t *n)
{
	const struct ss_grid *g = &st->grid;
	const size_t first = (size_t)(g->offset_j - r->row_first) * g->nx;
	size_t count = 0;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const size_t m = first + (size_t)j * g->nx + i;
			const double a = r->values[m];
			const int flows = ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j)) ==
			                  SS_CELL_FLOW;
			if (r->nodata && r->nodata[m]) {
				if (flows)
					return ss_error_input("%s has no data at %s: every cell that holds "
					                      "sand needs an angle", what,
					                      SS_GRID_CELL(g, i, j));
				continue;
			}
			if (!(a > 0.0 && a < 90.0))
				return ss_error_input("%s: the angle of %s is %g: expected degrees in "
				                      "(0, 90)", what, SS_GRID_CELL(g, i, j), a);
			distinct[count++] = a;
		}
	}
	*n = sort_distinct(distinct, count);
	return SS_OK;
}

static size_t find_angle(const double *angles, size_t n, double a)
{
	size_t lo = 0, hi = n;
	while (hi - lo > 1) {
		const size_t mid = lo + (hi - lo) / 2;
		if (angles[mid] <= a)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

int ss_materials_from_angles(struct ss_stepper *st, const struct ss_model_options *m,
                             const struct ss_raster *r, const char *what)
{
	const struct ss_grid *g = &st->grid;
	const size_t cells = (size_t)g->nx * (size_t)g->ny;
	if (g->offset_j < r->row_first || g->offset_j + g->ny > r->row_first + r->rows)
		SS_BUG("the angles hold rows %d + %d: not the slab's", r->row_first, r->rows);
	double *mine = ss_alloc(cells ? cells : 1, sizeof *mine, "repose angles");
	size_t n = 0, count = 0;
	int err = mine ? check_angles(st, r, what, mine, &n) : SS_ERR_FAIL;
	double *angles = NULL;
	if (!(err = ss_comm_agree(err)))
		err = merge_ranks(mine, n, &angles, &count);
	ss_free(mine);
	if (!err && count > MAX_MATERIALS)
		err = ss_error_input("%s holds %zu distinct angles: at most %d are accepted (round "
		                     "them, to 0.01 degree for example)", what, count, MAX_MATERIALS);
	if (!err && count == 0)
		err = ss_error_input("%s has no angle in a cell with data", what);
	struct ss_closure *closures = NULL;
	uint16_t *material = NULL;
	if (!err) {
		closures = ss_alloc(count, sizeof *closures, "materials");
		material = ss_alloc(cells ? cells : 1, sizeof *material, "materials");
		err = ss_comm_agree(closures && material ? SS_OK : SS_ERR_FAIL);
	}
	for (size_t k = 0; !err && k < count; k++)
		err = ss_closure_init(&closures[k], m->closure, angles[k], m->gamma, m->nu);
	if (!err) {
		const size_t first = (size_t)(g->offset_j - r->row_first) * g->nx;
		for (size_t c = 0; c < cells; c++) {
			const size_t q = first + c;
			material[c] = r->nodata && r->nodata[q]
				? 0 : (uint16_t)find_angle(angles, count, r->values[q]);
		}
		err = ss_stepper_set_materials(st, closures, (int)count, material);
	}
	ss_free(material);
	ss_free(closures);
	ss_free(angles);
	return ss_comm_agree(err);
}

/* The table's entry of this rank's cell m of r, or -1 after the message. */
static int class_of(const struct ss_stepper *st, const struct ss_material_table *t,
                    const struct ss_raster *r, size_t m, int i, int j, const char *what)
{
	const struct ss_grid *g = &st->grid;
	const int flows = ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j)) == SS_CELL_FLOW;
	if (r->nodata && r->nodata[m]) {
		if (flows)
			ss_error_input("%s has no data at %s: every cell that holds sand needs a "
			               "class", what, SS_GRID_CELL(g, i, j));
		return flows ? -1 : 0;
	}
	const double v = r->values[m];
	if (!(v >= 0.0 && v == floor(v) && v < 2147483648.0)) {
		ss_error_input("%s: the class of %s is %g: expected an integer >= 0", what,
		               SS_GRID_CELL(g, i, j), v);
		return -1;
	}
	for (int k = 0; k < t->count; k++)
		if ((double)t->item[k].class_value == v)
			return k;
	char classes[256] = "";
	for (int k = 0; k < t->count && strlen(classes) < sizeof classes - 24; k++)
		snprintf(classes + strlen(classes), sizeof classes - strlen(classes), "%s%lld",
		         k ? ", " : "", t->item[k].class_value);
	ss_error_input("%s: class %g of %s is not in the material table (its classes: %s)",
	               what, v, SS_GRID_CELL(g, i, j), classes);
	return -1;
}

int ss_materials_from_classes(struct ss_stepper *st, const struct ss_model_options *m,
                              const struct ss_material_table *t, const struct ss_raster *r,
                              const char *what)
{
	const struct ss_grid *g = &st->grid;
	const size_t cells = (size_t)g->nx * (size_t)g->ny;
	if (g->offset_j < r->row_first || g->offset_j + g->ny > r->row_first + r->rows)
		SS_BUG("the classes hold rows %d + %d: not the slab's", r->row_first, r->rows);
	struct ss_closure closures[SS_MATERIAL_MAX];
	double static_deg[SS_MATERIAL_MAX];   /* hysteresis: a class's own, or none */
	int err = SS_OK;
	for (int k = 0; k < t->count && !err; k++) {
		const struct ss_material_spec *s = &t->item[k];
		static_deg[k] = isnan(s->static_deg) ? s->angle_deg : s->static_deg;
		err = ss_closure_init(&closures[k], s->has_closure ? s->closure : m->closure,
		                      s->angle_deg, isnan(s->gamma) ? m->gamma : s->gamma,
		                      isnan(s->nu) ? m->nu : s->nu);
		if (err) {
			char why[512];
			snprintf(why, sizeof why, "%s", ss_error_last_message());
			err = ss_error_input("%s: [material %s]: %s", s->where, s->name, why);
		}
	}
	uint16_t *material = err ? NULL : ss_alloc(cells ? cells : 1, sizeof *material,
	                                           "materials");
	if (!err && !material)
		err = SS_ERR_FAIL;
	const size_t first = err ? 0 : (size_t)(g->offset_j - r->row_first) * g->nx;
	for (int j = 0; j < g->ny && !err; j++)
		for (int i = 0; i < g->nx && !err; i++) {
			const int k = class_of(st, t, r, first + (size_t)j * g->nx + i, i, j, what);
			if (k < 0)
				err = SS_ERR_INPUT;
			else
				material[(size_t)j * g->nx + i] = (uint16_t)k;
		}
	if (!(err = ss_comm_agree(err)))
		err = ss_stepper_set_hysteresis_materials(st, closures, static_deg, t->count,
		                                          material);
	ss_free(material);
	return ss_comm_agree(err);
}

/* Cell (i, j)'s angle now: its material's, or the closure's. */
static double angle_now(const struct ss_stepper *st, int i, int j)
{
	return st->material
		? st->materials[st->material[ss_grid_index(&st->grid, i, j)]].repose_angle_deg
		: st->closure.repose_angle_deg;
}

/* Each cell's law (closure, gamma and nu: all but the angle) into law[]
 * (this rank's cells, [y][x]) and the distinct laws into laws[] (at most
 * st's material count): st's materials are the same on every rank. */
static int cell_laws(const struct ss_stepper *st, uint16_t *law, struct ss_closure *laws)
{
	const struct ss_grid *g = &st->grid;
	const int count = st->material ? st->material_count : 1;
	const struct ss_closure *given = st->material ? st->materials : &st->closure;
	uint16_t law_of[UINT16_MAX];   /* 128 KiB: count <= UINT16_MAX */
	int n = 0;
	for (int m = 0; m < count; m++) {
		const struct ss_closure *c = &given[m];
		int l = 0;
		while (l < n && !(laws[l].kind == c->kind && laws[l].gamma == c->gamma &&
		                  laws[l].nu == c->nu))
			l++;
		if (l == n)
			laws[n++] = *c;
		law_of[m] = (uint16_t)l;
	}
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			law[(size_t)j * g->nx + i] =
				law_of[st->material ? st->material[ss_grid_index(g, i, j)] : 0];
	return n;
}

int ss_materials_change_angles(struct ss_stepper *st, const double *angle_deg, const char *what)
{
	const struct ss_grid *g = &st->grid;
	const size_t cells = (size_t)g->nx * (size_t)g->ny;
	if (st->hysteresis)
		return ss_comm_agree(ss_error_input("%s: not with a static angle (hysteresis takes "
		                                    "one repose angle)", what));
	double *angle = ss_alloc(cells ? cells : 1, sizeof *angle, "repose angles");
	double *mine = ss_alloc(cells ? cells : 1, sizeof *mine, "repose angles");
	uint16_t *law = ss_alloc(cells ? cells : 1, sizeof *law, "materials");
	uint16_t *material = ss_alloc(cells ? cells : 1, sizeof *material, "materials");
	const int most = st->material ? st->material_count : 1;
	struct ss_closure *laws = ss_alloc((size_t)most, sizeof *laws, "materials");
	int err = angle && mine && law && material && laws ? SS_OK : SS_ERR_FAIL;
	/* the angle each cell takes: a flow cell's is checked; a wall's stays
	 * (no face of it slides); an open cell's, which its faces take, is
	 * the one given when it is an angle, else it stays */
	for (int j = 0; !err && j < g->ny; j++)
		for (int i = 0; !err && i < g->nx; i++) {
			const size_t c = (size_t)j * g->nx + i;
			const double a = angle_deg[c];
			const enum ss_cell_type type =
				ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j));
			const int valid = a > 0.0 && a < 90.0;
			if (type == SS_CELL_FLOW && !valid)
				err = ss_error_input("%s: item %zu, the angle of %s, is %g: expected "
				                     "degrees in (0, 90)", what, c, SS_GRID_CELL(g, i, j),
				                     a);
			angle[c] = type != SS_CELL_WALL && valid ? a : angle_now(st, i, j);
		}
	err = ss_comm_agree(err);
	const int laws_count = err ? 0 : cell_laws(st, law, laws);
	/* each law's distinct angles over the whole grid, laws one after the
	 * other: every rank numbers them alike (merge_ranks) */
	double **angles = err ? NULL : ss_alloc((size_t)laws_count, sizeof *angles, "materials");
	size_t *count = err ? NULL : ss_alloc((size_t)laws_count, sizeof *count, "materials");
	if (!err)
		err = ss_comm_agree(angles && count ? SS_OK : SS_ERR_FAIL);
	for (int l = 0; !err && l < laws_count; l++)
		angles[l] = NULL;
	size_t total = 0;
	for (int l = 0; !err && l < laws_count; l++) {
		size_t n = 0;
		for (size_t c = 0; c < cells; c++)
			if (law[c] == l)
				mine[n++] = angle[c];
		if (!(err = merge_ranks(mine, sort_distinct(mine, n), &angles[l], &count[l])))
			total += count[l];
	}
	if (!err && total > MAX_MATERIALS)
		err = ss_error_input("%s holds %zu distinct angles: at most %d are accepted (round "
		                     "them, to 0.01 degree for example)", what, total, MAX_MATERIALS);
	struct ss_closure *closures = err ? NULL : ss_alloc(total, sizeof *closures, "materials");
	if (!err)
		err = ss_comm_agree(closures ? SS_OK : SS_ERR_FAIL);
	for (size_t l = 0, first = 0; !err && l < (size_t)laws_count; first += count[l++]) {
		for (size_t k = 0; !err && k < count[l]; k++)
			err = ss_closure_init(&closures[first + k], laws[l].kind, angles[l][k],
			                      laws[l].gamma, laws[l].nu);
		for (size_t c = 0; !err && c < cells; c++)
			if (law[c] == l)
				material[c] = (uint16_t)(first + find_angle(angles[l], count[l], angle[c]));
	}
	if (!err)
		err = ss_stepper_change_materials(st, closures, (int)total, material);
	for (int l = 0; angles && l < laws_count; l++)
		ss_free(angles[l]);
	ss_free(angles);
	ss_free(count);
	ss_free(closures);
	ss_free(laws);
	ss_free(material);
	ss_free(law);
	ss_free(mine);
	ss_free(angle);
	return ss_comm_agree(err);
}
