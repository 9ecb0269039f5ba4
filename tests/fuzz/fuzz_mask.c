/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_mask.c - PNG masks of `mask = PNG` shapes, read by
 * ss_shape_rasterize (src/model/shape.c, libpng's simplified API).
 *
 * Input: the PNG file, its chunk CRCs made right.  The grid takes the size
 * the IHDR chunk states when it is at most 64 x 64 pixels (so that most
 * inputs get past the size check and are decoded), else 8 x 6 cells.  A mask that is read must set
 * exactly the cells it counts, and only cells of the grid.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/shape.h"

enum { MAX_SIDE = 64 };

static uint32_t be32(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_temp_path("mask.png");
	uint8_t *png = malloc(size ? size : 1);
	FUZZ_CHECK(png);
	memcpy(png, data, size);
	fuzz_png_fix_crcs(png, size);
	fuzz_write_file(path, png, size);
	free(png);

	int nx = 8, ny = 6;
	if (size >= 24 && memcmp(data + 12, "IHDR", 4) == 0) {
		const uint32_t w = be32(data + 16), h = be32(data + 20);
		if (w >= 1 && w <= MAX_SIDE && h >= 1 && h <= MAX_SIDE)
			nx = (int)w, ny = (int)h;
	}
	struct ss_grid g;
	FUZZ_CHECK(ss_grid_init(&g, nx, ny, 0.5, 0.25, -1.0, 2.0) == SS_OK);

	/* exactly nx * ny bytes on the heap, so AddressSanitizer sees a
	 * write past them */
	uint8_t *mask = calloc((size_t)nx * ny, 1);
	FUZZ_CHECK(mask);
	struct ss_shape shape;
	memset(&shape, 0, sizeof shape);
	shape.kind = SS_SHAPE_MASK;
	shape.mask_path = (char *)path;
	snprintf(shape.where, sizeof shape.where, "fuzz.ini:1");
	long long covered = -1;

	fuzz_quiet_begin();
	const int err = ss_shape_rasterize(&shape, &g, mask, &covered);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL);
	if (err == SS_OK) {
		long long set = 0;
		for (int k = 0; k < nx * ny; k++) {
			FUZZ_CHECK(mask[k] <= 1);
			set += mask[k];
		}
		FUZZ_CHECK(set == covered);
	}
	free(mask);
	return 0;
}
