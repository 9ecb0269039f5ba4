/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * observations.h - what `sandslide fit` fits a sliding law to: the
 * observed states of a real or synthetic experiment, read and checked.
 *
 * The file says what it holds:
 *
 *   OBS.h5, .nc, .hdf5 (or any HDF5 file)
 *       a series of heights: /time (time) in s and /height (time, y, x) in m,
 *       as `sandslide run` writes them (doc/output.md) or as another program
 *       writes the same two names; optional /x, /y cell centres (m, evenly
 *       spaced, increasing: /y south to north) and /cell_type (y, x), whose
 *       walls (1) and cells without data (3) are not observed.
 *       (ss_snapshot_read_height_series in snapshot.h reads it.)
 *
 *   CSV with the header  time,path
 *       a raster of heights per line, at that time (s): any raster
 *       ss_dem_read reads (.asc, .tif with GDAL, 16-bit .png,
 *       FILE.h5[:/dataset]; dem.h), its path relative to the CSV's folder
 *       unless absolute.  Every raster has the first one's size; the cell
 *       size and corner are the first one's (and must agree where later
 *       ones state theirs).  Nodata cells are not observed; a raster's
 *       NaN is refused by ss_dem_read.  A sandslide output named as a
 *       raster is its last snapshot as a DEM: walls at 0 m, observed (name
 *       the output itself as OBS to have them not observed).
 *
 *   CSV with the header  time,x,y
 *       the front: points (m, the grid's coordinates) on the boundary of
 *       the sand-covered region, at least 3 per time.  The rows of one time
 *       come together and the times do not decrease down the file.
 *
 * CSV: the header in any case, with spaces and a UTF-8 byte order mark
 * tolerated; fields separated by commas (a path may hold no comma), spaces
 * around them ignored; CRLF line ends, blank lines and lines starting with
 * '#' are skipped.  Times are finite, >= 0 and strictly increasing
 * (repeated only within a front's rows).
 *
 * Every refusal is SS_ERR_INPUT with one message naming the file (and the
 * line of a CSV: "obs.csv:7: ..."), what is wrong and what is accepted;
 * SS_ERR_FAIL only when memory runs out.  A series whose heights need more
 * memory than the machine has available is refused before it is
 * allocated.
 */
#ifndef SANDSLIDE_IO_OBSERVATIONS_H
#define SANDSLIDE_IO_OBSERVATIONS_H

enum ss_observation_kind {
	SS_OBSERVED_HEIGHTS,        /* a height series (HDF5, or a CSV of rasters) */
	SS_OBSERVED_FRONT,          /* the support's boundary (a CSV of points) */
};

struct ss_observations {
	enum ss_observation_kind kind;
	char *path;                 /* the file as given, for messages (owned) */
	long long times;            /* observation times, >= 1 */
	double *time;               /* [times], s: finite, >= 0, strictly
	                             * increasing */

	/* SS_OBSERVED_HEIGHTS (zero, NAN and NULL for a front) */
	int nx, ny;                 /* cells: columns west to east, rows south
	                             * to north */
	double dx, dy;              /* cell size, m; NAN when the source does
	                             * not say (a generic HDF5 without /x, /y,
	                             * a PNG without dx_m) */
	double origin_x, origin_y;  /* lower-left corner of the grid (edge, not
	                             * centre), m; NAN when unknown */
	double *height;             /* [times][ny][nx], south row first, m:
	                             * height[(k * ny + j) * nx + i] is column i,
	                             * row j at time[k]; NAN = not observed
	                             * (NaN in the file, walls, nodata); never
	                             * infinite */
	long long observed;         /* finite values in height, >= 1 */

	/* SS_OBSERVED_FRONT (zero and NULL for heights) */
	long long points;           /* all times' points, >= 3 * times */
	double *point_x, *point_y;  /* [points], m, in the file's order */
	long long *first_point;     /* [times + 1]: time k's points are
	                             * first_point[k] .. first_point[k + 1] - 1;
	                             * first_point[times] == points */
};

/* Read and check path into o (which need not be initialised): SS_OK, or
 * SS_ERR_INPUT / SS_ERR_FAIL after one message, o then released. */
int ss_observations_read(struct ss_observations *o, const char *path);

/* Free what o holds and zero it; a zeroed or released o is a no-op. */
void ss_observations_release(struct ss_observations *o);

#endif
