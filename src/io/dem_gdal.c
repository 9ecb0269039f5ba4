/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem_gdal.c - GeoTIFF and other GDAL rasters (see dem.h), only when built
 * with GDAL (the Makefile defines SS_HAVE_GDAL when pkg-config finds it).
 * Without it dem.c refuses these formats before calling in here.
 *
 * Band 1 is read as float64 (after the band's scale and offset, if any);
 * north-up geotransforms only: a rotated or south-up raster would need
 * resampling onto the grid, which is the user's choice to make (gdalwarp).
 * Writing is always GeoTIFF, float64, deflate-compressed, with the
 * geotransform, CRS and nodata value.  GDAL's own messages are silenced
 * and folded into ours, so each error is still printed once.
 */
#include "io/dem_internal.h"

#include "base/strings.h"
#include "sandslide/error.h"

#ifdef SS_HAVE_GDAL

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_srs_api.h>

static void gdal_start(void)
{
	/* atomic: two threads may read rasters at once; both registering is
	 * harmless (GDALAllRegister locks and skips known drivers) */
	static atomic_int registered;
	if (!atomic_load(&registered)) {
		GDALAllRegister();
		atomic_store(&registered, 1);
	}
	CPLPushErrorHandler(CPLQuietErrorHandler);
	CPLErrorReset();
}

/* GDAL's last message, or a stand-in when it gave none. */
static const char *gdal_message(void)
{
	const char *m = CPLGetLastErrorMsg();
	return m && *m ? m : "no reason given";
}

int ss_dem_gdal_identify(const char *path)
{
	gdal_start();
	const int found = GDALIdentifyDriver(path, NULL) != NULL;
	CPLPopErrorHandler();
	return found;
}

/* Swap rows so that row 0 is the south row. */
static void flip_rows(double *v, int nx, int ny)
{
	for (int a = 0, b = ny - 1; a < b; a++, b--) {
		double *p = v + (size_t)a * nx, *q = v + (size_t)b * nx;
		for (int i = 0; i < nx; i++) {
			const double t = p[i];
			p[i] = q[i];
			q[i] = t;
		}
	}
}

/* 1 when wkt is a geographic CRS (coordinates in degrees of longitude and
 * latitude, which the model would take for metres: every face ~90 deg),
 * with its name in name. */
static int geographic(const char *wkt, char *name, size_t size)
{
	OGRSpatialReferenceH srs = OSRNewSpatialReference(wkt);
	const int g = srs && OSRIsGeographic(srs);
	const char *n = g ? OSRGetName(srs) : NULL;
	snprintf(name, size, "%s", n && *n ? n : "a geographic CRS");
	if (srs)
		OSRDestroySpatialReference(srs);
	return g;
}

int ss_dem_gdal_same_crs(const char *a, const char *b)
{
	OGRSpatialReferenceH sa = OSRNewSpatialReference(a), sb = OSRNewSpatialReference(b);
	/* WKT GDAL cannot read is compared as text */
	const int same = sa && sb ? OSRIsSame(sa, sb) != 0 : strcmp(a, b) == 0;
	if (sa)
		OSRDestroySpatialReference(sa);
	if (sb)
		OSRDestroySpatialReference(sb);
	return same;
}

/* x (> 0) rounded to two significant digits: 82.4 -> 82, 772 -> 770,
 * 0.927 -> 0.93 (divided by a power of ten, not multiplied by its
 * inexact inverse, so that the text is short). */
static double two_digits(double x)
{
	const int e = (int)floor(log10(x)) - 1;
	return e >= 0 ? round(x / pow(10.0, e)) * pow(10.0, e)
	              : round(x * pow(10.0, -e)) / pow(10.0, -e);
}

/*
 * The refusal of a DEM in degrees, with the gdalwarp command that puts it
 * in metres: the UTM zone (WGS 84) of its centre, and cells about as large
 * as the source's there, when the geotransform gives them.  At latitude
 * phi a degree is (WGS 84 ellipsoid, the series of the NGA's
 * "length of a degree")
 *
 *   north   111132.92 - 559.82 cos 2 phi + 1.175 cos 4 phi - 0.0023 cos 6 phi  m
 *   east    111412.84 cos phi - 93.5 cos 3 phi + 0.118 cos 5 phi               m
 *
 * and the square cell suggested has the area of the source's, sqrt(cx cy),
 * to two digits: about as many cells, where gdalwarp's own default gave a
 * small raster cells of 772 m.  -ot Float32 keeps the interpolated heights
 * of an integer raster (an Int16 DEM would stay Int16, rounded), and
 * -dstnodata marks what lies outside the source after the rotation of the
 * projection, which would otherwise be 0 m: a cliff all round.
 */
int ss_dem_refuse_degrees(const char *path, const char *context, const char *crs,
                          const struct ss_raster *r, int nx, int ny)
{
	char target[64] = "EPSG:<a projected CRS in metres, e.g. your UTM zone>";
	char cells[160] = "", size[96] = "";
	if (r->has_geotransform) {
		/* x is longitude, y latitude: GDAL's traditional GIS order */
		const double *gt = r->geotransform;
		const double lon = gt[0] + 0.5 * nx * gt[1];
		const double lat = gt[3] + 0.5 * ny * gt[5];
		if (lon >= -180.0 && lon <= 180.0 && lat >= -90.0 && lat <= 90.0) {
			int zone = (int)floor((lon + 180.0) / 6.0) + 1;
			zone = zone < 1 ? 1 : zone > 60 ? 60 : zone;
			snprintf(target, sizeof target, "EPSG:%d", (lat >= 0.0 ? 32600 : 32700) + zone);
			const double phi = lat * (M_PI / 180.0);
			const double north = 111132.92 - 559.82 * cos(2.0 * phi) + 1.175 * cos(4.0 * phi) -
			                     0.0023 * cos(6.0 * phi);
			const double east = 111412.84 * cos(phi) - 93.5 * cos(3.0 * phi) +
			                     0.118 * cos(5.0 * phi);
			const double cx = gt[1] * east, cy = -gt[5] * north, c = sqrt(cx * cy);
			if (isfinite(c) && c > 0.0) {
				const double t = two_digits(c);
				snprintf(cells, sizeof cells, " (about %.3g x %.3g m there)", cx, cy);
				snprintf(size, sizeof size, "-tr %s %s ", SS_REAL(t), SS_REAL(t));
			}
		}
	}
	return ss_error_input_at(context, "'%s' is in %s: its cells are degrees, not metres%s; "
	                         "reproject it first, e.g. gdalwarp -t_srs %s %s-r bilinear "
	                         "-ot Float32 -dstnodata -9999 '%s' dem-m.tif", path, crs, cells,
	                         target, size, path);
}

static int read_dataset(GDALDatasetH ds, const char *path, const char *context,
                        const struct ss_dem_read_options *opt, struct ss_raster *r)
{
	const int bands = GDALGetRasterCount(ds);
	if (bands != 1)
		return ss_error_input_at(context, "'%s' has %d bands: expected one band of heights", path,
		                         bands);
	const int nx = GDALGetRasterXSize(ds), ny = GDALGetRasterYSize(ds);
	if (nx < 1 || ny < 1 || nx > 1 << 30 || ny > 1 << 30)
		return ss_error_input_at(context, "'%s' is %d x %d cells: expected 1 to 2^30 a side",
		                         path, nx, ny);
	double gt[6];
	if (GDALGetGeoTransform(ds, gt) == CE_None) {
		if (gt[2] != 0.0 || gt[4] != 0.0)
			return ss_error_input_at(context, "'%s' has a rotated geotransform (terms %g, %g): "
			                         "expected a north-up raster; resample it first, e.g. "
			                         "gdalwarp", path, gt[2], gt[4]);
		/* a south-up (or east-to-west) raster is the same cells in another
		 * order: gdalwarp's output is north-up, and nearest-neighbour at
		 * the same cell size moves each cell whole, values unchanged */
		if (gt[1] != 0.0 && gt[5] != 0.0 && isfinite(gt[1]) && isfinite(gt[5]) &&
		    !(gt[1] > 0.0 && gt[5] < 0.0) && isfinite(gt[0]) && isfinite(gt[3]))
			return ss_error_input_at(context, "'%s' is %s (pixel size %s x %s): expected a "
			                         "north-up raster (width > 0, height < 0 in the "
			                         "geotransform); flip it first, e.g. gdalwarp -r near "
			                         "-tr %s %s '%s' dem-north-up.tif", path,
			                         gt[5] > 0.0 ? "south-up" : "stored east to west",
			                         SS_REAL(gt[1]), SS_REAL(gt[5]), SS_REAL(fabs(gt[1])),
			                         SS_REAL(fabs(gt[5])), path);
		if (!(gt[1] > 0.0 && gt[5] < 0.0 && isfinite(gt[0]) && isfinite(gt[3])))
			return ss_error_input_at(context, "'%s' has pixel size %s x %s: expected a north-up "
			                         "raster (width > 0, height < 0 in the geotransform)", path,
			                         SS_REAL(gt[1]), SS_REAL(gt[5]));
		memcpy(r->geotransform, gt, sizeof gt);
		r->has_geotransform = 1;
		r->cellsize = gt[1];
		r->cellsize_y = -gt[5];
		r->x0 = gt[0];
		r->y0 = gt[3] + ny * gt[5];
	}
	const char *wkt = GDALGetProjectionRef(ds);
	char crs[160];
	if (wkt && *wkt && geographic(wkt, crs, sizeof crs))
		return ss_dem_refuse_degrees(path, context, crs, r, nx, ny);
	if (wkt && *wkt && !(r->crs_wkt = ss_dem_strdup(wkt)))
		return SS_ERR_FAIL;

	GDALRasterBandH band = GDALGetRasterBand(ds, 1);
	int has_nodata = 0, has_scale = 0, has_offset = 0;
	const double nodata = GDALGetRasterNoDataValue(band, &has_nodata);
	double scale = GDALGetRasterScale(band, &has_scale);
	double offset = GDALGetRasterOffset(band, &has_offset);
	scale = has_scale ? scale : 1.0;
	offset = has_offset ? offset : 0.0;
	r->has_nodata_value = has_nodata;
	r->nodata_value = has_nodata ? nodata : NAN;

	r->nx = nx;
	r->ny = ny;
	int err = ss_dem_window(opt, path, context, r);
	if (err || r->rows == 0)
		return err;
	const size_t n = ss_raster_cells(r);
	const int rows = r->rows, file_first = ny - r->row_first - rows;   /* north first */
	r->values = ss_alloc(n, sizeof(double), "raster heights");
	if (!r->values)
		return SS_ERR_FAIL;
	/* the window in runs of whole blocks (strips or tiles) of the file, so
	 * that GDAL decodes each block once and holds a few in its cache */
	int block_nx = 0, block_ny = 0;
	GDALGetBlockSize(band, &block_nx, &block_ny);
	const int run = block_ny > 0 ? block_ny * ((256 + block_ny - 1) / block_ny) : 256;
	for (int a = file_first; a < file_first + rows;) {
		const int b = (a / run + 1) * run < file_first + rows ? (a / run + 1) * run
		                                                      : file_first + rows;
		if (GDALRasterIO(band, GF_Read, 0, a, nx, b - a, r->values + (size_t)(a - file_first) * nx,
		                 nx, b - a, GDT_Float64, 0, 0) != CE_None)
			return ss_error_input_at(context, "cannot read the heights of '%s': %s", path,
			                         gdal_message());
		/* read once: out of GDAL's cache, which would otherwise keep up
		 * to 5 % of the machine's memory of a window read already */
		GDALFlushCache(ds);
		a = b;
	}
	for (size_t k = 0; k < n; k++) {   /* still north row first */
		const double v = r->values[k];
		if (has_nodata && (v == nodata || (isnan(v) && isnan(nodata)))) {
			if (!r->nodata && !(r->nodata = ss_alloc(n, 1, "nodata flags")))
				return SS_ERR_FAIL;
			r->nodata[k] = 1;
			r->values[k] = 0.0;
			continue;
		}
		const double h = offset + scale * v;
		if (!isfinite(h))
			return ss_error_input_at(context, "%s: height %g of %s is not finite: heights "
			                         "must be finite numbers (mark missing cells with the band's "
			                         "nodata value)", path, h,
			                         SS_RASTER_CELL(r, (long long)(k % (size_t)nx),
			                                        r->ny - 1 - (long long)(k / (size_t)nx) -
			                                        file_first));
		r->values[k] = h;
	}
	flip_rows(r->values, nx, rows);
	if (r->nodata) {
		for (int a = 0, b = rows - 1; a < b; a++, b--) {
			uint8_t *p = r->nodata + (size_t)a * nx, *q = r->nodata + (size_t)b * nx;
			for (int i = 0; i < nx; i++) {
				const uint8_t t = p[i];
				p[i] = q[i];
				q[i] = t;
			}
		}
	}
	return SS_OK;
}

/*
 * What the file at path is, for a GDAL that opened none of it and said
 * nothing ("no reason given" told the user nothing): empty, text (its
 * first line), a format known by its first bytes, or bytes of no raster
 * format.  Virtual paths (/vsizip/...) that fopen cannot read get "".
 */
static void describe_file(const char *path, char *out, size_t size)
{
	static const struct { const char *magic; size_t n; const char *what; } known[] = {
		{"\x89HDF\r\n\x1a\n", 8, "an HDF5 file (name it .h5 to read it as a sandslide one)"},
		{"\x89PNG\r\n\x1a\n", 8, "a PNG image (name it .png)"},
		{"\x1f\x8b", 2, "a gzip archive (unpack it first)"},
		{"PK\x03\x04", 4, "a zip archive (unpack it, or give /vsizip/FILE.zip/NAME)"},
		{"%PDF", 4, "a PDF document"},
	};
	unsigned char head[64];
	*out = '\0';
	FILE *f = fopen(path, "rb");
	if (!f)
		return;
	const size_t n = fread(head, 1, sizeof head, f);
	long bytes = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
	fclose(f);
	if (n == 0) {
		snprintf(out, size, "it is an empty file");
		return;
	}
	for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
		if (n >= known[k].n && memcmp(head, known[k].magic, known[k].n) == 0) {
			snprintf(out, size, "it is %s", known[k].what);
			return;
		}
	int text = 1;
	size_t line = n;   /* the first line's length within head */
	for (size_t k = 0; k < n && text; k++) {
		const unsigned char c = head[k];
		text = c == '\n' || c == '\r' || c == '\t' || (c >= 0x20 && c != 0x7f);
		if ((c == '\n' || c == '\r') && line == n)
			line = k;
	}
	if (text && n >= 5 && strncasecmp((const char *)head, "ncols", 5) == 0) {
		snprintf(out, size, "it is an ESRI ASCII grid (name it .asc)");
	} else if (text) {
		const int shown = line < 40 ? (int)line : 40;
		snprintf(out, size, "it is a text file of %ld bytes, starting '%.*s'%s", bytes, shown,
		         (const char *)head, (long)shown < bytes && line > (size_t)shown ? "..." : "");
	} else {
		snprintf(out, size, "it is %ld bytes of binary data in no raster format GDAL knows",
		         bytes);
	}
}

int ss_dem_read_gdal(const char *path, const char *context, const struct ss_dem_read_options *opt,
                     struct ss_raster *r)
{
	gdal_start();
	int err;
	GDALDatasetH ds = GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, NULL, NULL, NULL);
	if (!ds) {
		char what[160] = "";
		const char *m = CPLGetLastErrorMsg();
		if (!(m && *m))
			describe_file(path, what, sizeof what);
		err = ss_error_input_at(context, "cannot read '%s' as a GDAL raster: %s; expected "
		                        SS_DEM_ACCEPTED_READ, path, *what ? what : gdal_message());
	} else {
		err = read_dataset(ds, path, context, opt, r);
		GDALClose(ds);
	}
	CPLPopErrorHandler();
	return err;
}

