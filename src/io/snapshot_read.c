/*
 * snapshot_read.c - every read of a sandslide HDF5 file (snapshot.h).
 */
#include "sandslide/snapshot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "sandslide/error.h"
#include "io/snapshot_layout.h"

static void quiet_hdf5(void)
{
	H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

static int read_attr_string(hid_t obj, const char *name, char *out, size_t size)
{
	out[0] = '\0';
	if (H5Aexists(obj, name) <= 0)
		return -1;
	hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
	hid_t ft = H5Aget_type(a);
	int r = -1;
	if (H5Tget_class(ft) == H5T_STRING && !H5Tis_variable_str(ft)) {
		size_t n = H5Tget_size(ft);
		char *buf = calloc(1, n + 1);
		if (buf && H5Aread(a, ft, buf) >= 0) {
			snprintf(out, size, "%s", buf);
			r = 0;
		}
		free(buf);
	}
	H5Tclose(ft);
	H5Aclose(a);
	return r;
}

static double read_attr_double(hid_t obj, const char *name)
{
	double v = NAN;
	if (H5Aexists(obj, name) > 0) {
		hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
		if (H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0)
			v = NAN;
		H5Aclose(a);
	}
	return v;
}

static hid_t open_file(const char *path)
{
	quiet_hdf5();
	FILE *f = fopen(path, "rb");
	if (!f) {
		ss_error_input("cannot open '%s': %s", path, strerror(errno));
		return -1;
	}
	fclose(f);
	if (H5Fis_hdf5(path) <= 0) {
		ss_error_input("'%s' is not an HDF5 file", path);
		return -1;
	}
	hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
	if (file < 0)
		ss_error_input("cannot open HDF5 file '%s'", path);
	return file;
}

static int read_series(hid_t file, const char *name, long long count, double *out)
{
	hid_t d = H5Dopen2(file, name, H5P_DEFAULT);
	if (d < 0)
		return -1;
	hid_t fs = H5Dget_space(d);
	hsize_t n = 0;
	int ok = H5Sget_simple_extent_ndims(fs) == 1 &&
	         H5Sget_simple_extent_dims(fs, &n, NULL) == 1 && n == (hsize_t)count;
	herr_t r = ok ? H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) : -1;
	H5Sclose(fs);
	H5Dclose(d);
	return r < 0 ? -1 : 0;
}

