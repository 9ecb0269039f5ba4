/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_png.c - the 16-bit PNG heightmap reader, ss_dem_read on a .png
 * file (src/io/dem.c, src/io/dem_png.c).
 *
 * Input: the file, its chunk CRCs made right, read twice: with the range
 * of its text chunks (zmin_m, zmax_m), and with a scale, offset and cell
 * size given as `relax --zscale 0.25 --zoffset -1 --cellsize 2` would.  A heightmap that is read
 * must hold what dem.h promises (fuzz_dem.h) and come back within half a
 * grey level when written and read again.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "fuzz_dem.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"

static void read_png(const char *path, const struct ss_dem_read_options *opt)
{
	struct ss_raster r;
	fuzz_quiet_begin();
	const int err = ss_dem_read(path, "fuzz.ini:1", opt, &r);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL);
	if (err == SS_OK) {
		fuzz_check_raster(&r, SS_DEM_PNG);
		/* the written range is the data's or the stored one: half a grey
		 * level of it, and the rounding of heights near 1e308 */
		double lo = INFINITY, hi = -INFINITY;
		const size_t n = (size_t)r.nx * (size_t)r.ny;
		for (size_t k = 0; k < n; k++) {
			if (!fuzz_flag(&r, k)) {
				lo = fmin(lo, r.values[k]);
				hi = fmax(hi, r.values[k]);
			}
		}
		if (isfinite(r.png_zmin) && isfinite(r.png_zmax)) {
			lo = fmin(lo, r.png_zmin);
			hi = fmax(hi, r.png_zmax);
		}
		const double tol = lo <= hi ? 0.5 * (hi - lo) / 65534.0 * (1 + 1e-9) +
		                              4e-16 * fmax(fabs(lo), fabs(hi)) : 0.0;
		if (isfinite(tol))
			fuzz_round_trip(&r, "back.png", SS_DEM_PNG, tol);
	}
	ss_raster_release(&r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_temp_path("dem.png");
	uint8_t *png = malloc(size ? size : 1);
	FUZZ_CHECK(png);
	memcpy(png, data, size);
	fuzz_png_fix_crcs(png, size);
	fuzz_write_file(path, png, size);
	free(png);

	struct ss_dem_read_options opt;
	ss_dem_read_options_init(&opt);
	read_png(path, &opt);
	opt.zscale = 0.25;
	opt.zoffset = -1.0;
	opt.cellsize = 2.0;
	read_png(path, &opt);
	return 0;
}
