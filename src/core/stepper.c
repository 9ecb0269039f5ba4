/*
 * stepper.c - adaptive forward-Euler substeps, events and accounting (see
 * stepper.h for the rules).
 */
#include "sandslide/stepper.h"

#include <math.h>
#include <string.h>

#include "sandslide/error.h"
#include "sandslide/parallel.h"

double ss_stepper_memory_bytes(const struct ss_grid *g)
{
	/* height and source_rate (doubles) and the packed types; the fast
	 * sweep's ring rows and buffers are below 2 % of that */
	return (double)ss_grid_storage_cells(g) * (2.0 * sizeof(double) + 0.25);
}

int ss_stepper_init(struct ss_stepper *st, const struct ss_grid *g,
                    const struct ss_closure *c, const struct ss_boundary *b,
                    double cfl, int tile_nx, int tile_ny)
{
	memset(st, 0, sizeof *st);
	if (!(cfl > 0.0 && cfl <= 1.0))
		return ss_error_input("cfl %g is outside (0, 1]", cfl);
	int err = ss_boundary_check(b);
	if (err)
		return err;

	st->grid = *g;
	st->closure = *c;
	st->boundary = *b;
	st->cfl = cfl;
	ss_cfl_bound_init(&st->cfl_bound, c);
	ss_face_rule_init(&st->face_rule, c);
	ss_tiling_init(&st->tiling, g, tile_nx, tile_ny);

	const size_t n = ss_grid_storage_cells(g);
	st->height = ss_alloc(n, sizeof(double), "heights");
	st->cell_types = ss_alloc(ss_cell_types_bytes(n), 1, "cell types");
	st->row_scratch = ss_alloc((size_t)g->ny, sizeof(double), "row sums");
	if (!st->height || !st->cell_types || !st->row_scratch) {
		ss_stepper_release(st);
		return SS_ERR_FAIL;
	}
	return SS_OK;
}

void ss_stepper_release(struct ss_stepper *st)
{
	for (int k = 0; k < st->source_count; k++)
		ss_free(st->sources[k].cells);
	ss_free(st->sources);
	ss_free(st->open_faces);
	ss_free(st->open_flux);
	ss_sweep_fast_release(&st->fast);
	ss_free(st->bedrock);
	ss_free(st->source_rate);
	ss_free(st->row_scratch);
	ss_free(st->flux_y);
	ss_free(st->flux_x);
	ss_free(st->cell_type_bytes);
	ss_free(st->cell_types);
	ss_free(st->height);
	memset(st, 0, sizeof *st);
}

int ss_stepper_add_source(struct ss_stepper *st, const uint8_t *mask,
                          double rate, double start, double stop)
{
	const struct ss_grid *g = &st->grid;
	if (st->source_count >= SS_MAX_SOURCES)
		return ss_error_input("at most %d sources are supported", SS_MAX_SOURCES);
	if (!st->sources) {
		st->sources = ss_alloc(SS_MAX_SOURCES, sizeof *st->sources, "sources");
		if (!st->sources)
			return SS_ERR_FAIL;
	}
	size_t count = 0;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			count += mask[(size_t)j * g->nx + i] &&
			         ss_cell_type_get(st->cell_types, ss_grid_index(g, i, j)) ==
			         SS_CELL_FLOW;
	struct ss_source *s = &st->sources[st->source_count];
	s->cells = ss_alloc(count ? count : 1, sizeof *s->cells, "source cells");
	if (!s->cells)
		return SS_ERR_FAIL;
	size_t n = 0;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (mask[(size_t)j * g->nx + i] &&
			    ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				s->cells[n++] = k;
		}
	}
	s->cell_count = n;
	s->rate = rate;
	s->start = start;
	s->stop = stop;
	st->source_count++;
	return SS_OK;
}

