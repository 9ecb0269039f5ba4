/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * run.h - `sandslide run`: case file in, HDF5 snapshots out.
 *
 * Everything that can be checked is checked before the output file is
 * touched: the case, the set-up (regions, initial file, memory) and the
 * output folder.  Then the run claims its output (no other run may write
 * it meanwhile), writes snapshot 0 at t = 0 and one every output_every
 * seconds (and at the end, or when the state is steady).  The library
 * prints nothing but error messages: progress and the summary go to the
 * caller.
 */
#ifndef SANDSLIDE_RUN_H
#define SANDSLIDE_RUN_H

#include <signal.h>
#include <stddef.h>

#include "sandslide/job.h"
#include "sandslide/option.h"

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

/* What a run is about to write, told once its input is checked and before
 * its output is touched (ss_run_options.on_plan). */
struct ss_run_plan {
	const char *output;          /* the output file */
	double snapshots;            /* snapshots it will add; INFINITY: a
	                              * steady run without max_time */
	int at_most;                 /* a steady run: it may stop sooner */
	double snapshot_bytes;       /* bytes each adds without deflate
	                              * (ss_snapshot_bytes) */
	double bytes;                /* snapshots x snapshot_bytes */
	double free_bytes;           /* free on the output's file system;
	                              * < 0: unknown */
	int deflate;                 /* the deflate level: bytes is then an
	                              * upper bound */
};

struct ss_run_options {
	const char *case_path;
	struct ss_job job;           /* output (NULL: out/<case name>.h5),
	                              * force, threads, tile, history, the stop
	                              * signal (when it becomes non-zero the
	                              * run finishes its substep, writes a
	                              * snapshot and returns SS_OK) and the
	                              * progress after every substep (job.h) */
	struct ss_option_list overrides; /* in order: "SECTION.KEY=VALUE" sets a
	                              * key, "SECTION.KEY" or "SECTION" unsets
	                              * (case.h) */
	int reference_kernel;        /* use the reference sweep (sweep.h) */
	int deflate;                 /* HDF5 deflate level 0..9 */
	const char *restart;         /* continue the run in this output from its
	                              * last snapshot (case_path may be NULL) */
	/* Called after every snapshot (NULL: none), e.g. to render it; a
	 * non-zero return (a status, message printed) stops the run. */
	int (*on_snapshot)(void *context, const struct ss_run_snapshot *s);
	void *snapshot_context;
	/* Called once before the output is touched (NULL: not called), e.g.
	 * to print the projected size.  A run with a fixed end and no deflate
	 * whose projection exceeds the free space is refused (SS_ERR_INPUT,
	 * naming the time.output_every that fits) before this is called. */
	void (*on_plan)(void *context, const struct ss_run_plan *p);
	void *plan_context;
};

/* run's options: name, kind, default, range, help of each (option.h),
 * continued by the job's at o->job.  The command line, the options set by
 * name (ss_option_object_create) and the Python module all read them from
 * here. */
extern const struct ss_option_table ss_run_option_table;

/* Every option at its default (the table's). */
void ss_run_options_init(struct ss_run_options *o);

/* How a run ended. */
enum ss_run_end {
	SS_RUN_DONE,            /* at `end` */
	SS_RUN_STEADY,          /* end = steady, and it is */
	SS_RUN_NOT_STEADY,      /* end = steady, stopped by max_time */
	SS_RUN_INTERRUPTED,     /* by *stop_signal: the last snapshot is then */
};

/* What the command line says when a run is over. */
struct ss_run_summary {
	char output[4096];
	enum ss_run_end end;
	long long snapshots;         /* in the file */
	double time;                 /* simulated time reached, s */
	long long steps;             /* substeps since t = 0 */
	long long steps_here;        /* substeps this process took */
	long long evaluations;       /* stencil evaluations since t = 0 */
	long long evaluations_here;  /* those this process made */
	const char *integrator;      /* "euler" or "rkl2" */
	int stages_max;              /* RKL2: the stage cap (rkl2_max_stages) */
	double bytes_per_cell;       /* the stepper's arrays over the cells
	                                (of a rank's slab) */
	double memory_peak_bytes;    /* the largest peak resident memory of
	                                any rank (ss_memory_peak_bytes) */
	double cells;                /* of the grid */
	double cell_updates_here;    /* cells this process updated: of its
	                              * evaluations, the cells of the tiles
	                              * they swept (ss_stepper_swept_fraction:
	                              * the fast sweep skips sleeping tiles) */
	double wall_seconds;         /* the whole run */
	double measure_seconds;      /* measuring the largest slope */
	double sweep_seconds;        /* sweeping */
	double output_seconds;       /* writing snapshots */
	double comm_seconds;         /* in MPI calls, rank 0 (comm.h) */
	int threads;                 /* OpenMP threads of each rank */
	int ranks;                   /* MPI ranks (comm.h) */
	/* what the overrides made of the case: the keys they dropped (case.h) */
	char notes[8][512];
	int note_count;
};

/* Returns SS_OK, SS_ERR_INPUT or SS_ERR_FAIL (message already printed);
 * *summary is filled when SS_OK. */
int ss_run_case(const struct ss_run_options *o, struct ss_run_summary *summary);

/* The summary as JSON into buf (size bytes, NUL-terminated): "output",
 * "end" ("done", "steady", "not steady", "interrupted"), "snapshots",
 * "time", "steps", "evaluations", "integrator", the threads, ranks and
 * timings, and the "notes" of the overrides; SS_ERR_INPUT when it does not fit (the message says how many
 * bytes it needs). */
int ss_run_summary_json(const struct ss_run_summary *s, char *buf, size_t size);

/* ss_run_case with the summary as JSON (ss_run_summary_json): a flat
 * entry point for foreign callers. */
int ss_run_case_json(const struct ss_run_options *o, char *summary_json, size_t size);

#endif
