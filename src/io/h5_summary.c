/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_summary.c - what is read of a whole sandslide file at once
 * (snapshot.h): `sandslide info`'s summary (the attributes, every
 * diagnostic series, the cell counts), which ss_snapshot_open_append also
 * reads to check a file it continues, and the restart state of the last
 * snapshot with the case it was run from (`run --restart`, and the rows a
 * rank of a distributed run continues from).  The file is opened and its
 * snapshots read through the snapshot reader (h5_read.c); every size is
 * checked against the file there and in h5_checked.c.
 */
#include "sandslide/snapshot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "io/h5_checked.h"
#include "io/h5_read.h"
#include "io/snapshot_layout.h"

/* ---- info: the summary ----------------------------------------------- */

/* Count the cell types a block of rows at a time. */
static int count_cells(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	const int block = ss_snapshot_file_block_rows(f);
	uint8_t *types = ss_alloc((size_t)block * (size_t)f->nx, 1, "cell type rows");
	if (!types)
		return SS_ERR_FAIL;
	int err = SS_OK;
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		err = ss_snapshot_file_read_cell_flags(f, j0, rows, types);
		for (size_t k = 0; k < (size_t)rows * (size_t)f->nx && !err; k++) {
			sum->flow_cells += types[k] == SS_CELL_FLOW;
			sum->wall_cells += types[k] == SS_CELL_WALL;
			sum->open_cells += types[k] == SS_CELL_OPEN;
			sum->nodata_cells += types[k] == SS_SNAPSHOT_CELL_NODATA;
		}
	}
	ss_free(types);
	return err;
}

/* The diagnostic series into sum->diag. */
static int read_diagnostics(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	const long long n = f->count;
	double *col = malloc((size_t)(n ? n : 1) * sizeof *col);
	if (!col)
		return ss_error_fail("out of memory");
	int err = SS_OK;
	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT && !err; k++) {
		struct ss_h5_var v;
		const int opened = ss_h5_var_open(&f->h5->in, ss_snapshot_diag_name(k), &v);
		ss_h5_var_close(&v);
		if (opened < 0) {   /* damaged: said so already (read_series would again) */
			err = opened;
			break;
		}
		if (k == SS_SNAPSHOT_DIAG_EVALUATIONS && opened == SS_H5_VAR_MISSING) {
			/* written before RKL2: one evaluation per step */
			for (long long m = 0; m < n; m++)
				sum->diag[m].evaluations = sum->diag[m].steps;
			continue;
		}
		err = ss_h5_read_series(&f->h5->in, ss_snapshot_diag_name(k), n, col);
		for (long long m = 0; m < n && !err; m++)
			*ss_snapshot_diag_field(&sum->diag[m], k) = col[m];
	}
	free(col);
	return err;
}

int ss_snapshot_file_summary(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	memset(sum, 0, sizeof *sum);
	const struct ss_h5_file *in = &f->h5->in;
	sum->nx = f->nx;
	sum->ny = f->ny;
	sum->count = f->count;
	sum->dx = f->dx;
	sum->dy = f->dy;
	sum->origin_x = f->origin_x;
	sum->origin_y = f->origin_y;
	int err;
	if ((err = ss_h5_attr_read_string(in, in->file, "source", sum->source,
	                                  sizeof sum->source)) ||
	    (err = ss_h5_attr_read_string(in, in->file, "closure", sum->closure,
	                                  sizeof sum->closure)) ||
	    (err = ss_h5_attr_read_string(in, in->file, "integrator", sum->integrator,
	                                  sizeof sum->integrator)) ||
	    (err = ss_h5_attr_read_string(in, in->file, "title", sum->title, sizeof sum->title)))
		return err;
	sum->repose_angle_deg = ss_h5_attr_read_double(in->file, "repose_angle_deg");
	sum->nu = ss_h5_attr_read_double(in->file, "nu");
	sum->gamma = ss_h5_attr_read_double(in->file, "gamma");

	const size_t n = (size_t)(f->count ? f->count : 1);
	sum->time = malloc(n * sizeof *sum->time);
	sum->diag = calloc(n, sizeof *sum->diag);
	if (!sum->time || !sum->diag)
		err = ss_error_fail("out of memory");
	else
		memcpy(sum->time, f->time, (size_t)f->count * sizeof *sum->time);
	if (!err)
		err = read_diagnostics(f, sum);
	if (!err)
		err = count_cells(f, sum);
	if (err)
		ss_snapshot_summary_release(sum);
	return err;
}

