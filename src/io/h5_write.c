/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_write.c - HDF5 + XDMF output (see snapshot.h for the layout);
 * the reads are in h5_read.c.
 *
 * File types are explicit little-endian IEEE (H5T_IEEE_F64LE, H5T_STD_I8LE),
 * memory types native.  Heights are copied a band of chunk rows at a time,
 * with NaN (the CF _FillValue) at walls and at cells without data, so
 * that netCDF readers, GDAL and ParaView show them as missing rather than
 * as floor at 0 m; the reader (h5_read.c) gives them 0 m again.
 * Cells without data (meta.nodata, relax's DEM) are /cell_type 3
 * (SS_SNAPSHOT_CELL_NODATA), whatever the stepper made of them; only then
 * does flag_values have a fourth value, so a run's file is as before.  HDF5's own error stack
 * printing is off: each failure prints one sandslide message.
 *
 * Beside the file: the XDMF sidecar (run.xmf, for ParaView) and GDAL's
 * .aux.xml (run.h5.aux.xml), which gives GDAL's HDF5 driver the
 * georeferencing it cannot find itself (it reads no dimension scales).
 *
 * In a run of several ranks (make MPI=1, comm.h) every rank opens the one
 * file through MPI-IO and makes every metadata call (create, extend,
 * attributes, dimension scales) with the same arguments, as parallel HDF5
 * requires; each writes its own rows of the grid variables (/height
 * collectively: a filtered dataset must be), rank 0 the coordinates and the
 * series.  Rank 0 alone checks the space, renames the file and writes the
 * sidecar; the outcome is agreed.
 */
#include "sandslide/snapshot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <hdf5.h>
#include <hdf5_hl.h>

#include "base/comm_mpi.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "io/h5_checked.h"
#include "io/snapshot_layout.h"
#include "io/sidecar.h"

static double diag_get(const struct ss_diagnostics *d, int k)
{
	struct ss_diagnostics copy = *d;
	return *ss_snapshot_diag_field(&copy, k);
}

struct ss_snapshot {
	char *path;
	char *partial_path;     /* written here until snapshot 0 is complete */
	char *xmf_path;
	hid_t file;
	hid_t height, time, diag[SS_SNAPSHOT_DIAG_COUNT];
	hid_t moving;           /* /moving (hysteresis), or -1: none */
	struct ss_grid grid;
	long long count;
	int failed;             /* a write failed (and said so): the close that
	                           follows will fail too, silently */
	double *times;          /* for the sidecar */
	long long times_cap;
	double *band;           /* band_rows x nx heights being written */
	uint8_t *band_types;    /* a row of unpacked cell types */
	int band_rows;          /* rows of a chunk of /height */
	char *crs_wkt;          /* for the .aux.xml; NULL: none */
	int has_bedrock;        /* /bedrock written */
	uint8_t *nodata;        /* this rank's rows of the cells without data
	                           (nx x ny, south row first), NULL: none */
};

void ss_snapshot_library_init(void)
{
	/* HDF5 1.10 crashes in its exit handler on a file whose close failed
	 * (a full disk, a file-size limit); we close every file ourselves, so
	 * it need not clean up at exit.  Only effective as the first call. */
	H5dont_atexit();
	ss_h5_quiet();
}

/* ---- attributes (h5_checked.h) ------------------------------------------ */

static int attr_units(hid_t obj, const char *units, const char *long_name)
{
	return ss_h5_attr_write_string(obj, "units", units) ||
	       ss_h5_attr_write_string(obj, "long_name", long_name);
}

/* ---- ranks ----------------------------------------------------------- */

static int is_root(void)
{
	return ss_comm_rank() == 0;
}

/* Raw-data transfer: collective in a parallel file (every rank calls the
 * write, with its own selection, maybe none); the default otherwise. */
static hid_t transfer(void)
{
	hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
#ifdef SS_HAVE_MPI
	if (ss_comm_size() > 1)
		H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
#endif
	return dxpl;
}

/* ---- creation -------------------------------------------------------- */

/* An extendible 1-D float64 variable along time. */
static hid_t create_series(hid_t file, const char *name, const char *units,
                           const char *long_name)
{
	hsize_t dim = 0, maxdim = H5S_UNLIMITED, chunk = 256;
	hid_t space = H5Screate_simple(1, &dim, &maxdim);
	hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
	H5Pset_chunk(dcpl, 1, &chunk);
	hid_t d = H5Dcreate2(file, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
	H5Pclose(dcpl);
	H5Sclose(space);
	if (d >= 0 && attr_units(d, units, long_name)) {
		H5Dclose(d);
		return -1;
	}
	return d;
}

static hid_t create_coordinate(hid_t file, const char *name, int n, double origin,
                               double spacing, const char *long_name, const char *axis,
                               const char *standard_name)
{
	hsize_t dim = (hsize_t)n;
	double *v = ss_alloc((size_t)n, sizeof *v, "coordinates");
	if (!v)
		return -1;
	for (int k = 0; k < n; k++)
		v[k] = origin + (k + 0.5) * spacing;
	hid_t space = H5Screate_simple(1, &dim, NULL);
	hid_t d = H5Dcreate2(file, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT,
	                     H5P_DEFAULT);
	/* rank 0 writes the values (independently); every rank the attributes */
	int bad = d < 0 ||
	          (is_root() && H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0) ||
	          attr_units(d, "m", long_name) || ss_h5_attr_write_string(d, "axis", axis) ||
	          (standard_name &&
	           ss_h5_attr_write_string(d, "standard_name", standard_name));
	ss_free(v);
	H5Sclose(space);
	if (bad && d >= 0) {
		H5Dclose(d);
		return -1;
	}
	return d;
}

/* A scalar float64 attribute NaN named _FillValue: the CF and netCDF
 * name of the value that marks a missing cell (walls in /height, cells
 * without rock in /bedrock), matching the dataset's fill value. */
static int attr_fill_nan(hid_t d)
{
	const double fill = NAN;
	return ss_h5_attr_write_doubles(d, "_FillValue", &fill, 1);
}

/* Cells along a side of a /height chunk (snapshot_layout.h): a chunk is
 * 1 x chunk_side(ny) x chunk_side(nx). */
static int chunk_side(long long n)
{
	return n < SS_SNAPSHOT_CHUNK_SIDE ? (int)n : SS_SNAPSHOT_CHUNK_SIDE;
}

/* Rows j0 .. j0 + n - 1 (of the whole grid) of a (y, x) dataset of nx
 * columns from block, in memory type mem_type; nonzero on failure.  An
 * independent write of an unfiltered dataset: each rank its own rows. */
static int write_rows(hid_t dataset, hid_t file_space, int j0, int n, int nx, hid_t mem_type,
                      const void *block)
{
	hsize_t start[2] = {(hsize_t)j0, 0}, count[2] = {(hsize_t)n, (hsize_t)nx};
	hid_t mem = H5Screate_simple(2, count, NULL);
	const int bad = mem < 0 ||
	      H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
	      H5Dwrite(dataset, mem_type, mem, file_space, H5P_DEFAULT, block) < 0;
	if (mem >= 0)
		H5Sclose(mem);
	return bad;
}

/* The packed cell types (grid.h) as bytes, a block of rows at a time: a
 * full unpacked copy would cost a byte per cell, 4 times the packed array.
 * Cells without data (nodata: this rank's rows, or NULL) are
 * SS_SNAPSHOT_CELL_NODATA. */
static int write_cell_types(hid_t dataset, hid_t file_space, const struct ss_grid *g,
                            const uint8_t *cell_types, const uint8_t *nodata)
{
	const int rows = g->ny < 64 ? g->ny : 64;
	uint8_t *block = ss_alloc((size_t)rows * (size_t)g->nx, 1, "cell type rows");
	if (!block)
		return 1;
	int bad = 0;
	for (int j0 = 0; j0 < g->ny && !bad; j0 += rows) {
		const int n = g->ny - j0 < rows ? g->ny - j0 : rows;
		for (int j = 0; j < n; j++)
			ss_cell_types_unpack(cell_types, ss_grid_index(g, 0, j0 + j), (size_t)g->nx,
			                     block + (size_t)j * g->nx);
		const uint8_t *none = nodata ? nodata + (size_t)j0 * g->nx : NULL;
		for (size_t k = 0; none && k < (size_t)n * g->nx; k++)
			if (none[k])
				block[k] = SS_SNAPSHOT_CELL_NODATA;
		bad = write_rows(dataset, file_space, (int)g->offset_j + j0, n, g->nx,
		                 H5T_NATIVE_UINT8, block);   /* converted to int8 */
	}
	ss_free(block);
	return bad;
}

/* bedrock (y, x), m: NaN (the _FillValue) where no sand can lie (walls,
 * open cells), written a block of rows at a time. */
static int write_bedrock(hid_t file, hid_t x, hid_t y, const struct ss_grid *g,
                         const double *bedrock, int crs)
{
	hsize_t dims[2] = {(hsize_t)g->global_ny, (hsize_t)g->nx};
	hid_t space = H5Screate_simple(2, dims, NULL);
	hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
	const double fill = NAN;
	H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &fill);
	hid_t d = H5Dcreate2(file, "bedrock", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl,
	                     H5P_DEFAULT);
	H5Pclose(dcpl);
	const int rows = g->ny < 64 ? g->ny : 64;
	double *block = ss_alloc((size_t)rows * (size_t)g->nx, sizeof *block, "bedrock rows");
	int bad = d < 0 || !block;
	for (int j0 = 0; j0 < g->ny && !bad; j0 += rows) {
		const int n = g->ny - j0 < rows ? g->ny - j0 : rows;
		for (int j = 0; j < n; j++) {
			const double *row = bedrock + ss_grid_index(g, 0, j0 + j);
			for (int i = 0; i < g->nx; i++)
				block[(size_t)j * g->nx + i] = isinf(row[i]) ? NAN : row[i];
		}
		bad = write_rows(d, space, (int)g->offset_j + j0, n, g->nx, H5T_NATIVE_DOUBLE, block);
	}
	ss_free(block);
	bad = bad || attr_units(d, "m", "non-erodible bedrock under the sand") ||
	      attr_fill_nan(d) || (crs && ss_h5_attr_write_string(d, "grid_mapping", "crs")) ||
	      H5DSattach_scale(d, y, 0) < 0 || H5DSattach_scale(d, x, 1) < 0;
	if (d >= 0)
		H5Dclose(d);
	H5Sclose(space);
	return bad;
}

/* The CF grid mapping variable of a georeferenced grid: a scalar "crs"
 * with the input DEM's coordinate reference system as WKT, under the CF
 * name (crs_wkt, CF 1.7 section 5.6) and GDAL's (spatial_ref), which
 * gdalinfo, QGIS and xarray's rioxarray read.  A WKT does not give CF's
 * grid_mapping_name without a projection library; readers use the WKT. */
static int write_crs(hid_t file, const char *wkt)
{
	hid_t space = H5Screate(H5S_SCALAR);
	hid_t d = H5Dcreate2(file, "crs", H5T_STD_I32LE, space, H5P_DEFAULT, H5P_DEFAULT,
	                     H5P_DEFAULT);
	const int zero = 0;
	const int bad = d < 0 ||
	      (is_root() && H5Dwrite(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, &zero) < 0) ||
	      ss_h5_attr_write_string(d, "crs_wkt", wkt) ||
	      ss_h5_attr_write_string(d, "spatial_ref", wkt) ||
	      ss_h5_attr_write_string(d, "long_name", "coordinate reference system of x and y");
	if (d >= 0)
		H5Dclose(d);
	H5Sclose(space);
	return bad;
}

static int write_static(struct ss_snapshot *s, const uint8_t *cell_types,
                        const struct ss_snapshot_meta *meta)
{
	const struct ss_grid *g = &s->grid;
	hid_t f = s->file;
	int bad = 0;
	const int crs = meta->crs_wkt && *meta->crs_wkt;

	hid_t x = create_coordinate(f, "x", g->nx, g->origin_x, g->dx,
	                            "x coordinate of cell centre (west to east)", "X",
	                            crs ? "projection_x_coordinate" : NULL);
	hid_t y = create_coordinate(f, "y", (int)g->global_ny, g->origin_y, g->dy,
	                            "y coordinate of cell centre (south to north)", "Y",
	                            crs ? "projection_y_coordinate" : NULL);
	/* "seconds", a duration without a reference date: xarray decodes it as
	 * elapsed time (timedelta64) and CDO counts from 0000-00-00, where
	 * "seconds since <date>" would make both invent calendar dates for a
	 * simulation that has none; "s" was read by neither as time */
	s->time = create_series(f, "time", "seconds", "simulated time since the start");
	if (x < 0 || y < 0 || s->time < 0)
		bad = 1;
	bad = bad || ss_h5_attr_write_string(s->time, "axis", "T");
	bad = bad || H5DSset_scale(x, "x") < 0 || H5DSset_scale(y, "y") < 0 ||
	      H5DSset_scale(s->time, "time") < 0;
	bad = bad || (crs && write_crs(f, meta->crs_wkt));

	/* height (time, y, x) */
	const hsize_t ny = (hsize_t)g->global_ny;
	hsize_t dims[3] = {0, ny, (hsize_t)g->nx};
	hsize_t maxdims[3] = {H5S_UNLIMITED, ny, (hsize_t)g->nx};
	hsize_t chunk[3] = {1, (hsize_t)chunk_side(g->global_ny), (hsize_t)chunk_side(g->nx)};
	hid_t space = H5Screate_simple(3, dims, maxdims);
	hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
	H5Pset_chunk(dcpl, 3, chunk);
	if (meta->deflate > 0) {
		H5Pset_shuffle(dcpl);
		H5Pset_deflate(dcpl, (unsigned)meta->deflate);
	}
	H5Pset_fletcher32(dcpl);
	const double fill = NAN;   /* the _FillValue: a cell never written is missing */
	H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &fill);
	s->height = bad ? -1 : H5Dcreate2(f, "height", H5T_IEEE_F64LE, space, H5P_DEFAULT,
	                                  dcpl, H5P_DEFAULT);
	H5Pclose(dcpl);
	H5Sclose(space);
	bad = bad || s->height < 0 || attr_units(s->height, "m", "height of the sand surface") ||
	      ss_h5_attr_write_string(s->height, "standard_name", "surface_altitude") ||
	      attr_fill_nan(s->height) ||
	      (crs && ss_h5_attr_write_string(s->height, "grid_mapping", "crs")) ||
	      H5DSattach_scale(s->height, s->time, 0) < 0 ||
	      H5DSattach_scale(s->height, y, 1) < 0 || H5DSattach_scale(s->height, x, 2) < 0;

	/* moving (time, y, x), hysteresis: each flow cell at rest (0) or moving
	 * (1), what a restart needs besides the heights (doc/output.md) */
	if (meta->moving && !bad) {
		space = H5Screate_simple(3, dims, maxdims);
		dcpl = H5Pcreate(H5P_DATASET_CREATE);
		H5Pset_chunk(dcpl, 3, chunk);
		if (meta->deflate > 0) {
			H5Pset_shuffle(dcpl);
			H5Pset_deflate(dcpl, (unsigned)meta->deflate);
		}
		H5Pset_fletcher32(dcpl);
		const int8_t rest = 0;
		H5Pset_fill_value(dcpl, H5T_NATIVE_INT8, &rest);
		s->moving = H5Dcreate2(f, "moving", H5T_STD_I8LE, space, H5P_DEFAULT, dcpl,
		                       H5P_DEFAULT);
		H5Pclose(dcpl);
		H5Sclose(space);
		bad = s->moving < 0 ||
		      attr_units(s->moving, "1", "sand moving (1) or at rest (0): hysteresis") ||
		      ss_h5_attr_write_string(s->moving, "flag_meanings", "at_rest moving") ||
		      (crs && ss_h5_attr_write_string(s->moving, "grid_mapping", "crs")) ||
		      H5DSattach_scale(s->moving, s->time, 0) < 0 ||
		      H5DSattach_scale(s->moving, y, 1) < 0 || H5DSattach_scale(s->moving, x, 2) < 0;
	}

	/* cell_type (y, x): signed bytes, NC_BYTE to netCDF, which every netCDF
	 * reader takes (VTK's netCDF-CF reader, ParaView's, rejects NC_UBYTE) */
	hsize_t dims2[2] = {ny, (hsize_t)g->nx};
	space = H5Screate_simple(2, dims2, NULL);
	hid_t ct = bad ? -1 : H5Dcreate2(f, "cell_type", H5T_STD_I8LE, space, H5P_DEFAULT,
	                                 H5P_DEFAULT, H5P_DEFAULT);
	bad = bad || ct < 0 || write_cell_types(ct, space, g, cell_types, s->nodata) ||
	      attr_units(ct, "1", "cell type") ||
	      ss_h5_attr_write_string(ct, "flag_meanings", meta->nodata ? "flow wall open nodata"
	                                                                : "flow wall open") ||
	      (crs && ss_h5_attr_write_string(ct, "grid_mapping", "crs")) ||
	      H5DSattach_scale(ct, y, 0) < 0 || H5DSattach_scale(ct, x, 1) < 0;
	if (!bad) {
		/* an attribute: every rank writes the same values */
		const int8_t flags[4] = {SS_CELL_FLOW, SS_CELL_WALL, SS_CELL_OPEN,
		                         SS_SNAPSHOT_CELL_NODATA};
		hsize_t n = meta->nodata ? 4 : 3;
		hid_t as = H5Screate_simple(1, &n, NULL);
		hid_t a = H5Acreate2(ct, "flag_values", H5T_STD_I8LE, as, H5P_DEFAULT, H5P_DEFAULT);
		bad = a < 0 || H5Awrite(a, H5T_NATIVE_INT8, flags) < 0;
		if (a >= 0)
			H5Aclose(a);
		H5Sclose(as);
	}
	H5Sclose(space);
	if (ct >= 0)
		H5Dclose(ct);

	bad = bad || (meta->bedrock && write_bedrock(f, x, y, g, meta->bedrock, crs));

	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT && !bad; k++) {
		s->diag[k] = create_series(f, ss_snapshot_diag_name(k), ss_snapshot_diag_units(k),
		                          ss_snapshot_diag_long_name(k));
		bad = s->diag[k] < 0 || H5DSattach_scale(s->diag[k], s->time, 0) < 0;
	}

	/* global attributes */
	char sides[128] = "";
	if (meta->boundary)
		for (int k = 0; k < 4; k++)
			snprintf(sides + strlen(sides), sizeof sides - strlen(sides), "%s%s=%s",
			         k ? " " : "", ss_side_name(k), ss_side_kind_name(meta->boundary->side[k]));
	char source[64];
	snprintf(source, sizeof source, SS_SNAPSHOT_SOURCE " %s", SS_VERSION);
	bad = bad || ss_h5_attr_write_string(f, "Conventions", "CF-1.8") ||
	      ss_h5_attr_write_string(f, "title", meta->title) ||
	      ss_h5_attr_write_string(f, "history", meta->history) ||
	      ss_h5_attr_write_string(f, "source", source) ||
	      ss_h5_attr_write_string(f, "closure", ss_closure_name(meta->model->closure)) ||
	      ss_h5_attr_write_doubles(f, "repose_angle_deg", &meta->model->angle_deg, 1) ||
	      ss_h5_attr_write_doubles(f, "nu", &meta->model->nu, 1) ||
	      ss_h5_attr_write_doubles(f, "gamma", &meta->model->gamma, 1) ||
	      ss_h5_attr_write_doubles(f, "dx", &g->dx, 1) ||
	      ss_h5_attr_write_doubles(f, "dy", &g->dy, 1) ||
	      ss_h5_attr_write_string(f, "case", meta->case_text) ||
	      (meta->integrator && ss_h5_attr_write_string(f, "integrator", meta->integrator)) ||
	      ss_h5_attr_write_string(f, "case_overrides",
	                              meta->case_overrides ? meta->case_overrides : "") ||
	      (meta->boundary && ss_h5_attr_write_string(f, SS_SNAPSHOT_BOUNDARY, sides));
	if (x >= 0)
		H5Dclose(x);
	if (y >= 0)
		H5Dclose(y);
	return bad ? -1 : 0;
}

