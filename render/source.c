/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * source.c - a sandslide output file (doc/output.md) as the renderer
 * reads it: the file through the one reader of src/io/h5_read.c
 * (snapshot.h), which checks it and serialises HDF5 between the threads
 * that render frames, and its cell types (one byte per cell, the file's
 * own: a cell without data is one, not a wall), read once.
 * Heights are read a block of whole chunks of rows at a time, so a
 * 16384^2 snapshot never needs to be in memory at once.
 */
#include "internal.h"

#include <math.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"

void ss_render_source_close(struct ss_render_source *s)
{
	ss_snapshot_file_close(&s->file);
	ss_free(s->cell_type);
	s->cell_type = NULL;
}

int ss_render_source_open(struct ss_render_source *s, const char *path)
{
	memset(s, 0, sizeof *s);
	int err = ss_snapshot_file_open(&s->file, path);
	if (err)
		return err;
	const struct ss_snapshot_file *f = &s->file;
	s->cell_type = ss_alloc((size_t)f->nx * (size_t)f->ny, 1, "cell types");
	if (!s->cell_type)
		err = SS_ERR_FAIL;
	const int block = ss_snapshot_file_block_rows(f);
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		err = ss_snapshot_file_read_cell_flags(&s->file, j0, rows,
		                                       s->cell_type + (size_t)j0 * f->nx);
	}
	if (err)
		ss_render_source_close(s);
	return err;
}

int ss_render_source_range(struct ss_render_source *s, long long first, long long last,
                           double *zmin, double *zmax)
{
	const int nx = s->file.nx, ny = s->file.ny, block = ss_snapshot_file_block_rows(&s->file);
	double lo = INFINITY, hi = -INFINITY;
	double *buf = ss_alloc((size_t)block * (size_t)nx, sizeof *buf, "height rows");
	if (!buf)
		return SS_ERR_FAIL;
	int err = SS_OK;
	for (long long t = first; t <= last && !err; t++) {
		for (int j0 = 0; j0 < ny && !err; j0 += block) {
			const int rows = ny - j0 < block ? ny - j0 : block;
			if ((err = ss_snapshot_file_read_rows(&s->file, t, j0, rows, buf)))
				break;
			const uint8_t *ct = s->cell_type + (size_t)j0 * nx;
			#pragma omp parallel for schedule(static) reduction(min:lo) reduction(max:hi) \
				if((size_t)rows * nx > 65536)
			for (int j = 0; j < rows; j++)
				for (int i = 0; i < nx; i++) {
					const size_t k = (size_t)j * nx + i;
					const double v = buf[k];
					if (!ss_render_no_sand(ct[k]) && isfinite(v)) {
						lo = v < lo ? v : lo;
						hi = v > hi ? v : hi;
					}
				}
		}
	}
	ss_free(buf);
	*zmin = lo;
	*zmax = hi;
	return err;
}
