/*
 * xdmf.c - the XDMF sidecar of an HDF5 output (xdmf.h): a temporal
 * collection of 2DCoRectMesh grids, height from time slice k of /height
 * through a HyperSlab DataItem, cell_type from /cell_type.
 */
#include "io/xdmf.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* name as XML text: a file may be named "a&b.h5".  (A ':' or '|' in the
 * name cannot be written so that XDMF3 reads it: it splits the reference
 * at them.) */
static void put_xml_text(FILE *f, const char *name)
{
	for (const char *c = name; *c; c++) {
		switch (*c) {
		case '&': fputs("&amp;", f); break;
		case '<': fputs("&lt;", f); break;
		case '>': fputs("&gt;", f); break;
		case '"': fputs("&quot;", f); break;
		default: fputc(*c, f); break;
		}
	}
}

static void put_grid(FILE *f, const char *h5_name, int nx, int ny, double origin_x,
                     double origin_y, double dx, double dy, double time, long long k,
                     long long count)
{
	fprintf(f, "   <Grid Name=\"snapshot_%lld\" GridType=\"Uniform\">\n"
	           "    <Time Value=\"%.17g\"/>\n"
	           "    <Topology TopologyType=\"2DCoRectMesh\" Dimensions=\"%d %d\"/>\n"
	           "    <Geometry GeometryType=\"ORIGIN_DXDY\">\n"
	           "     <DataItem Format=\"XML\" Dimensions=\"2\">%.17g %.17g</DataItem>\n"
	           "     <DataItem Format=\"XML\" Dimensions=\"2\">%.17g %.17g</DataItem>\n"
	           "    </Geometry>\n"
	           "    <Attribute Name=\"height\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
	           "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 %d %d\" Type=\"HyperSlab\">\n"
	           "      <DataItem Dimensions=\"3 3\" Format=\"XML\">%lld 0 0 1 1 1 1 %d %d</DataItem>\n"
	           "      <DataItem Format=\"HDF\" NumberType=\"Float\" Precision=\"8\" "
	           "Dimensions=\"%lld %d %d\">",
	        k, time, ny + 1, nx + 1, origin_y, origin_x, dy, dx, ny, nx, k, ny, nx, count, ny,
	        nx);
	put_xml_text(f, h5_name);
	fprintf(f, ":/height</DataItem>\n"
	           "     </DataItem>\n    </Attribute>\n"
	           "    <Attribute Name=\"cell_type\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
	           "     <DataItem Format=\"HDF\" NumberType=\"UChar\" Precision=\"1\" "
	           "Dimensions=\"%d %d\">",
	        ny, nx);
	put_xml_text(f, h5_name);
	fputs(":/cell_type</DataItem>\n    </Attribute>\n   </Grid>\n", f);
}

int ss_xdmf_write(const char *xmf_path, const char *h5_path, int nx, int ny,
                  double origin_x, double origin_y, double dx, double dy,
                  const double *times, long long count)
{
	const char *slash = strrchr(h5_path, '/');
	const char *h5_name = slash ? slash + 1 : h5_path;
	const size_t len = strlen(xmf_path);
	char *tmp = malloc(len + sizeof ".tmp");
	if (!tmp) {
		errno = ENOMEM;
		return -1;
	}
	memcpy(tmp, xmf_path, len);
	memcpy(tmp + len, ".tmp", sizeof ".tmp");

	FILE *f = fopen(tmp, "w");
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

	int bad = ferror(f);
	int e = errno;
	if (fclose(f) != 0 && !bad) {
		bad = 1;
		e = errno;
	}
	if (!bad && rename(tmp, xmf_path) != 0) {
		bad = 1;
		e = errno;
	}
	if (bad) {
		remove(tmp);
		errno = e ? e : EIO;   /* a stream error need not leave errno */
	}
	free(tmp);
	return bad ? -1 : 0;
}
