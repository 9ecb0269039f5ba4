/*
 * run.h - `sandslide run`: case file in, HDF5 snapshots out.
 *
 * Everything that can be checked is checked before the output file is
 * touched: the case, the set-up (regions, initial file, memory) and the
 * output folder.  Then snapshot 0 is written at t = 0 and one every
 * output_every seconds (and at the end, or when the state is steady).
 */
#ifndef SANDSLIDE_RUN_H
#define SANDSLIDE_RUN_H

#include <signal.h>

/* What a run reports after each snapshot is written and flushed. */
struct ss_run_snapshot {
	const char *path;            /* the output file */
	long long index;             /* snapshot number, 0 at t = 0 */
	double time;                 /* s */
	double source_rise;          /* m: the most the sources can add to one
	                              * cell over the whole run (each source's
	                              * rate times its time on, summed);
	                              * INFINITY if a source never stops */
	double open_level;           /* m, held on open cells and sides */
	int any_open_side;           /* a side of the grid is open */
};

struct ss_run_options {
	const char *case_path;
	const char *output;          /* NULL: out/<case name>.h5 */
	const char *const *overrides; /* "SECTION.KEY=VALUE" */
	int override_count;
	int threads;                 /* <= 0: all processors */
	int tile_nx, tile_ny;        /* <= 0: defaults */
	int reference_kernel;        /* use the reference sweep (sweep.h) */
	int deflate;                 /* HDF5 deflate level 0..9 */
	int quiet;                   /* no progress, no summary */
	const char *history;         /* the command line, for the file */
	int force;                   /* replace an existing output (else refused) */
	const char *restart;         /* continue the run in this output from its
	                              * last snapshot (case_path may be NULL) */
	const volatile sig_atomic_t *stop_signal; /* when it becomes non-zero, the
	                              * run finishes its substep, writes a
	                              * snapshot and returns SS_OK */
	/* Called after every snapshot (NULL: none), e.g. to render it; a
	 * non-zero return (a status, message printed) stops the run. */
	int (*on_snapshot)(void *context, const struct ss_run_snapshot *s);
	void *snapshot_context;
};

/* Returns SS_OK, SS_ERR_INPUT or SS_ERR_FAIL (message already printed). */
int ss_run_case(const struct ss_run_options *o);

#endif
