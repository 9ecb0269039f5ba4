/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem.c - raster input and output (see dem.h): the format from the path,
 * read options, the HDF5 reader, and the atomic write every writer goes
 * through.  The formats themselves are in dem_asc.c, dem_png.c and
 * dem_gdal.c.
 */
#include "sandslide/dem.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/strings.h"
#include "io/dem_internal.h"
#include "sandslide/error.h"
#include "sandslide/snapshot.h"

/* ------------------------------------------------------------------ */
/* rasters and options                                                  */

static void raster_clear(struct ss_raster *r)
{
	memset(r, 0, sizeof *r);
	r->cellsize = r->cellsize_y = NAN;
	r->x0 = r->y0 = NAN;
	r->nodata_value = NAN;
	r->png_zmin = r->png_zmax = NAN;
}

int ss_raster_init(struct ss_raster *r, int nx, int ny)
{
	raster_clear(r);
	if (nx < 1 || ny < 1)
		SS_BUG("ss_raster_init: %d x %d cells", nx, ny);
	r->nx = nx;
	r->ny = ny;
	r->rows = ny;
	r->values = ss_alloc((size_t)nx * (size_t)ny, sizeof(double), "raster heights");
	return r->values ? SS_OK : SS_ERR_FAIL;
}

void ss_raster_release(struct ss_raster *r)
{
	ss_free(r->values);
	ss_free(r->nodata);
	ss_free(r->source);
	ss_free(r->crs_wkt);
	raster_clear(r);
}

void ss_dem_read_options_init(struct ss_dem_read_options *o)
{
	o->format = SS_DEM_AUTO;
	o->zscale = o->zoffset = o->cellsize = NAN;
	o->row_first = 0;
	o->rows = -1;
}

int ss_dem_window(const struct ss_dem_read_options *opt, const char *spec,
                  const char *context, struct ss_raster *r)
{
	if (opt->rows < 0) {
		r->row_first = 0;
		r->rows = r->ny;
		return SS_OK;
	}
	if (opt->row_first < 0 || opt->row_first > r->ny || opt->rows > r->ny - opt->row_first)
		return ss_error_input_at(context, "'%s' has %d rows: rows %d to %d (from the south) "
		                         "are not in it", spec, r->ny, opt->row_first,
		                         opt->row_first + opt->rows - 1);
	r->row_first = opt->row_first;
	r->rows = opt->rows;
	return SS_OK;
}

size_t ss_raster_cells(const struct ss_raster *r)
{
	return (size_t)r->nx * (size_t)r->rows;
}

char *ss_dem_strdup(const char *s)
{
	const size_t n = strlen(s) + 1;
	char *d = ss_alloc(n, 1, "a string");
	if (d)
		memcpy(d, s, n);
	return d;
}

double ss_dem_dy(const struct ss_raster *r)
{
	return isnan(r->cellsize_y) ? r->cellsize : r->cellsize_y;
}

/* ------------------------------------------------------------------ */
/* formats                                                              */

const char *ss_dem_format_name(enum ss_dem_format format)
{
	switch (format) {
	case SS_DEM_ASC:  return "ESRI ASCII grid";
	case SS_DEM_H5:   return "sandslide HDF5";
	case SS_DEM_PNG:  return "16-bit greyscale PNG";
	case SS_DEM_GDAL: return "GeoTIFF (GDAL)";
	case SS_DEM_AUTO: break;
	}
	return "raster";
}

int ss_dem_gdal_available(void)
{
#ifdef SS_HAVE_GDAL
	return 1;
#else
	return 0;
#endif
}

/* Whether x and y, both known (not NaN), differ by more than tol. */
static int differ(double x, double y, double tol)
{
	return !isnan(x) && !isnan(y) && fabs(x - y) > tol;
}

/* The name of a CRS for a message: its WKT's first quoted name. */
static const char *crs_name(const char *wkt, char *buf, size_t size)
{
	const char *q = strchr(wkt, '"');
	const char *end = q ? strchr(q + 1, '"') : NULL;
	if (!end)
		return wkt;
	snprintf(buf, size, "%.*s", (int)(end - q - 1), q + 1);
	return buf;
}