int ss_stepper_set_bedrock(struct ss_stepper *st, const double *bedrock)
{
	const struct ss_grid *g = &st->grid;
	if (!st->bedrock) {
		st->bedrock = ss_alloc(ss_grid_storage_cells(g), sizeof(double), "bedrock");
		if (!st->bedrock)
			return SS_ERR_FAIL;
	}
	for (size_t k = 0; k < ss_grid_storage_cells(g); k++)
		st->bedrock[k] = -INFINITY;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const double b = bedrock[(size_t)j * g->nx + i];
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (!isfinite(b))
				return ss_error_input("bedrock of cell (%d, %d) at x = %g m, y = %g m "
				                      "is %g: it must be finite", i, j,
				                      ss_grid_x(g, i), ss_grid_y(g, j), b);
			if (ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				st->bedrock[k] = b;
		}
	}
	return SS_OK;
}

/* Bedrock ghosts: a periodic side copies the cell it wraps to; elsewhere no
 * sand lies outside the grid (-infinity: no limit). */
static void fill_bedrock_halo(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const struct ss_boundary *b = &st->boundary;
	double *r = st->bedrock;
	const int nx = g->nx, ny = g->ny;
	const int px = b->side[SS_WEST] == SS_SIDE_PERIODIC;
	const int py = b->side[SS_SOUTH] == SS_SIDE_PERIODIC;
	for (int j = 0; j < ny; j++) {
		r[ss_grid_index(g, -1, j)] = px ? r[ss_grid_index(g, nx - 1, j)] : -INFINITY;
		r[ss_grid_index(g, nx, j)] = px ? r[ss_grid_index(g, 0, j)] : -INFINITY;
	}
	for (int i = -1; i <= nx; i++) {
		r[ss_grid_index(g, i, -1)] = py ? r[ss_grid_index(g, i, ny - 1)] : -INFINITY;
		r[ss_grid_index(g, i, ny)] = py ? r[ss_grid_index(g, i, 0)] : -INFINITY;
	}
}

static int open_faces_build(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const uint8_t *t = st->cell_types;
	const ptrdiff_t stride = g->stride;
	/* two passes: count, then fill (axis, neighbour offset, sign) */
	for (int pass = 0; pass < 2; pass++) {
		size_t n = 0;
		for (int j = 0; j < g->ny; j++) {
			for (int i = 0; i < g->nx; i++) {
				const ptrdiff_t k = ss_grid_index(g, i, j);
				if (ss_cell_type_get(t, k) != SS_CELL_FLOW)
					continue;
				/* west, east, south, north faces of flow cell k */
				const struct ss_open_face f[4] = {
					{k, 0, -1}, {k + 1, 0, +1},
					{k, 1, -1}, {k + stride, 1, +1},
				};
				const ptrdiff_t nb[4] = {k - 1, k + 1, k - stride, k + stride};
				for (int m = 0; m < 4; m++) {
					if (ss_cell_type_get(t, nb[m]) != SS_CELL_OPEN)
						continue;
					if (pass == 1)
						st->open_faces[n] = f[m];
					n++;
				}
			}
		}
		if (pass == 0) {
			st->open_face_count = n;
			st->open_faces = ss_alloc(n ? n : 1, sizeof *st->open_faces,
			                          "open face list");
			if (!st->open_faces)
				return SS_ERR_FAIL;
		}
	}
	return SS_OK;
}