int ss_snapshot_named_netcdf(const char *path)
{
	const size_t n = strlen(path);
	return (n > 3 && !strcasecmp(path + n - 3, ".nc")) ||
	       (n > 4 && !strcasecmp(path + n - 4, ".nc4"));
}

/* "run.h5" -> "run.xmf" (doc/output.md#sidecars); any other name keeps its
 * extension, "run.nc" -> "run.nc.xmf", so that run.h5 and run.nc beside it
 * do not share (and overwrite) one sidecar. */
void ss_snapshot_sidecar_path(const char *path, char *out, size_t size)
{
	const size_t n = strlen(path);
	const int h5 = n > 3 && !strcasecmp(path + n - 3, ".h5") && path[n - 4] != '/';
	snprintf(out, size, "%.*s.xmf", (int)(h5 ? n - 3 : n), path);
}

static void close_handles(struct ss_snapshot *s)
{
	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT; k++)
		if (s->diag[k] >= 0)
			H5Dclose(s->diag[k]);
	if (s->time >= 0)
		H5Dclose(s->time);
	if (s->height >= 0)
		H5Dclose(s->height);
	if (s->moving >= 0)
		H5Dclose(s->moving);
}

int ss_snapshot_destroy(struct ss_snapshot *s)
{
	if (!s)
		return SS_OK;
	int err = SS_OK;
	close_handles(s);
	if (s->file >= 0 && H5Fclose(s->file) < 0)
		err = s->failed ? SS_ERR_FAIL : ss_error_fail("cannot close '%s'", s->path);
	if (s->count == 0 && s->partial_path && is_root())
		remove(s->partial_path);   /* never complete: leave nothing */
	free(s->times);
	ss_free(s->nodata);
	ss_free(s->band);
	ss_free(s->band_types);
	free(s->crs_wkt);
	free(s->xmf_path);
	free(s->partial_path);
	free(s->path);
	free(s);
	return err;
}

