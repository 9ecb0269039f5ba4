/*
 * xdmf.h - the XDMF sidecar OUT.xmf of an HDF5 output: a temporal
 * collection of one uniform grid per snapshot, so that ParaView opens the
 * series with its default reader (XDMF3, "Xdmf3ReaderS").  The layout it
 * describes is SPEC section 5: height (time, y, x) float64, cell_type (y, x)
 * 8-bit, cell-centred, row 0 the south row.  Not installed.
 */
#ifndef SANDSLIDE_IO_XDMF_H
#define SANDSLIDE_IO_XDMF_H

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