int ss_snapshot_read_summary(const char *path, struct ss_snapshot_summary *sum)
{
	memset(sum, 0, sizeof *sum);
	hid_t file = open_file(path);
	if (file < 0)
		return SS_ERR_INPUT;
	int err = SS_OK;
	if (read_attr_string(file, "source", sum->source, sizeof sum->source) ||
	    strncmp(sum->source, "sandslide", 9) != 0 || H5Lexists(file, "height", H5P_DEFAULT) <= 0) {
		err = ss_error_input("'%s' is not a sandslide output file (no 'source = sandslide' "
		                     "attribute or no /height)", path);
		goto out;
	}
	read_attr_string(file, "closure", sum->closure, sizeof sum->closure);
	read_attr_string(file, "title", sum->title, sizeof sum->title);
	sum->repose_angle_deg = read_attr_double(file, "repose_angle_deg");
	sum->nu = read_attr_double(file, "nu");
	sum->gamma = read_attr_double(file, "gamma");
	sum->dx = read_attr_double(file, "dx");
	sum->dy = read_attr_double(file, "dy");

	hid_t d = H5Dopen2(file, "height", H5P_DEFAULT);
	hid_t fs = H5Dget_space(d);
	hsize_t dims[3] = {0, 0, 0};
	int rank = H5Sget_simple_extent_ndims(fs);
	if (rank == 3)
		H5Sget_simple_extent_dims(fs, dims, NULL);
	H5Sclose(fs);
	H5Dclose(d);
	if (rank != 3) {
		err = ss_error_input("'%s': /height is not a (time, y, x) variable", path);
		goto out;
	}
	sum->count = (long long)dims[0];
	sum->ny = (int)dims[1];
	sum->nx = (int)dims[2];

	const long long n = sum->count;
	sum->time = calloc((size_t)(n ? n : 1), sizeof *sum->time);
	sum->diag = calloc((size_t)(n ? n : 1), sizeof *sum->diag);
	double *col = calloc((size_t)(n ? n : 1), sizeof *col);
	if (!sum->time || !sum->diag || !col) {
		free(col);
		err = ss_error_fail("out of memory");
		goto out;
	}
	if (read_series(file, "time", n, sum->time)) {
		free(col);
		err = ss_error_input("'%s': cannot read /time", path);
		goto out;
	}
	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT; k++) {
		if (read_series(file, ss_snapshot_diag_name(k), n, col)) {
			free(col);
			err = ss_error_input("'%s': cannot read /%s", path, ss_snapshot_diag_name(k));
			goto out;
		}
		for (long long m = 0; m < n; m++)
			*ss_snapshot_diag_field(&sum->diag[m], k) = col[m];
	}
	free(col);

	/* the origin from the first cell centres */
	double xy[2];
	hsize_t one = 1, zero = 0;
	hid_t ms = H5Screate_simple(1, &one, NULL);
	for (int a = 0; a < 2; a++) {
		hid_t ds = H5Dopen2(file, a ? "y" : "x", H5P_DEFAULT);
		hid_t sp = ds >= 0 ? H5Dget_space(ds) : -1;
		if (sp < 0 || H5Sselect_hyperslab(sp, H5S_SELECT_SET, &zero, NULL, &one, NULL) < 0 ||
		    H5Dread(ds, H5T_NATIVE_DOUBLE, ms, sp, H5P_DEFAULT, &xy[a]) < 0)
			xy[a] = NAN;
		if (sp >= 0)
			H5Sclose(sp);
		if (ds >= 0)
			H5Dclose(ds);
	}
	H5Sclose(ms);
	sum->origin_x = xy[0] - 0.5 * sum->dx;
	sum->origin_y = xy[1] - 0.5 * sum->dy;

	uint8_t *types = malloc((size_t)sum->nx * (size_t)sum->ny);
	hid_t ct = H5Dopen2(file, "cell_type", H5P_DEFAULT);
	if (types && ct >= 0 &&
	    H5Dread(ct, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, types) >= 0) {
		for (size_t k = 0; k < (size_t)sum->nx * (size_t)sum->ny; k++) {
			sum->flow_cells += types[k] == SS_CELL_FLOW;
			sum->wall_cells += types[k] == SS_CELL_WALL;
			sum->open_cells += types[k] == SS_CELL_OPEN;
		}
	}
	if (ct >= 0)
		H5Dclose(ct);
	free(types);
out:
	H5Fclose(file);
	if (err)
		ss_snapshot_summary_release(sum);
	return err;
}

void ss_snapshot_summary_release(struct ss_snapshot_summary *sum)
{
	free(sum->time);
	free(sum->diag);
	sum->time = NULL;
	sum->diag = NULL;
}

int ss_snapshot_read_field(const char *path, const char *dataset, long long index,
                           int *nx, int *ny, double **values)
{
	*values = NULL;
	hid_t file = open_file(path);
	if (file < 0)
		return SS_ERR_INPUT;
	const char *name = dataset && *dataset ? dataset : "/height";
	int err = SS_OK;
	hid_t d = H5Lexists(file, name[0] == '/' ? name + 1 : name, H5P_DEFAULT) > 0
	          ? H5Dopen2(file, name, H5P_DEFAULT) : -1;
	if (d < 0) {
		H5Fclose(file);
		return ss_error_input("'%s' has no dataset '%s'", path, name);
	}
	hid_t fs = H5Dget_space(d);
	int rank = H5Sget_simple_extent_ndims(fs);
	hsize_t dims[3] = {1, 0, 0};
	if (rank == 2 || rank == 3)
		H5Sget_simple_extent_dims(fs, rank == 3 ? dims : dims + 1, NULL);
	if ((rank != 2 && rank != 3) || dims[1] < 1 || dims[2] < 1 || dims[0] < 1 ||
	    dims[1] > (1u << 30) || dims[2] > (1u << 30)) {
		err = ss_error_input("'%s:%s' is not a (y, x) or non-empty (time, y, x) variable",
		                     path, name);
		goto out;
	}
	long long t = index < 0 ? (long long)dims[0] + index : index;
	if (t < 0 || t >= (long long)dims[0]) {
		err = ss_error_input("'%s:%s' has %llu snapshots: index %lld is out of range", path,
		                     name, (unsigned long long)dims[0], index);
		goto out;
	}
	*ny = (int)dims[1];
	*nx = (int)dims[2];
	*values = ss_alloc((size_t)dims[1] * dims[2], sizeof(double), "input heights");
	if (!*values) {
		err = SS_ERR_FAIL;
		goto out;
	}
	hsize_t start[3] = {(hsize_t)t, 0, 0}, count[3] = {1, dims[1], dims[2]};
	if (rank == 3)
		H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
	hid_t ms = H5Screate_simple(2, dims + 1, NULL);
	if (H5Dread(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, *values) < 0) {
		ss_free(*values);
		*values = NULL;
		err = ss_error_input("cannot read '%s:%s' as numbers", path, name);
	}
	H5Sclose(ms);
out:
	H5Sclose(fs);
	H5Dclose(d);
	H5Fclose(file);
	return err;
}

