/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_case.c - the case-file parser, ss_case_parse (src/model/case.c).
 *
 * Input: the case text, then up to four --set overrides, each after a NUL
 * byte ("[grid]\nnx = 3 ...\0model.closure=casson\0source s.rate=1").
 * Nothing is read from disk: file names in the case are only stored.  A
 * case the parser accepts must hold what finish() promises the set-up.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "sandslide/case.h"
#include "sandslide/error.h"

enum { MAX_OVERRIDES = 4 };

static void check_case(const struct ss_case *c)
{
	FUZZ_CHECK(c->path && c->text);
	FUZZ_CHECK(c->nx >= 1 && c->ny >= 1);
	FUZZ_CHECK(c->dx > 0.0 && isfinite(c->dx) && c->dy > 0.0 && isfinite(c->dy));
	FUZZ_CHECK(isfinite(c->origin_x) && isfinite(c->origin_y));
	FUZZ_CHECK(isfinite(c->origin_x + c->nx * c->dx) && isfinite(c->origin_y + c->ny * c->dy));
	FUZZ_CHECK(c->model.angle_deg > 0.0 && c->model.angle_deg < 90.0);
	FUZZ_CHECK(c->model.nu > 0.0 && isfinite(c->model.nu));
	FUZZ_CHECK(c->model.gamma > 0.0 && isfinite(c->model.gamma));
	FUZZ_CHECK(c->model.cfl > 0.0 && c->model.cfl <= 1.0);
	FUZZ_CHECK(c->output_every > 0.0 && isfinite(c->output_every));
	FUZZ_CHECK(c->steady ? isinf(c->end) : c->end > 0.0 && isfinite(c->end));
	FUZZ_CHECK(c->model.steady_tol > 0.0);
	FUZZ_CHECK(c->steady || isnan(c->model.max_time));
	FUZZ_CHECK(c->note_count >= 0 && c->note_count <= SS_CASE_MAX_NOTES);
	FUZZ_CHECK(c->initial != SS_INITIAL_FILE || c->initial_file);
	FUZZ_CHECK(c->region_count >= 0 && (c->region_count == 0 || c->regions));
	for (int k = 0; k < c->region_count; k++) {
		const struct ss_region *r = &c->regions[k];
		const struct ss_shape *s = &r->shape;
		FUZZ_CHECK(s->kind != SS_SHAPE_NONE);
		FUZZ_CHECK(s->kind != SS_SHAPE_MASK || s->mask_path);
		if (s->kind == SS_SHAPE_POLYGON) {
			FUZZ_CHECK(s->polygon_points >= 3 && s->polygon);
			for (int a = 0; a < 2 * s->polygon_points; a++)
				FUZZ_CHECK(isfinite(s->polygon[a]));
		}
		if (r->role == SS_REGION_SOURCE)
			FUZZ_CHECK(r->rate > 0.0 && r->stop > r->start && r->start >= 0.0);
	}
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char *text = malloc(size + 1);
	if (!text)
		return 0;
	memcpy(text, data, size);
	text[size] = '\0';
	const char *overrides[MAX_OVERRIDES];
	int count = 0;
	for (char *s = text + strlen(text); s < text + size && count < MAX_OVERRIDES;) {
		overrides[count++] = ++s;
		s += strlen(s);
	}

	struct ss_case c;
	fuzz_quiet_begin();
	/* a folder in the path: relative file names are resolved against it */
	const int err = ss_case_parse(&c, "fuzz/case.ini", text, overrides, count);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL);
	if (err == SS_OK)
		check_case(&c);
	ss_case_release(&c);
	free(text);
	return 0;
}