/* File access of a writer: the v1.8 format (readable by every netCDF-4 and
 * HDF5 >= 1.8 reader), and changed metadata kept in memory until the flush
 * that ends a snapshot: evicted early, a chunk index could reach the disk
 * before the superblock that covers it, and a run killed in the middle of
 * a snapshot would leave an unreadable file.  The file's metadata is a few
 * kB, so the cache never needs to evict. */
static hid_t writer_access(void)
{
	hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
	H5Pset_libver_bounds(fapl, H5F_LIBVER_EARLIEST, H5F_LIBVER_V18);
	H5AC_cache_config_t mdc;
	mdc.version = H5AC__CURR_CACHE_CONFIG_VERSION;
	if (H5Pget_mdc_config(fapl, &mdc) >= 0) {
		mdc.evictions_enabled = 0;
		mdc.incr_mode = H5C_incr__off;
		mdc.flash_incr_mode = H5C_flash_incr__off;
		mdc.decr_mode = H5C_decr__off;
		H5Pset_mdc_config(fapl, &mdc);
	}
#ifdef SS_HAVE_MPI
	/* several ranks: every rank through MPI-IO, metadata read by one and
	 * broadcast, and written collectively.  One rank keeps the POSIX
	 * driver: MPI-IO wrote the 4096^2 cone's snapshots at half its speed
	 * (doc/performance.md#mpi-overhead). */
	if (ss_comm_size() > 1) {
		H5Pset_fapl_mpio(fapl, ss_comm_mpi(), MPI_INFO_NULL);
		H5Pset_all_coll_metadata_ops(fapl, 1);
		H5Pset_coll_metadata_write(fapl, 1);
	}
#endif
	return fapl;
}

