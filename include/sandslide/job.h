/*
 * job.h - what every long command shares, whatever it computes: where its
 * output goes and whether it may replace it, the threads and the tiles of
 * the sweep, the command line for the output's history, and how another
 * party follows and stops it (a stop flag, a progress callback).  run,
 * relax and fit embed a struct ss_job in their options, and their option
 * tables continue with the job's (ss_job_option_table), so that each of
 * these options is defined, parsed and documented once.
 */
#ifndef SANDSLIDE_JOB_H
#define SANDSLIDE_JOB_H

#include <signal.h>

#include "sandslide/option.h"
#include "sandslide/progress.h"

struct ss_watch;

struct ss_job {
	const char *output;          /* the command's output file; NULL: the
	                              * command's default (its --help) */
	int force;                   /* replace an existing output (else refused) */
	int threads;                 /* OpenMP threads; <= 0: OMP_NUM_THREADS,
	                              * else the processors this process may
	                              * run on over the node's ranks
	                              * (parallel.h) */
	int tile[2];                 /* cells per tile of the sweep, nx and ny;
	                              * <= 0: the defaults (the same bits for
	                              * any tile size) */
	const char *history;         /* the command line, for the output */
	const volatile sig_atomic_t *stop_signal; /* when it becomes non-zero,
	                              * the command stops after its substep and
	                              * writes what it has (NULL: none) */
	ss_progress_fn *progress;    /* after every substep (NULL: none) */
	void *progress_context;
};

/* The job's options (force, threads, tile, history): a part of the run,
 * relax and fit tables (option.h).  The output is each command's own row
 * (its meaning and default differ), stored in the job. */
extern const struct ss_option_table ss_job_option_table;

/* The job in options whose table is t (the part of t that is the job's),
 * or NULL when t has none: for foreign callers that hold an options
 * object (ss_option_object_create) and its table. */
struct ss_job *ss_job_of(const struct ss_option_table *t, void *options);

/* Attach watch w (watch.h): its stop flag becomes the job's stop_signal
 * and its callback the progress, replacing any set; w NULL detaches (no
 * stop signal, no progress).  w must outlive the command's call. */
void ss_job_set_watch(struct ss_job *job, struct ss_watch *w);

#endif