/* The side of a GeoTIFF's tiles, cells. */
#define GDAL_TILE 256

/* The geotransform, CRS and nodata value of the new dataset. */
static int write_metadata(GDALDatasetH ds, const struct ss_dem_writer *w)
{
	const struct ss_raster *r = w->head;
	const char *path = w->path;
	const int ny = r->ny;
	double gt[6] = {0};
	if (r->has_geotransform) {
		memcpy(gt, r->geotransform, sizeof gt);
	} else if (r->cellsize > 0.0) {
		const double dy = ss_dem_dy(r);
		const double x0 = isnan(r->x0) ? 0.0 : r->x0, y0 = isnan(r->y0) ? 0.0 : r->y0;
		const double g[6] = {x0, r->cellsize, 0.0, y0 + ny * dy, 0.0, -dy};
		memcpy(gt, g, sizeof gt);
	}
	if ((r->has_geotransform || r->cellsize > 0.0) && GDALSetGeoTransform(ds, gt) != CE_None)
		return ss_error_fail("cannot write '%s': geotransform: %s", path, gdal_message());
	if (r->crs_wkt && GDALSetProjection(ds, r->crs_wkt) != CE_None)
		return ss_error_input("cannot write '%s': the CRS is not one GDAL accepts: %s", path,
		                      gdal_message());
	GDALRasterBandH band = GDALGetRasterBand(ds, 1);
	if (w->has_nodata && GDALSetRasterNoDataValue(band, w->nodata) != CE_None)
		return ss_error_fail("cannot write '%s': nodata value: %s", path, gdal_message());
	return SS_OK;
}

