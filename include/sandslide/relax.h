/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax.h - `sandslide relax`: a DEM in, the surface relaxed to the repose
 * angle out (quasi-static shaping of piles on real terrain).
 *
 * The DEM becomes the initial surface of a run that goes on until steady
 * (max |dh/dt| < tol and no sand face steeper than the repose angle:
 * doc/model.md) or max_time.  Cells without data are
 * walls by default (sand never enters them, so a DEM below the repose angle
 * comes back bit for bit however its outline is clipped), or open (sand
 * leaves there, held at open_level).  With a bedrock only the sand above
 * it moves (face.h).  A source can pour sand on the DEM first.  The output
 * is a raster in the input's format (its georeferencing and nodata kept),
 * or with an .h5 output the full series of snapshots and
 * diagnostics (snapshot.h).  The input is never modified; every output is
 * written under a temporary name and renamed when complete, and claimed
 * while the run lasts (no other run may write it meanwhile).  It shares the
 * time loop of `run` (src/app/drive.h), with its guards: a stop signal ends
 * the run with the surface as it was then in the output, and a height that
 * becomes non-finite stops it with the last good state kept.
 */
#ifndef SANDSLIDE_RELAX_H
#define SANDSLIDE_RELAX_H

#include <signal.h>
#include <stddef.h>

#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/dem.h"
#include "sandslide/job.h"
#include "sandslide/model_options.h"
#include "sandslide/option.h"
#include "sandslide/shape.h"
#include "sandslide/stepper.h"

struct ss_relax_options {
	const char *dem;                  /* input: path or FILE.h5[:/dataset] */
	struct ss_dem_read_options read;  /* PNG range, cell size */
	struct ss_job job;                /* output (NULL: out/<stem>-relaxed.<ext>),
	                                   * force, threads, tile (<= 0: relax's
	                                   * defaults, setup.h), history, the stop
	                                   * signal (non-zero: stop after the
	                                   * substep and write what there is) and
	                                   * the progress after every substep
	                                   * (job.h) */
	struct ss_model_options model;    /* closure, angle, nu, tol, integrator,
	                                   * ... (model_options.h); max_time NaN:
	                                   * until steady */
	enum ss_side_kind sides;          /* all four grid sides */
	enum ss_cell_type nodata_type;    /* SS_CELL_WALL (default) or
	                                     SS_CELL_OPEN */
	double open_level;                /* m; NAN: the lowest height of the DEM */
	const char *bedrock;              /* raster of the fixed base, or NULL */
	const char *material_table;       /* [material NAME] sections of
	                                   * model.materials_file's classes */
	struct ss_shape sand_shape;       /* pour sand on it (rect or disk, m;
	                                   * SS_SHAPE_NONE: none): */
	double sand_rate;                 /*   m/s */
	double sand_duration;             /*   s, from t = 0 */
	double output_every;              /* s, .h5 output only; NAN: 20 snapshots
	                                     over max_time, else only first and
	                                     last */
	const char *report;               /* JSON diagnostics file, or NULL */
	/* In memory, for a program that holds its rasters (the Python module).
	 * Each, when set, replaces a file: input_raster is relaxed instead of
	 * reading dem and bedrock_raster is the base instead of reading
	 * bedrock (dem and bedrock then only name them in messages and the
	 * report, and must be set), and the relaxed heights go to the values
	 * of output_raster, which must have the input's size, instead of a
	 * file (0 where the input has no data, as rasters store it): nothing
	 * is claimed or written, job.output and job.force are unused.
	 * angle_raster, the repose angles, replaces reading
	 * model.angle_file, which names it.  The caller owns all four. */
	const struct ss_raster *input_raster;
	const struct ss_raster *bedrock_raster;
	const struct ss_raster *angle_raster;
	struct ss_raster *output_raster;
};

/* relax's options: name, kind, default, range, help of each (option.h),
 * continued by the model's at o->model and the job's at o->job.  The
 * command line, the options set by name (ss_option_object_create) and the
 * Python module all read them from here. */
extern const struct ss_option_table ss_relax_option_table;

/* Every option at its default (the table's). */
void ss_relax_options_init(struct ss_relax_options *o);

/* The words of --sides ("wall" or "open": periodic sides make no sense for
 * a DEM) and --nodata ("wall" or "open"); 0, or -1 if word is not one. */
int ss_relax_sides_parse(const char *word, enum ss_side_kind *sides);
int ss_relax_nodata_parse(const char *word, enum ss_cell_type *type);