int ss_dem_check_aligned(const struct ss_raster *dem, const char *dem_name,
                         const struct ss_raster *r, const char *what)
{
	const double dx = dem->cellsize, dy = dem->cellsize_y;
	if (differ(r->cellsize, dx, 1e-9 * dx) || differ(r->cellsize_y, dy, 1e-9 * dy))
		return ss_error_input("%s has cells of %.10g x %.10g m: expected the DEM's (%s) "
		                      "%.10g x %.10g m", what, r->cellsize, r->cellsize_y, dem_name,
		                      dx, dy);
	const double cell = isnan(dx) ? 1.0 : fmin(dx, isnan(dy) ? dx : dy);
	if (differ(r->x0, dem->x0, 1e-6 * cell) || differ(r->y0, dem->y0, 1e-6 * cell))
		return ss_error_input("%s has its lower-left corner at (%.10g, %.10g): expected the "
		                      "DEM's (%s) (%.10g, %.10g)", what, r->x0, r->y0, dem_name,
		                      dem->x0, dem->y0);
	if (!r->crs_wkt || !dem->crs_wkt)
		return SS_OK;
	const int same = ss_dem_gdal_available() ? ss_dem_gdal_same_crs(r->crs_wkt, dem->crs_wkt)
	                                         : strcmp(r->crs_wkt, dem->crs_wkt) == 0;
	char a[128], b[128];
	return same ? SS_OK
	            : ss_error_input("%s is in the CRS %s: expected the DEM's (%s), %s (gdalwarp "
	                             "-t_srs puts it in the DEM's)", what,
	                             crs_name(r->crs_wkt, a, sizeof a), dem_name,
	                             crs_name(dem->crs_wkt, b, sizeof b));
}

static int has_suffix(const char *s, const char *suffix)
{
	size_t a = strlen(s), b = strlen(suffix);
	return a >= b && strcasecmp(s + a - b, suffix) == 0;
}

/* The HDF5 file name inside "FILE.h5:/dataset", or NULL if spec is not one;
 * *dataset points into spec. */
static const char *h5_dataset(const char *spec)
{
	const char *p = spec, *hit = NULL;
	while ((p = strchr(p, ':'))) {   /* the last ".h5:" wins */
		if (p - spec >= 3 && strncasecmp(p - 3, ".h5", 3) == 0)
			hit = p;
		p++;
	}
	return hit ? hit + 1 : NULL;
}

enum ss_dem_format ss_dem_format_of(const char *path)
{
	if (has_suffix(path, ".asc"))
		return SS_DEM_ASC;
	if (has_suffix(path, ".png"))
		return SS_DEM_PNG;
	if (has_suffix(path, ".tif") || has_suffix(path, ".tiff"))
		return SS_DEM_GDAL;
	if (has_suffix(path, ".h5") || ss_snapshot_named_netcdf(path) || h5_dataset(path))
		return SS_DEM_H5;
	return SS_DEM_AUTO;
}

int ss_dem_format_from_path(const char *path, const char *context, enum ss_dem_format *format)
{
	*format = ss_dem_format_of(path);
	if (*format != SS_DEM_AUTO)
		return SS_OK;
	return ss_error_input_at(context, "'%s': unknown raster format: expected " SS_DEM_ACCEPTED_READ,
	                         path);
}

static int gdal_unavailable(const char *path, const char *context)
{
	return ss_error_input_at(context, "'%s': GeoTIFF and other GDAL rasters are unavailable in this "
	                         "build (built without GDAL: install libgdal-dev and rebuild); "
	                         "this build reads an ESRI ASCII grid (.asc), a sandslide HDF5 file "
	                         "(.h5 or .h5:/dataset) or a 16-bit greyscale PNG (.png)", path);
}

/* ------------------------------------------------------------------ */
/* reading                                                              */

/* The cells without data of a sandslide file (relax's nodata,
 * SS_SNAPSHOT_CELL_NODATA) as r->nodata, left NULL when there are none;
 * their values are 0 already (read as walls). */
static int read_h5_nodata(struct ss_snapshot_file *f, struct ss_raster *r)
{
	const size_t n = ss_raster_cells(r);
	uint8_t *flags = ss_alloc(n ? n : 1, 1, "cell types");
	if (!flags)
		return SS_ERR_FAIL;
	int err = n ? ss_snapshot_file_read_cell_flags(f, r->row_first, r->rows, flags) : SS_OK;
	size_t none = 0;
	for (size_t k = 0; k < n && !err; k++)
		none += (flags[k] = flags[k] == SS_SNAPSHOT_CELL_NODATA);
	if (!err && none > 0)
		r->nodata = flags;
	else
		ss_free(flags);
	return err;
}

