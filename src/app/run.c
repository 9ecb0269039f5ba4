/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * run.c - `sandslide run` (see run.h): case -> set-up -> the shared time
 * loop (drive.h) -> snapshots.
 */
#include "sandslide/run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app/drive.h"
#include "base/strings.h"
#include "io/output.h"
#include "model/setup.h"
#include "sandslide/case.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

/* Everything one run holds, released by run_release. */
struct run {
	const struct ss_run_options *o;
	struct ss_case c;
	struct ss_restart_info restart;   /* with o->restart */
	struct ss_stepper st;
	struct ss_drive drive;
	char output[4096];
	struct ss_run_plan plan;          /* the output's projected size */
};

/* "cases/door.ini" -> "out/door.h5" */
static void default_output(const char *case_path, char *out, size_t size)
{
	const char *base = strrchr(case_path, '/') ? strrchr(case_path, '/') + 1 : case_path;
	const char *dot = strrchr(base, '.');
	int stem = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
	snprintf(out, size, "out/%.*s.h5", stem, base);
}

/* The case of a run being continued: the text and overrides stored in its
 * file.  A case file named as well must be that same text; its files (masks,
 * DEMs) are then found beside it, so a run started elsewhere can be continued
 * from any folder.  Without one they are found beside the path the run was
 * started with (the file's title), relative to the current folder. */
static int restart_case(const struct ss_run_options *o, const struct ss_restart_info *r,
                        struct ss_case *c)
{
	memset(c, 0, sizeof *c);
	if (o->overrides.count > 0)
		return ss_error_input("--restart %s: --set and --unset cannot change a run being "
		                      "continued (it keeps the overrides it was started with)",
		                      o->restart);
	int err = SS_OK;
	if (o->case_path) {
		struct ss_case given;
		err = ss_case_load(&given, o->case_path, NULL, 0);
		if (!err && strcmp(given.text, r->case_text) != 0)
			err = ss_error_input("--restart %s: '%s' is not the case that file was run "
			                     "from ('%s' as it was then); give that case or none",
			                     o->restart, o->case_path, r->case_path);
		ss_case_release(&given);
		if (err)
			return err;
	}
	int n = 0;
	for (const char *p = r->case_overrides; *p; p++)
		n += *p == '\n';
	char *copy = strdup(r->case_overrides);
	const char **v = calloc((size_t)n + 1, sizeof *v);
	if (!copy || !v) {
		free(copy);
		free(v);
		return ss_error_fail("out of memory");
	}
	int m = 0;
	/* split at the newlines, empty lines skipped (not strtok: its state is
	 * shared by every thread, and two runs may restart at once) */
	for (char *line = copy, *next; line && m < n; line = next) {
		if ((next = strchr(line, '\n')))
			*next++ = '\0';
		if (*line)
			v[m++] = line;
	}
	err = ss_case_parse(c, o->case_path ? o->case_path : r->case_path, r->case_text, v, m);
	free(v);
	free(copy);
	return err;
}

/* The case and the output: a new run's, or the one being continued. */
static int resolve(struct run *r)
{
	const struct ss_run_options *o = r->o;
	int err;
	if (!o->restart) {
		if ((err = ss_case_load(&r->c, o->case_path, o->overrides.items, o->overrides.count)))
			return err;
		if (o->job.output)
			snprintf(r->output, sizeof r->output, "%s", o->job.output);
		else
			default_output(o->case_path, r->output, sizeof r->output);
		return ss_output_check_folder(r->output, o->job.output == NULL);
	}
	/* the heights later, each rank its rows (start_stepper) */
	if ((err = ss_snapshot_read_restart_case(o->restart, &r->restart)) ||
	    (err = restart_case(o, &r->restart, &r->c)))
		return err;
	if (o->job.output && strcmp(o->job.output, o->restart) != 0)
		return ss_error_input("--restart %s continues that file: drop -o %s", o->restart,
		                      o->job.output);
	snprintf(r->output, sizeof r->output, "%s", o->restart);
	return SS_OK;
}

/* A restart without its case named: the case's files are found beside the
 * path it was started with, which may mean nothing from this folder. */
