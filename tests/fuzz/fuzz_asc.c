/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz_asc.c - the ESRI ASCII grid reader, ss_dem_read on a .asc file
 * (src/io/dem.c, src/io/dem_asc.c).
 *
 * Input: the file.  A grid that is read must hold what dem.h promises
 * (fuzz_dem.h) and come back bit for bit when written and read again.
 */
#include <stdint.h>

#include "fuzz.h"
#include "fuzz_dem.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *path = fuzz_temp_path("dem.asc");
	fuzz_write_file(path, data, size);

	struct ss_raster r;
	fuzz_quiet_begin();
	const int err = ss_dem_read(path, "fuzz.ini:1", NULL, &r);
	fuzz_quiet_end();
	FUZZ_CHECK(err == SS_OK || err == SS_ERR_INPUT || err == SS_ERR_FAIL);
	if (err == SS_OK) {
		fuzz_check_raster(&r, SS_DEM_ASC);
		FUZZ_CHECK(isfinite(r.cellsize) && isfinite(r.x0) && isfinite(r.y0));
		fuzz_round_trip(&r, "back.asc", SS_DEM_ASC, 0.0);
	}
	ss_raster_release(&r);
	return 0;
}