int ss_dem_gdal_begin(struct ss_dem_writer *w)
{
	const struct ss_raster *r = w->head;
	gdal_start();
	int err = SS_OK;
	GDALDriverH drv = GDALGetDriverByName("GTiff");
	if (!drv) {
		err = ss_error_input("cannot write '%s': this GDAL has no GTiff driver", w->path);
		goto out;
	}
	/* lossless: deflate with the floating-point predictor; in tiles, so
	 * that a reader's window (dem.h) decodes only its rows, and so that
	 * the writer holds one row of tiles (flushed when complete) */
	char **options = NULL;
	char block[16];
	snprintf(block, sizeof block, "%d", GDAL_TILE);
	options = CSLSetNameValue(options, "COMPRESS", "DEFLATE");
	options = CSLSetNameValue(options, "PREDICTOR", "3");
	options = CSLSetNameValue(options, "BIGTIFF", "IF_SAFER");
	options = CSLSetNameValue(options, "TILED", "YES");
	options = CSLSetNameValue(options, "BLOCKXSIZE", block);
	options = CSLSetNameValue(options, "BLOCKYSIZE", block);
	GDALDatasetH ds = GDALCreate(drv, w->tmp, r->nx, r->ny, 1, GDT_Float64, options);
	CSLDestroy(options);
	if (!ds) {
		err = ss_error_input("cannot write '%s': %s", w->path, gdal_message());
		goto out;
	}
	w->state = ds;
	err = write_metadata(ds, w);
out:
	CPLPopErrorHandler();
	return err;
}

