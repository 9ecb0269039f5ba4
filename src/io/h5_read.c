/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_read.c - the snapshot reader (snapshot.h): the one definition of a
 * sandslide file, checked as it is opened, and what is read of one: the
 * rows of a snapshot and the cell types a block at a time (the renderer's
 * frames, ss_snapshot_file_*), a 2-D field of any HDF5 file (.h5 DEMs,
 * ss_snapshot_read_field) and a series of heights of any HDF5 file (fit's
 * observations, ss_snapshot_read_height_series).  `sandslide info`'s
 * summary and `run --restart`'s state are read in h5_summary.c, and
 * ss_snapshot_open_append's check reads the summary; all of them open the
 * file here.
 *
 * Every read goes through h5_checked.c, which checks each size a file
 * states against the file before anything of that size is allocated (a
 * damaged file is SS_ERR_INPUT with one message saying so) and turns
 * HDF5's own error printing off: each failure prints one sandslide
 * message.
 */
#include "sandslide/snapshot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "base/strings.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "io/h5_checked.h"
#include "io/h5_read.h"
#include "io/snapshot_layout.h"

#define BLOCK_BYTES (8ll << 20)     /* rows per block read: about 8 MB */

int ss_snapshot_threadsafe(void)
{
	hbool_t safe = 0;
	return H5is_library_threadsafe(&safe) >= 0 && safe;
}


/* The centre of cell k along an axis from edge x0 (0 when unknown) in steps
 * of d, as the raster readers name cells (NaN without d: no coordinates). */
#define CENTRE(x0, d, k) ((isnan(x0) ? 0.0 : (x0)) + ((double)(k) + 0.5) * (d))

/* ---- a series of a sandslide file -------------------------------------- */

int ss_h5_read_series(const struct ss_h5_file *in, const char *name, long long n, double *out)
{
	struct ss_h5_var v;
	int err = ss_h5_var_open(in, name, &v);
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] < (hsize_t)n ||
	                         v.dims[0] > (hsize_t)n + 1)))
		err = ss_error_input("'%s' is not a sandslide output file: no /%s (time) of %lld "
		                     "values", in->name, name, n);
	const hsize_t start = 0, count = (hsize_t)n;
	char what[80];
	snprintf(what, sizeof what, "/%s", name);
	if (!err && n > 0)
		err = ss_h5_var_read(in, &v, &start, &count, H5T_NATIVE_DOUBLE, out, what);
	ss_h5_var_close(&v);
	return err;
}

/* ---- a sandslide file ------------------------------------------------ */

static int not_sandslide(const struct ss_h5_file *in, const char *why)
{
	return ss_error_input("'%s' is not a sandslide output file: %s", in->name, why);
}

/* /height (time, y, x) and /cell_type (y, x) of a grid of 1 .. 2^30 cells
 * a side, into f. */
static int check_grid(struct ss_snapshot_file *f)
{
	struct ss_snapshot_file_h5 *h = f->h5;
	int err = ss_h5_var_open(&h->in, "height", &h->height);
	if (err > 0 || (!err && h->height.rank != 3))
		return not_sandslide(&h->in, "no /height (time, y, x) of numbers (doc/output.md)");
	if (err)
		return err;
	const hsize_t *hd = h->height.dims;
	if (hd[1] < 1 || hd[2] < 1 || hd[1] > SS_SNAPSHOT_MAX_SIDE || hd[2] > SS_SNAPSHOT_MAX_SIDE)
		return ss_error_input("'%s' is not a sandslide output file: /height has %llu x %llu "
		                      "cells", h->in.name, (unsigned long long)hd[2],
		                      (unsigned long long)hd[1]);
	f->ny = (int)hd[1];
	f->nx = (int)hd[2];
	err = ss_h5_var_open(&h->in, "cell_type", &h->cell_type);
	const hsize_t *cd = h->cell_type.dims;
	if (err > 0 || (!err && (h->cell_type.rank != 2 || cd[0] != hd[1] || cd[1] != hd[2])))
		return not_sandslide(&h->in, "/cell_type (y, x) does not match /height");
	if (err)
		return err;
	/* /moving of a run with hysteresis: the shape of /height */
	err = ss_h5_var_open(&h->in, "moving", &h->moving);
	const hsize_t *md = h->moving.dims;
	if (err == SS_H5_VAR_MISSING) {
		ss_h5_var_close(&h->moving);
		h->moving.d = -1;
		return SS_OK;
	}
	/* (a run killed between the two extents leaves /height one longer) */
	if (err > 0 || (!err && (h->moving.rank != 3 || md[0] > hd[0] || md[0] + 1 < hd[0] ||
	                         md[1] != hd[1] || md[2] != hd[2])))
		return not_sandslide(&h->in, "/moving (time, y, x) does not match /height");
	return err;
}