static struct ss_snapshot *snapshot_alloc(const char *path, const struct ss_grid *g)
{
	struct ss_snapshot *s = calloc(1, sizeof *s);
	if (!s)
		return NULL;
	s->file = s->height = s->time = s->moving = -1;
	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT; k++)
		s->diag[k] = -1;
	s->grid = *g;
	s->path = strdup(path);
	s->xmf_path = malloc(strlen(path) + 8);
	s->partial_path = malloc(strlen(path) + 16);
	s->band_rows = chunk_side(g->global_ny);
	s->band = ss_alloc((size_t)s->band_rows * (size_t)g->nx, sizeof *s->band,
	                   "a band of heights to write");
	s->band_types = ss_alloc((size_t)g->nx, 1, "a row of cell types");
	if (!s->path || !s->xmf_path || !s->partial_path || !s->band || !s->band_types) {
		ss_snapshot_destroy(s);
		return NULL;
	}
	ss_snapshot_sidecar_path(path, s->xmf_path, strlen(path) + 8);
	snprintf(s->partial_path, strlen(path) + 16, "%s.partial", path);
	return s;
}

int ss_snapshot_create(struct ss_snapshot **out, const char *path,
                       const struct ss_grid *g, const uint8_t *cell_types,
                       const struct ss_snapshot_meta *meta)
{
	ss_h5_quiet();
	*out = NULL;
	struct ss_snapshot *s = snapshot_alloc(path, g);
	if (!s)
		return ss_error_fail("out of memory");

	hid_t fapl = writer_access();
	s->file = H5Fcreate(s->partial_path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
	H5Pclose(fapl);
	if (s->file < 0) {
		int e = errno;
		ss_snapshot_destroy(s);
		return ss_error_fail("cannot create '%s'%s%s", path, e ? ": " : "",
		                     e ? strerror(e) : "");
	}
	if (meta->crs_wkt && *meta->crs_wkt && !(s->crs_wkt = strdup(meta->crs_wkt))) {
		ss_snapshot_destroy(s);
		return ss_error_fail("out of memory");
	}
	s->has_bedrock = meta->bedrock != NULL;
	if (meta->nodata) {   /* this rank's rows */
		const size_t cells = (size_t)g->ny * (size_t)g->nx;
		if (!(s->nodata = ss_alloc(cells, 1, "cells without data"))) {
			ss_snapshot_destroy(s);
			return SS_ERR_FAIL;
		}
		memcpy(s->nodata, meta->nodata, cells);
	}
	if (write_static(s, cell_types, meta) || H5Fflush(s->file, H5F_SCOPE_GLOBAL) < 0) {
		ss_snapshot_destroy(s);
		return ss_error_fail("cannot write the static variables of '%s'", path);
	}
	*out = s;
	return SS_OK;
}

static int append_value(hid_t d, long long index, double v)
{
	hsize_t n = (hsize_t)index + 1, start = (hsize_t)index, one = 1;
	if (H5Dset_extent(d, &n) < 0)
		return -1;
	hid_t fs = H5Dget_space(d);
	hid_t ms = H5Screate_simple(1, &one, NULL);
	H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &one, NULL);
	if (!is_root()) {   /* rank 0's value (wall_seconds differs) */
		H5Sselect_none(fs);
		H5Sselect_none(ms);
	}
	hid_t dxpl = transfer();
	herr_t r = H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, dxpl, &v);
	H5Pclose(dxpl);
	H5Sclose(ms);
	H5Sclose(fs);
	return r < 0 ? -1 : 0;
}

