/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * drive.c - the time loop of `run` and `relax` (see drive.h).
 */
#include "app/drive.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"

void ss_drive_init(struct ss_drive *d, struct ss_stepper *st, double started)
{
	memset(d, 0, sizeof *d);
	d->stepper = st;
	d->output_every = INFINITY;
	d->end = INFINITY;
	d->started = started;
	d->trouble.good_step = -1;
	d->trouble.good_snapshot = -1;
}

int ss_drive_check_device(const struct ss_device *d, const char *what, const char *command)
{
	char name[16], option[32];
	if (!what) {
		snprintf(option, sizeof option, "--device %s", ss_device_format(d, name, sizeof name));
		what = option;
	}
	const int err = ss_device_check(d, what);
	if (err || d->kind == SS_DEVICE_CPU)
		return err;
	/* the GPU's loop is forward Euler on one closure, what bench measures;
	 * the rest of the time loop is not on the device yet (doc/gpu.md) */
	return ss_error_input("%s: %s does not run on a GPU yet, only bench does "
	                      "(doc/gpu.md#what-runs-on-the-gpu)", what, command);
}

void ss_drive_set_threads(int threads)
{
	if (threads > 0)
		ss_parallel_set_threads(threads);
	else
		ss_parallel_use_default_threads(ss_comm_node_ranks());
}

int ss_drive_claim(struct ss_drive *d, const char *output, int make_folder, int force,
                   int appending, const char *hint)
{
	snprintf(d->output, sizeof d->output, "%s", output);
	int err = make_folder ? ss_output_make_folder(output) : SS_OK;
	if (!err && !d->claimed)
		d->claimed = (err = ss_output_claim(&d->claim, output)) == SS_OK;
	if (!err && !appending)
		err = ss_output_check_absent(output, force, hint);
	return err;
}

long long ss_drive_snapshots(const struct ss_drive *d)
{
	return d->snapshot ? ss_snapshot_count(d->snapshot) : 0;
}

/* Returned by keep_state, without a message, for a state with a non-finite
 * height: it is not written. */
enum { STATE_NONFINITE = 1 };

/* The state at a target: checked and, with a series, appended with its
 * diagnostics and restart state. */
static int keep_state(struct ss_drive *d)
{
	struct ss_stepper *st = d->stepper;
	struct ss_diagnostics diag;
	struct ss_restart_state state;
	const double t0 = ss_parallel_wall_seconds();
	ss_stepper_diagnostics(st, &diag);
	diag.wall_seconds = t0 - d->started;
	if (!isfinite(diag.volume) || !isfinite(diag.max_height))
		return STATE_NONFINITE;
	if (!d->snapshot)
		return SS_OK;
	ss_stepper_restart_state(st, &state);
	const int err = ss_snapshot_append(d->snapshot, st->time, st->height, st->cell_types,
	                                   st->hysteresis ? st->material : NULL, &diag, &state);
	d->seconds_output += ss_parallel_wall_seconds() - t0;
	return err;
}

/* Tell on_snapshot that the last snapshot is in the file. */
static int announce(const struct ss_drive *d)
{
	if (!d->snapshot || !d->on_snapshot)
		return SS_OK;
	return d->on_snapshot(d->snapshot_context, d->output, ss_snapshot_count(d->snapshot) - 1,
	                      d->stepper->time);
}

int ss_drive_create(struct ss_drive *d, const struct ss_snapshot_meta *meta)
{
	const struct ss_stepper *st = d->stepper;
	int err = ss_snapshot_create(&d->snapshot, d->output, &st->grid, st->cell_types, meta);
	if (!err)
		err = keep_state(d);
	if (err == STATE_NONFINITE)
		err = ss_error_input("%s: the initial surface has a non-finite height", meta->title);
	return err ? err : announce(d);
}

int ss_drive_append(struct ss_drive *d)
{
	return ss_snapshot_open_append(&d->snapshot, d->output, &d->stepper->grid);
}

/* The first target after t: k * output_every clipped to the end (k counts
 * on from *k, which is left at the target's k). */
static double next_target(const struct ss_drive *d, double t, long long *k)
{
	for (;; ++*k) {
		const double target = fmin((double)*k * d->output_every, d->end);
		if (target > t)
			return target;
	}
}

