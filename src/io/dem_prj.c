/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem_prj.c - the CRS of an ESRI ASCII grid: the ".prj" file beside it
 * (see dem.h).
 *
 * An .asc holds no CRS; GDAL's AAIGrid driver, ArcGIS and QGIS keep it in
 * X.prj beside X.asc (the same name, the extension replaced), in ESRI's
 * dialect of WKT (GDAL: morphToESRI on writing, importFromESRI on
 * reading).  We do as GDAL does, so that `relax dem.asc -o x.tif` carries
 * the CRS that `gdalinfo dem.asc` shows:
 *
 *   reading   X.prj, or X.PRJ when there is no X.prj (GDAL's order); with
 *             GDAL its text is converted to OGC WKT through OSR, as GDAL's
 *             own driver does; without GDAL the WKT is kept as read.  A
 *             .prj that cannot be read or is not a CRS is refused, naming
 *             it (GDAL ignores it silently; a CRS lost without a word
 *             would surface only as a GeoTIFF in the wrong place).  A
 *             geographic CRS is refused as it is for a GDAL raster: the
 *             cells would be degrees, not metres.
 *   writing   X.prj in ESRI WKT (with GDAL: morphToESRI; without, the text
 *             as held), written to a temporary file before the grid takes
 *             its name and renamed after it.  A grid without a CRS removes
 *             an X.prj (and X.PRJ) left beside it by an earlier file, which
 *             would otherwise claim a CRS for it (GDAL leaves it).
 */
#include "io/dem_internal.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#ifdef SS_HAVE_GDAL
#include <cpl_conv.h>
#include <cpl_error.h>
#include <ogr_srs_api.h>
#endif

#include "sandslide/error.h"

/* A .prj is a few hundred bytes; a file far larger is not one, and is not
 * read into memory whole. */
#define PRJ_MAX_BYTES (1 << 20)

/* path with the extension of its file name (from its last '.') replaced by
 * "." ext, or ext appended when it has none, as GDAL forms a grid's .prj
 * (CPLFormFilename of CPLGetBasename).  -1 when it does not fit. */
static int sibling(const char *path, const char *ext, char *out, size_t size)
{
	const char *slash = strrchr(path, '/');
	const char *name = slash ? slash + 1 : path;
	const char *dot = strrchr(name, '.');
	const int stem = (int)(dot ? (size_t)(dot - path) : strlen(path));
	const int n = snprintf(out, size, "%.*s.%s", stem, path, ext);
	return n < 0 || (size_t)n >= size ? -1 : 0;
}

/* The .prj of the grid at path that exists, into out (X.prj, else X.PRJ):
 * 1 when there is one, 0 when neither exists, -1 when the name does not
 * fit. */
static int find_prj(const char *path, char *out, size_t size)
{
	static const char *const ext[] = {"prj", "PRJ"};
	struct stat sb;
	for (int k = 0; k < 2; k++) {
		if (sibling(path, ext[k], out, size))
			return -1;
		if (stat(out, &sb) == 0)
			return 1;
	}
	return 0;
}

static int same_file(const char *a, const char *b)
{
	struct stat sa, sb;
	return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
	       sa.st_ino == sb.st_ino;
}

/* ------------------------------------------------------------------ */
/* reading                                                              */

/* The whole of prj, NUL-terminated (ss_free it); NULL after a message. */
static char *read_prj_text(const char *prj, const char *grid, const char *context, int *err)
{
	FILE *f = fopen(prj, "rb");
	if (!f) {
		*err = ss_error_input_at(context, "cannot open '%s', the CRS of '%s': %s (remove it "
		                         "to read the grid without a CRS)", prj, grid, strerror(errno));
		return NULL;
	}
	char *text = ss_alloc(PRJ_MAX_BYTES + 1, 1, "a .prj file");
	if (!text) {
		fclose(f);
		*err = SS_ERR_FAIL;
		return NULL;
	}
	const size_t n = fread(text, 1, PRJ_MAX_BYTES + 1, f);
	const int bad = ferror(f), saved = errno;
	fclose(f);
	if (bad || n > PRJ_MAX_BYTES) {
		ss_free(text);
		*err = bad ? ss_error_input_at(context, "cannot read '%s', the CRS of '%s': %s", prj,
		                               grid, strerror(saved))
		           : ss_error_input_at(context, "'%s', the CRS of '%s', is over %d bytes: "
		                               "expected the WKT of a CRS, as GDAL writes it", prj,
		                               grid, PRJ_MAX_BYTES);
		return NULL;
	}
	text[n] = '\0';
	return text;
}

/* s without leading and trailing white space (in place). */
static char *trim(char *s)
{
	while (isspace((unsigned char)*s))
		s++;
	size_t n = strlen(s);
	while (n > 0 && isspace((unsigned char)s[n - 1]))
		s[--n] = '\0';
	return s;
}

#ifdef SS_HAVE_GDAL

/* The text of a .prj (ESRI WKT, or the older "Projection UTM" lines) as
 * OGC WKT into r->crs_wkt, through OSR's importFromESRI as GDAL's AAIGrid
 * driver reads it; a geographic CRS refused. */
static int prj_to_crs(char *text, const char *prj, const char *grid, const char *context,
                      struct ss_raster *r)
{
	/* importFromESRI takes the file's lines */
	size_t lines = 1;
	for (const char *p = text; *p; p++)
		lines += *p == '\n';
	char **v = ss_alloc(lines + 1, sizeof *v, "the lines of a .prj file");
	if (!v)
		return SS_ERR_FAIL;
	size_t k = 0;
	for (char *p = text; p;) {
		v[k++] = p;
		p = strchr(p, '\n');
		if (p)
			*p++ = '\0';
	}
	for (size_t i = 0; i < k; i++)
		v[i][strcspn(v[i], "\r")] = '\0';

	CPLPushErrorHandler(CPLQuietErrorHandler);
	CPLErrorReset();
	OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
	int err = SS_OK;
	char *wkt = NULL;
	if (!srs) {
		err = ss_error_fail("cannot read '%s': out of memory", prj);
	} else if (OSRImportFromESRI(srs, v) != OGRERR_NONE || OSRExportToWkt(srs, &wkt) != OGRERR_NONE ||
	           !wkt || !*wkt) {
		const char *why = CPLGetLastErrorMsg();
		err = ss_error_input_at(context, "'%s', the CRS of '%s', is not a CRS GDAL reads (%s): "
		                        "expected the ESRI WKT of a .prj, as GDAL writes it; fix or "
		                        "remove it", prj, grid, why && *why ? why : "corrupt data");
	} else if (OSRIsGeographic(srs)) {
		const char *name = OSRGetName(srs);
		char crs[4096 + 256];
		snprintf(crs, sizeof crs, "%s ('%s')", name && *name ? name : "a geographic CRS", prj);
		/* the GDAL reader's refusal, from the grid's corner and cells */
		struct ss_raster g = *r;
		const double gt[6] = {r->x0, r->cellsize, 0.0, r->y0 + r->ny * ss_dem_dy(r), 0.0,
		                      -ss_dem_dy(r)};
		memcpy(g.geotransform, gt, sizeof gt);
		g.has_geotransform = 1;
		err = ss_dem_refuse_degrees(grid, context, crs, &g, r->nx, r->ny);
	} else if (!(r->crs_wkt = ss_dem_strdup(wkt))) {
		err = SS_ERR_FAIL;
	}
	CPLFree(wkt);
	if (srs)
		OSRDestroySpatialReference(srs);
	CPLPopErrorHandler();
	ss_free(v);
	return err;
}

#else /* !SS_HAVE_GDAL */

/* The UTM zone (WGS 84) of the centre of a grid in degrees, as "EPSG:N",
 * when its corner is a longitude and latitude. */
static void utm_zone(const struct ss_raster *r, char *out, size_t size)
{
	const double lon = r->x0 + 0.5 * r->nx * r->cellsize;
	const double lat = r->y0 + 0.5 * r->ny * ss_dem_dy(r);
	if (!(lon >= -180.0 && lon <= 180.0 && lat >= -90.0 && lat <= 90.0)) {
		snprintf(out, size, "EPSG:<a projected CRS in metres, e.g. your UTM zone>");
		return;
	}
	int zone = (int)floor((lon + 180.0) / 6.0) + 1;
	zone = zone < 1 ? 1 : zone > 60 ? 60 : zone;
	snprintf(out, size, "EPSG:%d", (lat >= 0.0 ? 32600 : 32700) + zone);
}

/* Without GDAL the WKT is kept as read: it must look like WKT (a keyword,
 * '[', ..., ']'), and a geographic CRS is refused by its keyword. */
static int prj_to_crs(char *text, const char *prj, const char *grid, const char *context,
                      struct ss_raster *r)
{
	const char *wkt = text;
	size_t key = 0;
	while (isalnum((unsigned char)wkt[key]) || wkt[key] == '_')
		key++;
	const size_t n = strlen(wkt);
	if (key == 0 || wkt[key] != '[' || wkt[n - 1] != ']')
		return ss_error_input_at(context, "'%s', the CRS of '%s', is not WKT: this build "
		                         "(without GDAL) reads a .prj in WKT only, e.g. PROJCS[...] as "
		                         "GDAL writes it; fix or remove it", prj, grid);
	static const char *const geographic[] = {"GEOGCS", "GEOGCRS", "GEOGRAPHICCRS"};
	for (size_t k = 0; k < sizeof geographic / sizeof *geographic; k++) {
		if (key == strlen(geographic[k]) && !strncasecmp(wkt, geographic[k], key)) {
			char target[80];
			utm_zone(r, target, sizeof target);
			return ss_error_input_at(context, "'%s' is in a geographic CRS ('%s' is %.*s): "
			                         "its cells are degrees, not metres; reproject it first, "
			                         "e.g. gdalwarp -t_srs %s -r bilinear -ot Float32 "
			                         "-dstnodata -9999 '%s' dem-m.tif", grid, prj, (int)key,
			                         wkt, target, grid);
		}
	}
	return (r->crs_wkt = ss_dem_strdup(wkt)) ? SS_OK : SS_ERR_FAIL;
}

#endif

int ss_dem_read_prj(const char *path, const char *context, struct ss_raster *r)
{
	char prj[4096];
	const int found = find_prj(path, prj, sizeof prj);
	if (found <= 0)
		return SS_OK;   /* no .prj (or a name too long for one): no CRS */
	int err = SS_OK;
	char *text = read_prj_text(prj, path, context, &err);
	if (!text)
		return err;
	char *wkt = trim(text);
	if (!*wkt)
		err = ss_error_input_at(context, "'%s', the CRS of '%s', is empty: expected the WKT "
		                        "of a CRS, as GDAL writes it; remove it to read the grid "
		                        "without a CRS", prj, path);
	else
		err = prj_to_crs(wkt, prj, path, context, r);
	ss_free(text);
	return err;
}

/* ------------------------------------------------------------------ */
/* writing                                                              */

/* SS_ERR_INPUT when the .prj of an .asc written to path would be the one
 * r was read with. */
static int check_not_source_prj(const char *path, const struct ss_raster *r)
{
	char src[4096], out[4096];
	if (!r->source || r->format != SS_DEM_ASC || find_prj(r->source, src, sizeof src) != 1)
		return SS_OK;
	static const char *const ext[] = {"prj", "PRJ"};
	for (int k = 0; k < 2; k++) {
		if (sibling(path, ext[k], out, sizeof out) == 0 && same_file(out, src))
			return ss_error_input("cannot write '%s': its CRS would go to '%s', the CRS of "
			                      "the grid it is made from, which is never modified: choose "
			                      "another output name", path, out);
	}
	return SS_OK;
}

int ss_dem_prj_check_not_source(const char *path, const struct ss_raster *r)
{
	return ss_dem_format_of(path) == SS_DEM_ASC ? check_not_source_prj(path, r) : SS_OK;
}

/* The ESRI WKT of r's CRS (ss_free it); NULL after a message. */
static char *esri_wkt(const char *path, const struct ss_raster *r, int *err)
{
#ifdef SS_HAVE_GDAL
	CPLPushErrorHandler(CPLQuietErrorHandler);
	CPLErrorReset();
	OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
	char *in = r->crs_wkt, *wkt = NULL, *out = NULL;
	if (!srs) {
		*err = ss_error_fail("cannot write '%s': out of memory", path);
	} else if (OSRImportFromWkt(srs, &in) != OGRERR_NONE || OSRMorphToESRI(srs) != OGRERR_NONE ||
	           OSRExportToWkt(srs, &wkt) != OGRERR_NONE || !wkt) {
		const char *why = CPLGetLastErrorMsg();
		*err = ss_error_input("cannot write '%s': its CRS is not one GDAL reads (%s), so it "
		                      "cannot be written as a .prj", path,
		                      why && *why ? why : "corrupt data");
	} else if (!(out = ss_dem_strdup(wkt))) {
		*err = SS_ERR_FAIL;
	}
	CPLFree(wkt);
	if (srs)
		OSRDestroySpatialReference(srs);
	CPLPopErrorHandler();
	return out;
#else
	(void)path;
	char *out = ss_dem_strdup(r->crs_wkt);
	if (!out)
		*err = SS_ERR_FAIL;
	return out;
#endif
}

/* text into a new temporary file beside dest (".X.prj.tmp-PID-N"), its
 * name into tmp, complete on disk. */
static int write_temp(const char *path, const char *dest, const char *text, char *tmp,
                      size_t size)
{
	const char *slash = strrchr(dest, '/');
	const int dir_len = slash ? (int)(slash - dest) + 1 : 0;
	int fd = -1;
	for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
		const int n = snprintf(tmp, size, "%.*s.%s.tmp-%ld-%d", dir_len, dest, dest + dir_len,
		                       (long)getpid(), attempt);
		if (n < 0 || (size_t)n >= size)
			return ss_error_input("cannot write '%s': the path of its .prj is too long", path);
		fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd < 0 && errno != EEXIST)
			break;
	}
	if (fd < 0) {
		const int saved = errno;
		tmp[0] = '\0';
		return ss_error_input("cannot write '%s': cannot create its CRS file '%s': %s", path,
		                      dest, strerror(saved));
	}
	const size_t n = strlen(text);
	size_t done = 0;
	while (done < n) {
		const ssize_t w = write(fd, text + done, n - done);
		if (w < 0 && errno == EINTR)
			continue;
		if (w <= 0)
			break;
		done += (size_t)w;
	}
	const int ok = done == n && fsync(fd) == 0;
	const int saved = errno;
	if (close(fd) || !ok)
		return ss_error_fail("cannot write '%s': %s", dest, strerror(ok ? errno : saved));
	return SS_OK;
}