int ss_stepper_prepare(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_types(g, &st->boundary, st->cell_types);
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			const enum ss_cell_type type = ss_cell_type_get(st->cell_types, k);
			if (type == SS_CELL_OPEN)
				st->height[k] = st->boundary.open_level;
			else if (type == SS_CELL_WALL)
				st->height[k] = 0.0;
			else if (st->height[k] == 0.0)
				st->height[k] = 0.0;   /* no -0: h + 0 then keeps every bit */
			if (!isfinite(st->height[k]))
				return ss_error_input("initial height of cell (%d, %d) at x = %g m, "
				                      "y = %g m is %g: heights must be finite",
				                      i, j, ss_grid_x(g, i), ss_grid_y(g, j),
				                      st->height[k]);
			if (st->bedrock && type == SS_CELL_FLOW && st->bedrock[k] > st->height[k])
				return ss_error_input("bedrock of cell (%d, %d) at x = %g m, y = %g m "
				                      "is %.17g m, above the surface %.17g m: the "
				                      "surface must be at or above the bedrock",
				                      i, j, ss_grid_x(g, i), ss_grid_y(g, j),
				                      st->bedrock[k], st->height[k]);
		}
	}
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	if (st->bedrock)
		fill_bedrock_halo(st);
	if (st->source_count > 0) {
		st->source_rate = ss_alloc(ss_grid_storage_cells(g), sizeof(double),
		                           "source rates");
		if (!st->source_rate)
			return SS_ERR_FAIL;
	}
	int err = open_faces_build(st);
	if (err)
		return err;
	if (st->kernel == SS_KERNEL_REFERENCE) {
		/* the reference sweep reads one type byte per cell */
		const size_t n = ss_grid_storage_cells(g);
		st->flux_x = ss_alloc(n, sizeof(double), "x-face fluxes");
		st->flux_y = ss_alloc(n, sizeof(double), "y-face fluxes");
		st->cell_type_bytes = ss_alloc(n, 1, "cell types");
		if (!st->flux_x || !st->flux_y || !st->cell_type_bytes)
			return SS_ERR_FAIL;
		ss_cell_types_unpack(st->cell_types, 0, n, st->cell_type_bytes);
		return SS_OK;
	}
	st->open_flux = ss_alloc(st->open_face_count ? st->open_face_count : 1,
	                         sizeof(double), "open-face fluxes");
	if (!st->open_flux)
		return SS_ERR_FAIL;
	err = ss_sweep_fast_init(&st->fast, g, &st->tiling,
	                         ss_parallel_max_threads(),
	                         st->boundary.side[SS_WEST] == SS_SIDE_PERIODIC,
	                         st->boundary.side[SS_SOUTH] == SS_SIDE_PERIODIC,
	                         st->cell_types, st->open_faces, st->open_face_count);
	if (err)
		return err;
	ss_sweep_fast_wake_all(&st->fast, g, st->height, st->cell_types);
	return SS_OK;
}

void ss_stepper_heights_changed(struct ss_stepper *st)
{
	ss_boundary_fill_heights(&st->grid, &st->boundary, st->height);
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_wake_all(&st->fast, &st->grid, st->height, st->cell_types);
}

double ss_stepper_next_source_event(const struct ss_stepper *st, double t)
{
	double next = INFINITY;
	for (int k = 0; k < st->source_count; k++) {
		const struct ss_source *s = &st->sources[k];
		if (s->start > t && s->start < next)
			next = s->start;
		if (s->stop > t && s->stop < next)
			next = s->stop;
	}
	return next;
}

/* Rebuild the source field when the set of active sources changes; sources
 * are summed in file order, so the field has the same bits every run. */
static void sources_update(struct ss_stepper *st)
{
	uint64_t on = 0;
	for (int k = 0; k < st->source_count; k++) {
		const struct ss_source *s = &st->sources[k];
		if (s->start <= st->time && st->time < s->stop && s->cell_count > 0)
			on |= UINT64_C(1) << k;
	}
	if (on == st->sources_on)
		return;
	st->sources_on = on;
	st->source_rate_max = 0.0;
	st->source_volume_rate = 0.0;
	if (!on) {
		if (st->kernel == SS_KERNEL_FAST)
			ss_sweep_fast_mark_sources(&st->fast, &st->grid, NULL);
		return;
	}
	const size_t n = ss_grid_storage_cells(&st->grid);
	memset(st->source_rate, 0, n * sizeof(double));
	for (int k = 0; k < st->source_count; k++) {
		if (!(on >> k & 1))
			continue;
		const struct ss_source *s = &st->sources[k];
		for (size_t m = 0; m < s->cell_count; m++)
			st->source_rate[s->cells[m]] += s->rate;
	}
	/* the volume rate in storage order, deterministic */
	double rate_max = 0.0, volume_rate = 0.0;
	for (size_t k = 0; k < n; k++) {
		volume_rate += st->source_rate[k];
		rate_max = fmax(rate_max, st->source_rate[k]);
	}
	st->source_rate_max = rate_max;
	st->source_volume_rate = volume_rate * st->grid.dx * st->grid.dy;
	if (st->kernel == SS_KERNEL_FAST)
		ss_sweep_fast_mark_sources(&st->fast, &st->grid, st->source_rate);
}

