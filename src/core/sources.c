/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sources.c - the sources and the rate field of a stepper, summed into the
 * field the sweep adds (see sources.h).
 */
#include "core/sources.h"

#include <math.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

int ss_sources_create(struct ss_sources **out)
{
	struct ss_sources *s = ss_alloc(1, sizeof *s, "sources");
	*out = s;
	if (!s)
		return SS_ERR_FAIL;
	memset(s, 0, sizeof *s);
	return SS_OK;
}

void ss_sources_destroy(struct ss_sources *s)
{
	if (!s)
		return;
	for (int k = 0; k < s->count; k++)
		ss_free(s->list[k].cells);
	ss_free(s->list);
	ss_free(s->rate);
	ss_free(s->field);
	ss_free(s);
}

int ss_sources_add(struct ss_sources *s, const struct ss_grid *g, const uint8_t *cell_types,
                   const uint8_t *mask, double rate, double start, double stop)
{
	if (s->count >= SS_MAX_SOURCES)
		return ss_error_input("at most %d sources are supported", SS_MAX_SOURCES);
	if (!s->list) {
		s->list = ss_alloc(SS_MAX_SOURCES, sizeof *s->list, "sources");
		if (!s->list)
			return SS_ERR_FAIL;
	}
	size_t count = 0;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			count += mask[(size_t)j * g->nx + i] &&
			         ss_cell_type_get(cell_types, ss_grid_index(g, i, j)) == SS_CELL_FLOW;
	struct ss_source *src = &s->list[s->count];
	double none = 0.0;
	src->cell_count_all = (double)count;
	ss_comm_reduce(&none, 0, &src->cell_count_all, 1);
	src->cells = ss_alloc(count ? count : 1, sizeof *src->cells, "source cells");
	if (!src->cells)
		return SS_ERR_FAIL;
	size_t n = 0;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (mask[(size_t)j * g->nx + i] && ss_cell_type_get(cell_types, k) == SS_CELL_FLOW)
				src->cells[n++] = k;
		}
	}
	src->cell_count = n;
	src->rate = rate;
	src->start = start;
	src->stop = stop;
	s->count++;
	return SS_OK;
}

int ss_sources_prepare(struct ss_sources *s, const struct ss_grid *g)
{
	if (s->count == 0)
		return SS_OK;
	s->rate = ss_alloc(ss_grid_storage_cells(g), sizeof(double), "source rates");
	return s->rate ? SS_OK : SS_ERR_FAIL;
}

double ss_sources_next_event(const struct ss_sources *s, double t)
{
	double next = INFINITY;
	for (int k = 0; k < s->count; k++) {
		const struct ss_source *src = &s->list[k];
		if (src->start > t && src->start < next)
			next = src->start;
		if (src->stop > t && src->stop < next)
			next = src->stop;
	}
	return next;
}

int ss_sources_update(struct ss_sources *s, const struct ss_grid *g, double t)
{
	uint64_t on = 0;
	for (int k = 0; k < s->count; k++) {
		const struct ss_source *src = &s->list[k];
		if (src->start <= t && t < src->stop && src->cell_count_all > 0)
			on |= UINT64_C(1) << k;
	}
	if (on == s->on && !s->stale)
		return 0;
	s->on = on;
	s->stale = 0;
	s->rate_on = on || s->field_on;
	s->rate_max = 0.0;
	s->volume_rate = 0.0;
	if (!s->rate_on)
		return 1;
	const size_t n = ss_grid_storage_cells(g);
	memset(s->rate, 0, n * sizeof(double));
	for (int k = 0; k < s->count; k++) {
		if (!(on >> k & 1))
			continue;
		const struct ss_source *src = &s->list[k];
		for (size_t m = 0; m < src->cell_count; m++)
			s->rate[src->cells[m]] += src->rate;
	}
	if (s->field_on)
		for (size_t k = 0; k < n; k++)
			s->rate[k] += s->field[k];
	/* the volume rate in storage order, deterministic: on several ranks
	 * one fold carried from rank to rank (the ghost rows between add
	 * zeros, which change no bit of a sum that starts at +0) */
	double rate_max = 0.0, volume_rate = 0.0;
	ss_comm_fold_start(&volume_rate, 1);
	for (size_t k = 0; k < n; k++) {
		volume_rate += s->rate[k];
		rate_max = fmax(rate_max, fabs(s->rate[k]));
	}
	ss_comm_fold_finish(&volume_rate, 1);
	ss_comm_reduce(&rate_max, 1, NULL, 0);
	s->rate_max = rate_max;
	s->volume_rate = volume_rate * g->dx * g->dy;
	return 1;
}

int ss_sources_set_field(struct ss_sources *s, const struct ss_grid *g,
                         const uint8_t *cell_types, int with_bedrock, const double *rate)
{
	const size_t n = ss_grid_storage_cells(g);
	int any = 0;
	if (rate) {
		/* every value checked before any is kept */
		for (int j = 0; j < g->ny; j++)
			for (int i = 0; i < g->nx; i++) {
				const double r = rate[(size_t)j * g->nx + i];
				const size_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(cell_types, k) != SS_CELL_FLOW)
					continue;
				if (!isfinite(r))
					return ss_error_input("rate field: %s is %g m/s: expected a "
					                      "finite rate", SS_GRID_CELL(g, i, j), r);
				if (r < 0.0 && with_bedrock)
					return ss_error_input("rate field: %s is %g m/s: a negative "
					                      "rate (erosion) needs a model without a "
					                      "bedrock", SS_GRID_CELL(g, i, j), r);
				any |= r != 0.0;
			}
		if (!s->rate && !(s->rate = ss_alloc(n, sizeof(double), "source rates")))
			return SS_ERR_FAIL;
		if (!s->field && !(s->field = ss_alloc(n, sizeof(double), "the rate field")))
			return SS_ERR_FAIL;
		memset(s->field, 0, n * sizeof(double));
		for (int j = 0; j < g->ny; j++)
			for (int i = 0; i < g->nx; i++) {
				const size_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(cell_types, k) == SS_CELL_FLOW)
					s->field[k] = rate[(size_t)j * g->nx + i];
			}
	}
	s->field_on = any;
	s->stale = 1;
	return SS_OK;
}
