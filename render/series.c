/*
 * series.c - reading a sandslide output file (SPEC section 5) for the
 * renderer: the only file of render/ that includes <hdf5.h>.
 *
 * A file is taken as sandslide output when its root attribute `source`
 * starts with "sandslide" and it has /height (time, y, x), /time (time) and
 * /cell_type (y, x) of matching sizes and positive dx, dy attributes.  The
 * cell types (one byte per cell) and the times are read once; heights are
 * read a block of whole chunks of rows at a time, so a 16384^2 snapshot
 * never needs to be in memory at once.
 *
 * Reads may come from several threads rendering different frames.  HDF5
 * is serialised by a critical section: Debian's library is built
 * thread-safe, but others need not be, and the reads are I/O bound anyway.
 */
#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"

struct ss_render_h5 {
	hid_t file;
	hid_t height;
};

/* A string attribute (fixed or variable length) into out; -1 if absent. */
static int attr_string(hid_t obj, const char *name, char *out, size_t size)
{
	out[0] = '\0';
	if (H5Aexists(obj, name) <= 0)
		return -1;
	hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
	hid_t ft = a >= 0 ? H5Aget_type(a) : -1;
	int r = -1;
	if (ft >= 0 && H5Tget_class(ft) == H5T_STRING) {
		if (H5Tis_variable_str(ft) > 0) {
			hid_t mt = H5Tcopy(H5T_C_S1);
			H5Tset_size(mt, H5T_VARIABLE);
			char *v = NULL;
			if (H5Aread(a, mt, &v) >= 0 && v) {
				snprintf(out, size, "%s", v);
				r = 0;
			}
			if (v)
				H5free_memory(v);
			H5Tclose(mt);
		} else {
			size_t n = H5Tget_size(ft);
			char *buf = calloc(1, n + 1);
			if (buf && H5Aread(a, ft, buf) >= 0) {
				snprintf(out, size, "%s", buf);
				r = 0;
			}
			free(buf);
		}
	}
	if (ft >= 0)
		H5Tclose(ft);
	if (a >= 0)
		H5Aclose(a);
	return r;
}

static double attr_double(hid_t obj, const char *name)
{
	double v = NAN;
	if (H5Aexists(obj, name) > 0) {
		hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
		if (a < 0 || H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0)
			v = NAN;
		if (a >= 0)
			H5Aclose(a);
	}
	return v;
}

/* Rank and sizes of a dataset; rank -1 if it does not exist. */
static int dataset_dims(hid_t file, const char *name, hsize_t dims[3])
{
	if (H5Lexists(file, name, H5P_DEFAULT) <= 0)
		return -1;
	hid_t d = H5Dopen2(file, name, H5P_DEFAULT);
	if (d < 0)
		return -1;
	hid_t sp = H5Dget_space(d);
	int rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
	if (rank >= 1 && rank <= 3)
		H5Sget_simple_extent_dims(sp, dims, NULL);
	else
		rank = -1;
	if (sp >= 0)
		H5Sclose(sp);
	H5Dclose(d);
	return rank;
}

/* The first value of a 1-D coordinate variable, NAN if unreadable. */
static double first_value(hid_t file, const char *name)
{
	double v = NAN;
	hsize_t dims[3] = {0, 0, 0}, zero = 0, one = 1;
	if (dataset_dims(file, name, dims) != 1 || dims[0] < 1)
		return NAN;
	hid_t d = H5Dopen2(file, name, H5P_DEFAULT);
	hid_t fs = d >= 0 ? H5Dget_space(d) : -1;
	hid_t ms = H5Screate_simple(1, &one, NULL);
	if (fs < 0 || H5Sselect_hyperslab(fs, H5S_SELECT_SET, &zero, NULL, &one, NULL) < 0 ||
	    H5Dread(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, &v) < 0)
		v = NAN;
	H5Sclose(ms);
	if (fs >= 0)
		H5Sclose(fs);
	if (d >= 0)
		H5Dclose(d);
	return v;
}

static int read_all(hid_t file, const char *name, hid_t mem_type, void *out)
{
	hid_t d = H5Dopen2(file, name, H5P_DEFAULT);
	herr_t r = d < 0 ? -1 : H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out);
	if (d >= 0)
		H5Dclose(d);
	return r < 0 ? -1 : 0;
}

/* The checks that make a file sandslide output; the sizes into s. */
static int check_layout(struct ss_render_source *s, hid_t file)
{
	const char *p = s->path;
	char source[256];
	if (attr_string(file, "source", source, sizeof source) || strncmp(source, "sandslide", 9))
		return ss_error_input("'%s' is not a sandslide output file: no root attribute "
		                      "source = \"sandslide ...\" (SPEC section 5)", p);
	hsize_t hd[3] = {0, 0, 0}, td[3] = {0, 0, 0}, cd[3] = {0, 0, 0};
	if (dataset_dims(file, "height", hd) != 3)
		return ss_error_input("'%s' is not a sandslide output file: no /height (time, y, x)",
		                      p);
	if (dataset_dims(file, "time", td) != 1 || td[0] != hd[0])
		return ss_error_input("'%s' is not a sandslide output file: /time does not match "
		                      "/height (%llu snapshots)", p, (unsigned long long)hd[0]);
	if (dataset_dims(file, "cell_type", cd) != 2 || cd[0] != hd[1] || cd[1] != hd[2])
		return ss_error_input("'%s' is not a sandslide output file: /cell_type (y, x) does "
		                      "not match /height", p);
	if (hd[1] < 1 || hd[2] < 1 || hd[1] > (1u << 30) || hd[2] > (1u << 30))
		return ss_error_input("'%s': /height has %llu x %llu cells", p,
		                      (unsigned long long)hd[2], (unsigned long long)hd[1]);
	s->dx = attr_double(file, "dx");
	s->dy = attr_double(file, "dy");
	if (!(s->dx > 0.0) || !(s->dy > 0.0) || !isfinite(s->dx) || !isfinite(s->dy))
		return ss_error_input("'%s' is not a sandslide output file: no positive dx, dy "
		                      "attributes", p);
	s->count = (long long)hd[0];
	s->ny = (int)hd[1];
	s->nx = (int)hd[2];
	/* the corner from the first cell centres (x, y are optional here) */
	s->origin_x = first_value(file, "x") - 0.5 * s->dx;
	s->origin_y = first_value(file, "y") - 0.5 * s->dy;
	return SS_OK;
}

