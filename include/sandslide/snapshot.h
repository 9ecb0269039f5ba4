/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * snapshot.h - the HDF5 output of a run (doc/output.md), its XDMF
 * sidecar, and the one reader of such files.  The files src/io/h5_* are
 * the only code that includes <hdf5.h>: h5_write.c (the writer),
 * h5_read.c (every read: the renderer, .h5 DEMs, fit's series),
 * h5_summary.c (`info`'s summary, restarts) and h5_checked.c (the HDF5
 * calls they share).  No HDF5 type appears here.
 *
 * Layout (netCDF-4 / CF-1.8 compatible, dimensions as HDF5 dimension scales):
 *   /height      float64 (time, y, x), chunked, extendible in time
 *   /time        float64 (time), s
 *   /x, /y       float64 cell centres, m
 *   /cell_type   int8 (y, x), flag_values 0 1 2, "flow wall open"; with
 *                cells without data (relax of a DEM with nodata) 0 1 2 3,
 *                "flow wall open nodata"
 *   /bedrock     float64 (y, x), m, only with a bedrock (NaN off flow cells)
 *   /volume /inflow /outflow /max_height /max_slope_deg /steps
 *   /active_fraction /wall_seconds      float64 (time)
 *   root attributes: Conventions, title, history, source, closure,
 *   repose_angle_deg, nu, gamma, dx, dy, case
 * The file is flushed after every snapshot and the sidecar OUT.xmf is
 * rewritten (temporary file + rename), so a run killed at any moment leaves
 * a readable file with every snapshot already reported.
 */
#ifndef SANDSLIDE_SNAPSHOT_H
#define SANDSLIDE_SNAPSHOT_H

#include <stddef.h>
#include <stdint.h>

#include "sandslide/boundary.h"
#include "sandslide/diagnostics.h"
#include "sandslide/grid.h"
#include "sandslide/model_options.h"

struct ss_snapshot;   /* opaque: owns the HDF5 handles */

/* /cell_type of a cell without data (a nodata cell of relax's DEM).  Not a
 * cell type of the stepper (grid.h), which holds such a cell as a wall, or
 * as open with --nodata open: the file says that it has no data, so that
 * the renderer draws it as absent rather than as a wall, and a DEM read
 * from the file has it as nodata again.  /height is NaN there, as at
 * walls.  Every other reader takes it for a wall (ss_snapshot_file_read_
 * cell_types). */
#define SS_SNAPSHOT_CELL_NODATA 3

struct ss_snapshot_meta {
	const char *title;
	const char *history;     /* the command line */
	const char *case_text;   /* the whole case file */
	const struct ss_model_options *model; /* the closure, angle, nu and
	                          * gamma written as attributes */
	const char *integrator;  /* "euler" or "rkl2" (attribute integrator): the
	                          * one the stepper resolved, or NULL: not
	                          * written */
	int deflate;             /* 0 (none) .. 9 */
	const double *bedrock;   /* m, the grid's halo layout, or NULL */
	const char *case_overrides; /* the --set values, one per line, or NULL */
	const char *crs_wkt;     /* coordinate reference system of x and y (WKT,
	                          * from the input DEM), or NULL: written as the
	                          * CF grid mapping variable /crs */
	const struct ss_boundary *boundary; /* the grid's sides (root attribute
	                          * boundary), or NULL: not written */
	int moving;              /* 1: each snapshot has /moving, the cells'
	                          * states of hysteresis (stepper.h), which
	                          * a restart continues */
	const uint8_t *nodata;   /* this rank's rows of the cells without data
	                          * (nx x ny of its slab, south row first,
	                          * nonzero: no data, as a window of struct
	                          * ss_raster holds them), or NULL: none (on
	                          * every rank, or on none).  Written as /cell_type
	                          * SS_SNAPSHOT_CELL_NODATA and NaN in /height,
	                          * whatever the stepper's type of the cell */
};

/* Call first in a program: HDF5 quiet (errors are reported by the callers)
 * and no clean-up at exit, which crashes HDF5 1.10 after a failed close. */
void ss_snapshot_library_init(void);

/* 1 when the HDF5 library linked serializes its own calls (built
 * thread-safe: H5is_library_threadsafe), so that calls writing or reading
 * different files may run in different threads at once; else 0, and the
 * caller must let one thread at a time into anything that touches HDF5
 * (run, fit, an .h5 DEM or output). */
int ss_snapshot_threadsafe(void);

/* Create the output and write the static variables; cell_types are packed
 * in the grid's halo layout (grid.h).  The file is written as "path.partial" and renamed to
 * path when the first snapshot is complete (an existing file of that name is
 * replaced only then).  SS_ERR_FAIL with a message on any HDF5 error. */
int ss_snapshot_create(struct ss_snapshot **out, const char *path,
                       const struct ss_grid *g, const uint8_t *cell_types,
                       const struct ss_snapshot_meta *meta);

/* The bytes one more snapshot of grid g (the whole grid's) adds to a file
 * without deflate: whole chunks of /height and 1 KiB for its time series
 * and chunk index; deflate makes it smaller. */
double ss_snapshot_bytes(const struct ss_grid *g);

/* Append one snapshot (height with the grid's halo layout; walls and
 * cells without data are written as NaN, the _FillValue, so cell_types in
 * the same layout; moving, in the same layout, odd where sand moves (the
 * stepper's material numbers with hysteresis, stepper.h):
 * /moving of a file created with meta->moving, else not used) and, when
 * state is not NULL, the restart state (root
 * attribute restart_state_even or _odd by the snapshot's index), flushed
 * so that a run killed at any moment leaves every earlier snapshot whole
 * (doc/output.md#written-as-the-run-goes); then rewrite the XDMF sidecar. */
int ss_snapshot_append(struct ss_snapshot *s, double time_s, const double *height,
                       const uint8_t *cell_types, const uint16_t *moving,
                       const struct ss_diagnostics *d, const struct ss_restart_state *state);

/* Reopen an output of grid g to append snapshots to it (a restart, or the
 * guard of drive.h), with the cells without data it has.  SS_ERR_INPUT if
 * it is not a sandslide output (ss_snapshot_file_open) of that grid with
 * at least one snapshot. */
int ss_snapshot_open_append(struct ss_snapshot **out, const char *path,
                            const struct ss_grid *g);

/* The last snapshot of an output and what a restart needs with it. */
struct ss_restart_info {
	int nx, ny;
	long long count;         /* snapshots in the file */
	double time;             /* of the last one, s */
	double *height;          /* nx * rows, south row first (ss_free); NULL
	                          * when no row was asked for */
	uint8_t *moving;         /* the same rows of /moving (hysteresis), 1
	                          * where sand moves; NULL: the file has none */
	long long first_row;     /* the rows height holds: first_row .. */
	int rows;                /*   first_row + rows - 1 of the grid */
	struct ss_restart_state state;
	char *case_text;         /* the case file's text */
	char *case_path;         /* where it was read from */
	char *case_overrides;    /* --set values, one per line */
};

/* SS_ERR_INPUT naming what is missing for a file that cannot be continued
 * (not a sandslide output, damaged, no snapshot, no case text or restart
 * state). */
int ss_snapshot_read_restart(const char *path, struct ss_restart_info *r);

/* The same without the case (left NULL): the last snapshot and its restart
 * state, as the guard of a run needs them to take its steps again. */
int ss_snapshot_read_last_state(const char *path, struct ss_restart_info *r);
void ss_restart_info_release(struct ss_restart_info *r);

/* A rank's part of them (comm.h): the case and the restart state without
 * any height, and the last snapshot's rows first_row .. first_row + rows - 1
 * with its restart state, so that no rank holds the whole grid. */
int ss_snapshot_read_restart_case(const char *path, struct ss_restart_info *r);
int ss_snapshot_read_last_rows(const char *path, long long first_row, int rows,
                               struct ss_restart_info *r);

/* Snapshots written so far. */
long long ss_snapshot_count(const struct ss_snapshot *s);

/* Time of the last snapshot written (NaN before the first), s. */
double ss_snapshot_last_time(const struct ss_snapshot *s);

/* Close the file; returns SS_ERR_FAIL if the final close fails.
 * ss_snapshot_destroy(NULL) is a no-op. */
int ss_snapshot_destroy(struct ss_snapshot *s);

/* 1 when path ends in .nc or .nc4: the same HDF5 file, under a name that
 * makes GDAL (and QGIS) open it with its netCDF driver, which reads the
 * coordinates and CRS itself and shows the grid north up; no .aux.xml is
 * written for it. */
int ss_snapshot_named_netcdf(const char *path);

/* Path of the XDMF sidecar for an output path: "run.h5" -> "run.xmf",
 * another name gets ".xmf" added ("run.nc" -> "run.nc.xmf"). */
void ss_snapshot_sidecar_path(const char *path, char *out, size_t size);

/* What `sandslide info` prints.  Arrays have `count` entries. */
struct ss_snapshot_summary {
	int nx, ny;
	long long count;         /* snapshots */
	double dx, dy, origin_x, origin_y;
	char closure[64], source[64], title[256];
	char integrator[16];     /* "euler", "rkl2", or "" (written before RKL2) */
	double repose_angle_deg, nu, gamma;
	double *time;
	struct ss_diagnostics *diag;
	long long flow_cells, wall_cells, open_cells;
	long long nodata_cells;  /* without data (SS_SNAPSHOT_CELL_NODATA), not
	                          * counted in wall_cells */
};

/* Read the summary of a sandslide file; SS_ERR_INPUT if it is not one or
 * is damaged. */
int ss_snapshot_read_summary(const char *path, struct ss_snapshot_summary *sum);
void ss_snapshot_summary_release(struct ss_snapshot_summary *sum);

/*
 * Read a 2-D field from an HDF5 file: dataset is any (time, y, x) variable,
 * in which case snapshot `index` is read (negative: from the end, -1 the
 * last), or (y, x) variable of any HDF5 file; without a dataset (NULL or
 * "") snapshot `index` of /height of a sandslide file.  *values is
 * allocated (nx * ny, south row first) and owned by the caller (ss_free).
 */
int ss_snapshot_read_field(const char *path, const char *dataset, long long index,
                           int *nx, int *ny, double **values);

/* ---- a series of heights of any HDF5 file ---------------------------- */

/*
 * /time (time) and /height (time, y, x) of any HDF5 file: a sandslide
 * output, or a file another program wrote with the same names and no
 * sandslide attributes (the observations `sandslide fit` reads,
 * src/io/observations.h).  Optional, and checked when present:
 *   /x (x), /y (y)   cell centres, m: finite, increasing, evenly spaced
 *                    (/y south to north, as /height's rows are stored)
 *   /cell_type (y, x) as doc/output.md: walls (1) and cells without data
 *                    (3) read as NaN, whatever /height holds there
 * Sizes are checked against the file (the reader's rules above) and the
 * heights against the memory available before anything is allocated.
 * Times and heights are returned as stored: the caller checks their values.
 * /height may hold one snapshot more than /time (a run killed while it
 * wrote one: doc/output.md#written-as-the-run-goes); /time counts those
 * read.
 */
struct ss_height_series {
	int nx, ny;                 /* cells: columns west to east, rows south
	                             * to north */
	long long count;            /* times (0: an empty series) */
	double *time;               /* [count], s, as stored (ss_free); NULL when
	                             * count is 0 */
	double *height;             /* [count][ny][nx], south row first, m;
	                             * NaN where the file has NaN, at walls and
	                             * at cells without data (ss_free) */
	double dx, dy;              /* cell size, m: from /x, /y, else the root
	                             * attributes dx, dy; NAN when neither */
	double origin_x, origin_y;  /* lower-left corner (edge), m: first centre
	                             * minus half a cell; NAN without /x, /y */
};

/* Read path into s.  SS_ERR_INPUT naming the file and what is wrong (not
 * HDF5, damaged, no /time or /height, sizes that do not match, more than
 * memory holds); SS_ERR_FAIL when an allocation fails.  s is released on
 * failure. */
int ss_snapshot_read_height_series(const char *path, struct ss_height_series *s);
/* Free what s holds; a zeroed or released s is a no-op. */
void ss_height_series_release(struct ss_height_series *s);

/* ---- the reader ------------------------------------------------------ */

/*
 * A sandslide file, open for reading.  A file is one when it has
 *   - a root attribute `source` (a string, fixed or variable length)
 *     starting with "sandslide",
 *   - /height (time, y, x) of numbers, with 1 <= y, x <= 2^30, its last
 *     snapshot stored,
 *   - /time (time) of numbers, as many as /height has snapshots,
 *   - /cell_type (y, x) of numbers, of the size of a snapshot,
 *   - positive finite root attributes dx and dy;
 * /x and /y are optional: their first values give the lower-left corner.
 * Numbers are IEEE floats or standard integers of either byte order.
 *
 * A file whose sizes cannot be true is damaged (SS_ERR_INPUT, "... is
 * damaged: ..."): every size is checked against the file before anything
 * of that size is allocated, by this reader or by HDF5 (a dataset's
 * values, its chunks, a string), and a read that fails is damage too.
 * What HDF5 decodes before any size reaches the reader (object headers,
 * heaps) is beyond these checks: tests/fuzz/README.md lists the damaged
 * files that crash or hang Debian's libhdf5 1.10.8 itself.
 */
struct ss_snapshot_file_h5;     /* opaque: the HDF5 handles */

struct ss_snapshot_file {
	char *name;                 /* the path, or the name given to an image */
	int nx, ny;                 /* cells */
	long long count;            /* snapshots */
	double dx, dy;              /* cell size, m */
	double origin_x, origin_y;  /* lower-left corner, m (NAN without /x, /y) */
	double *time;               /* count entries, s */
	char *crs_wkt;              /* the CRS of x and y (/crs), NULL if none */
	unsigned wall_sides;        /* bit 1 << enum ss_side (boundary.h) for each
	                             * side that is a wall; 0 when the file does
	                             * not say (written before the attribute) */
	struct ss_snapshot_file_h5 *h5;
};

/* Open and check a sandslide file and read its times.  SS_ERR_INPUT with
 * a message if it is not one, cannot be read or is damaged; on failure f
 * holds nothing to close (closing it is harmless). */
int ss_snapshot_file_open(struct ss_snapshot_file *f, const char *path);

/* The same for a file image of size bytes in memory (HDF5's core driver),
 * named `name` in messages; data is copied. */
int ss_snapshot_file_open_image(struct ss_snapshot_file *f, const char *name,
                                const void *data, size_t size);

/* Close the file and free what it holds; a zeroed or closed f is a no-op. */
void ss_snapshot_file_close(struct ss_snapshot_file *f);

/* Whether the file has /moving (a run with hysteresis), and its rows j0 ..
 * j0 + rows - 1 of snapshot t into out (rows * nx bytes, 1 where sand
 * moves), as ss_snapshot_file_read_rows reads /height. */
int ss_snapshot_file_has_moving(const struct ss_snapshot_file *f);
int ss_snapshot_file_read_moving(struct ss_snapshot_file *f, long long t, int j0, int rows,
                                 uint8_t *out);

/* Rows j0 .. j0 + rows - 1 of snapshot t of /height into out (rows * nx
 * values, south row first).  May be called from several OpenMP threads at
 * once (HDF5 is called by one at a time).  SS_ERR_INPUT if the file is
 * damaged there (a checksum that does not match, say). */
int ss_snapshot_file_read_rows(struct ss_snapshot_file *f, long long t, int j0, int rows,
                               double *out);

/* Rows j0 .. j0 + rows - 1 of /cell_type into out (rows * nx, south row
 * first) as the stepper's cell types (enum ss_cell_type): a cell without
 * data is a wall, as the stepper held it by default.  SS_ERR_INPUT if a
 * value is not one of the file's (0 flow, 1 wall, 2 open, 3 no data) or
 * the rows cannot be read.  Thread-safe as read_rows. */
int ss_snapshot_file_read_cell_types(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out);
/* The same as the file has them: SS_SNAPSHOT_CELL_NODATA for a cell
 * without data (the renderer, and a DEM read from the file). */
int ss_snapshot_file_read_cell_flags(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out);

/* Rows per read that take whole chunks of /height, about 8 MB of them. */
int ss_snapshot_file_block_rows(const struct ss_snapshot_file *f);

/* ss_snapshot_read_summary and ss_snapshot_read_restart of an open file. */
int ss_snapshot_file_summary(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum);
int ss_snapshot_file_restart(struct ss_snapshot_file *f, struct ss_restart_info *r);

#endif