/* /time (time) into f->time; its length is the count of complete
 * snapshots.  /height holds as many, or one more that a killed run did not
 * finish (the writer's append). */
static int read_times(struct ss_snapshot_file *f)
{
	const struct ss_snapshot_file_h5 *h = f->h5;
	const struct ss_h5_file *in = &h->in;
	struct ss_h5_var v;
	int err = ss_h5_var_open(in, "time", &v);
	const hsize_t stored = h->height.dims[0];
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] > stored || v.dims[0] + 1 < stored))) {
		char why[96];
		snprintf(why, sizeof why, "/time does not match /height (%llu snapshots)",
		         (unsigned long long)stored);
		err = not_sandslide(in, why);
	}
	if (!err)
		f->count = (long long)v.dims[0];
	ss_h5_var_close(&v);
	/* snapshots are written in order: the last one stored, all are */
	const hsize_t last[3] = {(hsize_t)f->count - 1, 0, 0},
	              one[3] = {1, h->height.dims[1], h->height.dims[2]};
	if (!err && f->count > 0)
		err = ss_h5_var_check_chunks(in, &h->height, last, one);
	if (!err && !(f->time = malloc((size_t)(f->count ? f->count : 1) * sizeof *f->time)))
		err = ss_error_fail("out of memory");
	return err ? err : ss_h5_read_series(in, "time", f->count, f->time);
}

/* The first value of the optional 1-D variable name into *v (NAN if it is
 * absent or empty). */
static int first_value(const struct ss_h5_file *in, const char *name, double *v)
{
	struct ss_h5_var x;
	*v = NAN;
	int err = ss_h5_var_open(in, name, &x);
	if (err > 0)
		return SS_OK;
	if (!err && x.rank == 1 && x.dims[0] >= 1) {
		const hsize_t start = 0, one = 1;
		err = ss_h5_var_read(in, &x, &start, &one, H5T_NATIVE_DOUBLE, v, name);
	}
	ss_h5_var_close(&x);
	return err;
}

/* The wall sides from the root attribute boundary ("west=wall east=open
 * ..."); none when it is missing.  A word that is not side=kind makes the
 * file damaged. */
static int read_wall_sides(struct ss_snapshot_file *f)
{
	const struct ss_h5_file *in = &f->h5->in;
	char text[256], *save = NULL;
	int err = ss_h5_attr_read_string(in, in->file, SS_SNAPSHOT_BOUNDARY, text, sizeof text);
	for (char *w = strtok_r(text, " ", &save); w && !err; w = strtok_r(NULL, " ", &save)) {
		char *eq = strchr(w, '=');
		enum ss_side_kind kind;
		int side = -1;
		for (int k = 0; eq && k < 4; k++)
			if ((size_t)(eq - w) == strlen(ss_side_name(k)) &&
			    !strncmp(w, ss_side_name(k), (size_t)(eq - w)))
				side = k;
		if (side < 0 || ss_side_kind_parse(eq + 1, &kind))
			err = ss_h5_damaged(in, "root attribute %s has '%s': expected SIDE=KIND, "
			                    "SIDE west, east, south or north and KIND wall, open or "
			                    "periodic", SS_SNAPSHOT_BOUNDARY, w);
		else if (kind == SS_SIDE_WALL)
			f->wall_sides |= 1u << side;
	}
	return err;
}