void ss_render_source_close(struct ss_render_source *s)
{
	if (s->h5) {
		if (s->h5->height >= 0)
			H5Dclose(s->h5->height);
		if (s->h5->file >= 0)
			H5Fclose(s->h5->file);
		free(s->h5);
	}
	free(s->time);
	ss_free(s->cell_type);
	s->h5 = NULL;
	s->time = NULL;
	s->cell_type = NULL;
}

int ss_render_source_open(struct ss_render_source *s, const char *path)
{
	memset(s, 0, sizeof *s);
	snprintf(s->path, sizeof s->path, "%s", path);
	H5Eset_auto2(H5E_DEFAULT, NULL, NULL);   /* one message of ours per failure */

	FILE *probe = fopen(path, "rb");
	if (!probe)
		return ss_error_input("cannot open '%s': %s", path, strerror(errno));
	fclose(probe);
	if (H5Fis_hdf5(path) <= 0)
		return ss_error_input("'%s' is not an HDF5 file (expected sandslide output, "
		                      "SPEC section 5)", path);
	s->h5 = calloc(1, sizeof *s->h5);
	if (!s->h5)
		return ss_error_fail("out of memory");
	s->h5->height = -1;
	s->h5->file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
	int err = SS_OK;
	if (s->h5->file < 0) {
		err = ss_error_input("cannot open HDF5 file '%s'", path);
		goto out_close;
	}
	if ((err = check_layout(s, s->h5->file)))
		goto out_close;
	s->h5->height = H5Dopen2(s->h5->file, "height", H5P_DEFAULT);
	s->time = malloc((size_t)(s->count ? s->count : 1) * sizeof *s->time);
	s->cell_type = ss_alloc((size_t)s->nx * (size_t)s->ny, 1, "cell types");
	if (!s->time || !s->cell_type) {
		err = s->time ? SS_ERR_FAIL : ss_error_fail("out of memory");
		goto out_close;
	}
	if (s->h5->height < 0 || (s->count && read_all(s->h5->file, "time", H5T_NATIVE_DOUBLE,
	                                                s->time)) ||
	    read_all(s->h5->file, "cell_type", H5T_NATIVE_UINT8, s->cell_type)) {
		err = ss_error_input("'%s': cannot read /height, /time or /cell_type", path);
		goto out_close;
	}
	return SS_OK;

out_close:
	ss_render_source_close(s);
	return err;
}

int ss_render_source_block_rows(const struct ss_render_source *s)
{
	/* whole chunks (256 rows) and about 8 MB, so each chunk is read once */
	long long rows = (8ll << 20) / (8ll * s->nx);
	rows = rows < 256 ? 256 : rows / 256 * 256;
	return rows > s->ny ? s->ny : (int)rows;
}

int ss_render_source_read_rows(struct ss_render_source *s, long long t, int j0, int rows,
                               double *buf)
{
	herr_t r = -1;
	#pragma omp critical(ss_render_hdf5)
	{
		hid_t fs = H5Dget_space(s->h5->height);
		hsize_t start[3] = {(hsize_t)t, (hsize_t)j0, 0};
		hsize_t count[3] = {1, (hsize_t)rows, (hsize_t)s->nx};
		hid_t ms = H5Screate_simple(3, count, NULL);
		if (fs >= 0 && ms >= 0 &&
		    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
			r = H5Dread(s->h5->height, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf);
		if (ms >= 0)
			H5Sclose(ms);
		if (fs >= 0)
			H5Sclose(fs);
	}
	if (r < 0)
		return ss_error_fail("'%s': cannot read rows %d..%d of snapshot %lld of /height",
		                     s->path, j0, j0 + rows - 1, t);
	return SS_OK;
}

int ss_render_source_range(struct ss_render_source *s, long long first, long long last,
                           double *zmin, double *zmax)
{
	const int nx = s->nx, block = ss_render_source_block_rows(s);
	double lo = INFINITY, hi = -INFINITY;
	double *buf = ss_alloc((size_t)block * (size_t)nx, sizeof *buf, "height rows");
	if (!buf)
		return SS_ERR_FAIL;
	int err = SS_OK;
	for (long long t = first; t <= last && !err; t++) {
		for (int j0 = 0; j0 < s->ny && !err; j0 += block) {
			const int rows = s->ny - j0 < block ? s->ny - j0 : block;
			if ((err = ss_render_source_read_rows(s, t, j0, rows, buf)))
				break;
			const uint8_t *ct = s->cell_type + (size_t)j0 * nx;
			#pragma omp parallel for schedule(static) reduction(min:lo) reduction(max:hi) \
				if((size_t)rows * nx > 65536)
			for (int j = 0; j < rows; j++)
				for (int i = 0; i < nx; i++) {
					const size_t k = (size_t)j * nx + i;
					const double v = buf[k];
					if (ct[k] != SS_CELL_WALL && isfinite(v)) {
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
