/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax_inputs.c - the DEM, bedrock and angles relax reads, and the stepper it sets
 * up from them (see relax_inputs.h).
 */
#include "app/relax_inputs.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model/setup.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

/* A copy of a caller's raster (values, nodata and geometry: the writers'
 * metadata is not needed in memory) into r, whole (one rank). */
static int raster_copy(const struct ss_raster *from, struct ss_raster *r)
{
	const size_t cells = (size_t)from->nx * (size_t)from->ny;
	if (ss_comm_size() > 1 || from->rows != from->ny)
		return ss_error_input("relax of a raster in memory runs on one rank, of a whole "
		                      "raster: give the file to each rank");
	int err = ss_raster_init(r, from->nx, from->ny);
	if (!err && from->nodata && !(r->nodata = ss_alloc(cells, 1, "nodata flags")))
		err = SS_ERR_FAIL;
	if (err)
		return err;
	memcpy(r->values, from->values, cells * sizeof *r->values);
	if (from->nodata)
		memcpy(r->nodata, from->nodata, cells);
	r->cellsize = from->cellsize;
	r->cellsize_y = from->cellsize_y;
	r->x0 = from->x0;
	r->y0 = from->y0;
	return SS_OK;
}

/* What the options need together (the table checks each alone). */
static int check_options(const struct ss_relax_options *o)
{
	const int pour = o->sand_shape.kind != SS_SHAPE_NONE;
	if (!o->dem)
		return ss_error_input("relax needs a DEM");
	if (pour != !isnan(o->sand_rate) || pour != !isnan(o->sand_duration))
		return ss_error_input("--add-sand, --sand-rate and --sand-duration go together");
	if (!isnan(o->read.zoffset) && isnan(o->read.zscale))
		return ss_error_input("--zoffset needs --zscale");
	return SS_OK;
}

/* Flags for r's rows when another rank's rows have some: the snapshot's
 * nodata (snapshot.h) is given by every rank or by none. */
static int agree_nodata(struct ss_raster *r)
{
	double any = r->nodata ? 1.0 : 0.0;
	ss_comm_reduce(&any, 1, NULL, 0);
	if (any == 0.0 || r->nodata)
		return SS_OK;
	const size_t cells = (size_t)r->nx * (size_t)r->rows;
	if (!(r->nodata = ss_alloc(cells ? cells : 1, 1, "nodata flags")))
		return SS_ERR_FAIL;
	memset(r->nodata, 0, cells ? cells : 1);
	return SS_OK;
}

/* The memory the DEM's size asks for, from its header (or the caller's
 * raster), before any raster is read: a raster too large for the machine
 * is refused at once (exit 2), as run and bench refuse a grid, rather than
 * failing to allocate after minutes of reading. */
static int check_memory(const struct ss_relax_options *o)
{
	struct ss_raster header;
	int err = SS_OK;
	int nx, ny;
	if (o->input_raster) {
		nx = o->input_raster->nx;
		ny = o->input_raster->ny;
	} else {
		struct ss_dem_read_options opt = o->read;
		opt.rows = 0;   /* the header alone */
		err = ss_dem_read(o->dem, NULL, &opt, &header);
		nx = header.nx;
		ny = header.ny;
		ss_raster_release(&header);   /* either way (dem.h) */
		if (err)
			return err;
	}
	/* the copy or the read, and the bedrock's */
	return ss_setup_check_raster_memory(o->dem, nx, ny, 1 + (o->bedrock != NULL) +
	                                    (o->model.angle_file || o->model.materials_file),
	                                    &o->model,
	                                    o->bedrock != NULL);
}

