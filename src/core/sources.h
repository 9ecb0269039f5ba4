/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sources.h - what the stepper pours (doc/model.md#sources): the case's
 * sources, each a rate on a set of flow cells while start <= t < stop, and
 * the rate field set from outside (the BMI's deposition rate), summed into
 * one field of m/s that the sweep adds to dh/dt.  The stepper rebuilds the
 * field at each step whose set of sources on differs from the last, or
 * after the rate field was set; its largest |rate| sets the source rule of
 * the time step (stepper.h), its volume rate the inflow (ledger.h).
 */
#ifndef SANDSLIDE_CORE_SOURCES_H
#define SANDSLIDE_CORE_SOURCES_H

#include <stddef.h>
#include <stdint.h>

#include "sandslide/grid.h"

#define SS_MAX_SOURCES 64

struct ss_source {
	double rate;            /* m/s of height added on each covered flow cell */
	double start, stop;     /* active for start <= t < stop, s */
	ptrdiff_t *cells;       /* storage indices of the flow cells covered */
	size_t cell_count;      /* on this rank */
	double cell_count_all;  /* on every rank */
};

struct ss_sources {
	struct ss_source *list;  /* count of them, room for SS_MAX_SOURCES */
	int count;
	uint64_t on;             /* bit k: source k is active now */
	double *rate;            /* m/s, with halo: the sources that are on
	                          * plus the rate field; NULL when neither was
	                          * ever set */
	double *field;           /* m/s, with halo: the rate field; NULL: none */
	int field_on;            /* field has a non-zero cell */
	int rate_on;             /* rate is added by the sweep now (a source
	                          * on, or the rate field) */
	int stale;               /* rebuild rate at the next step */
	double rate_max;         /* largest |rate| of any cell now, m/s */
	double volume_rate;      /* sum of rate dx dy now, m^3/s */
};

/* None yet, on the heap (NULL and SS_ERR_FAIL if it cannot be). */
int ss_sources_create(struct ss_sources **out);
void ss_sources_destroy(struct ss_sources *s);

/* ss_stepper_add_source (stepper.h) on the cell types given
 * (collective). */
int ss_sources_add(struct ss_sources *s, const struct ss_grid *g, const uint8_t *cell_types,
                   const uint8_t *mask, double rate, double start, double stop);

/* The field, when there are sources (ss_stepper_prepare). */
int ss_sources_prepare(struct ss_sources *s, const struct ss_grid *g);

/* ss_stepper_set_rate_field (stepper.h); with_bedrock refuses erosion. */
int ss_sources_set_field(struct ss_sources *s, const struct ss_grid *g,
                         const uint8_t *cell_types, int with_bedrock, const double *rate);

/* Time of the next source switch after t (INFINITY if none). */
double ss_sources_next_event(const struct ss_sources *s, double t);

/* The sources on at time t, and the field rebuilt if they changed or the
 * rate field was set: sources summed in file order and the rate field
 * last, so the field has the same bits every run (collective).  Returns 1
 * when it was rebuilt or switched off (the fast sweep marks its tiles
 * again), else 0. */
int ss_sources_update(struct ss_sources *s, const struct ss_grid *g, double t);

/* What the sweep adds: the field, or NULL while nothing is poured. */
static inline const double *ss_sources_rate(const struct ss_sources *s)
{
	return s->rate_on ? s->rate : NULL;
}

#endif
