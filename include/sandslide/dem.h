/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem.h - raster heights in and out (digital elevation models).
 *
 * Formats (SS_DEM_*), chosen from the path or given explicitly:
 *
 *   .asc           ESRI ASCII grid: ncols, nrows, xllcorner|xllcenter,
 *                  yllcorner|yllcenter, cellsize (or dx and dy, as GDAL
 *                  writes for rectangular cells), optional NODATA_value.
 *                  Written with "%.17g", so values come back bit for bit.
 *                  The CRS is in the ".prj" beside it, as GDAL keeps it:
 *                  read from X.prj (else X.PRJ), ESRI WKT converted to OGC
 *                  WKT with GDAL (kept as read without); written to X.prj
 *                  in ESRI WKT when the raster has one, else a stale X.prj
 *                  is removed.  A .prj that is no CRS, or a geographic
 *                  one, is refused.
 *   .h5[:/dataset] sandslide HDF5 (read only here; the snapshot module writes
 *                  it): "FILE.h5" is the last snapshot of /height of a
 *                  sandslide output, with its cell size and corner;
 *                  "FILE.h5:/dataset" any (y, x) or (time, y, x) variable
 *                  (the last time), with no geometry.
 *   .png           16-bit greyscale heightmap (no CRS) in the renderer's gray16 form:
 *                  grey 0 is no data (tRNS-transparent), grey v >= 1 is
 *                  zmin + (v - 1) (zmax - zmin) / 65534, zmin and zmax in
 *                  the tEXt chunks "zmin_m" and "zmax_m"; optional chunks
 *                  "dx_m", "dy_m" (if not dx_m), "x0_m", "y0_m" give the
 *                  cell size and lower-left corner.  Numbers as "%.17g".
 *                  Any other 16-bit grey PNG needs zscale (and zoffset) in
 *                  the read options: height = zoffset + zscale * grey, no
 *                  data only where a tRNS chunk says.  Other PNGs (8-bit,
 *                  colour, alpha) are refused.
 *   .tif, .tiff    GeoTIFF through GDAL, and on reading any raster GDAL
 *                  opens whose extension is not one of the above; only in
 *                  builds with GDAL (ss_dem_gdal_available()).  Band 1 as
 *                  float64, north-up geotransforms only; the geotransform,
 *                  CRS (WKT) and band nodata value are kept.
 *
 * Values are stored south row first, as the grid stores them (files are
 * north row first: the readers and writers flip).  Cells with no data are
 * flagged in `nodata`, their value is 0, never NaN; any NaN or infinite
 * value that is not the file's nodata value is refused, naming the cell.
 *
 * Writers go to a temporary file in the destination's folder and rename it
 * into place only when complete, so a failed write leaves any earlier file
 * untouched; they refuse to replace the file the raster was read from.
 */
#ifndef SANDSLIDE_DEM_H
#define SANDSLIDE_DEM_H

#include <stdint.h>

enum ss_dem_format {
	SS_DEM_AUTO = 0,   /* from the path's extension */
	SS_DEM_ASC,        /* ESRI ASCII grid */
	SS_DEM_H5,         /* sandslide HDF5 (not written by ss_dem_write) */
	SS_DEM_PNG,        /* 16-bit greyscale PNG heightmap */
	SS_DEM_GDAL,       /* GeoTIFF or another GDAL raster (GDAL builds only) */
};

struct ss_raster {
	int nx, ny;             /* columns (west to east), rows (south to north)
	                           of the whole raster */
	int row_first, rows;    /* the rows held: row_first .. row_first + rows - 1
	                           (from the south); 0 and ny for a whole raster,
	                           a rank's rows for a window (read options) */
	double *values;         /* nx * rows heights, m; values[j * nx + i] is
	                           row row_first + j; 0 where nodata is set */
	uint8_t *nodata;        /* nx * rows flags (1: no data), NULL when no
	                           cell held lacks data */
	double cellsize;        /* x spacing, m, NAN when the file does not say */
	double cellsize_y;      /* y spacing, m: cellsize unless the file has
	                           rectangular cells; NAN when unknown */
	double x0, y0;          /* lower-left corner (edge, not centre), m; NAN
	                           when unknown */