static int restart_files_reachable(const struct run *r)
{
	const struct ss_case *c = &r->c;
	const char *missing = c->initial_file && access(c->initial_file, R_OK) != 0
	                      ? c->initial_file : NULL;
	if (!missing && c->bedrock_file && access(c->bedrock_file, R_OK) != 0)
		missing = c->bedrock_file;
	for (int k = 0; k < c->region_count && !missing; k++) {
		const char *mask = c->regions[k].shape.mask_path;
		if (mask && access(mask, R_OK) != 0)
			missing = mask;
	}
	if (!missing || r->o->case_path || access(r->restart.case_path, R_OK) == 0)
		return SS_OK;
	return ss_error_input("--restart %s: the run was started with '%s', which is not here, so "
	                      "its file '%s' is not found: name the case to find its files beside "
	                      "it, sandslide run --restart %s PATH/TO/CASE.ini", r->o->restart,
	                      r->restart.case_path, missing, r->o->restart);
}

static enum ss_kernel kernel_of(const struct ss_run_options *o)
{
	return o->reference_kernel ? SS_KERNEL_REFERENCE : SS_KERNEL_FAST;
}

/* The driver's rebuild: the case's stepper at t = 0. */
static int rebuild(void *context, struct ss_stepper *st)
{
	const struct run *r = context;
	return ss_setup_stepper(&r->c, r->o->job.tile[0], r->o->job.tile[1], kernel_of(r->o), st);
}

/* The stepper of the case, where the restart file left it. */
static int start_stepper(struct run *r)
{
	const struct ss_restart_info *rs = &r->restart;
	int err = r->o->restart ? restart_files_reachable(r) : SS_OK;
	if (err || (err = rebuild(r, &r->st)) || !r->o->restart)
		return err;
	const struct ss_grid *g = &r->st.grid;
	if (rs->nx != g->global_nx || rs->ny != g->global_ny)
		return ss_error_input("--restart %s: its snapshots are %d x %d cells, its case "
		                      "gives %lld x %lld", r->o->restart, rs->nx, rs->ny,
		                      g->global_nx, g->global_ny);
	/* this rank's rows of the last snapshot, read now that the slab is known */
	struct ss_restart_info rows;
	if ((err = ss_comm_agree(ss_snapshot_read_last_rows(r->o->restart, g->offset_j, g->ny,
	                                                    &rows))))
		return err;
	if (rows.time != rs->time || rows.count != rs->count)
		err = ss_error_input("--restart %s: the file changed while it was read",
		                     r->o->restart);
	else if (r->st.hysteresis && !rows.moving)
		/* written before /moving was: which cells move is not known */
		err = ss_error_input("--restart %s: its case has hysteresis (a static_angle above "
		                     "its repose_angle), but the file does not say which cells move "
		                     "(no /moving): run it again from the start", r->o->restart);
	else
		ss_stepper_restore(&r->st, rows.time, rows.height, rows.moving, &rows.state);
	ss_restart_info_release(&rows);
	return err;
}

/* The most the sources can add to one cell by time `stop`: each source's
 * rate times its time on, summed, as sources may overlap (m). */
static double source_rise(const struct ss_case *c, double stop)
{
	double rise = 0.0;
	for (int k = 0; k < c->region_count; k++) {
		const struct ss_region *r = &c->regions[k];
		const double on = fmin(r->stop, stop) - r->start;
		if (r->role == SS_REGION_SOURCE && on > 0.0)
			rise += r->rate * on;
	}
	return rise;
}

/* The driver's on_snapshot: o->on_snapshot with what a frame needs. */
static int report_snapshot(void *context, const char *path, long long index, double time)
{
	const struct run *r = context;
	const struct ss_boundary *b = &r->c.boundary;
	const struct ss_run_snapshot s = {
		.path = path, .index = index, .time = time,
		.source_rise = source_rise(&r->c, r->c.steady ? ss_model_time_limit(&r->c.model)
		                                              : r->c.end),
		.open_level = b->open_level,
		.any_open_side = b->side[SS_WEST] == SS_SIDE_OPEN || b->side[SS_EAST] == SS_SIDE_OPEN ||
		                 b->side[SS_SOUTH] == SS_SIDE_OPEN || b->side[SS_NORTH] == SS_SIDE_OPEN,
	};
	return r->o->on_snapshot(r->o->snapshot_context, &s);
}

/* The snapshots a run from t0 to end writes, output_every apart (drive.c's
 * targets: k * output_every clipped to end), with snapshot 0 if first. */
static double snapshots_between(double t0, double end, double output_every, int first)
{
	double n = first ? 1.0 : 0.0;
	if (!(end > t0))
		return n;
	if (isinf(end))
		return isinf(output_every) ? n + 1.0 : INFINITY;
	if (isfinite(output_every)) {
		const double k_min = floor(t0 / output_every) + 1.0;
		const double k_max = ceil(end / output_every) - 1.0;
		if (k_max >= k_min)
			n += k_max - k_min + 1.0;
	}
	return n + 1.0;   /* the one at end */
}