static int read_here(const struct ss_relax_options *o, struct ss_relax_inputs *in)
{
	if ((o->input_raster && !o->dem) || (o->bedrock_raster && !o->bedrock))
		SS_BUG("ss_relax_run: an input raster without its name (dem, bedrock)");
	int err = check_options(o);
	if (!err)
		err = check_memory(o);
	if (err)
		return err;
	const int tx = o->job.tile[0], ty = o->job.tile[1];
	err = o->input_raster ? raster_copy(o->input_raster, &in->dem)
	                      : ss_setup_read_window(o->dem, NULL, o->read, tx, ty, &in->dem);
	if (!err && o->model.angle_file && o->model.materials_file)
		err = ss_error_input("--angle %s and --materials %s: give the angles one way",
		                     o->model.angle_file, o->model.materials_file);
	if (!err && !o->model.materials_file != !o->material_table)
		err = ss_error_input("--materials and --material-table go together (only %s %s "
		                     "was given)", o->model.materials_file ? "--materials"
		                     : "--material-table", o->model.materials_file
		                     ? o->model.materials_file : o->material_table);
	if (!err && o->material_table) {
		in->table = ss_alloc(1, sizeof *in->table, "material table");
		err = in->table ? ss_material_table_read(in->table, o->material_table) : SS_ERR_FAIL;
		if (!err)
			err = ss_material_table_check(in->table, o->material_table);
	}
	const char *field = o->model.angle_file ? o->model.angle_file : o->model.materials_file;
	const char *option = o->model.angle_file ? "--angle" : "--materials";
	if (!err && field) {
		/* the values as they are: a DEM's read options (z scale) are its own */
		struct ss_dem_read_options plain;
		ss_dem_read_options_init(&plain);
		err = o->angle_raster && o->model.angle_file
			? raster_copy(o->angle_raster, &in->angles)
			: ss_setup_read_window(field, option, plain, tx, ty, &in->angles);
		if (!err && (in->angles.nx != in->dem.nx || in->angles.ny != in->dem.ny))
			err = ss_error_input("%s %s is %d x %d cells: expected the DEM's %d x %d",
			                     option, field, in->angles.nx, in->angles.ny, in->dem.nx,
			                     in->dem.ny);
		char what[4200];
		snprintf(what, sizeof what, "%s %s", option, field);
		if (!err)
			err = ss_dem_check_aligned(&in->dem, o->dem, &in->angles, what);
	}
	if (err || !o->bedrock)
		return err;
	if ((err = o->bedrock_raster
	           ? raster_copy(o->bedrock_raster, &in->bedrock)
	           : ss_setup_read_window(o->bedrock, "--bedrock", o->read, tx, ty, &in->bedrock)))
		return err;
	if (in->bedrock.nx != in->dem.nx || in->bedrock.ny != in->dem.ny)
		return ss_error_input("--bedrock %s is %d x %d cells: expected the DEM's %d x %d",
		                      o->bedrock, in->bedrock.nx, in->bedrock.ny, in->dem.nx,
		                      in->dem.ny);
	char what[4200];
	snprintf(what, sizeof what, "--bedrock %s", o->bedrock);
	return ss_dem_check_aligned(&in->dem, o->dem, &in->bedrock, what);
}

int ss_relax_inputs_read(const struct ss_relax_options *o, struct ss_relax_inputs *in)
{
	memset(in, 0, sizeof *in);
	int err = ss_comm_agree(read_here(o, in));
	if (!err)
		err = ss_comm_agree(agree_nodata(&in->dem));
	return err;
}

void ss_relax_inputs_release(struct ss_relax_inputs *in)
{
	ss_raster_release(&in->angles);
	ss_free(in->table);
	ss_raster_release(&in->bedrock);
	ss_raster_release(&in->dem);
}

int ss_relax_setup_stepper(const struct ss_relax_options *o, const struct ss_relax_inputs *in,
                           int steady, struct ss_stepper *st, struct ss_pour_cover *cover)
{
	char what[4200];
	snprintf(what, sizeof what, "%s %s", o->model.angle_file ? "--angle" : "--materials",
	         o->model.angle_file ? o->model.angle_file
	         : o->model.materials_file ? o->model.materials_file : "");
	const struct ss_raster_setup s = {
		.model = &o->model, .name = o->dem, .heights = &in->dem, .dx = o->read.cellsize,
		.sides = o->sides, .nodata_type = o->nodata_type, .open_level = o->open_level,
		.bedrock = o->bedrock ? &in->bedrock : NULL, .steady = steady,
		.angles = o->model.angle_file || o->model.materials_file ? &in->angles : NULL,
		.classes = in->table, .angles_what = what,
		.tile_nx = o->job.tile[0], .tile_ny = o->job.tile[1],
		.pour = o->sand_shape.kind != SS_SHAPE_NONE ? &o->sand_shape : NULL,
		.pour_rate = o->sand_rate, .pour_duration = o->sand_duration,
		.pour_cover = cover,
	};
	return ss_setup_stepper_from_raster(&s, st);
}