/* ss_progress from the stepper after each substep. */
static void report_progress(void *context, const struct ss_stepper *st)
{
	const struct ss_drive *d = context;
	const struct ss_progress p = {
		.time = st->time, .time_start = d->time_start, .end = d->end,
		.steady_tol = d->steady_tol, .steps = st->steps,
		.steps_here = st->steps - d->steps_start, .rate_max = st->rate_max,
		.cells = (double)st->grid.global_nx * st->grid.global_ny,
		.wall_seconds = ss_parallel_wall_seconds() - d->started,
	};
	d->job->progress(d->job->progress_context, &p);
}

/* Take the steps of the loop again on st, towards the same targets, until
 * it has taken last_step steps. */
static int replay(const struct ss_drive *d, struct ss_stepper *st, long long last_step)
{
	struct ss_advance_options o = {.steady_tol = d->steady_tol,
	                               .steady_slope_tol = d->steady_slope_tol};
	long long k = 1;
	enum ss_advance_end e = SS_ADVANCE_REACHED;
	while (st->steps < last_step && st->time < d->end &&
	       (e == SS_ADVANCE_REACHED || e == SS_ADVANCE_STEPS)) {
		o.max_steps = last_step - st->steps;
		const double target = next_target(d, st->time, &k);
		o.samples = d->samples && target < d->end;
		e = ss_stepper_advance(st, target, &o);
	}
	if (st->steps != last_step)
		return ss_error_fail("taking the steps since the last snapshot again ended at "
		                     "step %lld, not %lld", st->steps, last_step);
	return SS_OK;
}

/* A fresh stepper in the state the guard restarts from: the last snapshot
 * of the series, or t = 0 without one. */
static int restart_point(struct ss_drive *d, struct ss_stepper *fresh)
{
	int err = d->rebuild(d->rebuild_context, fresh);
	if (err || !d->snapshot)
		return err;
	const int closed = ss_snapshot_destroy(d->snapshot);
	d->snapshot = NULL;
	if (closed)
		return closed;
	struct ss_restart_info r;
	err = ss_comm_agree(ss_snapshot_read_last_rows(d->output, fresh->grid.offset_j,
	                                               fresh->grid.ny, &r));
	if (!err)
		ss_stepper_restore(fresh, r.time, r.height, r.moving, &r.state);   /* this rank's rows */
	ss_restart_info_release(&r);
	if (!err)
		err = ss_snapshot_open_append(&d->snapshot, d->output, &fresh->grid);
	return err;
}

/*
 * The guard (drive.h): a height became non-finite in the substep just
 * taken.  Keeps the state after the step before in d->stepper and, with a
 * series, as its last snapshot.  Errors on the way are printed; what the
 * guard found is left for ss_drive_nonfinite_error.
 */
static void keep_last_good_state(struct ss_drive *d)
{
	struct ss_drive_trouble *t = &d->trouble;
	struct ss_stepper *st = d->stepper, fresh;
	int i, j;
	snprintf(t->cell, sizeof t->cell, "a cell");
	const struct ss_grid *g = &st->grid;
	if (ss_stepper_first_nonfinite(st, &i, &j))   /* global (i, j) */
		snprintf(t->cell, sizeof t->cell, "%s",
		         SS_CELL(i, j, g->origin_x + (i + 0.5) * g->dx,
		                 g->origin_y + (j + 0.5) * g->dy));
	t->step = st->steps;
	t->time = st->time;
	t->snapshots = ss_drive_snapshots(d);
	t->last_time = d->snapshot ? ss_snapshot_last_time(d->snapshot) : NAN;
	memset(&fresh, 0, sizeof fresh);
	int err = restart_point(d, &fresh);
	if (!err && fresh.steps < t->step - 1)
		err = replay(d, &fresh, t->step - 1);
	if (err) {
		ss_stepper_release(&fresh);
		return;
	}
	ss_stepper_release(st);
	*st = fresh;   /* the stepper owns only heap arrays: a move */
	t->good_step = st->steps;
	t->good_time = st->time;
	if (!d->snapshot)
		return;
	const long long before = ss_snapshot_count(d->snapshot);
	const int on = before > 0 && ss_snapshot_last_time(d->snapshot) == st->time;
	if (!on && (err = keep_state(d)) != SS_OK) {
		if (err == STATE_NONFINITE)
			ss_error_fail("step %lld, taken again, was not finite either", st->steps);
		t->good_step = -1;
		return;
	}
	t->good_snapshot = ss_snapshot_count(d->snapshot) - 1;
}