/* The definition of snapshot.h, the sizes and geometry into f. */
static int check_definition(struct ss_snapshot_file *f)
{
	const struct ss_h5_file *in = &f->h5->in;
	char source[256];
	int err = ss_h5_attr_read_string(in, in->file, "source", source, sizeof source);
	if (err)
		return err;
	if (strncmp(source, SS_SNAPSHOT_SOURCE, strlen(SS_SNAPSHOT_SOURCE)))
		return not_sandslide(in, "no root attribute source = \"sandslide ...\" "
		                         "(doc/output.md#the-one-reader)");
	if ((err = check_grid(f)) || (err = read_times(f)))
		return err;
	f->dx = ss_h5_attr_read_double(in->file, "dx");
	f->dy = ss_h5_attr_read_double(in->file, "dy");
	if (!(f->dx > 0.0) || !(f->dy > 0.0) || !isfinite(f->dx) || !isfinite(f->dy))
		return not_sandslide(in, "no positive dx, dy attributes");
	double x0, y0;
	if ((err = first_value(in, "x", &x0)) || (err = first_value(in, "y", &y0)))
		return err;
	/* the corner from the first cell centres */
	f->origin_x = x0 - 0.5 * f->dx;
	f->origin_y = y0 - 0.5 * f->dy;
	f->origin_x = isfinite(f->origin_x) ? f->origin_x : NAN;
	f->origin_y = isfinite(f->origin_y) ? f->origin_y : NAN;
	if ((err = read_wall_sides(f)))
		return err;
	/* the optional CF grid mapping variable /crs of a georeferenced run */
	if (H5Lexists(in->file, "crs", H5P_DEFAULT) > 0) {
		hid_t crs = H5Oopen(in->file, "crs", H5P_DEFAULT);
		if (crs >= 0) {
			err = ss_h5_attr_read_text(in, crs, "crs_wkt", &f->crs_wkt);
			H5Oclose(crs);
		}
	}
	return err;
}

void ss_snapshot_file_close(struct ss_snapshot_file *f)
{
	if (f->h5) {
		ss_h5_var_close(&f->h5->height);
		ss_h5_var_close(&f->h5->cell_type);
		ss_h5_var_close(&f->h5->moving);
		ss_h5_file_close(&f->h5->in);
		free(f->h5);
	}
	free(f->time);
	free(f->name);
	free(f->crs_wkt);
	memset(f, 0, sizeof *f);
}

static int file_open(struct ss_snapshot_file *f, const char *name, const void *data,
                     size_t size)
{
	memset(f, 0, sizeof *f);
	f->origin_x = f->origin_y = NAN;
	f->name = strdup(name);
	f->h5 = calloc(1, sizeof *f->h5);
	if (!f->name || !f->h5) {
		ss_snapshot_file_close(f);
		return ss_error_fail("out of memory");
	}
	f->h5->height.d = f->h5->cell_type.d = f->h5->moving.d = f->h5->in.file = -1;
	int err = ss_h5_file_open(&f->h5->in, f->name, data, size);
	if (!err)
		err = check_definition(f);
	if (err)
		ss_snapshot_file_close(f);
	return err;
}

int ss_snapshot_file_open(struct ss_snapshot_file *f, const char *path)
{
	return file_open(f, path, NULL, 0);
}

int ss_snapshot_file_open_image(struct ss_snapshot_file *f, const char *name,
                                const void *data, size_t size)
{
	static const char none;
	return file_open(f, name, size ? data : &none, size);
}

int ss_snapshot_file_block_rows(const struct ss_snapshot_file *f)
{
	/* whole chunks, so that each chunk is read once */
	long long rows = BLOCK_BYTES / (8ll * f->nx);
	rows = rows < SS_SNAPSHOT_CHUNK_SIDE ? SS_SNAPSHOT_CHUNK_SIDE
	                                     : rows / SS_SNAPSHOT_CHUNK_SIDE * SS_SNAPSHOT_CHUNK_SIDE;
	return rows > f->ny ? f->ny : (int)rows;
}

