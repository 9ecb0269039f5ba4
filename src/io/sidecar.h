/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sidecar.h - the files beside an HDF5 output that other tools read.  Not
 * installed.
 *
 * GDAL's OUT.h5.aux.xml: `gdalinfo OUT.h5` picks GDAL's HDF5 driver (its
 * netCDF driver takes HDF5 files only named .nc, .nc4, .cdf), which reads
 * no dimension scales and so finds no georeferencing; the sidecar gives
 * each grid variable the geotransform, the CRS and NaN as no data.
 *
 * The XDMF sidecar OUT.xmf: a temporal
 * collection of one uniform grid per snapshot, so that ParaView opens the
 * series with its default reader (XDMF3, "Xdmf3ReaderS").  The layout it
 * describes is doc/output.md#variables: height (time, y, x) float64, cell_type (y, x)
 * 8-bit, cell-centred, row 0 the south row.
 */
#ifndef SANDSLIDE_IO_SIDECAR_H
#define SANDSLIDE_IO_SIDECAR_H

/*
 * Write h5_path.aux.xml: for the subdatasets //height, //cell_type (and
 * //bedrock when has_bedrock) the geotransform x = origin_x + column dx,
 * y = origin_y + row dy (row 0 is the south row, so the pixel height is
 * positive: GDAL, gdalwarp and QGIS place the picture right), crs_wkt
 * (or none when NULL) and NaN as no data for the heights.  Atomic as
 * ss_xdmf_write; 0, or -1 with errno set.
 */
int ss_gdal_sidecar_write(const char *h5_path, double origin_x, double origin_y, double dx,
                          double dy, const char *crs_wkt, int has_bedrock);

/*
 * Write the sidecar xmf_path for the snapshots at times[0 .. count - 1] of
 * the HDF5 file h5_path on a grid of nx x ny cells of dx x dy m whose
 * south-west corner is (origin_x, origin_y) m.  The sidecar names the HDF5
 * file by its name alone (without folders): the two sit side by side.
 *
 * The whole file is written to "xmf_path.tmp" and renamed over xmf_path,
 * so a reader never sees half a sidecar.  Returns 0, or -1 with errno set
 * (the temporary file is removed then).  Prints nothing.
 */
int ss_xdmf_write(const char *xmf_path, const char *h5_path, int nx, int ny,
                  double origin_x, double origin_y, double dx, double dy,
                  const double *times, long long count);

#endif
