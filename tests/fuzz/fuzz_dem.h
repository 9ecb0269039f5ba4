/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_dem.h - what the DEM reader harnesses (fuzz_asc.c, fuzz_png.c)
 * check of a raster that ss_dem_read accepted (include/sandslide/dem.h):
 *
 *   - at least one cell, heights finite, 0 in cells without data;
 *   - cell sizes and corners unknown (NAN) or finite, sizes > 0;
 *   - written back in the same format, it reads again with the same size
 *     and nodata cells, heights within tol (0: bit for bit) and the same
 *     cell size.
 */
#ifndef SANDSLIDE_TESTS_FUZZ_DEM_H
#define SANDSLIDE_TESTS_FUZZ_DEM_H

#include <math.h>
#include <string.h>

#include "fuzz.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"

static inline int fuzz_unknown_or_finite(double v)
{
	return isnan(v) || isfinite(v);
}

static inline double fuzz_dy(const struct ss_raster *r)
{
	return isnan(r->cellsize_y) ? r->cellsize : r->cellsize_y;
}

static inline void fuzz_check_raster(const struct ss_raster *r, enum ss_dem_format format)
{
	FUZZ_CHECK(r->nx >= 1 && r->ny >= 1 && r->values);
	FUZZ_CHECK(r->format == format && r->source);
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	for (size_t k = 0; k < n; k++) {
		if (r->nodata && r->nodata[k])
			FUZZ_CHECK(r->nodata[k] == 1 && r->values[k] == 0.0);
		else
			FUZZ_CHECK(isfinite(r->values[k]));
	}
	FUZZ_CHECK(isnan(r->cellsize) || (isfinite(r->cellsize) && r->cellsize > 0.0));
	FUZZ_CHECK(isnan(r->cellsize_y) || (isfinite(r->cellsize_y) && r->cellsize_y > 0.0));
	FUZZ_CHECK(fuzz_unknown_or_finite(r->x0) && fuzz_unknown_or_finite(r->y0));
	/* the far corner too, when the geometry is known */
	FUZZ_CHECK(isnan(r->x0) || isnan(r->cellsize) || isfinite(r->x0 + r->nx * r->cellsize));
	FUZZ_CHECK(isnan(r->y0) || isnan(fuzz_dy(r)) || isfinite(r->y0 + r->ny * fuzz_dy(r)));
	FUZZ_CHECK(fuzz_unknown_or_finite(r->png_zmin) && fuzz_unknown_or_finite(r->png_zmax));
}

static inline int fuzz_flag(const struct ss_raster *r, size_t k)
{
	return r->nodata ? r->nodata[k] : 0;
}

/* Write r to name in the temporary folder, read it back, compare.  The
 * writer may refuse (SS_ERR_*), but what it wrote must read back. */
static inline void fuzz_round_trip(const struct ss_raster *r, const char *name,
                                   enum ss_dem_format format, double tol)
{
	const char *path = fuzz_temp_path(name);
	fuzz_quiet_begin();
	int err = ss_dem_write(path, format, r);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL);
	if (err)
		return;
	struct ss_raster back;
	fuzz_quiet_begin();
	err = ss_dem_read(path, "fuzz round trip", NULL, &back);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK);
	fuzz_check_raster(&back, format);
	FUZZ_CHECK(back.nx == r->nx && back.ny == r->ny);
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	for (size_t k = 0; k < n; k++) {
		FUZZ_CHECK(fuzz_flag(&back, k) == fuzz_flag(r, k));
		if (tol == 0.0)
			FUZZ_CHECK(memcmp(&back.values[k], &r->values[k], sizeof(double)) == 0);
		else
			FUZZ_CHECK(fabs(back.values[k] - r->values[k]) <= tol);
	}
	if (!isnan(r->cellsize))
		FUZZ_CHECK(back.cellsize == r->cellsize && fuzz_dy(&back) == fuzz_dy(r));
	ss_raster_release(&back);
}

#endif