/* x rounded up to two significant digits, for a value a user types. */
static double round_up_2(double x)
{
	const double unit = pow(10.0, floor(log10(x)) - 1.0);
	return ceil(x / unit) * unit;
}

/* The output's projected size into r->plan, refused when a run with a
 * fixed end and no deflate would fill its file system: a long run that
 * fails at the snapshot that does not fit has spent its time for a file
 * that fills the disk.  A steady run's count is only an upper bound, and
 * deflate's ratio is not known before the first snapshot, so those are
 * told, not refused (the check before each snapshot still stops a full
 * disk, h5_write.c).  From the case's grid, before the set-up allocates
 * it: a grid of 10^8 cells takes seconds to set up. */
static int plan_output(struct run *r)
{
	struct ss_grid g;
	int err = ss_grid_init(&g, r->c.nx, r->c.ny, r->c.dx, r->c.dy, 0.0, 0.0);
	if (err)
		return err;
	const int first = r->o->restart == NULL;
	const double t0 = first ? 0.0 : r->restart.time;
	const double end = r->c.steady ? ss_model_time_limit(&r->c.model) : r->c.end;
	struct ss_run_plan p = {
		.output = r->output, .at_most = r->c.steady,
		.snapshots = snapshots_between(t0, end, r->c.output_every, first),
		.snapshot_bytes = ss_snapshot_bytes(&g), .deflate = r->o->deflate,
	};
	p.bytes = p.snapshots * p.snapshot_bytes;
	p.free_bytes = ss_comm_rank() == 0 ? ss_output_free_bytes(r->output) : 0.0;
	ss_comm_broadcast(&p.free_bytes, sizeof p.free_bytes, 0);
	r->plan = p;
	/* a grid too large for memory is the set-up's to refuse, naming its
	 * [grid] line: the more basic complaint */
	const int bedrock = r->c.bedrock_file != NULL;
	const double memory = ss_setup_node_bytes(&g, ss_integrator_resolve(r->c.model.integrator,
	                                                                    bedrock, 0),
	                                          ss_setup_rest_mode(&r->c.model, r->c.steady,
	                                                             bedrock));
	const double available = ss_memory_available_bytes();
	if (available > 0.0 && memory > available)
		return SS_OK;
	if (!r->c.steady && !p.deflate && p.free_bytes >= 0.0 && p.bytes > p.free_bytes) {
		char need[32], each[32], have[32];
		const double fit = floor(p.free_bytes / p.snapshot_bytes);
		const double fixed = snapshots_between(t0, end, INFINITY, first);
		char advice[160];
		if (fit < fixed) {
			snprintf(advice, sizeof advice, "not even the %.0f at the start and end fit: "
			         "use a coarser grid or free some space", fixed);
		} else {
			/* output_every = span / (inner snapshots that fit), rounded up
			 * and checked against the count drive.c will make */
			const double span = end - t0, inner = fit - fixed;
			double every = inner > 0.0 ? round_up_2(span / inner) : round_up_2(end);
			while (snapshots_between(t0, end, every, first) > fit)
				every = round_up_2(every * 1.01);
			snprintf(advice, sizeof advice, "give --set time.output_every=%g or more (%.0f "
			         "snapshots) or a coarser grid", every,
			         snapshots_between(t0, end, every, first));
		}
		return ss_error_input("'%s' would grow by %s (%.0f snapshots of %s), more than the "
		                      "%s free on its file system: %s", r->output,
		                      ss_format_bytes(p.bytes, need), p.snapshots,
		                      ss_format_bytes(p.snapshot_bytes, each),
		                      ss_format_bytes(p.free_bytes, have), advice);
	}
	return SS_OK;
}

