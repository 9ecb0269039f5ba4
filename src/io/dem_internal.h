/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem_internal.h - what the raster format files (dem_*.c) share with dem.c.
 * Not installed; dem.h is the public interface.
 */
#ifndef SANDSLIDE_DEM_INTERNAL_H
#define SANDSLIDE_DEM_INTERNAL_H

#include <stddef.h>
#include <stdio.h>

#include "base/strings.h"
#include "sandslide/dem.h"

/* Cell (i, j) of r (column from the west, row from the south of the whole
 * raster) named as every message names a cell (SS_CELL, base/strings.h):
 * its centre in the raster's coordinates, from 0 where the file gives no
 * corner, as the writers place it; just "cell (i, j)" without a cell
 * size.  Returns buf (SS_CELL_TEXT_SIZE bytes). */
const char *ss_raster_cell_text(const struct ss_raster *r, long long i, long long j, char *buf);
#define SS_RASTER_CELL(r, i, j) ss_raster_cell_text((r), (i), (j), (char[SS_CELL_TEXT_SIZE]){0})

/* What the extension-less error messages list as accepted. */
#define SS_DEM_ACCEPTED_READ                                                    \
	"an ESRI ASCII grid (.asc), a sandslide HDF5 file (.h5, .nc or .h5:/dataset), " \
	"a 16-bit greyscale PNG (.png) or a GeoTIFF (.tif, .tiff)"

/* Readers: r is zeroed with unknown geometry on entry; r->source is set. */
int ss_dem_read_asc(const char *path, const char *context,
                    const struct ss_dem_read_options *opt, struct ss_raster *r);
int ss_dem_read_png(const char *path, const char *context,
                    const struct ss_dem_read_options *opt, struct ss_raster *r);
int ss_dem_read_gdal(const char *path, const char *context,
                     const struct ss_dem_read_options *opt, struct ss_raster *r);
/* 1 if GDAL has a driver that recognises path (quietly), else 0. */
int ss_dem_gdal_identify(const char *path);

/* The window of opt (dem.h) into r->row_first and r->rows, once the
 * reader knows r->ny: the whole raster when opt->rows < 0, else checked
 * against r->ny (SS_ERR_INPUT naming spec). */
int ss_dem_window(const struct ss_dem_read_options *opt, const char *spec,
                  const char *context, struct ss_raster *r);

/* Cells held: nx * rows. */
size_t ss_raster_cells(const struct ss_raster *r);

/* A write in progress (dem.h's streamed writing): the file is written to
 * tmp (created empty), which takes path's name when complete. */
struct ss_dem_writer {
	enum ss_dem_format format;
	char path[4096], tmp[4096];
	const struct ss_raster *head;   /* size, geometry, metadata */
	int has_nodata;                 /* write a nodata value: */
	double nodata;                  /*   this one, for cells without data */
	double zmin, zmax;              /* PNG: heights of grey 1 and 65535 */
	int line;                       /* file rows written, north first */
	int err;                        /* the first failure */
	FILE *f;                        /* ESRI ASCII, PNG */
	void *state;                    /* the format's own (libpng, GDAL) */
	double *row;                    /* one row as written */
};

/* The formats' writers: begin (the header), rows (the next rows, north
 * first, values with nodata cells already set to w->nodata), end (finish
 * and free the state, also after a failure).  Messages name w->path. */
int ss_dem_asc_begin(struct ss_dem_writer *w);
int ss_dem_asc_rows(struct ss_dem_writer *w, const double *values, int rows);
int ss_dem_png_begin(struct ss_dem_writer *w);
int ss_dem_png_rows(struct ss_dem_writer *w, const double *values, const uint8_t *nodata,
                    int rows);
int ss_dem_png_end(struct ss_dem_writer *w);
int ss_dem_gdal_begin(struct ss_dem_writer *w);
int ss_dem_gdal_rows(struct ss_dem_writer *w, const double *values, int rows);
int ss_dem_gdal_end(struct ss_dem_writer *w);

/* The CRS of an ESRI ASCII grid, in the .prj beside it (dem_prj.c): read
 * into r->crs_wkt after the grid (SS_OK and no CRS when there is none). */
int ss_dem_read_prj(const char *path, const char *context, struct ss_raster *r);

/* Its .prj written with an .asc: prepared (the text in a temporary file
 * beside it) before the grid is renamed into place, committed (renamed to
 * X.prj; with no CRS, a stale X.prj or X.PRJ removed) after, discarded
 * (the temporary file removed, if still there) always. */
struct ss_dem_prj {
	char dest[4096];    /* X.prj */
	char tmp[4096];     /* the temporary file, "" when none */
	int remove;         /* r has no CRS: remove a stale one */
};
int ss_dem_prj_prepare(const char *path, const struct ss_raster *r, struct ss_dem_prj *p);
int ss_dem_prj_commit(const char *path, struct ss_dem_prj *p);
void ss_dem_prj_discard(struct ss_dem_prj *p);
/* SS_ERR_INPUT when writing path as .asc would replace the .prj r's grid
 * was read with (dem.asc read, dem.ASC written). */
int ss_dem_prj_check_not_source(const char *path, const struct ss_raster *r);

/* dem_gdal.c's refusal of a raster in degrees (crs: its name), from r's
 * geotransform; GDAL builds only. */
/* 1 when the CRSes of WKT a and b are the same (dem_gdal.c: OSRIsSame). */
int ss_dem_gdal_same_crs(const char *a, const char *b);

int ss_dem_refuse_degrees(const char *path, const char *context, const char *crs,
                          const struct ss_raster *r, int nx, int ny);

/* Cell sizes to write: cellsize and cellsize_y (cellsize_y NAN: cellsize). */
double ss_dem_dy(const struct ss_raster *r);

/* A copy of s with ss_alloc (NULL and a message when out of memory). */
char *ss_dem_strdup(const char *s);

#endif