/* The restart state of snapshot k (steps, inflow sum and carry, outflow
 * sum and carry, evaluations, RKL2's next super-step limit, the approach
 * to rest's stages): a restart
 * continues the compensated sums with the very same bits.  Even snapshots
 * write root attribute restart_state_even, odd ones restart_state_odd, so
 * that the state of the last complete snapshot is never the one being
 * written (see append). */
static int write_restart_state(hid_t file, long long k, const struct ss_restart_state *r)
{
	const double v[SS_SNAPSHOT_RESTART_VALUES] = {
		(double)r->steps, r->inflow.sum, r->inflow.carry, r->outflow.sum,
		r->outflow.carry, (double)r->evaluations, r->rkl2_tau, (double)r->rest_stages,
	};
	return ss_h5_attr_update_doubles(file, ss_snapshot_restart_attribute(k), v,
	                                 SS_SNAPSHOT_RESTART_VALUES);
}

double ss_snapshot_bytes(const struct ss_grid *g)
{
	const double ny = (double)g->global_ny;
	const double cy = chunk_side(g->global_ny), cx = chunk_side(g->nx);
	const double chunks = ceil(ny / cy) * ceil(g->nx / cx);
	/* its time, diagnostics and chunk index: about 0.7 KiB measured on
	 * cases/door.ini */
	return chunks * cy * cx * sizeof(double) + 1024.0;
}