/* The last snapshot of a sandslide file (the window's rows: a hyperslab),
 * with its cell size and corner, and its cells without data. */
static int read_h5_output(const char *path, const char *context,
                          const struct ss_dem_read_options *opt, struct ss_raster *r)
{
	struct ss_snapshot_file f;
	int err = ss_snapshot_file_open(&f, path);
	if (!err && f.count < 1)
		err = ss_error_input("'%s' holds no snapshot", path);
	if (!err) {
		r->nx = f.nx;
		r->ny = f.ny;
		err = ss_dem_window(opt, path, context, r);
	}
	const size_t n = ss_raster_cells(r);
	if (!err && !(r->values = ss_alloc(n ? n : 1, sizeof *r->values, "input heights")))
		err = SS_ERR_FAIL;
	if (!err && n)
		err = ss_snapshot_file_read_rows(&f, f.count - 1, r->row_first, r->rows, r->values);
	if (!err)
		err = read_h5_nodata(&f, r);
	if (!err) {
		r->cellsize = f.dx;
		r->cellsize_y = f.dy;
		r->x0 = f.origin_x;
		r->y0 = f.origin_y;
		if (f.crs_wkt && !(r->crs_wkt = ss_dem_strdup(f.crs_wkt)))
			err = SS_ERR_FAIL;
	}
	if (err) {
		ss_free(r->values);
		r->values = NULL;
	}
	ss_snapshot_file_close(&f);
	return err;
}

/* Any (y, x) or (time, y, x) dataset: read whole (ss_snapshot_read_field),
 * then cut to the window. */
static int read_h5_dataset(const char *path, const char *dataset, const char *spec,
                           const char *context, const struct ss_dem_read_options *opt,
                           struct ss_raster *r)
{
	int err = ss_snapshot_read_field(path, dataset, -1, &r->nx, &r->ny, &r->values);
	if (!err)
		err = ss_dem_window(opt, spec, context, r);
	if (!err && r->row_first > 0)
		memmove(r->values, r->values + (size_t)r->row_first * r->nx,
		        ss_raster_cells(r) * sizeof *r->values);
	return err;
}

/* sandslide HDF5: "file.h5" (the last snapshot of a sandslide file, with
 * the run's cell size and corner) or "file.h5:/dataset" (any (y, x) or
 * (time, y, x) variable of any HDF5 file: its last snapshot, no
 * geometry). */
static int read_h5(const char *spec, const char *context, const struct ss_dem_read_options *opt,
                   struct ss_raster *r)
{
	const char *dataset = h5_dataset(spec);
	char *path = ss_dem_strdup(spec);
	if (!path)
		return SS_ERR_FAIL;
	if (dataset)
		path[dataset - 1 - spec] = '\0';
	r->source = path;

	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_input_at(context, "cannot open '%s': %s", path, strerror(errno));
	fclose(f);
	int err = dataset ? read_h5_dataset(path, dataset, spec, context, opt, r)
	                  : read_h5_output(path, context, opt, r);
	if (err)
		return err;
	const size_t n = ss_raster_cells(r);
	for (size_t k = 0; k < n; k++) {
		if (!isfinite(r->values[k]))
			return ss_error_input_at(context, "%s: height %g of %s is not finite: heights must "
			                         "be finite numbers", spec, r->values[k],
			                         SS_RASTER_CELL(r, (long long)(k % (size_t)r->nx),
			                                        (long long)(k / (size_t)r->nx) +
			                                        r->row_first));
	}
	return SS_OK;
}

const char *ss_raster_cell_text(const struct ss_raster *r, long long i, long long j, char *buf)
{
	const double dy = isnan(r->cellsize_y) ? r->cellsize : r->cellsize_y;
	const double x0 = isnan(r->x0) ? 0.0 : r->x0, y0 = isnan(r->y0) ? 0.0 : r->y0;
	return ss_cell_text(i, j, x0 + (i + 0.5) * r->cellsize, y0 + (j + 0.5) * dy, buf);
}