/* Claim the output, then continue its series or create it with snapshot 0. */
static int open_output(struct run *r)
{
	const struct ss_run_options *o = r->o;
	struct ss_drive *d = &r->drive;
	char hint[4200];
	d->output_every = r->c.output_every;
	d->end = r->c.steady ? ss_model_time_limit(&r->c.model) : r->c.end;
	d->steady_tol = r->c.steady ? r->c.model.steady_tol : 0.0;
	d->steady_slope_tol = r->c.model.steady_slope_tol;
	d->job = &o->job;
	d->on_snapshot = o->on_snapshot ? report_snapshot : NULL;
	d->snapshot_context = r;
	d->rebuild = rebuild;
	d->rebuild_context = r;
	snprintf(hint, sizeof hint, ", or --restart %s to continue that run", r->output);
	int err = ss_drive_claim(d, r->output, !o->job.output && !o->restart, o->job.force,
	                         o->restart != NULL, hint);
	if (err || o->restart)
		return err ? err : ss_drive_append(d);
	char *overrides = ss_strings_join(o->overrides.items, o->overrides.count, "\n", 1);
	if (!overrides)
		return SS_ERR_FAIL;
	const struct ss_snapshot_meta meta = {
		.title = r->c.path, .history = o->job.history ? o->job.history : "",
		.case_text = r->c.text, .model = &r->c.model,
		.integrator = ss_integrator_name(r->st.integrator),
		.deflate = o->deflate, .bedrock = r->st.bedrock, .case_overrides = overrides,
		.boundary = &r->st.boundary, .moving = r->st.hysteresis,
	};
	err = ss_drive_create(d, &meta);
	free(overrides);
	return err;
}

static void summarise(const struct run *r, enum ss_drive_end end, struct ss_run_summary *s)
{
	const struct ss_stepper *st = &r->st;
	memset(s, 0, sizeof *s);
	snprintf(s->output, sizeof s->output, "%s", r->output);
	s->end = end == SS_DRIVE_INTERRUPTED ? SS_RUN_INTERRUPTED
	       : end == SS_DRIVE_STEADY ? SS_RUN_STEADY
	       : r->c.steady ? SS_RUN_NOT_STEADY : SS_RUN_DONE;
	s->snapshots = ss_drive_snapshots(&r->drive);
	s->time = st->time;
	s->steps = st->steps;
	s->steps_here = st->steps - r->drive.steps_start;
	s->evaluations = st->evaluations;
	s->evaluations_here = st->evaluations - r->drive.evaluations_start;
	s->integrator = ss_integrator_name(st->integrator);
	s->stages_max = st->rkl2_max_stages;
	s->cells = (double)st->grid.global_nx * st->grid.global_ny;
	s->cell_updates_here = (double)s->evaluations_here * s->cells *
	                       ss_stepper_swept_fraction(st);
	s->bytes_per_cell = ss_stepper_bytes(st) / ((double)st->grid.nx * st->grid.ny);
	s->ranks = ss_comm_size();
	s->wall_seconds = ss_parallel_wall_seconds() - r->drive.started;
	ss_stepper_kernel_seconds(st, &s->measure_seconds, &s->sweep_seconds);
	s->output_seconds = r->drive.seconds_output;
	s->comm_seconds = ss_comm_seconds();
	s->memory_peak_bytes = ss_memory_peak_bytes();
	ss_comm_reduce(&s->memory_peak_bytes, 1, NULL, 0);
	s->threads = ss_parallel_max_threads();
	const int notes = (int)(sizeof s->notes / sizeof *s->notes);
	for (int k = 0; k < r->c.note_count && k < notes; k++)
		snprintf(s->notes[s->note_count++], sizeof s->notes[k], "%s", r->c.notes[k]);
}

int ss_run_case(const struct ss_run_options *o, struct ss_run_summary *summary)
{
	if (ss_drive_check_device(&o->job.device, NULL, "run"))
		return SS_ERR_INPUT;
	const double started = ss_parallel_wall_seconds();
	struct run r;
	memset(&r, 0, sizeof r);
	r.o = o;
	ss_drive_init(&r.drive, &r.st, started);
	ss_drive_set_threads(o->job.threads);

	/* a restart reads the file it will write: claimed first, as a live run
	 * may be writing it (a missing file is left to the reading to report) */
	enum ss_drive_end end = SS_DRIVE_END;
	const int exists = o->restart && access(o->restart, F_OK) == 0;
	int err = exists ? ss_output_claim(&r.drive.claim, o->restart) : SS_OK;
	r.drive.claimed = exists && !err;
	if (!err)
		err = resolve(&r);
	if (!err)
		err = plan_output(&r);
	if (!err)
		err = start_stepper(&r);
	/* told once the set-up has checked everything else */
	if (!err && o->on_plan)
		o->on_plan(o->plan_context, &r.plan);
	if (!err)
		err = open_output(&r);
	if (!err)
		err = ss_drive_run(&r.drive, &end);
	if (!err && end == SS_DRIVE_NONFINITE)
		err = ss_drive_nonfinite_error(&r.drive, NULL);
	if (!err)
		summarise(&r, end, summary);
	err = ss_drive_finish(&r.drive, err);
	ss_stepper_release(&r.st);
	ss_restart_info_release(&r.restart);
	ss_case_release(&r.c);
	return err;
}