/* ---- restarts -------------------------------------------------------- */

/* A string attribute as a new string (NULL if absent or not a string). */
static char *read_attr_text(hid_t obj, const char *name)
{
	if (H5Aexists(obj, name) <= 0)
		return NULL;
	hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
	hid_t ft = a >= 0 ? H5Aget_type(a) : -1;
	char *buf = NULL;
	if (ft >= 0 && H5Tget_class(ft) == H5T_STRING && !H5Tis_variable_str(ft)) {
		buf = calloc(1, H5Tget_size(ft) + 1);
		if (buf && H5Aread(a, ft, buf) < 0) {
			free(buf);
			buf = NULL;
		}
	}
	if (ft >= 0)
		H5Tclose(ft);
	if (a >= 0)
		H5Aclose(a);
	return buf;
}

void ss_restart_info_release(struct ss_restart_info *r)
{
	free(r->case_text);
	free(r->case_path);
	free(r->case_overrides);
	ss_free(r->height);
	memset(r, 0, sizeof *r);
}

int ss_snapshot_read_restart(const char *path, struct ss_restart_info *r)
{
	memset(r, 0, sizeof *r);
	struct ss_snapshot_summary sum;
	int err = ss_snapshot_read_summary(path, &sum);
	if (err)
		return err;
	r->count = sum.count;
	r->nx = sum.nx;
	r->ny = sum.ny;
	r->time = sum.count > 0 ? sum.time[sum.count - 1] : NAN;
	ss_snapshot_summary_release(&sum);
	if (r->count < 1)
		return ss_error_input("cannot restart from '%s': it holds no snapshot", path);

	hid_t file = open_file(path);
	if (file < 0)
		return SS_ERR_INPUT;
	r->case_text = read_attr_text(file, "case");
	r->case_path = read_attr_text(file, "title");
	r->case_overrides = read_attr_text(file, "case_overrides");
	double v[5] = {NAN, NAN, NAN, NAN, NAN};
	hid_t a = H5Aexists(file, "restart_state") > 0
	          ? H5Aopen(file, "restart_state", H5P_DEFAULT) : -1;
	hid_t as = a >= 0 ? H5Aget_space(a) : -1;
	const int five = as >= 0 && H5Sget_simple_extent_npoints(as) == 5;
	if (!(five && H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0))
		v[0] = NAN;
	if (as >= 0)
		H5Sclose(as);
	if (a >= 0)
		H5Aclose(a);
	H5Fclose(file);
	if (!r->case_text || !r->case_path || !r->case_overrides || !*r->case_text)
		err = ss_error_input("cannot restart from '%s': it does not hold the case it was "
		                     "run from (written by sandslide run?)", path);
	else if (!(v[0] >= 0.0) || !isfinite(v[1] + v[2] + v[3] + v[4]))
		err = ss_error_input("cannot restart from '%s': its restart state is missing or "
		                     "damaged (written by an older sandslide?)", path);
	if (!err) {
		r->state.steps = (long long)v[0];
		r->state.inflow_sum = v[1];
		r->state.inflow_carry = v[2];
		r->state.outflow_sum = v[3];
		r->state.outflow_carry = v[4];
		int nx, ny;
		err = ss_snapshot_read_field(path, "/height", r->count - 1, &nx, &ny, &r->height);
	}
	if (err)
		ss_restart_info_release(r);
	return err;
}