static void check_rows(const struct ss_snapshot_file *f, int j0, int rows)
{
	if (j0 < 0 || rows < 1 || rows > f->ny - j0)
		SS_BUG("rows %d .. %d of a grid of %d rows", j0, j0 + rows - 1, f->ny);
}

/* Walls are stored as NaN (the _FillValue, h5_write.c) and held at
 * 0 m by the stepper: give them 0 m again, so that a restart, a frame or a
 * DEM read from the file sees what the run had; so are cells without data
 * (read as walls), and a DEM read from the file has them as nodata, whose
 * value is 0 (dem.h).  A NaN anywhere else is left for the caller's checks
 * to find. */
static int walls_to_zero(struct ss_snapshot_file *f, int j0, int rows, double *out)
{
	const size_t n = (size_t)rows * (size_t)f->nx;
	size_t k = 0;
	while (k < n && !isnan(out[k]))
		k++;
	if (k == n)
		return SS_OK;
	uint8_t *types = ss_alloc(n, 1, "cell type rows");
	if (!types)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_cell_types(f, j0, rows, types);
	for (; k < n && !err; k++)
		if (types[k] == SS_CELL_WALL && isnan(out[k]))
			out[k] = 0.0;
	ss_free(types);
	return err;
}

/* Rows j0 .. j0 + rows - 1 of snapshot t of the (time, y, x) variable v
 * (/name) into out as mem_type; `what` (its size) gets its description. */
static int read_snapshot_block(struct ss_snapshot_file *f, struct ss_h5_var *v,
                               const char *name, long long t, int j0, int rows,
                               hid_t mem_type, void *out, char *what, size_t size)
{
	check_rows(f, j0, rows);
	if (t < 0 || t >= f->count)
		SS_BUG("snapshot %lld of %lld", t, f->count);
	const hsize_t start[3] = {(hsize_t)t, (hsize_t)j0, 0};
	const hsize_t count[3] = {1, (hsize_t)rows, (hsize_t)f->nx};
	snprintf(what, size, "snapshot %lld of /%s, rows %d .. %d", t, name, j0, j0 + rows - 1);
	int err;
	#pragma omp critical(ss_snapshot_hdf5)
	{
		ss_h5_quiet();
		err = ss_h5_var_read(&f->h5->in, v, start, count, mem_type, out, what);
	}
	return err;
}

int ss_snapshot_file_read_rows(struct ss_snapshot_file *f, long long t, int j0, int rows,
                               double *out)
{
	char what[96];
	const int err = read_snapshot_block(f, &f->h5->height, "height", t, j0, rows,
	                                    H5T_NATIVE_DOUBLE, out, what, sizeof what);
	return err ? err : walls_to_zero(f, j0, rows, out);
}

int ss_snapshot_file_has_moving(const struct ss_snapshot_file *f)
{
	return f->h5 && f->h5->moving.d >= 0;
}

int ss_snapshot_file_read_moving(struct ss_snapshot_file *f, long long t, int j0, int rows,
                                 uint8_t *out)
{
	if (!ss_snapshot_file_has_moving(f))
		SS_BUG("/moving of '%s', which has none", f->name);
	char what[96];
	int err = read_snapshot_block(f, &f->h5->moving, "moving", t, j0, rows,
	                              H5T_NATIVE_UINT8, out, what, sizeof what);
	const size_t n = (size_t)rows * (size_t)f->nx;
	for (size_t k = 0; k < n && !err; k++)
		if (out[k] > 1)
			err = ss_h5_damaged(&f->h5->in, "%s holds %d: expected 0 (at rest) or 1 "
			                    "(moving)", what, out[k]);
	return err;
}