int ss_drive_nonfinite_error(const struct ss_drive *d, const char *kept_in)
{
	const struct ss_drive_trouble *t = &d->trouble;
	char where[4400];
	if (t->good_step >= 0 && t->good_snapshot >= 0)
		snprintf(where, sizeof where, "the last good state, after step %lld at t = %.9g s, "
		         "is snapshot %lld in '%s'", t->good_step, t->good_time, t->good_snapshot,
		         d->output);
	else if (t->good_step >= 0 && kept_in)
		snprintf(where, sizeof where, "the last good state, after step %lld at t = %.9g s, "
		         "is in '%s'", t->good_step, t->good_time, kept_in);
	else if (t->snapshots > 0)
		snprintf(where, sizeof where, "the %lld snapshots before it, the last at t = %g s, "
		         "are in '%s'", t->snapshots, t->last_time, d->output);
	else
		snprintf(where, sizeof where, "nothing was written to '%s'", d->output);
	return ss_error_fail("the height of %s became non-finite in step %lld (t = %.9g s); %s",
	                     t->cell, t->step, t->time, where);
}

static int stalled(const struct ss_drive *d)
{
	const struct ss_stepper *st = d->stepper;
	char where[4200] = "";
	if (d->snapshot)
		snprintf(where, sizeof where, "; %lld snapshots are in '%s'",
		         ss_snapshot_count(d->snapshot), d->output);
	return ss_error_fail("the time step fell below the resolution of t = %g s (step %lld): "
	                     "the surface is too steep for this grid%s", st->time, st->steps,
	                     where);
}

int ss_drive_run(struct ss_drive *d, enum ss_drive_end *end)
{
	struct ss_stepper *st = d->stepper;
	struct ss_advance_options adv = {
		.steady_tol = d->steady_tol,
		.steady_slope_tol = d->steady_slope_tol,
		.progress = d->job && d->job->progress ? report_progress : NULL,
		.context = d,
		.stop = d->job ? d->job->stop_signal : NULL,
	};
	d->time_start = st->time;
	d->steps_start = st->steps;
	d->evaluations_start = st->evaluations;
	*end = SS_DRIVE_END;
	for (long long k = 1; st->time < d->end;) {
		/* the end is an event; with samples, the targets before it are
		 * not (drive.h) */
		const double target = next_target(d, st->time, &k);
		adv.samples = d->samples && target < d->end;
		const enum ss_advance_end e = ss_stepper_advance(st, target, &adv);
		if (e == SS_ADVANCE_STALLED)
			return stalled(d);
		/* steady or stopped before the clock moved: that state is the
		 * series' last snapshot already, and a second one at the same
		 * time would make the time axis non-unique (xarray) */
		const int kept = d->snapshot && ss_snapshot_count(d->snapshot) > 0 &&
		                 ss_snapshot_last_time(d->snapshot) == st->time;
		int err = e == SS_ADVANCE_NONFINITE ? STATE_NONFINITE : kept ? SS_OK : keep_state(d);
		if (err == STATE_NONFINITE) {
			keep_last_good_state(d);
			*end = SS_DRIVE_NONFINITE;
			return SS_OK;
		}
		if (err || (!kept && (err = announce(d))))
			return err;
		if (e == SS_ADVANCE_STEADY || e == SS_ADVANCE_INTERRUPTED) {
			*end = e == SS_ADVANCE_STEADY ? SS_DRIVE_STEADY : SS_DRIVE_INTERRUPTED;
			break;
		}
	}
	return SS_OK;
}

int ss_drive_finish(struct ss_drive *d, int err)
{
	if (ss_snapshot_destroy(d->snapshot) && !err)
		err = SS_ERR_FAIL;
	d->snapshot = NULL;
	ss_output_release(d->claim);
	d->claim = NULL;
	d->claimed = 0;
	return err;
}
