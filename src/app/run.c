/*
 * run.c - the `sandslide run` driver: case -> stepper -> snapshots, with a
 * progress line on a terminal (see run.h).
 */
#include "sandslide/run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sandslide/case.h"
#include "sandslide/error.h"
#include "io/output.h"
#include "sandslide/parallel.h"
#include "model/setup.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

/* "cases/door.ini" -> "out/door.h5" */
static void default_output(const char *case_path, char *out, size_t size)
{
	const char *base = strrchr(case_path, '/') ? strrchr(case_path, '/') + 1 : case_path;
	const char *dot = strrchr(base, '.');
	int stem = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
	snprintf(out, size, "out/%.*s.h5", stem, base);
}

/* An existing output is replaced only with --force (checked last, so that
 * a run with bad input says what is wrong with it first). */
static int check_not_existing(const char *path, int force)
{
	struct stat sb;
	if (!force && stat(path, &sb) == 0)
		return ss_error_input("'%s' exists: give --force to replace it, or --restart %s "
		                      "to continue that run", path, path);
	return SS_OK;
}

struct progress {
	int enabled;
	double started, last_print;
	double end;          /* INFINITY when steady */
	double steady_tol;   /* m/s */
	double cells;
	long long nan_step;  /* test hook: > 0 puts a NaN into a cell at this step */
	double *height;      /* the stepper's, for the hook */
	ptrdiff_t nan_cell;
};

static void format_duration(double s, char *buf, size_t size)
{
	if (!isfinite(s) || s < 0)
		snprintf(buf, size, "?");
	else if (s < 60)
		snprintf(buf, size, "%.0fs", s);
	else if (s < 3600)
		snprintf(buf, size, "%dm%02ds", (int)(s / 60), (int)fmod(s, 60));
	else
		snprintf(buf, size, "%dh%02dm", (int)(s / 3600), (int)fmod(s / 60, 60));
}

static void progress_print(void *context, const struct ss_stepper *st)
{
	struct progress *p = context;
	if (st->steps == p->nan_step)
		p->height[p->nan_cell] = NAN;   /* SANDSLIDE_TEST_NAN_STEP, see below */
	if (!p->enabled)
		return;
	const double now = ss_parallel_wall_seconds();
	if (now - p->last_print < 0.5)
		return;
	p->last_print = now;
	const double elapsed = now - p->started;
	const double rate = (double)st->steps * p->cells / fmax(elapsed, 1e-9);
	char tail[64];
	if (isfinite(p->end)) {
		char d[24];
		format_duration(st->time > 0.0 ? elapsed * (p->end - st->time) / st->time : NAN,
		                d, sizeof d);
		snprintf(tail, sizeof tail, "/ %.6g s  ETA %s", p->end, d);
	} else {
		snprintf(tail, sizeof tail, "s (steady below %.1e m/s)", p->steady_tol);
	}
	fprintf(stderr, "\r  t = %.6g %s  steps %lld  %.3g cells/s  max|dh/dt| %.2e m/s   ",
	        st->time, tail, st->steps, rate, st->rate_max);
	fflush(stderr);
}

/* Returned by write_snapshot, without a message, for a state with a
 * non-finite height: it is not written. */
enum { STATE_NONFINITE = 1 };

static int write_snapshot(struct ss_snapshot *snap, struct ss_stepper *st, double started,
                          double *seconds_output)
{
	struct ss_diagnostics d;
	const double t0 = ss_parallel_wall_seconds();
	ss_stepper_diagnostics(st, &d);
	d.wall_seconds = t0 - started;
	if (!isfinite(d.volume) || !isfinite(d.max_height))
		return STATE_NONFINITE;
	const struct ss_restart_state state = {
		.steps = st->steps,
		.inflow_sum = st->inflow_sum, .inflow_carry = st->inflow_carry,
		.outflow_sum = st->outflow_sum, .outflow_carry = st->outflow_carry,
	};
	int err = ss_snapshot_append(snap, st->time, st->height, &d, &state);
	*seconds_output += ss_parallel_wall_seconds() - t0;
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

/* Tell o->on_snapshot (if any) that the last snapshot is in the file. */
static int report_snapshot(const struct ss_run_options *o, const char *output,
                           const struct ss_snapshot *snap, const struct ss_stepper *st,
                           const struct ss_case *c)
{
	if (!o->on_snapshot)
		return SS_OK;
	const struct ss_boundary *b = &c->boundary;
	const struct ss_run_snapshot s = {
		.path = output, .index = ss_snapshot_count(snap) - 1, .time = st->time,
		.source_rise = source_rise(c, c->steady ? c->max_time : c->end),
		.open_level = b->open_level,
		.any_open_side = b->side[SS_WEST] == SS_SIDE_OPEN || b->side[SS_EAST] == SS_SIDE_OPEN ||
		                 b->side[SS_SOUTH] == SS_SIDE_OPEN || b->side[SS_NORTH] == SS_SIDE_OPEN,
	};
	return o->on_snapshot(o->snapshot_context, &s);
}

/* The first cell (in row order) whose height is not finite, as a message
 * fragment "cell (i, j) at x = .. m, y = .. m". */
static void first_nonfinite_cell(const struct ss_stepper *st, char *out, size_t size)
{
	const struct ss_grid *g = &st->grid;
	snprintf(out, size, "a cell");
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			if (!isfinite(st->height[ss_grid_index(g, i, j)])) {
				snprintf(out, size, "cell (%d, %d) at x = %g m, y = %g m", i, j,
				         ss_grid_x(g, i), ss_grid_y(g, j));
				return;
			}
		}
	}
}

