/*
 * dem.h - raster height input: ESRI ASCII grids (.asc) and sandslide HDF5
 * files ("FILE.h5" for the last snapshot of /height, "FILE.h5:/dataset" for
 * another variable).  Values come back south row first, as the grid stores
 * them; ESRI's nodata cells are flagged, never passed on as heights.
 */
#ifndef SANDSLIDE_DEM_H
#define SANDSLIDE_DEM_H

#include <stdint.h>

struct ss_raster {
	int nx, ny;             /* columns (west to east), rows (south to north) */
	double *values;         /* nx * ny heights, m; row j = j-th from the south */
	uint8_t *nodata;        /* nx * ny flags, or NULL when the file has none */
	double cellsize;        /* m, NAN when the format does not say */
	double x0, y0;          /* lower-left corner, m (NAN when unknown) */
};

/* Read spec into r.  SS_ERR_INPUT names the file (and line for text
 * formats) for an unreadable file, a malformed header, a missing value or a
 * NaN or infinite height, after `context` (where the file was named, e.g.
 * "case.ini:25"; may be NULL).  Release r with ss_raster_release either way.
 */
int ss_dem_read(const char *spec, const char *context, struct ss_raster *r);
void ss_raster_release(struct ss_raster *r);

#endif