int ss_snapshot_file_read_cell_flags(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out)
{
	check_rows(f, j0, rows);
	const hsize_t start[2] = {(hsize_t)j0, 0}, count[2] = {(hsize_t)rows, (hsize_t)f->nx};
	char what[96];
	snprintf(what, sizeof what, "/cell_type, rows %d .. %d", j0, j0 + rows - 1);
	int err;
	#pragma omp critical(ss_snapshot_hdf5)
	{
		ss_h5_quiet();
		err = ss_h5_var_read(&f->h5->in, &f->h5->cell_type, start, count, H5T_NATIVE_UINT8,
		                     out, what);
	}
	const size_t n = (size_t)rows * (size_t)f->nx;
	for (size_t k = 0; k < n && !err; k++)
		if (out[k] > SS_SNAPSHOT_CELL_NODATA)
			err = ss_h5_damaged(&f->h5->in, "/cell_type holds %d at %s: expected 0 "
			                    "(flow), 1 (wall), 2 (open) or 3 (no data)", out[k],
			                    SS_CELL((long long)(k % (size_t)f->nx),
			                            j0 + (long long)(k / (size_t)f->nx),
			                            CENTRE(f->origin_x, f->dx, k % (size_t)f->nx),
			                            CENTRE(f->origin_y, f->dy,
			                                   j0 + (long long)(k / (size_t)f->nx))));
	return err;
}

/* A cell without data is a wall to every reader but the renderer's: the
 * stepper held it as one (or as open, which left it at the open level),
 * and its height is stored as NaN like a wall's. */
int ss_snapshot_file_read_cell_types(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out)
{
	const int err = ss_snapshot_file_read_cell_flags(f, j0, rows, out);
	const size_t n = (size_t)rows * (size_t)f->nx;
	for (size_t k = 0; k < n && !err; k++)
		if (out[k] == SS_SNAPSHOT_CELL_NODATA)
			out[k] = SS_CELL_WALL;
	return err;
}

/* Snapshot t as a new array (nx * ny, south row first; ss_free). */
static int read_snapshot(struct ss_snapshot_file *f, long long t, double **out)
{
	*out = ss_alloc((size_t)f->nx * (size_t)f->ny, sizeof **out, "snapshot heights");
	if (!*out)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_rows(f, t, 0, f->ny, *out);
	if (err) {
		ss_free(*out);
		*out = NULL;
	}
	return err;
}

/* ---- a 2-D field of any file ----------------------------------------- */

/* Snapshot index (negative: from the end) of a (time, y, x) v, or the
 * (y, x) v, as a new array. */
static int read_field_var(const struct ss_h5_file *in, const struct ss_h5_var *v,
                          long long index, int *nx, int *ny, double **values)
{
	hsize_t dims[3] = {1, 0, 0};
	memcpy(v->rank == 3 ? dims : dims + 1, v->dims, (size_t)v->rank * sizeof *dims);
	if ((v->rank != 2 && v->rank != 3) || dims[0] < 1 || dims[1] < 1 || dims[2] < 1 ||
	    dims[1] > SS_SNAPSHOT_MAX_SIDE || dims[2] > SS_SNAPSHOT_MAX_SIDE)
		return ss_error_input("'%s:/%s' is not a (y, x) or non-empty (time, y, x) variable",
		                      in->name, v->name);
	const long long t = index < 0 ? (long long)dims[0] + index : index;
	if (t < 0 || t >= (long long)dims[0])
		return ss_error_input("'%s:/%s' has %llu snapshots: index %lld is out of range",
		                      in->name, v->name, (unsigned long long)dims[0], index);
	*ny = (int)dims[1];
	*nx = (int)dims[2];
	*values = ss_alloc((size_t)dims[1] * dims[2], sizeof(double), "input heights");
	if (!*values)
		return SS_ERR_FAIL;
	const hsize_t start[3] = {(hsize_t)t, 0, 0}, count[3] = {1, dims[1], dims[2]};
	char what[300];
	snprintf(what, sizeof what, "/%s", v->name);
	const int skip = 3 - v->rank;   /* (y, x): no time */
	const int err = ss_h5_var_read(in, v, start + skip, count + skip, H5T_NATIVE_DOUBLE,
	                               *values, what);
	if (err) {
		ss_free(*values);
		*values = NULL;
	}
	return err;
}

