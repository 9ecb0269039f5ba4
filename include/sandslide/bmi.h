/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * bmi.h - sandslide as a component of the CSDMS Basic Model Interface
 * (BMI 2.0, https://bmi.csdms.org), in the C binding's layout.
 *
 * struct Bmi below has exactly the members, in exactly the order and with
 * exactly the signatures of bmi-c's bmi.h (csdms/bmi-c), and BMI_SUCCESS /
 * BMI_FAILURE and the BMI_MAX_* sizes have its values, so a framework
 * compiled against bmi-c's header can drive a struct Bmi that
 * ss_bmi_register filled.  Both headers guard with BMI_H: include either
 * one, or both in any order (the first one wins; they declare the same).
 *
 *     struct Bmi *m = ss_bmi_create();       (or ss_bmi_register(&your_bmi))
 *     m->initialize(m, "case.ini");          the case file of `sandslide run`
 *     m->update_until(m, 10.0);
 *     m->get_value(m, "land_surface__elevation", heights);
 *     m->finalize(m);
 *     ss_bmi_destroy(m);
 *
 * The model:
 *   initialize(config)  config is a case file path (doc/case-file.md), read
 *                       with ss_case_load and set up as `sandslide run` sets
 *                       it up (fast kernel, default tiles, one rank); or a
 *                       BMI config, an INI file whose one section [bmi]
 *                       names a case (case = room.ini) or a DEM (dem =
 *                       terrain.tif, time_step and end in s, and relax's
 *                       options by name: angle = 33), set up as `sandslide
 *                       relax` sets it up, its CRS check included (bmi.c,
 *                       doc/bmi.md).  Any call before initialize, or a
 *                       second initialize before finalize, returns
 *                       BMI_FAILURE.
 *   time                seconds ("s"); start 0; end the case's [time] end,
 *                       or its max_time with end = steady (a DEM: end, else
 *                       max_time, else infinity); the time step is the
 *                       case's output_every (a DEM: time_step).  update advances by one
 *                       step: from a time on a multiple k * output_every to
 *                       (k + 1) * output_every (not clipped at the end: a
 *                       framework may drive the model past it), as `sandslide
 *                       run` advances from snapshot to snapshot, so the
 *                       heights after k updates are the bits run writes at
 *                       k * output_every; from any other time t, to
 *                       t + output_every.  update_until(t) advances to t in
 *                       one call (BMI_FAILURE for t before the current time).
 *                       Neither stops at steady state (a driven model is
 *                       never done), so for a case with end = steady the
 *                       bits are run's only until run would stop.  A stepper
 *                       that stops short (a non-finite height, a vanished
 *                       step) is BMI_FAILURE with the model where it stopped.
 *   get_value_ptr       BMI_FAILURE: the heights live with a halo ring, not
 *                       as one [y][x] array.
 *   grid 0              uniform_rectilinear, rank 2, shape {ny, nx}, spacing
 *                       {dy, dx}, origin {y0 + dy/2, x0 + dx/2}: the centre
 *                       of cell (0, 0), where (x0, y0) is the case's
 *                       lower-left corner ([grid] origin).  Row 0 is the
 *                       south row, as in the HDF5 output, whose /x and /y
 *                       are the same cell centres.  Other grid types'
 *                       functions return BMI_FAILURE.
 *   land_surface__elevation
 *                       m, double, grid 0, location "node", input and
 *                       output: ny * nx values, row-major [y][x], south row
 *                       first.  sandslide's heights are cell averages of a
 *                       finite-volume scheme; BMI's "node" is what a raster
 *                       component offers (a value per grid point of a
 *                       uniform_rectilinear grid, the points being the cell
 *                       centres above), where "face" would mean the 2-D
 *                       elements of an unstructured mesh.  Setting it
 *                       changes the flow cells only (wall and open cells
 *                       keep their heights: the boundary holds them); a
 *                       non-finite value, or one below the bedrock, is
 *                       BMI_FAILURE and nothing changes.  The volume the
 *                       set adds (or removes, < 0) on flow cells is booked
 *                       in the stepper's ledger as external
 *                       (ss_stepper_book_external), the output
 *                       sand__external_volume_change.
 *   land_surface__net_deposition_rate
 *                       m s-1, double, grid 0, location "node", input (and
 *                       readable with get_value): a source added to dh/dt
 *                       of every flow cell from the next update on, until
 *                       set again (0 until set), with the case's own
 *                       sources (ss_stepper_set_rate_field: the same bits
 *                       as a case source of that rate on those cells).  Its
 *                       volume is inflow.  Negative is erosion, refused in
 *                       a case with a bedrock (nothing stops erosion at the
 *                       rock); a non-finite rate is refused.  Values on
 *                       wall and open cells are kept but do nothing.
 *   bedrock_surface__elevation
 *                       m, double, grid 0, output, only in a case with a
 *                       bedrock ([initial] bedrock): NaN on wall and open
 *                       cells.
 *   read-only diagnostics, output only, double, location "node", each on
 *   grid 1 ("scalar": rank 0, size 1, no shape, spacing or origin), the
 *   values of ss_stepper_diagnostics (diagnostics.h) now:
 *     sand__volume                                m3   sand on flow cells
 *     sand__time_integral_of_source_volume_flux   m3   added by sources and
 *                                                      the deposition rate
 *     sand__time_integral_of_outflow_volume_flux  m3   left by open sides
 *     sand__external_volume_change                m3   set_value's changes
 *     sand_surface__max_of_slope_angle            deg  steepest sand face
 *   so that volume = initial volume + source - outflow + external, to
 *   rounding.  (Names in the CSDMS Standard Names' object__quantity
 *   pattern, chosen here; the outputs are listed in this order: the
 *   elevation, the bedrock when there is one, then these.)
 *
 * A call with an unknown name, a wrong grid or index, or (for the
 * *_at_indices calls) a count out of range returns BMI_FAILURE and
 * changes nothing.  Why goes through error.h, the library's one error
 * printer (ss_error_set_quiet, ss_error_last_message).
 */
#ifndef SANDSLIDE_BMI_H
#define SANDSLIDE_BMI_H

#ifndef BMI_H
#define BMI_H

#if defined(__cplusplus)
extern "C" {
#endif

/* As bmi-c declares them (its layout, not macros, so that including both
 * headers in either order compiles). */
static const int BMI_SUCCESS = 0;
static const int BMI_FAILURE = 1;

#define BMI_MAX_UNITS_NAME (2048)
#define BMI_MAX_TYPE_NAME (2048)
#define BMI_MAX_COMPONENT_NAME (2048)
#define BMI_MAX_VAR_NAME (2048)

typedef struct Bmi {
	void *data;

	/* Initialize, run, finalize (IRF) */
	int (*initialize)(struct Bmi *self, const char *config_file);
	int (*update)(struct Bmi *self);
	int (*update_until)(struct Bmi *self, double then);
	int (*finalize)(struct Bmi *self);

	/* Exchange items */
	int (*get_component_name)(struct Bmi *self, char *name);
	int (*get_input_item_count)(struct Bmi *self, int *count);
	int (*get_output_item_count)(struct Bmi *self, int *count);
	int (*get_input_var_names)(struct Bmi *self, char **names);
	int (*get_output_var_names)(struct Bmi *self, char **names);

	/* Variable information */
	int (*get_var_grid)(struct Bmi *self, const char *name, int *grid);
	int (*get_var_type)(struct Bmi *self, const char *name, char *type);
	int (*get_var_units)(struct Bmi *self, const char *name, char *units);
	int (*get_var_itemsize)(struct Bmi *self, const char *name, int *size);
	int (*get_var_nbytes)(struct Bmi *self, const char *name, int *nbytes);
	int (*get_var_location)(struct Bmi *self, const char *name, char *location);

	/* Time information */
	int (*get_current_time)(struct Bmi *self, double *time);
	int (*get_start_time)(struct Bmi *self, double *time);
	int (*get_end_time)(struct Bmi *self, double *time);
	int (*get_time_units)(struct Bmi *self, char *units);
	int (*get_time_step)(struct Bmi *self, double *time_step);

	/* Getters */
	int (*get_value)(struct Bmi *self, const char *name, void *dest);
	int (*get_value_ptr)(struct Bmi *self, const char *name, void **dest_ptr);
	int (*get_value_at_indices)(struct Bmi *self, const char *name, void *dest, int *inds,
	                            int count);

	/* Setters */
	int (*set_value)(struct Bmi *self, const char *name, void *src);
	int (*set_value_at_indices)(struct Bmi *self, const char *name, int *inds, int count,
	                            void *src);

	/* Grid information */
	int (*get_grid_rank)(struct Bmi *self, int grid, int *rank);
	int (*get_grid_size)(struct Bmi *self, int grid, int *size);
	int (*get_grid_type)(struct Bmi *self, int grid, char *type);

	/* Uniform rectilinear */
	int (*get_grid_shape)(struct Bmi *self, int grid, int *shape);
	int (*get_grid_spacing)(struct Bmi *self, int grid, double *spacing);
	int (*get_grid_origin)(struct Bmi *self, int grid, double *origin);

	/* Non-uniform rectilinear, curvilinear */
	int (*get_grid_x)(struct Bmi *self, int grid, double *x);
	int (*get_grid_y)(struct Bmi *self, int grid, double *y);
	int (*get_grid_z)(struct Bmi *self, int grid, double *z);

	/* Unstructured */
	int (*get_grid_node_count)(struct Bmi *self, int grid, int *count);
	int (*get_grid_edge_count)(struct Bmi *self, int grid, int *count);
	int (*get_grid_face_count)(struct Bmi *self, int grid, int *count);
	int (*get_grid_edge_nodes)(struct Bmi *self, int grid, int *edge_nodes);
	int (*get_grid_face_edges)(struct Bmi *self, int grid, int *face_edges);
	int (*get_grid_face_nodes)(struct Bmi *self, int grid, int *face_nodes);
	int (*get_grid_nodes_per_face)(struct Bmi *self, int grid, int *nodes_per_face);
} Bmi;

#if defined(__cplusplus)
}
#endif

#endif /* BMI_H */

#if defined(__cplusplus)
extern "C" {
#endif

/* Fill every function pointer of *model with sandslide's and set its data
 * to NULL (the state initialize allocates).  Returns model. */
struct Bmi *ss_bmi_register(struct Bmi *model);

/* A struct Bmi on the heap, registered; NULL (error.h says why) when the
 * allocation fails.  Release with ss_bmi_destroy, which finalizes first if
 * initialize was called without finalize. */
struct Bmi *ss_bmi_create(void);
void ss_bmi_destroy(struct Bmi *model);

#if defined(__cplusplus)
}
#endif

#endif