/*
 * Check that the next snapshot fits before HDF5 writes any of it: under the
 * file-size limit and in the free space of the file system.  A write that
 * fails half-way through a flush can leave metadata pointing past the end
 * of the file, unreadable; failing here leaves the file as the last flush
 * left it, every snapshot in it complete.  The estimate is whole chunks of
 * /height plus room for the metadata.  (Space taken by another process
 * between this check and the flush is not covered.)
 */
static int space_verdict(struct ss_snapshot *s)
{
	const struct ss_grid *g = &s->grid;
	struct stat sb;
	struct statvfs fs;
	struct rlimit limit;
	/* by path: under MPI-IO the file's handle is not a descriptor; until
	 * snapshot 0 is complete the file is the .partial one */
	const char *path = s->count == 0 ? s->partial_path : s->path;
	if (stat(path, &sb) != 0)
		return 0;
	const double bytes = ss_snapshot_bytes(g) + (256 << 10);
	if (getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
	    (double)sb.st_size + bytes > (double)limit.rlim_cur)
		return EFBIG;
	if (statvfs(path, &fs) == 0 && (double)fs.f_bavail * (double)fs.f_frsize < bytes)
		return ENOSPC;
	return 0;
}

/* The verdict of rank 0, for every rank: they skip or write together. */
static int check_snapshot_space(struct ss_snapshot *s)
{
	int verdict = is_root() ? space_verdict(s) : 0;
	ss_comm_broadcast(&verdict, sizeof verdict, 0);
	errno = verdict;
	return verdict ? -1 : 0;
}

/*
 * Snapshot k of /height: this rank's rows of height (halo layout), NaN at
 * walls and cells without data, one band of chunk rows of the whole grid
 * at a time.  Every rank
 * makes the same writes, one per band, selecting its rows of the band
 * (maybe none): a write per band keeps the copy small (band_rows x nx),
 * and each chunk of the filtered dataset is written once, by one
 * collective write, as parallel HDF5 requires of filtered data.
 */