/* Snapshot index of /height of a sandslide file. */
static int read_snapshot_field(const char *path, long long index, int *nx, int *ny,
                               double **values)
{
	struct ss_snapshot_file f;
	int err = ss_snapshot_file_open(&f, path);
	const long long t = index < 0 ? f.count + index : index;
	if (!err && (t < 0 || t >= f.count))
		err = ss_error_input("'%s' has %lld snapshots: index %lld is out of range", path,
		                     f.count, index);
	if (!err && !(err = read_snapshot(&f, t, values))) {
		*nx = f.nx;
		*ny = f.ny;
	}
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_field(const char *path, const char *dataset, long long index,
                           int *nx, int *ny, double **values)
{
	*values = NULL;
	if (!dataset || !*dataset)
		return read_snapshot_field(path, index, nx, ny, values);
	struct ss_h5_file in;
	int err = ss_h5_file_open(&in, path, NULL, 0);
	struct ss_h5_var v = {.d = -1};
	if (!err)
		err = ss_h5_var_open(&in, dataset, &v);
	if (err == SS_H5_VAR_MISSING)
		err = ss_error_input("'%s' has no dataset '%s'", path, dataset);
	else if (err == SS_H5_VAR_NOT_NUMBERS)
		err = ss_error_input("'%s:%s' is not a (y, x) or non-empty (time, y, x) variable "
		                     "of numbers", path, dataset);
	if (!err)
		err = read_field_var(&in, &v, index, nx, ny, values);
	ss_h5_var_close(&v);
	ss_h5_file_close(&in);
	return err;
}

/* ---- a series of heights of any file ---------------------------------- */

void ss_height_series_release(struct ss_height_series *s)
{
	ss_free(s->time);
	ss_free(s->height);
	memset(s, 0, sizeof *s);
	s->dx = s->dy = s->origin_x = s->origin_y = NAN;
}

/* "'obs.h5' is not a height series: ..., the layout it needs" */
static int not_series(const struct ss_h5_file *in, const char *why)
{
	return ss_error_input("'%s' is not a height series: %s (expected /time (time) in s and "
	                      "/height (time, y, x) in m, doc/output.md)", in->name, why);
}

/*
 * The optional cell centres name (/x or /y) of n cells into *d and
 * *origin: the spacing and the corner, NAN without them.  They must be
 * finite, increasing and evenly spaced, as a grid's are: a /y from north
 * to south would flip every snapshot without a word.
 */
static int read_centres(const struct ss_h5_file *in, const char *name, int n, double *d,
                        double *origin)
{
	struct ss_h5_var v;
	*d = *origin = NAN;
	int err = ss_h5_var_open(in, name, &v);
	if (err == SS_H5_VAR_MISSING)
		return SS_OK;
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] != (hsize_t)n))) {
		ss_h5_var_close(&v);
		return ss_error_input("'%s': /%s is not %d numbers, one per %s of /height", in->name,
		                      name, n, name[0] == 'x' ? "column" : "row");
	}
	double *c = err ? NULL : ss_alloc((size_t)n, sizeof *c, "cell centres");
	if (!err && !c)
		err = SS_ERR_FAIL;
	const hsize_t start = 0, count = (hsize_t)n;
	if (!err)
		err = ss_h5_var_read(in, &v, &start, &count, H5T_NATIVE_DOUBLE, c, name);
	ss_h5_var_close(&v);
	if (!err && n >= 2) {
		const double step = c[1] - c[0];
		if (!(step > 0.0) || !isfinite(step))
			err = ss_error_input("'%s': /%s does not increase (%s[0] = %g, %s[1] = %g): "
			                     "cell centres in m, %s", in->name, name, name, c[0], name,
			                     c[1], name[0] == 'x' ? "west to east"
			                                          : "south to north (row 0 the south row)");
		for (int k = 2; k < n && !err; k++) {
			const double want = c[0] + k * step;
			if (!isfinite(c[k]) || fabs(c[k] - want) > 1e-6 * step + 1e-12 * fabs(want))
				err = ss_error_input("'%s': /%s is not increasing evenly (%s %d is %g, "
				                     "%g expected): cell centres in m, %s", in->name,
				                     name, name, k, c[k], want,
				                     name[0] == 'x' ? "west to east"
				                                    : "south to north (row 0 the south row)");
		}
		*d = step;
	}
	if (!err && !isfinite(c[0]))
		err = ss_error_input("'%s': /%s[0] is %g: cell centres in m", in->name, name, c[0]);
	if (!err)
		*origin = c[0];     /* a centre: the caller takes half a cell off */
	ss_free(c);
	return err;
}