static int check_options(const struct ss_dem_read_options *o, enum ss_dem_format format,
                         const char *spec, const char *context)
{
	if (!isnan(o->zscale) && !(isfinite(o->zscale) && o->zscale != 0.0))
		return ss_error_input_at(context, "'%s': zscale = %g: expected a finite number of metres "
		                         "per grey level, not 0", spec, o->zscale);
	if (!isnan(o->zoffset) && !isfinite(o->zoffset))
		return ss_error_input_at(context, "'%s': zoffset = %g: expected a finite height, m", spec,
		                         o->zoffset);
	if (!isnan(o->zoffset) && isnan(o->zscale))
		return ss_error_input_at(context, "'%s': zoffset is given without zscale: give both, or "
		                         "neither to use the range stored in the PNG", spec);
	if ((!isnan(o->zscale) || !isnan(o->zoffset)) && format != SS_DEM_PNG)
		return ss_error_input_at(context, "'%s': zscale and zoffset apply to 16-bit PNG "
		                         "heightmaps only, not to a %s", spec, ss_dem_format_name(format));
	if (!isnan(o->cellsize) && !(isfinite(o->cellsize) && o->cellsize > 0.0))
		return ss_error_input_at(context, "'%s': cell size %g: expected a number > 0, m", spec,
		                         o->cellsize);
	return SS_OK;
}

/* The cell size option: fills in an unknown cell size, replaces a PNG's
 * stored one, and must agree with one any other file states. */
static int apply_cellsize(const struct ss_dem_read_options *o, const char *spec,
                          const char *context, struct ss_raster *r)
{
	const double c = o->cellsize;
	if (isnan(c))
		return SS_OK;
	if (r->format != SS_DEM_PNG && !isnan(r->cellsize)) {
		const double dy = ss_dem_dy(r);
		if (fabs(r->cellsize - c) > 1e-9 * c || fabs(dy - c) > 1e-9 * c)
			return ss_error_input_at(context, "'%s' has cell size %s x %s m: the given "
			                         "cell size %s m disagrees (leave it out to use the "
			                         "file's)", spec, SS_REAL(r->cellsize), SS_REAL(dy),
			                         SS_REAL(c));
		return SS_OK;
	}
	r->cellsize = r->cellsize_y = c;
	return SS_OK;
}

/* A corner that is known must be finite, and so must the far corner when
 * the cell size is known too: headers are numbers read from the file. */
static int check_extent(const char *spec, const char *context, const struct ss_raster *r)
{
	const double dy = ss_dem_dy(r);
	const double x1 = r->x0 + r->nx * r->cellsize, y1 = r->y0 + r->ny * dy;
	if ((!isnan(r->x0) && (!isfinite(r->x0) || (!isnan(x1) && !isfinite(x1)))) ||
	    (!isnan(r->y0) && (!isfinite(r->y0) || (!isnan(y1) && !isfinite(y1)))))
		return ss_error_input_at(context, "'%s': %d x %d cells of %s x %s m from (%s, %s) m "
		                         "end beyond the largest number: expected a finite extent",
		                         spec, r->nx, r->ny, SS_REAL(r->cellsize), SS_REAL(dy),
		                         SS_REAL(r->x0), SS_REAL(r->y0));
	return SS_OK;
}

int ss_dem_read(const char *spec, const char *context, const struct ss_dem_read_options *opt,
                struct ss_raster *r)
{
	struct ss_dem_read_options defaults;
	raster_clear(r);
	if (!opt) {
		ss_dem_read_options_init(&defaults);
		opt = &defaults;
	}
	/* a file that is not there is that, whatever its extension (GDAL said
	 * "no reason given", an unknown extension "unknown raster format");
	 * GDAL's virtual paths (/vsizip/, /vsicurl/) are GDAL's to check */
	const char *dataset = h5_dataset(spec);
	char file[4096];
	snprintf(file, sizeof file, "%.*s", dataset ? (int)(dataset - 1 - spec) : (int)strlen(spec),
	         spec);
	struct stat sb;
	if (strncmp(file, "/vsi", 4) != 0 && stat(file, &sb) != 0 && errno == ENOENT)
		return ss_error_input_at(context, "cannot open '%s': %s", file, strerror(ENOENT));
	enum ss_dem_format format = opt->format != SS_DEM_AUTO ? opt->format : ss_dem_format_of(spec);
	if (format == SS_DEM_AUTO) {
		/* any other raster GDAL recognises; else name what is accepted */
		if (ss_dem_gdal_available() && ss_dem_gdal_identify(spec))
			format = SS_DEM_GDAL;
		else
			return ss_dem_format_from_path(spec, context, &format);
	}
	int err = check_options(opt, format, spec, context);
	if (err)
		return err;
	r->format = format;
	if (format != SS_DEM_H5 && !(r->source = ss_dem_strdup(spec)))
		return SS_ERR_FAIL;

