/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sidecar.c - the files beside an HDF5 output that other tools read
 * (sidecar.h): GDAL's .aux.xml and the XDMF sidecar.
 *
 * The XDMF is in the form that ParaView's default reader for .xmf, XDMF3
 * (VTK's vtkXdmf3Reader), reads right: checked with ParaView 5.11 by
 * tests/cli/test_paraview.py.  Each snapshot is a uniform grid:
 *
 *   - Topology 3DCoRectMesh of 1 x (ny+1) x (nx+1) points, Geometry
 *     ORIGIN_DXDYDZ "0 y0 x0" / "1 dy dx" (slowest first).  Both XDMF
 *     readers of VTK turn a 2DCoRectMesh into a grid in VTK's y-z plane (x
 *     east along VTK y, y north along VTK z); one layer of points in z
 *     keeps x and y where they belong, the surface at z = 0.
 *   - The geometry's numbers carry NumberType="Float" Precision="8": XDMF's
 *     default is float32, which moved an origin of 1.3 m to 1.2999999523.
 *   - height: time slice k of /height (time, y, x) in XDMF3's own HDF
 *     syntax, "FILE:/height|START:STRIDE:COUNT:DATASPACE".  Not a
 *     DataItem of ItemType="HyperSlab": XDMF3 keeps such an item as a
 *     reference without a number type until it is read, and VTK asks the
 *     type first (vtkXdmf3DataSet::XdmfToVTKArray), so ParaView dropped
 *     the heights ("Skipping unrecognized array type [None]").  The legacy
 *     reader (XDMFReader, xdmf2) does not know this syntax, and it cannot
 *     read the 3-D grid's cell attributes either (it selects 0 layers of
 *     cells in z); no form of the time slice reads in both.
 *   - cell_type: /cell_type as NumberType="Char" (int8, CF flags 0 flow,
 *     1 wall, 2 open).  HDF5 converts as it reads, so files whose
 *     cell_type is uint8 read the same values.
 *
 * Times are written with 17 significant digits: each reads back as the
 * very double of /time.
 */
#include "io/sidecar.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* text as XML text: a file may be named "a&b.h5", a WKT has quotes.  (A
 * ':' or '|' in a file name cannot be written so that XDMF3 reads it: it
 * splits the reference at them.) */
static void put_xml_text(FILE *f, const char *text)
{
	for (const char *c = text; *c; c++) {
		switch (*c) {
		case '&': fputs("&amp;", f); break;
		case '<': fputs("&lt;", f); break;
		case '>': fputs("&gt;", f); break;
		case '"': fputs("&quot;", f); break;
		case '\'': fputs("&apos;", f); break;
		default: fputc(*c, f); break;
		}
	}
}

/* The end of a sidecar written to tmp: closed, renamed to path; 0, or -1
 * with errno set and tmp removed. */
static int finish(FILE *f, const char *tmp, const char *path)
{
	int bad = ferror(f);
	int e = errno;
	if (fclose(f) != 0 && !bad) {
		bad = 1;
		e = errno;
	}
	if (!bad && rename(tmp, path) != 0) {
		bad = 1;
		e = errno;
	}
	if (bad) {
		remove(tmp);
		errno = e ? e : EIO;   /* a stream error need not leave errno */
	}
	return bad ? -1 : 0;
}

/* path with suffix added ("run.h5" ".aux.xml"), malloc'ed; NULL with
 * errno ENOMEM */
static char *with_suffix(const char *path, const char *suffix)
{
	const size_t len = strlen(path), add = strlen(suffix) + 1;
	char *out = malloc(len + add);
	if (!out) {
		errno = ENOMEM;
		return NULL;
	}
	memcpy(out, path, len);
	memcpy(out + len, suffix, add);
	return out;
}

/* ---- GDAL's .aux.xml --------------------------------------------------- */

