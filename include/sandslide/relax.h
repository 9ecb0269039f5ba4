/*
 * relax.h - `sandslide relax`: a DEM in, the surface relaxed to the repose
 * angle out (quasi-static shaping of piles on real terrain).
 *
 * The DEM becomes the initial surface of a run that goes on until steady
 * (max |dh/dt| < tol, SPEC section 2) or max_time.  Cells without data are
 * open (sand leaves there, held at open_level) or walls.  With a bedrock
 * only the sand above it moves (face.h).  A source can pour sand on the DEM
 * first.  The output is a raster in the input's format (its georeferencing
 * and nodata kept), or with an .h5 output the full series of snapshots and
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

#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/dem.h"
#include "sandslide/progress.h"
#include "sandslide/shape.h"
#include "sandslide/stepper.h"

struct ss_relax_options {
	const char *dem;                  /* input: path or FILE.h5[:/dataset] */
	struct ss_dem_read_options read;  /* PNG range, cell size */
	const char *output;               /* NULL: out/<stem>-relaxed.<ext> */
	enum ss_closure_kind closure;
	double angle_deg;                 /* repose angle, (0, 90) */
	double gamma;                     /* herschel-bulkley exponent */
	double nu;                        /* m^2/s: sets the time scale only */
	double tol;                       /* m/s: steady when max |dh/dt| < tol */
	double slope_tol;                 /* and no sand face steeper than the
	                                     angle by more (stepper.h) */
	enum ss_integrator integrator;    /* auto: euler (relax.c says why) */
	int rkl2_max_stages;              /* stepper.h */
	double rkl2_tol;
	double max_time;                  /* s; INFINITY: until steady */
	double cfl;
	int threads;                      /* <= 0: the processors of this
	                                     * node over its ranks (comm.h) */
	enum ss_side_kind sides;          /* all four grid sides */
	enum ss_cell_type nodata_type;    /* SS_CELL_OPEN or SS_CELL_WALL */
	double open_level;                /* m; NAN: the lowest height of the DEM */
	const char *bedrock;              /* raster of the fixed base, or NULL */
	int add_sand;                     /* pour on sand_shape: */
	struct ss_shape sand_shape;       /*   rect or disk, m */
	double sand_rate;                 /*   m/s */
	double sand_duration;             /*   s, from t = 0 */
	double output_every;              /* s, .h5 output only; NAN: 20 snapshots
	                                     over max_time, else only first and
	                                     last */
	const char *report;               /* JSON diagnostics file, or NULL */
	const char *history;              /* the command line */
	int force;                        /* replace an existing output */
	const volatile sig_atomic_t *stop_signal; /* non-zero: stop after the
	                                     substep and write what there is */
	ss_progress_fn *progress;         /* after every substep (NULL: none) */
	void *progress_context;
};

void ss_relax_options_init(struct ss_relax_options *o);

struct ss_relax_report {
	int nx, ny;
	double dx, dy;                    /* m */
	long long cells_moved;            /* flow cells whose height changed */
	double volume_moved;              /* half the sum of |h - h0| dx dy, m^3 */
	double volume_before, volume_after; /* m^3, flow cells */
	double inflow, outflow;           /* m^3 */
	double max_slope_before_deg;      /* steepest face that can move sand */
	double max_slope_after_deg;
	long long steps;                  /* substeps (RKL2: super-steps) */
	long long evaluations;            /* stencil evaluations */
	const char *integrator;           /* "euler" or "rkl2" */
	double time;                      /* simulated, s */
	double wall_seconds;
	int steady;                       /* reached max |dh/dt| < tol */
	int interrupted;                  /* by *stop_signal: the output holds
	                                     the surface as it was then */
	char output[4096];
};

/* Returns SS_OK, SS_ERR_INPUT or SS_ERR_FAIL (message already printed);
 * *report is filled when SS_OK.  Prints nothing else: the caller shows the
 * progress and the report. */
int ss_relax_run(const struct ss_relax_options *o, struct ss_relax_report *report);

#endif