int ss_dem_gdal_rows(struct ss_dem_writer *w, const double *values, int rows)
{
	GDALRasterBandH band = GDALGetRasterBand(w->state, 1);
	gdal_start();
	int err = SS_OK;
	if (GDALRasterIO(band, GF_Write, 0, w->line, w->head->nx, rows, (void *)values,
	                 w->head->nx, rows, GDT_Float64, 0, 0) != CE_None)
		err = ss_error_fail("cannot write '%s': %s", w->path, gdal_message());
	/* a row of tiles complete: to the file, out of GDAL's cache (which
	 * would otherwise keep up to 5 % of the machine's memory of them) */
	const int done = w->line + rows;
	if (!err && done / GDAL_TILE != w->line / GDAL_TILE && done < w->head->ny) {
		GDALFlushCache(w->state);
		if (CPLGetLastErrorType() >= CE_Failure)
			err = ss_error_fail("cannot write '%s': %s", w->path, gdal_message());
	}
	CPLPopErrorHandler();
	return err;
}

int ss_dem_gdal_end(struct ss_dem_writer *w)
{
	if (!w->state)
		return SS_OK;
	gdal_start();
	CPLErrorReset();
	GDALClose(w->state);   /* flushes: a failure here is a failed write */
	w->state = NULL;
	int err = SS_OK;
	if (CPLGetLastErrorType() >= CE_Failure)
		err = ss_error_fail("cannot write '%s': %s", w->path, gdal_message());
	CPLPopErrorHandler();
	return err;
}

#else /* !SS_HAVE_GDAL: dem.c never calls these */

int ss_dem_gdal_same_crs(const char *a, const char *b)
{
	(void)a, (void)b;
	SS_BUG("GDAL's CRS comparison called in a build without GDAL");
}

int ss_dem_gdal_identify(const char *path)
{
	(void)path;
	return 0;
}

int ss_dem_read_gdal(const char *path, const char *context, const struct ss_dem_read_options *opt,
                     struct ss_raster *r)
{
	(void)path, (void)context, (void)opt, (void)r;
	SS_BUG("GDAL reader called in a build without GDAL");
}

int ss_dem_gdal_begin(struct ss_dem_writer *w)
{
	(void)w;
	SS_BUG("GDAL writer called in a build without GDAL");
}

int ss_dem_gdal_rows(struct ss_dem_writer *w, const double *values, int rows)
{
	(void)w, (void)values, (void)rows;
	SS_BUG("GDAL writer called in a build without GDAL");
}

int ss_dem_gdal_end(struct ss_dem_writer *w)
{
	(void)w;
	return SS_OK;
}

#endif