static int write_heights(struct ss_snapshot *s, long long k, const double *height,
                         const uint8_t *cell_types, const uint16_t *moving)
{
	const struct ss_grid *g = &s->grid;
	const long long first = g->offset_j, end = g->offset_j + g->ny;
	/* the heights, or (moving given) /moving as bytes in the same band */
	const hid_t dataset = moving ? s->moving : s->height;
	uint8_t *bytes = (uint8_t *)s->band;
	hid_t fs = H5Dget_space(dataset);
	hid_t dxpl = transfer();
	int bad = fs < 0 || dxpl < 0;
	for (long long b0 = 0; b0 < g->global_ny && !bad; b0 += s->band_rows) {
		const long long lo = b0 > first ? b0 : first;
		const long long b1 = b0 + s->band_rows < g->global_ny ? b0 + s->band_rows
		                                                      : g->global_ny;
		const long long hi = b1 < end ? b1 : end;
		/* the memory space has the file selection's shape, so that HDF5
		 * copies straight into the chunks (a 1-D one took the general
		 * gather-scatter path: 3x the output time of the 2048^2 cone) */
		const hsize_t mdims[3] = {1, hi > lo ? (hsize_t)(hi - lo) : 1, (hsize_t)g->nx};
		hid_t ms = H5Screate_simple(3, mdims, NULL);
		if (hi > lo) {
			for (long long j = lo; j < hi && moving; j++) {
				const ptrdiff_t row = ss_grid_index(g, 0, (int)(j - first));
				uint8_t *out = bytes + (size_t)(j - lo) * (size_t)g->nx;
				for (int i = 0; i < g->nx; i++)
					out[i] = moving[row + i] & 1;
			}
			for (long long j = lo; j < hi && !moving; j++) {
				const ptrdiff_t row = ss_grid_index(g, 0, (int)(j - first));
				double *out = s->band + (size_t)(j - lo) * (size_t)g->nx;
				ss_cell_types_unpack(cell_types, row, (size_t)g->nx, s->band_types);
				const uint8_t *none = s->nodata ? s->nodata + (size_t)(j - first) * g->nx
				                                : NULL;
				for (int i = 0; i < g->nx; i++)
					out[i] = s->band_types[i] == SS_CELL_WALL || (none && none[i])
					         ? NAN : height[row + i];
			}
			const hsize_t start[3] = {(hsize_t)k, (hsize_t)lo, 0};
			const hsize_t count[3] = {1, (hsize_t)(hi - lo), (hsize_t)g->nx};
			bad = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) < 0;
		} else {
			bad = H5Sselect_none(fs) < 0 || H5Sselect_none(ms) < 0;
		}
		/* the file's own types in memory: parallel HDF5 writes filtered
		 * data only collectively, and a conversion would take that away */
		bad = bad || ms < 0 ||
		      H5Dwrite(dataset, moving ? H5T_NATIVE_INT8 : H5T_NATIVE_DOUBLE, ms, fs, dxpl,
		               s->band) < 0;
		if (ms >= 0)
			H5Sclose(ms);
	}
	if (dxpl >= 0)
		H5Pclose(dxpl);
	if (fs >= 0)
		H5Sclose(fs);
	return bad;
}

static int append(struct ss_snapshot *s, double time_s, const double *height,
                  const uint8_t *cell_types, const uint16_t *moving,
                  const struct ss_diagnostics *d, const struct ss_restart_state *state)
{
	const struct ss_grid *g = &s->grid;
	const long long k = s->count;
	errno = 0;
	if (check_snapshot_space(s)) {
		const int e = errno;
		s->failed = 1;
		return ss_error_fail("cannot write snapshot %lld (t = %g s) to '%s': %s; the %lld "
		                     "snapshots before it are complete", k, time_s, s->path,
		                     strerror(e), k);
	}
	/* Two flushes, because HDF5 writes the metadata of one flush in no
	 * promised order and a run can be killed in the middle of it: first
	 * the heights and the diagnostics, then /time and the restart state.
	 * /time's length counts the complete snapshots; a run killed in the
	 * first flush leaves /height or a diagnostic one longer, which readers
	 * ignore and --restart overwrites.  The restart state goes to one of
	 * two attributes by k's parity, so the last complete snapshot's stays
	 * whole whenever the run dies. */
	hsize_t dims[3] = {(hsize_t)k + 1, (hsize_t)g->global_ny, (hsize_t)g->nx};
	if (H5Dset_extent(s->height, dims) < 0 || write_heights(s, k, height, cell_types, NULL))
		goto fail;
	if (s->moving >= 0 && (!moving || H5Dset_extent(s->moving, dims) < 0 ||
	                       write_heights(s, k, NULL, cell_types, moving)))
		goto fail;
	for (int m = 0; m < SS_SNAPSHOT_DIAG_COUNT; m++)
		if (append_value(s->diag[m], k, diag_get(d, m)))
			goto fail;
	if (H5Fflush(s->file, H5F_SCOPE_GLOBAL) < 0 || append_value(s->time, k, time_s) ||
	    (state && write_restart_state(s->file, k, state)) ||
	    H5Fflush(s->file, H5F_SCOPE_GLOBAL) < 0)
		goto fail;
	/* the file takes its name only once it holds a complete snapshot, so
	 * a run killed while it starts leaves no half-written file (and an
	 * existing file of that name intact) */
	int renamed = k > 0 || !is_root() || rename(s->partial_path, s->path) == 0 ? 0 : errno;
	ss_comm_broadcast(&renamed, sizeof renamed, 0);
	if (renamed) {
		errno = renamed;
		goto fail;
	}

	if (k + 1 > s->times_cap) {
		long long cap = s->times_cap ? 2 * s->times_cap : 64;
		double *t = realloc(s->times, (size_t)cap * sizeof *t);
		if (!t)
			return ss_error_fail("out of memory");
		s->times = t;
		s->times_cap = cap;
	}
	s->times[k] = time_s;
	s->count = k + 1;
	if (k == 0 && is_root() && !ss_snapshot_named_netcdf(s->path) &&
	    ss_gdal_sidecar_write(s->path, s->grid.origin_x, s->grid.origin_y, s->grid.dx,
	                          s->grid.dy, s->crs_wkt, s->has_bedrock))
		return ss_error_fail("cannot write GDAL's sidecar '%s.aux.xml': %s", s->path,
		                     strerror(errno));
	if (is_root() && ss_xdmf_write(s->xmf_path, s->path, g->nx, (int)g->global_ny, g->origin_x,
	                              g->origin_y, g->dx, g->dy, s->times, s->count))
		return ss_error_fail("cannot write the XDMF sidecar '%s': %s", s->xmf_path,
		                     strerror(errno));
	return SS_OK;
fail:
	s->failed = 1;
	return ss_error_fail("cannot write snapshot %lld (t = %g s) to '%s'%s%s", k, time_s,
	                     s->path, errno ? ": " : "", errno ? strerror(errno) : "");
}