	/* What a writer needs to write the same format back. */
	enum ss_dem_format format; /* format read from; SS_DEM_AUTO if built */
	char *source;           /* file read from (owned), NULL if built */
	int has_nodata_value;   /* asc NODATA_value or GDAL band nodata given */
	double nodata_value;    /* that value (may be NaN for GDAL); the writers
	                           use it if no valid cell equals it, else -9999 */
	int asc_center;         /* asc: the header gave xllcenter/yllcenter */
	double png_zmin;        /* PNG: heights of grey 1 and 65535, m (zmin_m, */
	double png_zmax;        /*   zmax_m); NAN: the writer takes the data's */
	int has_geotransform;   /* GDAL: geotransform below is set */
	double geotransform[6]; /* GDAL: x = g0 + col g1, y = g3 + row g5, row 0
	                           the north row; g2 = g4 = 0.  When set, the
	                           GeoTIFF writer uses it rather than x0, y0 */
	char *crs_wkt;          /* coordinate reference system as WKT (owned),
	                           NULL when none: a GDAL raster's, an .asc's
	                           .prj, an .h5's /crs */
};

/* Options of ss_dem_read; NULL means ss_dem_read_options_init's defaults. */
struct ss_dem_read_options {
	enum ss_dem_format format; /* SS_DEM_AUTO (default): from the path */
	double zscale;      /* PNG: m per grey level, > 0; NAN (default): the
	                       range in the file's text chunks */
	double zoffset;     /* PNG: height of grey 0, m, only with zscale;
	                       NAN (default) means 0 */
	double cellsize;    /* m, > 0: for files that give no cell size (PNG
	                       without sandslide:dx, HDF5 datasets, GDAL rasters
	                       without a geotransform); overrides sandslide:dx;
	                       must agree with a cell size the file states.
	                       NAN (default): the file's */
	/* A window: only rows row_first .. row_first + rows - 1 (from the
	 * south) are kept, so that a rank of a distributed run holds its rows
	 * and never the whole raster: GDAL reads the window (RasterIO, in
	 * blocks of the file's strips or tiles), HDF5 a hyperslab, ESRI ASCII
	 * streams the text (no more than a buffer of it in memory) and stops
	 * after the window, PNG decodes row by row (an interlaced PNG whole,
	 * as Adam7 needs).  rows = 0 reads the header alone (size, geometry,
	 * CRS, nodata value); rows < 0 (default) the whole raster.  A window
	 * past the raster's rows is SS_ERR_INPUT.  Values of rows outside the
	 * window are not checked. */
	int row_first, rows;
};

void ss_dem_read_options_init(struct ss_dem_read_options *o);

/* Read spec into r (which need not be initialised).  SS_ERR_INPUT names the
 * file (and line for text formats) for an unreadable or malformed file, a
 * missing value or a NaN or infinite height, after `context` (where the file
 * was named, e.g. "case.ini:25"; may be NULL).  Release r with
 * ss_raster_release either way. */
int ss_dem_read(const char *spec, const char *context,
                const struct ss_dem_read_options *opt, struct ss_raster *r);

/* Write r to path in format (SS_DEM_AUTO: from the path), keeping what the
 * format can hold: ESRI ASCII the corner (xllcenter if it was read so),
 * cell size and NODATA_value; PNG the range in the text chunks (r's
 * png_zmin/png_zmax if every value lies within them, else the data's
 * minimum and maximum, which then come back exactly; other values to half
 * a grey level), the cell size and corner, nodata cells as grey 0; GeoTIFF the
 * geotransform, CRS and nodata value; an .asc's CRS goes to the .prj beside
 * it (see above).  SS_ERR_INPUT for an unwritable path,
 * a format that cannot be written (HDF5, GDAL missing) or metadata the
 * format needs and r lacks (a cell size for .asc); SS_ERR_FAIL for a NaN or
 * infinite value in a cell with data. */
int ss_dem_write(const char *path, enum ss_dem_format format, const struct ss_raster *r);