/* The --set values as one string, a line each (stored for restarts). */
static char *join_overrides(const char *const *v, int n)
{
	size_t len = 1;
	for (int k = 0; k < n; k++)
		len += strlen(v[k]) + 1;
	char *s = malloc(len);
	if (!s)
		return NULL;
	s[0] = '\0';
	for (int k = 0; k < n; k++) {
		strcat(s, v[k]);
		strcat(s, "\n");
	}
	return s;
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
	if (o->override_count > 0)
		return ss_error_input("--restart %s: --set cannot change a run being continued "
		                      "(it keeps the overrides it was started with)", o->restart);
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
	for (char *line = strtok(copy, "\n"); line && m < n; line = strtok(NULL, "\n"))
		v[m++] = line;
	err = ss_case_parse(c, o->case_path ? o->case_path : r->case_path, r->case_text, v, m);
	free(v);
	free(copy);
	return err;
}

/* Put the stepper where the restart file's last snapshot left it. */
static int restart_stepper(const char *path, const struct ss_restart_info *r,
                           struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	if (r->nx != g->nx || r->ny != g->ny)
		return ss_error_input("--restart %s: its snapshots are %d x %d cells, its case "
		                      "gives %d x %d", path, r->nx, r->ny, g->nx, g->ny);
	for (int j = 0; j < g->ny; j++)
		memcpy(st->height + ss_grid_index(g, 0, j), r->height + (size_t)j * g->nx,
		       (size_t)g->nx * sizeof(double));
	st->time = r->time;
	st->steps = r->state.steps;
	st->inflow_sum = r->state.inflow_sum;
	st->inflow_carry = r->state.inflow_carry;
	st->outflow_sum = r->state.outflow_sum;
	st->outflow_carry = r->state.outflow_carry;
	st->inflow = st->inflow_sum + st->inflow_carry;
	st->outflow = st->outflow_sum + st->outflow_carry;
	ss_stepper_heights_changed(st);
	return SS_OK;
}

/*
 * The last good state of a run whose heights became non-finite in step
 * `bad_step`, appended to its output as a snapshot: the state after step
 * bad_step - 1.  An in-place sweep keeps no earlier copy, and a copy would
 * cost 8 B per cell for a case that should never arise; but a run is
 * deterministic, and its file holds all that a restart needs, so the steps
 * since the last snapshot are taken again, towards the same target time,
 * and the sweep stops one step short.  The caller has closed the file and
 * released its stepper.  *written: 1 if a snapshot was appended, 0 if the
 * last one already was that state.
 */
static int append_last_good_state(const struct ss_run_options *o, const struct ss_case *c,
                                  const char *output, double target, long long bad_step,
                                  double started, double *good_time, int *written)
{
	struct ss_restart_info r;
	struct ss_stepper st;
	struct ss_snapshot *snap = NULL;
	double seconds_output = 0.0;
	memset(&r, 0, sizeof r);
	memset(&st, 0, sizeof st);
	*written = 0;
	int err = ss_snapshot_read_restart(output, &r);
	if (!err)
		err = ss_setup_stepper(c, o->tile_nx, o->tile_ny, o->reference_kernel
		                       ? SS_KERNEL_REFERENCE : SS_KERNEL_FAST, &st);
	if (!err)
		err = restart_stepper(output, &r, &st);
	ss_restart_info_release(&r);
	if (err || st.steps >= bad_step - 1)
		goto out;
	const struct ss_advance_options replay = {
		.steady_tol = c->steady ? c->steady_tol : 0.0,
		.max_steps = bad_step - 1 - st.steps,
	};
	const enum ss_advance_end end = ss_stepper_advance(&st, target, &replay);
	if (end != SS_ADVANCE_STEPS || st.steps != bad_step - 1) {
		err = ss_error_fail("taking the steps since the last snapshot again ended at "
		                    "step %lld, not %lld", st.steps, bad_step - 1);
		goto out;
	}
	if ((err = ss_snapshot_open_append(&snap, output, &st.grid)))
		goto out;
	err = write_snapshot(snap, &st, started, &seconds_output);
	if (err == STATE_NONFINITE)
		err = ss_error_fail("step %lld, taken again, was not finite either", st.steps);
	*written = !err;
	*good_time = st.time;
out:
	if (ss_snapshot_destroy(snap) && !err)
		err = SS_ERR_FAIL;
	ss_stepper_release(&st);
	return err;
}

