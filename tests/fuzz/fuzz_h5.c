/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_h5.c - the HDF5 reader (src/io/h5_read.c, snapshot.h): what
 * `info`, `run --restart`, `render` and `.h5` DEMs read.
 *
 * Input: an HDF5 file.  Opened as an image in memory
 * (ss_snapshot_file_open_image, HDF5's core driver), it is read as the
 * commands read it: the cell types and the first and last snapshots in
 * blocks of rows (the renderer), the summary (`info`) and the restart
 * information.  Written as a file, it is read again by path, which must
 * agree with the image, and as DEMs: "in.h5" (the last snapshot, with
 * its geometry) and "in.h5:/height", "in.h5:/cell_type" (any (time, y, x)
 * or (y, x) dataset).  What a successful read returns must hold what
 * snapshot.h promises: sizes within the file's, positive cell sizes, cell
 * types 0 to 2, the same heights whichever way they are read.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "fuzz_dem.h"
#include "sandslide/error.h"
#include "sandslide/snapshot.h"

static int fuzz_status(int err)
{
	return err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL;
}

/* The cell types in blocks of `block` rows: each 0, 1 or 2 (a cell
 * without data, 3 in the file, is read as a wall). */
static void read_types(struct ss_snapshot_file *f, int block)
{
	uint8_t *t = malloc((size_t)block * (size_t)f->nx);
	FUZZ_CHECK(t);
	for (int j0 = 0; j0 < f->ny; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		fuzz_quiet_begin();
		const int err = ss_snapshot_file_read_cell_types(f, j0, rows, t);
		fuzz_quiet_end();
		FUZZ_CHECK(fuzz_status(err));
		if (err)
			break;
		for (size_t k = 0; k < (size_t)rows * (size_t)f->nx; k++)
			FUZZ_CHECK(t[k] <= 2);
	}
	free(t);
}

/* Snapshot t in blocks of `block` rows into h (nx * ny); 0 if it read. */
static int read_snapshot(struct ss_snapshot_file *f, long long t, int block, double *h)
{
	int err = SS_OK;
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		fuzz_quiet_begin();
		err = ss_snapshot_file_read_rows(f, t, j0, rows, h + (size_t)j0 * f->nx);
		fuzz_quiet_end();
		FUZZ_CHECK(fuzz_status(err));
	}
	return err;
}

static void check_file(const struct ss_snapshot_file *f, size_t size)
{
	FUZZ_CHECK(f->nx >= 1 && f->ny >= 1 && f->count >= 0 && f->time && f->name);
	/* a grid no larger than a plain file, or 1032 times a deflated one */
	FUZZ_CHECK((double)f->nx * f->ny <= 1032.0 * (double)size);
	FUZZ_CHECK((double)f->count <= 1032.0 * (double)size);
	FUZZ_CHECK(isfinite(f->dx) && f->dx > 0.0 && isfinite(f->dy) && f->dy > 0.0);
	FUZZ_CHECK(isnan(f->origin_x) || isfinite(f->origin_x));
	FUZZ_CHECK(isnan(f->origin_y) || isfinite(f->origin_y));
	volatile double sum = 0.0;   /* every time can be read (AddressSanitizer) */
	for (long long k = 0; k < f->count; k++)
		sum += f->time[k];
	(void)sum;
}

/* The summary agrees with the file; into s (released by the caller). */
static int check_summary(struct ss_snapshot_file *f, struct ss_snapshot_summary *s)
{
	fuzz_quiet_begin();
	const int err = ss_snapshot_file_summary(f, s);
	fuzz_quiet_end();
	FUZZ_CHECK(fuzz_status(err));
	if (!err) {
		FUZZ_CHECK(s->nx == f->nx && s->ny == f->ny && s->count == f->count);
		FUZZ_CHECK(s->flow_cells + s->wall_cells + s->open_cells + s->nodata_cells ==
		           (long long)f->nx * f->ny);
		FUZZ_CHECK(!memcmp(s->time, f->time, (size_t)f->count * sizeof *s->time));
		FUZZ_CHECK(memchr(s->source, 0, sizeof s->source) && !strncmp(s->source, "sandslide", 9));
	}
	return err;
}

/* Two summaries of one file, as an image and by path, are the same (the
 * two opens need not both succeed: HDF5's drivers differ on some damage). */
static void same_summary(const struct ss_snapshot_summary *a, const struct ss_snapshot_summary *b)
{
	FUZZ_CHECK(a->nx == b->nx && a->ny == b->ny && a->count == b->count);
	FUZZ_CHECK(!memcmp(a->time, b->time, (size_t)a->count * sizeof *a->time));
	FUZZ_CHECK(!memcmp(a->diag, b->diag, (size_t)a->count * sizeof *a->diag));
	FUZZ_CHECK(a->flow_cells == b->flow_cells && a->wall_cells == b->wall_cells &&
	           a->open_cells == b->open_cells && a->nodata_cells == b->nodata_cells);
	FUZZ_CHECK(!strcmp(a->title, b->title) && !strcmp(a->closure, b->closure));
}