int ss_gdal_sidecar_write(const char *h5_path, double origin_x, double origin_y, double dx,
                          double dy, const char *crs_wkt, int has_bedrock)
{
	char *path = with_suffix(h5_path, ".aux.xml");
	char *tmp = path ? with_suffix(path, ".tmp") : NULL;
	FILE *f = tmp ? fopen(tmp, "w") : NULL;
	if (!f) {
		free(tmp);
		free(path);
		return -1;
	}
	errno = 0;
	static const char *const names[] = {"height", "cell_type", "bedrock"};
	fputs("<PAMDataset>\n", f);
	for (int v = 0; v < (has_bedrock ? 3 : 2); v++) {
		fprintf(f, "  <Subdataset name=\"//%s\">\n    <PAMDataset>\n", names[v]);
		if (crs_wkt) {
			fputs("      <SRS dataAxisToSRSAxisMapping=\"1,2\">", f);
			put_xml_text(f, crs_wkt);
			fputs("</SRS>\n", f);
		}
		fprintf(f, "      <GeoTransform>%.17g, %.17g, 0, %.17g, 0, %.17g</GeoTransform>\n",
		        origin_x, dx, origin_y, dy);
		if (v != 1)   /* cell_type has no missing value */
			fputs("      <PAMRasterBand band=\"1\"><NoDataValue>nan</NoDataValue>"
			      "</PAMRasterBand>\n", f);
		fputs("    </PAMDataset>\n  </Subdataset>\n", f);
	}
	fputs("</PAMDataset>\n", f);
	const int err = finish(f, tmp, path);
	free(tmp);
	free(path);
	return err;
}

/* ---- XDMF ----------------------------------------------------------------- */

static void put_grid(FILE *f, const char *h5_name, int nx, int ny, double origin_x,
                     double origin_y, double dx, double dy, double time, long long k,
                     long long count)
{
	fprintf(f, "   <Grid Name=\"snapshot_%lld\" GridType=\"Uniform\">\n"
	           "    <Time Value=\"%.17g\"/>\n"
	           "    <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"1 %d %d\"/>\n"
	           "    <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
	           "     <DataItem Format=\"XML\" NumberType=\"Float\" Precision=\"8\" "
	           "Dimensions=\"3\">0 %.17g %.17g</DataItem>\n"
	           "     <DataItem Format=\"XML\" NumberType=\"Float\" Precision=\"8\" "
	           "Dimensions=\"3\">1 %.17g %.17g</DataItem>\n"
	           "    </Geometry>\n"
	           "    <Attribute Name=\"height\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
	           "     <DataItem Format=\"HDF\" NumberType=\"Float\" Precision=\"8\" "
	           "Dimensions=\"1 %d %d\">",
	        k, time, ny + 1, nx + 1, origin_y, origin_x, dy, dx, ny, nx);
	put_xml_text(f, h5_name);
	fprintf(f, ":/height|%lld 0 0:1 1 1:1 %d %d:%lld %d %d</DataItem>\n"
	           "    </Attribute>\n"
	           "    <Attribute Name=\"cell_type\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
	           "     <DataItem Format=\"HDF\" NumberType=\"Char\" Precision=\"1\" "
	           "Dimensions=\"%d %d\">",
	        k, ny, nx, count, ny, nx, ny, nx);
	put_xml_text(f, h5_name);
	fputs(":/cell_type</DataItem>\n    </Attribute>\n   </Grid>\n", f);
}

int ss_xdmf_write(const char *xmf_path, const char *h5_path, int nx, int ny,
                  double origin_x, double origin_y, double dx, double dy,
                  const double *times, long long count)
{
	const char *slash = strrchr(h5_path, '/');
	const char *h5_name = slash ? slash + 1 : h5_path;
	char *tmp = with_suffix(xmf_path, ".tmp");
	FILE *f = tmp ? fopen(tmp, "w") : NULL;
	if (!f) {
		free(tmp);
		return -1;
	}
	errno = 0;   /* what a failed write sets, for ferror below */
	fputs("<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
	      "<Xdmf Version=\"3.0\">\n <Domain>\n"
	      "  <Grid Name=\"sand\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", f);
	for (long long k = 0; k < count; k++)
		put_grid(f, h5_name, nx, ny, origin_x, origin_y, dx, dy, times[k], k, count);
	fputs("  </Grid>\n </Domain>\n</Xdmf>\n", f);
	const int err = finish(f, tmp, xmf_path);
	free(tmp);
	return err;
}