/* The guard of SPEC's explicit scheme: a height became NaN or infinite in the
 * step just taken towards `target` (which the CFL bound should prevent).
 * Closes the file and releases the stepper, appends the last good state and
 * says where the trouble began. */
static int stop_nonfinite(const struct ss_run_options *o, const struct ss_case *c,
                          const char *output, double target, double started,
                          struct ss_snapshot **snap, struct ss_stepper *st)
{
	char cell[160];
	first_nonfinite_cell(st, cell, sizeof cell);
	const long long bad_step = st->steps, count = ss_snapshot_count(*snap);
	const double bad_time = st->time, last_time = ss_snapshot_last_time(*snap);
	ss_stepper_release(st);
	int err = ss_snapshot_destroy(*snap);
	*snap = NULL;
	double good_time = last_time;
	int written = 0;
	if (!err)
		err = append_last_good_state(o, c, output, target, bad_step, started, &good_time,
		                             &written);
	if (err)
		return ss_error_fail("the height of %s became non-finite in step %lld (t = %g s); "
		                     "the %lld snapshots before it, the last at t = %g s, are in "
		                     "'%s'", cell, bad_step, bad_time, count, last_time, output);
	return ss_error_fail("the height of %s became non-finite in step %lld (t = %.9g s); "
	                     "the last good state, after step %lld at t = %.9g s, is snapshot "
	                     "%lld in '%s'", cell, bad_step, bad_time, bad_step - 1, good_time,
	                     count - 1 + written, output);
}