/* The restart information holds the last snapshot, as read by rows. */
static void check_restart(struct ss_snapshot_file *f, const double *last, int last_err)
{
	struct ss_restart_info r;
	fuzz_quiet_begin();
	const int err = ss_snapshot_file_restart(f, &r);
	fuzz_quiet_end();
	FUZZ_CHECK(fuzz_status(err));
	if (err)
		return;
	FUZZ_CHECK(r.count == f->count && r.count >= 1 && r.nx == f->nx && r.ny == f->ny);
	FUZZ_CHECK(r.case_text && r.case_text[0] && r.case_path && r.case_overrides);
	FUZZ_CHECK(r.state.steps >= 0 && isfinite(r.state.inflow.sum + r.state.outflow.sum));
	FUZZ_CHECK(last_err == SS_OK && r.height);
	FUZZ_CHECK(!memcmp(r.height, last, (size_t)f->nx * (size_t)f->ny * sizeof *last));
	ss_restart_info_release(&r);
}

/* Read everything as the commands do; the summary into sum (its status). */
static int read_image(const uint8_t *data, size_t size, struct ss_raster *last_snapshot,
                      struct ss_snapshot_summary *sum)
{
	struct ss_snapshot_file f;
	fuzz_quiet_begin();
	int err = ss_snapshot_file_open_image(&f, "fuzz.h5", data, size);
	fuzz_quiet_end();
	FUZZ_CHECK(fuzz_status(err));
	if (err)
		return err;
	check_file(&f, size);
	read_types(&f, 2);
	double *h = calloc((size_t)f.nx * (size_t)f.ny, sizeof *h);
	FUZZ_CHECK(h);
	int last_err = SS_ERR_INPUT;
	if (f.count > 0) {
		read_snapshot(&f, 0, 1, h);
		last_err = read_snapshot(&f, f.count - 1, ss_snapshot_file_block_rows(&f), h);
	}
	err = check_summary(&f, sum);
	check_restart(&f, h, last_err);
	if (!last_err) {   /* what the DEM reader must return */
		last_snapshot->nx = f.nx;
		last_snapshot->ny = f.ny;
		last_snapshot->values = h;
	} else {
		free(h);
	}
	ss_snapshot_file_close(&f);
	return err;
}

static int all_finite(const double *v, size_t n)
{
	for (size_t k = 0; k < n; k++)
		if (!isfinite(v[k]))
			return 0;
	return 1;
}

/* ss_dem_read of spec; a DEM that is read holds what dem.h promises and,
 * given the last snapshot as the image gave it, is that snapshot.  With
 * `must` (the file opens by path too), finite heights that the image gave
 * must read. */
static void read_dem(const char *spec, const struct ss_raster *last, int must)
{
	struct ss_raster r;
	fuzz_quiet_begin();
	const int err = ss_dem_read(spec, "fuzz.ini:1", NULL, &r);
	fuzz_quiet_end();
	FUZZ_CHECK(fuzz_status(err));
	const size_t n = (size_t)last->nx * (size_t)last->ny;
	if (must && last->values && all_finite(last->values, n))
		FUZZ_CHECK(err == SS_OK);
	if (!err) {
		fuzz_check_raster(&r, SS_DEM_H5);
		if (last->values) {
			FUZZ_CHECK(r.nx == last->nx && r.ny == last->ny);
			FUZZ_CHECK(!memcmp(r.values, last->values, n * sizeof *r.values));
		}
	}
	ss_raster_release(&r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static int started;
	if (!started) {
		ss_snapshot_library_init();
		started = 1;
	}
	struct ss_raster last = {0};
	struct ss_snapshot_summary image_sum = {0}, path_sum;
	const int image_err = read_image(data, size, &last, &image_sum);

	const char *path = fuzz_temp_path("in.h5");
	fuzz_write_file(path, data, size);
	fuzz_quiet_begin();
	const int path_err = ss_snapshot_read_summary(path, &path_sum);
	fuzz_quiet_end();
	FUZZ_CHECK(fuzz_status(path_err));
	if (!image_err && !path_err)
		same_summary(&image_sum, &path_sum);
	ss_snapshot_summary_release(&image_sum);
	ss_snapshot_summary_release(&path_sum);

	/* a sandslide file's last snapshot, by path and as a dataset */
	const struct ss_raster none = {0};
	read_dem(path, &last, 0);
	char spec[600];
	snprintf(spec, sizeof spec, "%s:/height", path);
	read_dem(spec, &last, !path_err);
	snprintf(spec, sizeof spec, "%s:/cell_type", path);
	read_dem(spec, &none, 0);
	free(last.values);
	return 0;
}