/*
 * Streamed writing, for a raster no process holds whole (a distributed
 * run's rows, dem.h's windows): the same file as ss_dem_write, written
 * row block by row block, so that the writer holds one block.
 *
 * What a writer must know of all the data before its first row (the PNG's
 * range, a nodata value no cell holds) is a summary: each rank summarises
 * the rows it holds, and the ranks combine the summaries by taking the
 * maxima of max[] and the sums of count[] (integers: exact in any order;
 * comm.h's ss_comm_reduce does both).
 */
#define SS_DEM_NODATA_CANDIDATES 4
struct ss_dem_summary {
	/* highest height, minus the lowest, 1 if a cell lacks data (0 else) */
	double max[3];
	/* cells with data holding each candidate nodata value: the raster's
	 * own nodata_value, -9999, -99999, -1e30 */
	double count[SS_DEM_NODATA_CANDIDATES];
};
void ss_dem_summarize(const struct ss_raster *r, struct ss_dem_summary *s);

struct ss_dem_writer;

/* Start writing path in format (SS_DEM_AUTO: from the path) with head's
 * size, geometry, CRS and metadata (its values are not read; head must
 * outlive the writer) and the summary of all the data.  Checks as
 * ss_dem_write; on SS_OK *w is open and ss_dem_writer_close must follow. */
int ss_dem_writer_open(struct ss_dem_writer **w, const char *path, enum ss_dem_format format,
                       const struct ss_raster *head, const struct ss_dem_summary *s);
/* The next `rows` rows of the file, north row first: values[k * nx + i]
 * (and nodata[k * nx + i], which may be NULL for none) is the file's next
 * row k.  After a failure (SS_ERR_FAIL, once) later calls do nothing and
 * return it again. */
int ss_dem_writer_put(struct ss_dem_writer *w, const double *values, const uint8_t *nodata,
                      int rows);
/* Finish: with keep and every row put and written, the file takes its
 * name (SS_OK, or the failure of the last write); else it is removed.  *w
 * is freed and set to NULL either way. */
int ss_dem_writer_close(struct ss_dem_writer **w, int keep);

/* SS_ERR_INPUT when path is the file r was read from, or an .asc whose
 * .prj is the one r was read with (the input is never modified): what
 * ss_dem_write refuses, for a caller to ask before it does the work whose
 * result it would write. */
int ss_dem_check_not_source(const char *path, const struct ss_raster *r);

/* The format of path from its extension, SS_DEM_AUTO when it is none of
 * those below; prints nothing. */
enum ss_dem_format ss_dem_format_of(const char *path);

/* The format of path from its extension (".asc", ".png", ".tif", ".tiff",
 * ".h5" or "FILE.h5:/dataset", any case).  SS_ERR_INPUT listing the
 * accepted extensions otherwise (after context, which may be NULL). */
int ss_dem_format_from_path(const char *path, const char *context,
                            enum ss_dem_format *format);

/* "ESRI ASCII grid", "sandslide HDF5", ... for messages. */
const char *ss_dem_format_name(enum ss_dem_format format);

/*
 * Whether r (`what`, e.g. "--angle angles.tif") lies on the cells of dem
 * (`dem_name`), as a raster read beside a DEM must: the same size (the
 * callers check it first), and where both files say, the same cell size,
 * lower-left corner (within a millionth of a cell) and CRS (GDAL's
 * OSRIsSame; without GDAL the same WKT).  What only one of them says is
 * not compared: an .asc without a .prj has no CRS.  SS_ERR_INPUT names
 * both values.
 */
int ss_dem_check_aligned(const struct ss_raster *dem, const char *dem_name,
                         const struct ss_raster *r, const char *what);

/* 1 when this build reads and writes GDAL rasters, else 0. */
int ss_dem_gdal_available(void);

/* An nx x ny raster of zeros with no nodata and unknown geometry
 * (SS_ERR_FAIL when out of memory, r released).  For rasters built in
 * memory; ss_dem_read initialises r itself. */
int ss_raster_init(struct ss_raster *r, int nx, int ny);
void ss_raster_release(struct ss_raster *r);

#endif