int ss_run_case(const struct ss_run_options *o)
{
	const double started = ss_parallel_wall_seconds();
	struct ss_case c;
	struct ss_stepper st;
	struct ss_snapshot *snap = NULL;
	struct ss_restart_info restart;
	char output[4096];
	double seconds_output = 0.0;
	char *overrides_text = NULL;

	memset(&restart, 0, sizeof restart);
	memset(&st, 0, sizeof st);
	ss_parallel_set_threads(o->threads > 0 ? o->threads : ss_parallel_processors());
	int err;
	if (o->restart) {
		memset(&c, 0, sizeof c);
		if ((err = ss_snapshot_read_restart(o->restart, &restart)) ||
		    (err = restart_case(o, &restart, &c)))
			goto out_case;
		if (o->output && strcmp(o->output, o->restart) != 0) {
			err = ss_error_input("--restart %s continues that file: drop -o %s", o->restart,
			                     o->output);
			goto out_case;
		}
		snprintf(output, sizeof output, "%s", o->restart);
	} else {
		if ((err = ss_case_load(&c, o->case_path, o->overrides, o->override_count)))
			goto out_case;
		if (o->output)
			snprintf(output, sizeof output, "%s", o->output);
		else
			default_output(o->case_path, output, sizeof output);
		if ((err = ss_output_check_folder(output, o->output == NULL)))
			goto out_case;
	}
	if ((err = ss_setup_stepper(&c, o->tile_nx, o->tile_ny,
	                            o->reference_kernel ? SS_KERNEL_REFERENCE : SS_KERNEL_FAST, &st))) {
		/* the files of a case named by a path from another folder */
		if (o->restart && !o->case_path && access(restart.case_path, R_OK) != 0)
			fprintf(stderr, "sandslide: (the run was started with '%s', which is not "
			        "here: name the case to find its files beside it,\n"
			        "    sandslide run --restart %s PATH/TO/CASE.ini)\n",
			        restart.case_path, o->restart);
		goto out_case;
	}
	if (o->restart && (err = restart_stepper(o->restart, &restart, &st)))
		goto out_stepper;
	if (!o->restart && (err = check_not_existing(output, o->force)))
		goto out_stepper;

	/* the run starts: from here on the output file is written */
	if (o->restart) {
		if ((err = ss_snapshot_open_append(&snap, output, &st.grid)))
			goto out_stepper;
	} else {
		if (!o->output && (err = ss_output_make_folder(output)))
			goto out_stepper;
		if (!(overrides_text = join_overrides(o->overrides, o->override_count))) {
			err = ss_error_fail("out of memory");
			goto out_stepper;
		}
		struct ss_snapshot_meta meta = {
			.title = c.path, .history = o->history ? o->history : "",
			.case_text = c.text, .closure = ss_closure_name(c.closure),
			.repose_angle_deg = c.repose_angle_deg, .nu = c.nu, .gamma = c.gamma,
			.deflate = o->deflate, .bedrock = st.bedrock,
			.case_overrides = overrides_text,
		};
		if ((err = ss_snapshot_create(&snap, output, &st.grid, st.cell_types, &meta)))
			goto out_stepper;
		err = write_snapshot(snap, &st, started, &seconds_output);
		if (err == STATE_NONFINITE)
			err = ss_error_input("%s: the initial surface has a non-finite height",
			                     c.path);
		if (err || (err = report_snapshot(o, output, snap, &st, &c)))
			goto out_snapshot;
	}

	/* SANDSLIDE_TEST_NAN_STEP=N (a test hook, not an option): a NaN height
	 * in the middle cell after substep N, to test the guard below */
	const char *hook = getenv("SANDSLIDE_TEST_NAN_STEP");
	struct progress prog = {
		.enabled = !o->quiet && isatty(fileno(stderr)),
		.started = started, .last_print = started,
		.end = c.steady ? c.max_time : c.end,
		.steady_tol = c.steady_tol,
		.cells = (double)st.grid.nx * st.grid.ny,
		.nan_step = hook && *hook ? atoll(hook) : -1,
		.height = st.height,
		.nan_cell = ss_grid_index(&st.grid, st.grid.nx / 2, st.grid.ny / 2),
	};
	struct ss_advance_options adv = {
		.steady_tol = c.steady ? c.steady_tol : 0.0,
		.progress = prog.enabled || prog.nan_step > 0 ? progress_print : NULL,
		.context = &prog,
		.stop = o->stop_signal,
	};
	const double stop = c.steady ? c.max_time : c.end;
	enum ss_advance_end end = SS_ADVANCE_REACHED;
	for (long long k = 1; st.time < stop; k++) {
		double target = fmin((double)k * c.output_every, stop);
		if (target <= st.time)
			continue;
		end = ss_stepper_advance(&st, target, &adv);
		if (end != SS_ADVANCE_NONFINITE && end != SS_ADVANCE_STALLED &&
		    (err = write_snapshot(snap, &st, started, &seconds_output)) == STATE_NONFINITE)
			end = SS_ADVANCE_NONFINITE;
		if (end == SS_ADVANCE_NONFINITE) {
			err = stop_nonfinite(o, &c, output, target, started, &snap, &st);
			goto out_snapshot;
		}
		if (end == SS_ADVANCE_STALLED) {
			err = ss_error_fail("the time step fell below the resolution of t = %g s "
			                    "(step %lld): the surface is too steep for this grid; "
			                    "%lld snapshots are in '%s'", st.time, st.steps,
			                    ss_snapshot_count(snap), output);
			goto out_snapshot;
		}
		if (err || (err = report_snapshot(o, output, snap, &st, &c)))
			goto out_snapshot;
		if (end == SS_ADVANCE_STEADY || end == SS_ADVANCE_INTERRUPTED)
			break;
	}
	if (prog.enabled)
		fputc('\n', stderr);
	if (end == SS_ADVANCE_INTERRUPTED) {
		fflush(stdout);
		fprintf(stderr, "sandslide: interrupted at t = %g s (step %lld): snapshot %lld is "
		        "in '%s'; continue with\n    sandslide run --restart %s\n", st.time,
		        st.steps, ss_snapshot_count(snap) - 1, output, output);
	}

	if (!o->quiet && end != SS_ADVANCE_INTERRUPTED) {
		const double wall = ss_parallel_wall_seconds() - started;
		const double updates = (double)st.steps * st.grid.nx * st.grid.ny;
		printf("wrote %s: %lld snapshots to t = %g s, %lld steps%s\n", output,
		       ss_snapshot_count(snap), st.time, st.steps,
		       end == SS_ADVANCE_STEADY ? " (steady)" :
		       c.steady ? " (not steady by max_time)" : "");
		printf("wall %.3f s: slope %.3f s, sweep %.3f s, output %.3f s; "
		       "%.3g cell-updates/s on %d threads\n", wall, st.seconds_measure,
		       st.seconds_sweep, seconds_output,
		       updates / fmax(st.seconds_measure + st.seconds_sweep, 1e-9),
		       ss_parallel_max_threads());
	}

out_snapshot:
	if (ss_snapshot_destroy(snap) && !err)
		err = SS_ERR_FAIL;
out_stepper:
	ss_stepper_release(&st);
out_case:
	free(overrides_text);
	ss_restart_info_release(&restart);
	ss_case_release(&c);
	return err;
}