struct ss_relax_report {
	const char *input;                /* the options' dem (its name) */
	struct ss_model_options model;    /* the model relaxed with */
	int nx, ny;
	double dx, dy;                    /* m */
	long long cells_moved;            /* flow cells whose height changed */
	double volume_moved;              /* half the sum of |h - h0| dx dy, m^3 */
	double volume_before, volume_after; /* m^3, flow cells */
	double inflow, outflow;           /* m^3 */
	long long pour_cells;             /* --add-sand: the cells it covers */
	long long pour_cells_nodata;      /*   of them without data, where
	                                     nothing is poured */
	double pour_extent[4];            /*   the centres poured on: x min,
	                                     x max, y min, y max, m */
	double max_slope_before_deg;      /* steepest face that can move sand */
	double max_slope_after_deg;
	int materials;                    /* distinct repose angles (--angle
	                                   * FILE: doc/model.md#materials), 1
	                                   * without */
	double repose_min_deg, repose_max_deg;  /*   their range */
	long long steps;                  /* substeps (RKL2: super-steps) */
	long long evaluations;            /* stencil evaluations */
	long long rest_steps;             /* of the steps: super-steps of the
	                                     approach to rest (doc/model.md) */
	long long rest_evaluations;       /* of the evaluations: theirs */
	const char *integrator;           /* "euler" or "rkl2" */
	double time;                      /* simulated, s */
	double wall_seconds;
	double read_seconds;              /* of wall_seconds: reading the inputs */
	double write_seconds;             /*   and writing a raster output (a
	                                     series is written as it goes) */
	int ranks;                        /* MPI ranks (comm.h) */
	double bytes_per_cell;            /* the stepper's arrays over the cells
	                                     of a rank's slab */
	double memory_peak_bytes;         /* the largest peak resident memory
	                                     of any rank, the output written */
	int steady;                       /* reached the steady rule */
	int interrupted;                  /* by *stop_signal: the output holds
	                                     the surface as it was then */
	const char *end;                  /* why it stopped: "steady", "max
	                                     time" (max_time reached first),
	                                     "interrupted" */
	char output[4096];
};

/* Returns SS_OK, SS_ERR_INPUT or SS_ERR_FAIL (message already printed);
 * *report is filled when SS_OK.  Prints nothing else: the caller shows the
 * progress and the report. */
int ss_relax_run(const struct ss_relax_options *o, struct ss_relax_report *report);

/* The JSON of `sandslide relax --report` for report r into buf (size
 * bytes, NUL-terminated); SS_ERR_INPUT when it does not fit (the message
 * says how many bytes it needs). */
int ss_relax_report_json(const struct ss_relax_report *r, char *buf, size_t size);

/* ss_relax_run on arrays, a flat entry point for foreign callers: nx x ny
 * heights (m), row-major, row j the j-th from the SOUTH, NaN where there is
 * no data; cells dx by dy m; bedrock the same layout, or NULL (its NaNs
 * are allowed only where heights is NaN too).  The relaxed surface goes
 * to `relaxed` (nx * ny, NaN where heights is; it may be heights itself)
 * and the report's JSON (ss_relax_report_json) to report_json
 * (report_size bytes), or nowhere when report_json is NULL.  The options'
 * dem and bedrock name the arrays in messages ("(array)" when NULL); their
 * job.output, job.force, dx and in-memory fields are not used, and report is
 * written when set.  An infinite height is refused.  Returns as
 * ss_relax_run; relaxed is written only when SS_OK. */
int ss_relax_heights(const struct ss_relax_options *o, int nx, int ny, double dx, double dy,
                     const double *heights, const double *bedrock, double *relaxed,
                     char *report_json, size_t report_size);

/* ss_relax_heights with each cell's repose angle (degrees, the heights'
 * layout; NaN only where heights is NaN), as --angle FILE gives them; the
 * options' model.angle_file names them in messages ("(array)" when NULL).
 * angles NULL: ss_relax_heights. */
int ss_relax_heights_angles(const struct ss_relax_options *o, int nx, int ny, double dx,
                            double dy, const double *heights, const double *bedrock,
                            const double *angles, double *relaxed, char *report_json,
                            size_t report_size);

/* ss_relax_run with the report as JSON (ss_relax_report_json) into
 * report_json (report_size bytes): `sandslide relax DEM -o OUT` for
 * foreign callers, the options (dem, output, force, ...) set by name.  The
 * files are read, checked (a DEM in degrees is refused) and written as the
 * command line reads, checks and writes them. */
int ss_relax_file_json(const struct ss_relax_options *o, char *report_json, size_t report_size);

#endif