/* Open path, read its summary (sum) or restart information (r), close it. */
static int read_path(const char *path, struct ss_snapshot_summary *sum,
                     struct ss_restart_info *r)
{
	struct ss_snapshot_file f;
	if (sum)
		memset(sum, 0, sizeof *sum);
	if (r)
		memset(r, 0, sizeof *r);
	int err = ss_snapshot_file_open(&f, path);
	if (!err)
		err = sum ? ss_snapshot_file_summary(&f, sum) : ss_snapshot_file_restart(&f, r);
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_summary(const char *path, struct ss_snapshot_summary *sum)
{
	return read_path(path, sum, NULL);
}

void ss_snapshot_summary_release(struct ss_snapshot_summary *sum)
{
	free(sum->time);
	free(sum->diag);
	sum->time = NULL;
	sum->diag = NULL;
}

/* ---- restarts -------------------------------------------------------- */

void ss_restart_info_release(struct ss_restart_info *r)
{
	free(r->case_text);
	free(r->case_path);
	free(r->case_overrides);
	ss_free(r->height);
	ss_free(r->moving);
	memset(r, 0, sizeof *r);
}

/* The case a restart continues: its text, path and --set values. */
static int read_case(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	const struct ss_h5_file *in = &f->h5->in;
	int err;
	if ((err = ss_h5_attr_read_text(in, in->file, "case", &r->case_text)) ||
	    (err = ss_h5_attr_read_text(in, in->file, "title", &r->case_path)) ||
	    (err = ss_h5_attr_read_text(in, in->file, "case_overrides", &r->case_overrides)))
		return err;
	if (!r->case_text || !r->case_path || !r->case_overrides || !*r->case_text)
		return ss_error_input("cannot restart from '%s': it does not hold the case it was "
		                      "run from (written by sandslide run?)", f->name);
	return SS_OK;
}

/* The restart state of the last snapshot, checked. */
static int read_state(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	const struct ss_h5_file *in = &f->h5->in;
	double v[SS_SNAPSHOT_RESTART_VALUES] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, 0.0};
	/* the last snapshot's by its parity; one restart_state in older files */
	const char *name = ss_snapshot_restart_attribute(f->count - 1);
	if (H5Aexists(in->file, name) <= 0)
		name = "restart_state";
	if (ss_h5_attr_read_doubles(in->file, name, SS_SNAPSHOT_RESTART_VALUES, v) &&
	    ss_h5_attr_read_doubles(in->file, name, SS_SNAPSHOT_RESTART_VALUES_RKL2, v) &&
	    !ss_h5_attr_read_doubles(in->file, name, SS_SNAPSHOT_RESTART_VALUES_OLD, v)) {
		/* before RKL2: Euler's evaluations are its steps */
		v[5] = v[0];
		v[6] = INFINITY;
	}
	/* the counts are stored as doubles: below 2^63 (the stages 2^31) to
	 * be ones; the super-step limit is a positive time or infinity */
	if (!(v[0] >= 0.0 && v[0] < 0x1p63) || !(v[5] >= 0.0 && v[5] < 0x1p63) ||
	    !(v[6] > 0.0) || !isfinite(v[1] + v[2] + v[3] + v[4]) ||
	    !(v[7] >= 0.0 && v[7] < 0x1p31 && v[7] == floor(v[7])))
		return ss_error_input("cannot restart from '%s': its restart state is missing or "
		                      "damaged (written by an older sandslide?)", f->name);
	r->state.steps = (long long)v[0];
	r->state.inflow.sum = v[1];
	r->state.inflow.carry = v[2];
	r->state.outflow.sum = v[3];
	r->state.outflow.carry = v[4];
	r->state.evaluations = (long long)v[5];
	r->state.rkl2_tau = v[6];
	r->state.rest_stages = (int)v[7];
	return SS_OK;
}