int ss_dem_prj_prepare(const char *path, const struct ss_raster *r, struct ss_dem_prj *p)
{
	memset(p, 0, sizeof *p);
	int err = check_not_source_prj(path, r);   /* an .asc by any name */
	if (err)
		return err;
	if (sibling(path, "prj", p->dest, sizeof p->dest))
		return ss_error_input("cannot write '%s': the path of its .prj is too long", path);
	if (!r->crs_wkt || !*r->crs_wkt) {
		p->remove = 1;
		return SS_OK;
	}
	char *text = esri_wkt(path, r, &err);
	if (!text)
		return err;
	err = write_temp(path, p->dest, text, p->tmp, sizeof p->tmp);
	ss_free(text);
	return err;
}

int ss_dem_prj_commit(const char *path, struct ss_dem_prj *p)
{
	if (p->tmp[0]) {
		if (rename(p->tmp, p->dest))
			return ss_error_fail("cannot write '%s': cannot rename the finished temporary "
			                     "file '%s' to its CRS file '%s': %s", path, p->tmp, p->dest,
			                     strerror(errno));
		p->tmp[0] = '\0';
		return SS_OK;
	}
	if (!p->remove)
		return SS_OK;
	/* no CRS: an earlier file's .prj would claim one for this grid */
	char upper[4096];
	const char *stale[2] = {p->dest, sibling(path, "PRJ", upper, sizeof upper) ? NULL : upper};
	for (int k = 0; k < 2; k++) {
		if (stale[k] && unlink(stale[k]) && errno != ENOENT)
			return ss_error_fail("wrote '%s', which has no CRS, but cannot remove the CRS "
			                     "file '%s' beside it, which would claim one: %s", path,
			                     stale[k], strerror(errno));
	}
	return SS_OK;
}

void ss_dem_prj_discard(struct ss_dem_prj *p)
{
	if (p->tmp[0])
		unlink(p->tmp);
	p->tmp[0] = '\0';
}