/* A failure of one rank's write is every rank's, before the next
 * collective call (comm.h). */
int ss_snapshot_append(struct ss_snapshot *s, double time_s, const double *height,
                       const uint8_t *cell_types, const uint16_t *moving,
                       const struct ss_diagnostics *d, const struct ss_restart_state *state)
{
	const int err = ss_comm_agree(append(s, time_s, height, cell_types, moving, d, state));
	if (err)
		s->failed = 1;
	return err;
}

long long ss_snapshot_count(const struct ss_snapshot *s)
{
	return s->count;
}

double ss_snapshot_last_time(const struct ss_snapshot *s)
{
	return s->count > 0 ? s->times[s->count - 1] : NAN;
}

/* This rank's rows of the cells without data of f into s->nodata: the
 * snapshots appended mark them as the first ones did. */
static int read_nodata(struct ss_snapshot *s, struct ss_snapshot_file *f,
                       const struct ss_grid *g)
{
	const size_t cells = (size_t)g->ny * (size_t)g->nx;
	if (!(s->nodata = ss_alloc(cells ? cells : 1, 1, "cells without data")))
		return SS_ERR_FAIL;
	const int err = g->ny > 0 ? ss_snapshot_file_read_cell_flags(f, (int)g->offset_j, g->ny,
	                                                             s->nodata) : SS_OK;
	for (size_t k = 0; k < cells && !err; k++)
		s->nodata[k] = s->nodata[k] == SS_SNAPSHOT_CELL_NODATA;
	return err;
}

/* A file to continue must be a sandslide file (ss_snapshot_file_open) of
 * grid g with at least one snapshot, and every series and cell type in it
 * must read (the summary): the appends that follow extend them all.  Its
 * times go into s, for the sidecar. */
static int check_append(struct ss_snapshot *s, const char *path, const struct ss_grid *g)
{
	struct ss_snapshot_file f;
	struct ss_snapshot_summary sum;
	memset(&sum, 0, sizeof sum);
	int err = ss_snapshot_file_open(&f, path);
	if (!err)
		err = ss_snapshot_file_summary(&f, &sum);
	if (!err && (f.nx != g->global_nx || f.ny != g->global_ny || f.count < 1))
		err = ss_error_input("cannot open '%s' to continue it: not a sandslide output of "
		                     "this %lld x %lld grid", path, g->global_nx, g->global_ny);
	if (!err) {
		s->count = f.count;
		s->times_cap = f.count + 64;
		if (!(s->times = calloc((size_t)s->times_cap, sizeof *s->times)))
			err = ss_error_fail("out of memory");
		else
			memcpy(s->times, f.time, (size_t)f.count * sizeof *s->times);
	}
	if (!err && sum.nodata_cells > 0)
		err = read_nodata(s, &f, g);
	ss_snapshot_summary_release(&sum);
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_open_append(struct ss_snapshot **out, const char *path,
                            const struct ss_grid *g)
{
	ss_h5_quiet();
	*out = NULL;
	struct ss_snapshot *s = snapshot_alloc(path, g);
	if (!s)
		return ss_error_fail("out of memory");
	int err = check_append(s, path, g);
	if (err) {
		ss_snapshot_destroy(s);
		return err;
	}
	hid_t fapl = writer_access();
	errno = 0;
	s->file = H5Fopen(path, H5F_ACC_RDWR, fapl);
	H5Pclose(fapl);
	int bad = s->file < 0;
	const int e = errno;
	if (!bad) {
		s->height = H5Dopen2(s->file, "height", H5P_DEFAULT);
		s->time = H5Dopen2(s->file, "time", H5P_DEFAULT);
		bad = s->height < 0 || s->time < 0;
		if (!bad && H5Lexists(s->file, "moving", H5P_DEFAULT) > 0)
			bad = (s->moving = H5Dopen2(s->file, "moving", H5P_DEFAULT)) < 0;
		for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT && !bad; k++)
			bad = (s->diag[k] = H5Dopen2(s->file, ss_snapshot_diag_name(k), H5P_DEFAULT)) < 0;
	}
	if (bad) {
		ss_snapshot_destroy(s);
		return ss_error_input("cannot open '%s' to continue it%s%s", path, e ? ": " : "",
		                      e ? strerror(e) : "");
	}
	*out = s;
	return SS_OK;
}