/* Rows first_row .. first_row + rows - 1 of snapshot t as a new array
 * (south row first; ss_free); rows < 0: every row, 0: none. */
static int read_snapshot_rows(struct ss_snapshot_file *f, long long t, long long first_row,
                              int rows, double **out)
{
	if (rows < 0) {
		first_row = 0;
		rows = f->ny;
	}
	if (rows == 0)
		return SS_OK;
	if (first_row < 0 || first_row + rows > f->ny)
		return ss_error_input("cannot restart from '%s': its snapshots have %d rows, not "
		                      "the %lld this grid needs", f->name, f->ny, first_row + rows);
	*out = ss_alloc((size_t)f->nx * (size_t)rows, sizeof **out, "snapshot heights");
	if (!*out)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_rows(f, t, (int)first_row, rows, *out);
	if (err) {
		ss_free(*out);
		*out = NULL;
	}
	return err;
}

/* The last snapshot (its rows first_row .. + rows - 1, all for rows < 0)
 * with its restart state, and with the case when with_case. */
static int read_last(struct ss_snapshot_file *f, struct ss_restart_info *r, int with_case,
                     long long first_row, int rows)
{
	memset(r, 0, sizeof *r);
	r->count = f->count;
	r->nx = f->nx;
	r->ny = f->ny;
	r->first_row = rows < 0 ? 0 : first_row;
	r->rows = rows < 0 ? f->ny : rows;
	if (f->count < 1)
		return ss_error_input("cannot restart from '%s': it holds no snapshot", f->name);
	r->time = f->time[f->count - 1];
	int err = with_case ? read_case(f, r) : SS_OK;
	if (!err)
		err = read_state(f, r);
	if (!err)
		err = read_snapshot_rows(f, f->count - 1, first_row, rows, &r->height);
	if (!err && r->height && ss_snapshot_file_has_moving(f)) {
		/* which cells move, for a run with hysteresis */
		r->moving = ss_alloc((size_t)f->nx * (size_t)r->rows, 1, "snapshot states");
		err = r->moving ? ss_snapshot_file_read_moving(f, f->count - 1, (int)r->first_row,
		                                               r->rows, r->moving) : SS_ERR_FAIL;
	}
	if (err)
		ss_restart_info_release(r);
	return err;
}

int ss_snapshot_file_restart(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	return read_last(f, r, 1, 0, -1);
}

/* Open path, read_last, close. */
static int read_last_of(const char *path, struct ss_restart_info *r, int with_case,
                        long long first_row, int rows)
{
	struct ss_snapshot_file f;
	memset(r, 0, sizeof *r);
	int err = ss_snapshot_file_open(&f, path);
	if (!err)
		err = read_last(&f, r, with_case, first_row, rows);
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_last_state(const char *path, struct ss_restart_info *r)
{
	return read_last_of(path, r, 0, 0, -1);
}

int ss_snapshot_read_last_rows(const char *path, long long first_row, int rows,
                               struct ss_restart_info *r)
{
	return read_last_of(path, r, 0, first_row, rows);
}

int ss_snapshot_read_restart(const char *path, struct ss_restart_info *r)
{
	return read_path(path, NULL, r);
}

int ss_snapshot_read_restart_case(const char *path, struct ss_restart_info *r)
{
	return read_last_of(path, r, 1, 0, 0);
}