	switch (format) {
	case SS_DEM_ASC:
		err = ss_dem_read_asc(spec, context, opt, r);
		if (!err)   /* its CRS, in the .prj beside it (dem_prj.c) */
			err = ss_dem_read_prj(spec, context, r);
		break;
	case SS_DEM_H5:
		err = read_h5(spec, context, opt, r);
		break;
	case SS_DEM_PNG:
		err = ss_dem_read_png(spec, context, opt, r);
		break;
	case SS_DEM_GDAL:
		err = ss_dem_gdal_available() ? ss_dem_read_gdal(spec, context, opt, r)
		                              : gdal_unavailable(spec, context);
		break;
	case SS_DEM_AUTO:
		SS_BUG("format not resolved");
	}
	if (!err)
		err = apply_cellsize(opt, spec, context, r);
	if (!err)
		err = check_extent(spec, context, r);
	return err;
}

/* ------------------------------------------------------------------ */
/* writing                                                              */

void ss_dem_summarize(const struct ss_raster *r, struct ss_dem_summary *s)
{
	const double candidate[SS_DEM_NODATA_CANDIDATES] = {r->nodata_value, -9999.0, -99999.0,
	                                                    -1e30};
	double lo = INFINITY, hi = -INFINITY;
	memset(s->count, 0, sizeof s->count);
	const size_t n = ss_raster_cells(r);
	for (size_t k = 0; k < n; k++) {
		if (r->nodata && r->nodata[k])
			continue;
		const double v = r->values[k];
		lo = fmin(lo, v);
		hi = fmax(hi, v);
		for (int a = 0; a < SS_DEM_NODATA_CANDIDATES; a++)
			s->count[a] += v == candidate[a];
	}
	s->max[0] = hi;
	s->max[1] = -lo;
	s->max[2] = r->nodata ? 1.0 : 0.0;
}

/* The value to write for nodata cells: head's nodata value when no cell
 * with data holds it (and it is not NaN, unless allow_nan), else the
 * first of -9999, -99999, -1e30 that none holds.  *has is 0 when there
 * are neither cells without data nor a nodata value (write none). */
static int pick_nodata(const struct ss_raster *head, const struct ss_dem_summary *s,
                       const char *path, int allow_nan, int *has, double *value)
{
	static const double fallback[] = {-9999.0, -99999.0, -1e30};
	*has = head->has_nodata_value || s->max[2] > 0.0;
	*value = NAN;
	if (!*has)
		return SS_OK;
	if (head->has_nodata_value && (allow_nan || !isnan(head->nodata_value)) &&
	    s->count[0] == 0.0) {
		*value = head->nodata_value;
		return SS_OK;
	}
	for (int a = 0; a < 3; a++) {
		if (s->count[a + 1] == 0.0) {
			*value = fallback[a];
			return SS_OK;
		}
	}
	return ss_error_fail("cannot write '%s': every candidate nodata value (-9999, -99999, "
	                     "-1e30) is a height of a cell with data", path);
}

/* A PNG's zmin, zmax: head's range if every value with data lies within
 * it (to half a grey level), else the data's own, so that the lowest and
 * the highest come back exactly. */
static void png_range(const struct ss_raster *head, const struct ss_dem_summary *s,
                      double *zmin, double *zmax)
{
	const double lo = -s->max[1], hi = s->max[0];
	*zmin = 0.0;
	*zmax = 1.0;
	if (!(lo <= hi))   /* no cell has data */
		return;
	const double a = head->png_zmin, b = head->png_zmax;
	const double half = 0.5 * (b - a) / 65534.0;
	const int within = isfinite(a) && isfinite(b) && a < b && lo >= a - half && hi <= b + half;
	*zmin = within ? a : lo;
	*zmax = within ? b : hi;
}