/* The cell size along name (/x or /y) and the corner: from the centres,
 * else (one cell, or none given) the root attribute of a sandslide file. */
static int series_geometry(const struct ss_h5_file *in, const char *name, int n, double *d,
                           double *origin)
{
	double first;
	const int err = read_centres(in, name, n, d, &first);
	if (err)
		return err;
	if (isnan(*d)) {
		const double a = ss_h5_attr_read_double(in->file, name[0] == 'x' ? "dx" : "dy");
		*d = a > 0.0 && isfinite(a) ? a : NAN;
	}
	*origin = first - 0.5 * *d;
	if (!isfinite(*origin))
		*origin = NAN;
	return SS_OK;
}

/* /cell_type, when the file has one: its walls and cells without data
 * as NaN in every snapshot. */
static int series_walls(const struct ss_h5_file *in, struct ss_height_series *s)
{
	struct ss_h5_var v;
	int err = ss_h5_var_open(in, "cell_type", &v);
	if (err == SS_H5_VAR_MISSING)
		return SS_OK;
	if (err > 0 || (!err && (v.rank != 2 || v.dims[0] != (hsize_t)s->ny ||
	                         v.dims[1] != (hsize_t)s->nx))) {
		ss_h5_var_close(&v);
		return ss_error_input("'%s': /cell_type is not %d x %d numbers (y, x) as /height's "
		                      "snapshots", in->name, s->nx, s->ny);
	}
	const size_t cells = (size_t)s->nx * (size_t)s->ny;
	uint8_t *types = err ? NULL : ss_alloc(cells, 1, "cell types");
	if (!err && !types)
		err = SS_ERR_FAIL;
	const hsize_t start[2] = {0, 0}, count[2] = {(hsize_t)s->ny, (hsize_t)s->nx};
	if (!err)
		err = ss_h5_var_read(in, &v, start, count, H5T_NATIVE_UINT8, types, "/cell_type");
	ss_h5_var_close(&v);
	for (size_t k = 0; k < cells && !err; k++) {
		if (types[k] > SS_SNAPSHOT_CELL_NODATA)
			err = ss_error_input("'%s': /cell_type holds %d at %s: expected 0 (flow), 1 "
			                     "(wall), 2 (open) or 3 (no data)", in->name, types[k],
			                     SS_CELL((long long)(k % (size_t)s->nx),
			                             (long long)(k / (size_t)s->nx),
			                             CENTRE(s->origin_x, s->dx, k % (size_t)s->nx),
			                             CENTRE(s->origin_y, s->dy, k / (size_t)s->nx)));
		if (types[k] != SS_CELL_WALL && types[k] != SS_SNAPSHOT_CELL_NODATA)
			continue;
		for (long long t = 0; t < s->count; t++)
			s->height[(size_t)t * cells + k] = NAN;
	}
	ss_free(types);
	return err;
}