/* Neumaier's compensated sum: *sum + *carry holds the total of every term
 * to about one rounding, however many substeps are added up. */
static void add_compensated(double *sum, double *carry, double term)
{
	const double t = *sum + term;
	if (fabs(*sum) >= fabs(term))
		*carry += (*sum - t) + term;
	else
		*carry += (term - t) + *sum;
	*sum = t;
}

/* Volume leaving through open faces per second with the current fluxes;
 * summed in list order, so the same bits for any thread count and kernel. */
static double outflow_rate(const struct ss_stepper *st)
{
	double sum_x = 0.0, sum_y = 0.0;
	for (size_t m = 0; m < st->open_face_count; m++) {
		const struct ss_open_face *f = &st->open_faces[m];
		const double flux = st->kernel == SS_KERNEL_FAST ? st->open_flux[m]
		                  : f->axis == 0 ? st->flux_x[f->index] : st->flux_y[f->index];
		if (f->axis == 0)
			sum_x += f->sign * flux;
		else
			sum_y += f->sign * flux;
	}
	return sum_x * st->grid.dy + sum_y * st->grid.dx;
}

enum ss_advance_end ss_stepper_advance(struct ss_stepper *st, double t_target,
                                       const struct ss_advance_options *o)
{
	const struct ss_grid *g = &st->grid;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	const double tiles = (double)st->tiling.tiles_x * st->tiling.tiles_y;
	const double source_rise = st->cfl * st->closure.tan_cr * fmin(g->dx, g->dy);

	long long steps_left = o->max_steps > 0 ? o->max_steps : -1;
	while (st->time < t_target) {
		if (steps_left == 0)
			return SS_ADVANCE_STEPS;
		sources_update(st);
		const double next_switch = ss_stepper_next_source_event(st, st->time);
		/* a state is steady only if no source will switch on later */
		const int may_be_steady = o->steady_tol > 0.0 && isinf(next_switch);
		const double next_event = fmin(next_switch, t_target);

		ss_boundary_fill_heights(g, &st->boundary, st->height);
		double t0 = ss_parallel_wall_seconds();
		const double s_max = st->kernel == SS_KERNEL_FAST
			? ss_sweep_fast_begin(&st->fast, g, st->height, st->cell_types)
			: ss_sweep_fluxes(g, &st->tiling, &st->face_rule, st->height,
			                  st->cell_type_bytes, st->flux_x, st->flux_y);
		st->seconds_measure += ss_parallel_wall_seconds() - t0;
		if (!isfinite(s_max)) {
			st->rate_max = NAN;
			return SS_ADVANCE_NONFINITE;
		}

		const double lambda = st->closure.nu * ss_cfl_bound_lookup(&st->cfl_bound, s_max);
		double dt = lambda > 0.0 ? st->cfl / (2.0 * lambda * inv_d2) : INFINITY;
		if (st->sources_on && source_rise / st->source_rate_max < dt)
			dt = source_rise / st->source_rate_max;

		if (isinf(dt)) {
			/* nothing slides and nothing is poured: the state is
			 * stationary until the next event */
			st->rate_max = 0.0;
			if (may_be_steady)
				return SS_ADVANCE_STEADY;
			st->time = next_event;
			continue;
		}

		const int lands = st->time + dt >= next_event;
		if (lands)
			dt = next_event - st->time;
		else if (st->time + dt == st->time)
			return SS_ADVANCE_STALLED;

		t0 = ss_parallel_wall_seconds();
		if (st->kernel == SS_KERNEL_FAST) {
			st->tile_sweeps += ss_sweep_fast_awake(&st->fast);
			st->rate_max = ss_sweep_fast_step(&st->fast, g, &st->face_rule, dt,
			                                  st->sources_on ? st->source_rate : NULL,
			                                  st->bedrock, st->cell_types, st->height,
			                                  st->open_flux);
		} else {
			st->tile_sweeps += tiles;
			if (st->bedrock)
				ss_sweep_limit(g, &st->tiling, dt, st->height, st->bedrock,
				               st->flux_x, st->flux_y);
			st->rate_max = ss_sweep_update(g, &st->tiling, dt, st->flux_x, st->flux_y,
			                               st->sources_on ? st->source_rate : NULL,
			                               st->cell_type_bytes, st->height);
		}
		st->seconds_sweep += ss_parallel_wall_seconds() - t0;
		st->tile_slots += tiles;
		add_compensated(&st->outflow_sum, &st->outflow_carry, dt * outflow_rate(st));
		add_compensated(&st->inflow_sum, &st->inflow_carry,
		                dt * st->source_volume_rate);
		st->outflow = st->outflow_sum + st->outflow_carry;
		st->inflow = st->inflow_sum + st->inflow_carry;
		st->time = lands ? next_event : st->time + dt;
		st->steps++;
		steps_left--;

		if (o->progress)
			o->progress(o->context, st);
		if (!isfinite(st->rate_max))
			return SS_ADVANCE_NONFINITE;
		if (may_be_steady && st->rate_max < o->steady_tol)
			return SS_ADVANCE_STEADY;
		if (o->stop && *o->stop)
			return SS_ADVANCE_INTERRUPTED;
	}
	return SS_ADVANCE_REACHED;
}