int ss_dem_check_not_source(const char *path, const struct ss_raster *r)
{
	struct stat a, b;
	if (r->source && stat(path, &a) == 0 && stat(r->source, &b) == 0 &&
	    a.st_dev == b.st_dev && a.st_ino == b.st_ino)
		return ss_error_input("cannot write '%s': it is the file the raster was read from, "
		                      "which is never overwritten: choose another output name", path);
	return ss_dem_prj_check_not_source(path, r);   /* nor its .prj */
}

/* Create an empty, new file beside path ("DIR/.BASE.tmp-PID-N") with the
 * permissions a plain creation would give; its name into tmp. */
static int create_temp(const char *path, char *tmp, size_t size, int *fd)
{
	const char *slash = strrchr(path, '/');
	const int dir_len = slash ? (int)(slash - path) + 1 : 0;
	const char *base = slash ? slash + 1 : path;
	if (!*base)
		return ss_error_input("cannot write '%s': expected a file name, not a folder", path);
	for (int attempt = 0; attempt < 100; attempt++) {
		int n = snprintf(tmp, size, "%.*s.%s.tmp-%ld-%d", dir_len, path, base,
		                 (long)getpid(), attempt);
		if (n < 0 || (size_t)n >= size)
			return ss_error_input("cannot write '%s': the path is too long", path);
		*fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (*fd >= 0)
			return SS_OK;
		if (errno != EEXIST)
			return ss_error_input("cannot write '%s': cannot create a file in '%.*s': %s",
			                      path, dir_len > 1 ? dir_len - 1 : 1, dir_len ? path : ".",
			                      strerror(errno));
	}
	return ss_error_input("cannot write '%s': cannot find a free temporary name beside it", path);
}

static int writer_end(struct ss_dem_writer *w)
{
	switch (w->format) {
	case SS_DEM_PNG:
		return ss_dem_png_end(w);
	case SS_DEM_GDAL:
		return ss_dem_gdal_end(w);
	default:
		return SS_OK;
	}
}

int ss_dem_writer_close(struct ss_dem_writer **wp, int keep)
{
	struct ss_dem_writer *w = *wp;
	*wp = NULL;
	if (!w)
		return SS_OK;
	if (keep && !w->err && w->line != w->head->ny)
		SS_BUG("ss_dem_writer_close: %d of %d rows put", w->line, w->head->ny);
	keep = keep && !w->err;
	const int ended = writer_end(w);
	int err = w->err ? w->err : keep ? ended : SS_OK;
	if (w->f) {
		/* complete on disk before it takes the name */
		if (keep && !err && (fflush(w->f) || fsync(fileno(w->f))))
			err = ss_error_fail("cannot write '%s': %s", w->path, strerror(errno));
		if (fclose(w->f) && keep && !err)
			err = ss_error_fail("cannot write '%s': %s", w->path, strerror(errno));
	}
	/* an .asc's CRS goes beside it, X.prj, ready before either is renamed */
	struct ss_dem_prj prj = {.tmp = ""};
	if (keep && !err && w->format == SS_DEM_ASC)
		err = ss_dem_prj_prepare(w->path, w->head, &prj);
	if (keep && !err && rename(w->tmp, w->path))
		err = ss_error_input("cannot write '%s': cannot rename the finished temporary file "
		                     "'%s' to it: %s", w->path, w->tmp, strerror(errno));
	if (keep && !err && w->format == SS_DEM_ASC)
		err = ss_dem_prj_commit(w->path, &prj);
	if (!keep || err)
		unlink(w->tmp);
	ss_dem_prj_discard(&prj);
	ss_free(w->row);
	ss_free(w);
	return err;
}