/* /time and /height: their sizes, then (memory allowing) their values. */
static int series_values(const struct ss_h5_file *in, struct ss_height_series *s)
{
	struct ss_h5_var h, t;
	int err = ss_h5_var_open(in, "height", &h);
	if (err > 0 || (!err && h.rank != 3)) {
		ss_h5_var_close(&h);
		return not_series(in, err == SS_H5_VAR_MISSING
		                      ? "no /height" : "/height is not (time, y, x) numbers");
	}
	if (err)
		return err;
	if ((err = ss_h5_var_open(in, "time", &t)) > 0 || (!err && t.rank != 1)) {
		ss_h5_var_close(&h);
		ss_h5_var_close(&t);
		return not_series(in, err == SS_H5_VAR_MISSING
		                      ? "no /time" : "/time is not (time) numbers");
	}
	const hsize_t *hd = h.dims;
	char d[96];
	/* a sandslide output killed while it wrote a snapshot has one more
	 * /height than /time (doc/output.md#written-as-the-run-goes): /time
	 * counts the complete ones */
	if (!err && t.dims[0] != hd[0] && t.dims[0] + 1 != hd[0]) {
		char why[96];
		snprintf(why, sizeof why, "/time has %llu values, /height %llu snapshots",
		         (unsigned long long)t.dims[0], (unsigned long long)hd[0]);
		err = not_series(in, why);
	}
	else if (!err && (hd[1] < 1 || hd[2] < 1 || hd[1] > SS_SNAPSHOT_MAX_SIDE ||
	                  hd[2] > SS_SNAPSHOT_MAX_SIDE))
		err = ss_error_input("'%s': /height is %s (time, y, x): expected 1 to %d cells a "
		                     "side", in->name, ss_h5_format_dims(3, hd, d, sizeof d),
		                     SS_SNAPSHOT_MAX_SIDE);
	s->count = (long long)(err ? hd[0] : t.dims[0]);
	s->ny = (int)hd[1];
	s->nx = (int)hd[2];
	const size_t cells = (size_t)s->nx * (size_t)s->ny;
	/* the file has been found to hold them; memory need not */
	const double need = 8.0 * (double)s->count * ((double)cells + 1.0);
	const double have = ss_memory_available_bytes();
	if (!err && s->count > 0 && (need > (double)SIZE_MAX / 2 || (have > 0.0 && need > have))) {
		char b[32], a[32];
		err = ss_error_input("'%s' holds %lld snapshots of %d x %d cells: they need %s of "
		                     "memory, more than the %s available", in->name, s->count,
		                     s->nx, s->ny, ss_format_bytes(need, b),
		                     ss_format_bytes(have, a));
	}
	if (!err && s->count > 0) {
		s->time = ss_alloc((size_t)s->count, sizeof *s->time, "observation times");
		s->height = s->time ? ss_alloc((size_t)s->count * cells, sizeof *s->height,
		                               "observed heights")
		                    : NULL;
		if (!s->height)
			err = SS_ERR_FAIL;
	}
	const hsize_t t0 = 0, tn = (hsize_t)s->count;
	if (!err && s->count > 0)
		err = ss_h5_var_read(in, &t, &t0, &tn, H5T_NATIVE_DOUBLE, s->time, "/time");
	for (long long k = 0; k < s->count && !err; k++) {
		const hsize_t start[3] = {(hsize_t)k, 0, 0}, count[3] = {1, hd[1], hd[2]};
		char what[64];
		snprintf(what, sizeof what, "snapshot %lld of /height", k);
		err = ss_h5_var_read(in, &h, start, count, H5T_NATIVE_DOUBLE,
		                     s->height + (size_t)k * cells, what);
	}
	ss_h5_var_close(&t);
	ss_h5_var_close(&h);
	return err;
}

int ss_snapshot_read_height_series(const char *path, struct ss_height_series *s)
{
	memset(s, 0, sizeof *s);
	s->dx = s->dy = s->origin_x = s->origin_y = NAN;
	struct ss_h5_file in;
	int err = ss_h5_file_open(&in, path, NULL, 0);
	if (!err)
		err = series_values(&in, s);
	if (!err)
		err = series_geometry(&in, "x", s->nx, &s->dx, &s->origin_x);
	if (!err)
		err = series_geometry(&in, "y", s->ny, &s->dy, &s->origin_y);
	if (!err)
		err = series_walls(&in, s);
	ss_h5_file_close(&in);
	if (err)
		ss_height_series_release(s);
	return err;
}