void ss_stepper_diagnostics(struct ss_stepper *st, struct ss_diagnostics *d)
{
	const struct ss_grid *g = &st->grid;
	double *row_volume = st->row_scratch, max_height = -INFINITY;

	/* rows summed in parallel, then the row sums in order: the same bits
	 * for any thread count */
	#pragma omp parallel for schedule(static) reduction(max:max_height)
	for (int j = 0; j < g->ny; j++) {
		double row = 0.0, top = -INFINITY;
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st->cell_types, k) != SS_CELL_FLOW)
				continue;
			const double h = st->height[k];
			row += h;
			top = h > top || h != h ? (h != h ? INFINITY : h) : top;
		}
		row_volume[j] = row;
		if (top > max_height)
			max_height = top;
	}
	double volume = 0.0;
	for (int j = 0; j < g->ny; j++)
		volume += row_volume[j];

	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double s_max = ss_sweep_max_slope(g, st->height, st->cell_types);
	d->volume = volume * g->dx * g->dy;
	d->inflow = st->inflow;
	d->outflow = st->outflow;
	d->max_height = max_height;
	d->max_slope_deg = atan(s_max) * (180.0 / M_PI);
	d->steps = (double)st->steps;
	d->active_fraction = st->tile_slots > 0.0 ? st->tile_sweeps / st->tile_slots : 0.0;
	st->tile_sweeps = st->tile_slots = 0.0;
}

void ss_stepper_restart_state(const struct ss_stepper *st, struct ss_restart_state *s)
{
	s->steps = st->steps;
	s->inflow_sum = st->inflow_sum;
	s->inflow_carry = st->inflow_carry;
	s->outflow_sum = st->outflow_sum;
	s->outflow_carry = st->outflow_carry;
}

void ss_stepper_restore(struct ss_stepper *st, double t, const double *height,
                        const struct ss_restart_state *s)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++)
		memcpy(st->height + ss_grid_index(g, 0, j), height + (size_t)j * g->nx,
		       (size_t)g->nx * sizeof(double));
	st->time = t;
	st->steps = s->steps;
	st->inflow_sum = s->inflow_sum;
	st->inflow_carry = s->inflow_carry;
	st->outflow_sum = s->outflow_sum;
	st->outflow_carry = s->outflow_carry;
	/* the totals as ss_stepper_advance forms them after every substep */
	st->inflow = st->inflow_sum + st->inflow_carry;
	st->outflow = st->outflow_sum + st->outflow_carry;
	ss_stepper_heights_changed(st);
}

int ss_stepper_first_nonfinite(const struct ss_stepper *st, int *i, int *j)
{
	const struct ss_grid *g = &st->grid;
	for (*j = 0; *j < g->ny; ++*j)
		for (*i = 0; *i < g->nx; ++*i)
			if (!isfinite(st->height[ss_grid_index(g, *i, *j)]))
				return 1;
	return 0;
}