int ss_dem_writer_open(struct ss_dem_writer **wp, const char *path, enum ss_dem_format format,
                       const struct ss_raster *head, const struct ss_dem_summary *s)
{
	*wp = NULL;
	if (format == SS_DEM_AUTO) {
		int err = ss_dem_format_from_path(path, NULL, &format);
		if (err)
			return err;
	}
	if (format == SS_DEM_H5)
		return ss_error_input("cannot write '%s' as a raster: sandslide HDF5 files are written "
		                      "by the snapshot module; rasters are written as .asc, .png or "
		                      ".tif", path);
	if (format == SS_DEM_GDAL && !ss_dem_gdal_available())
		return gdal_unavailable(path, NULL);
	if (head->nx < 1 || head->ny < 1)
		SS_BUG("ss_dem_writer_open: an empty raster");
	if (strlen(path) >= sizeof (*wp)->path)
		return ss_error_input("cannot write '%s': the path is too long", path);
	int err = ss_dem_check_not_source(path, head);
	if (err)
		return err;
	struct ss_dem_writer *w = ss_alloc(1, sizeof *w, "a raster writer");
	if (!w)
		return SS_ERR_FAIL;
	memset(w, 0, sizeof *w);
	w->format = format;
	w->head = head;
	snprintf(w->path, sizeof w->path, "%s", path);
	png_range(head, s, &w->zmin, &w->zmax);
	int fd = -1;
	if (!(w->row = ss_alloc((size_t)head->nx, sizeof *w->row, "a raster row")))
		err = SS_ERR_FAIL;
	if (!err)
		err = pick_nodata(head, s, path, format == SS_DEM_GDAL, &w->has_nodata, &w->nodata);
	if (!err)
		err = create_temp(path, w->tmp, sizeof w->tmp, &fd);
	if (err) {
		ss_free(w->row);
		ss_free(w);
		return err;
	}
	if (format == SS_DEM_GDAL) {
		close(fd);   /* the name is ours; GDAL rewrites the file */
	} else if (!(w->f = fdopen(fd, "wb"))) {
		close(fd);
		err = ss_error_fail("cannot write '%s': %s", path, strerror(errno));
	}
	if (!err)
		err = format == SS_DEM_ASC ? ss_dem_asc_begin(w)
		    : format == SS_DEM_PNG ? ss_dem_png_begin(w) : ss_dem_gdal_begin(w);
	if (err) {
		w->err = err;
		ss_dem_writer_close(&w, 0);
		return err;
	}
	*wp = w;
	return SS_OK;
}

int ss_dem_writer_put(struct ss_dem_writer *w, const double *values, const uint8_t *nodata,
                      int rows)
{
	const int nx = w->head->nx;
	if (w->line + rows > w->head->ny)
		SS_BUG("ss_dem_writer_put: %d rows past the raster's %d", w->line + rows, w->head->ny);
	for (int k = 0; k < rows && !w->err; k++, w->line++) {
		const double *v = values + (size_t)k * nx;
		const uint8_t *none = nodata ? nodata + (size_t)k * nx : NULL;
		for (int i = 0; i < nx; i++)
			w->row[i] = none && none[i] ? w->nodata : v[i];
		for (int i = 0; i < nx && !w->err; i++)
			if (!(none && none[i]) && !isfinite(v[i]))
				w->err = ss_error_fail("cannot write '%s': height %g of %s is not finite",
				                       w->path, v[i],
				                       SS_RASTER_CELL(w->head, i, w->head->ny - 1 - w->line));
		if (w->err)
			break;
		w->err = w->format == SS_DEM_ASC ? ss_dem_asc_rows(w, w->row, 1)
		       : w->format == SS_DEM_PNG ? ss_dem_png_rows(w, v, none, 1)
		                                 : ss_dem_gdal_rows(w, w->row, 1);
	}
	return w->err;
}

int ss_dem_write(const char *path, enum ss_dem_format format, const struct ss_raster *r)
{
	if (!r->values || r->nx < 1 || r->ny < 1 || r->row_first != 0 || r->rows != r->ny)
		SS_BUG("ss_dem_write: not a whole raster (rows %d + %d of %d)", r->row_first, r->rows,
		       r->ny);
	struct ss_dem_summary s;
	ss_dem_summarize(r, &s);
	struct ss_dem_writer *w;
	int err = ss_dem_writer_open(&w, path, format, r, &s);
	for (int j = r->ny - 1; j >= 0 && !err; j--)   /* north row first */
		err = ss_dem_writer_put(w, r->values + (size_t)j * r->nx,
		                        r->nodata ? r->nodata + (size_t)j * r->nx : NULL, 1);
	const int closed = ss_dem_writer_close(&w, !err);
	return err ? err : closed;
}
