/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_checked.c - the HDF5 calls that the reader (h5_read.c, h5_summary.c)
 * and the writer (h5_write.c) share (h5_checked.h): HDF5's error printing
 * turned off, a file opened for reading, attributes read and written,
 * datasets opened and read with every size they state checked against
 * the file.
 *
 * Damaged files.  HDF5 believes the sizes a file states: a changed byte in
 * a dataspace can make a 64 KB file claim 10^12 snapshots, and a changed
 * chunk size can make HDF5 itself allocate gigabytes before its read
 * fails.  So before anything of a stated size is allocated, here or by
 * HDF5, the size is checked against the file:
 *   - a dataset's values fit in the file: at most its size in bytes when
 *     stored plainly, 1032 times that with deflate (zlib's largest ratio);
 *     filters other than deflate, shuffle and fletcher32 are refused, as
 *     their ratio is unbounded (scale-offset) or unknown;
 *   - one chunk fits likewise, as HDF5 allocates a whole chunk to read any
 *     of it;
 *   - every chunk a read touches is stored, inside the file, and not
 *     smaller than its values can be packed into: a sandslide writer
 *     stores every value it declares, and an unstored chunk would read back
 *     as fill values;
 *   - a contiguous dataset's bytes lie inside the file; a fixed-length
 *     string is shorter than the file.
 * A file that fails one of these, or whose read fails (a fletcher32
 * checksum, say), is damaged: SS_ERR_INPUT with one message saying so.
 * Datasets with external or virtual storage are refused: they would read
 * other files.  Numbers must be IEEE floats or standard integers, so that
 * HDF5 converts them with its well-trodden code.
 *
 * HDF5's own error printing is off (per thread: OpenMP threads that read
 * turn it off too); each failure prints one sandslide message.
 */
#include "io/h5_checked.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sandslide/error.h"
#include "io/snapshot_layout.h"

#define DEFLATE_MAX_RATIO 1032.0    /* zlib: 1032:1 at most */

void ss_h5_quiet(void)
{
	H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/*
 * LeakSanitizer, in sanitized builds (make SANITIZE=1, the fuzz harnesses):
 * HDF5 1.10.8 loses memory of its own on some error paths of damaged files
 * (H5Dopen2 that fails in H5D__layout_oh_read leaks the chunk cache's
 * slots, 4176 bytes, from its free lists).  Debian's libhdf5 has no frame
 * pointers, so a leak's stack ends at its first frame in the library: the
 * suppression names the library.  The only memory HDF5 allocates for us,
 * variable-length strings, is freed with H5free_memory in attr_read_vlen.
 * Not listed at exit (a damaged file still gets its one line of stderr).
 * Weak, so that a program may set its own.
 */
const char *__lsan_default_suppressions(void) __attribute__((weak));
const char *__lsan_default_suppressions(void)
{
	return "leak:libhdf5_serial.so\nleak:libhdf5.so\n";
}

const char *__lsan_default_options(void) __attribute__((weak));
const char *__lsan_default_options(void)
{
	return "print_suppressions=0";
}

/* ---- an open HDF5 file and its messages ------------------------------ */

int ss_h5_damaged(const struct ss_h5_file *in, const char *fmt, ...)
{
	char what[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(what, sizeof what, fmt, ap);
	va_end(ap);
	return ss_error_input("'%s' is damaged: %s", in->name, what);
}

/* What the HDF5 error stack says about the last failure. */
struct h5why {
	char text[200];             /* the innermost description */
	int locked;                 /* another program holds the file lock */
};

static herr_t why_walk(unsigned n, const H5E_error2_t *e, void *data)
{
	struct h5why *w = data;
	if (n == 0 && e->desc)
		snprintf(w->text, sizeof w->text, "%s", e->desc);
	if (e->min_num == H5E_CANTLOCKFILE)
		w->locked = 1;
	return 0;
}

static void why_failed(struct h5why *w)
{
	memset(w, 0, sizeof *w);
	H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, why_walk, w);
	if (!w->text[0])
		snprintf(w->text, sizeof w->text, "no reason given");
}

int ss_h5_read_failed(const struct ss_h5_file *in, const char *what)
{
	struct h5why w;
	why_failed(&w);
	return ss_h5_damaged(in, "cannot read %s (HDF5: %s)", what, w.text);
}

const char *ss_h5_format_dims(int rank, const hsize_t *dims, char *out, size_t size)
{
	size_t at = 0;
	out[0] = '\0';
	for (int k = 0; k < rank && at < size; k++)
		at += (size_t)snprintf(out + at, size - at, "%s%llu", k ? " x " : "",
		                       (unsigned long long)dims[k]);
	return out;
}

/* ---- opening --------------------------------------------------------- */

/* HDF5's signature at 0, 512, 1024, 2048, ... (where the library looks). */
static int has_signature(const unsigned char *data, size_t size)
{
	static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
	for (size_t at = 0; at + 8 <= size; at = at ? 2 * at : 512)
		if (!memcmp(data + at, sig, 8))
			return 1;
	return 0;
}

/* File access of an image in memory: the core driver, no file behind it. */
static hid_t image_access(const void *data, size_t size)
{
	hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
	if (fapl >= 0 && (H5Pset_fapl_core(fapl, 64 << 10, 0) < 0 ||
	                  H5Pset_file_image(fapl, (void *)data, size) < 0)) {
		H5Pclose(fapl);
		fapl = -1;
	}
	return fapl;
}

int ss_h5_file_open(struct ss_h5_file *in, const char *name, const void *data,
                    size_t size)
{
	ss_h5_quiet();
	in->file = -1;
	in->name = name;
	hid_t fapl = H5P_DEFAULT;
	if (!data) {
		struct stat sb;
		FILE *probe = fopen(name, "rb");   /* says why: missing, no permission */
		if (!probe || stat(name, &sb) != 0) {
			const int e = errno;
			if (probe)
				fclose(probe);
			return ss_error_input("cannot open '%s': %s", name, strerror(e));
		}
		fclose(probe);
		in->bytes = (double)sb.st_size;
		if (S_ISDIR(sb.st_mode) || H5Fis_hdf5(name) <= 0)
			return ss_error_input("'%s' is not an HDF5 file", name);
	} else {
		in->bytes = (double)size;
		if (!has_signature(data, size))
			return ss_error_input("'%s' is not an HDF5 file", name);
		if ((fapl = image_access(data, size)) < 0)
			return ss_error_fail("'%s': cannot set up HDF5 to read an image", name);
	}
	in->file = H5Fopen(name, H5F_ACC_RDONLY, fapl);
	if (fapl != H5P_DEFAULT)
		H5Pclose(fapl);
	if (in->file >= 0)
		return SS_OK;
	struct h5why w;
	why_failed(&w);
	if (w.locked)
		return ss_error_input("cannot open '%s': another program is writing it (HDF5 "
		                      "file lock)", name);
	return ss_h5_damaged(in, "HDF5 cannot open it (%s)", w.text);
}

void ss_h5_file_close(struct ss_h5_file *in)
{
	if (in->file >= 0)
		H5Fclose(in->file);
	in->file = -1;
}

/* ---- attributes ------------------------------------------------------ */

/* An open attribute with its file type and dataspace. */
struct attr {
	hid_t a, type, space;
};

static void attr_close(struct attr *at)
{
	if (at->space >= 0)
		H5Sclose(at->space);
	if (at->type >= 0)
		H5Tclose(at->type);
	if (at->a >= 0)
		H5Aclose(at->a);
}

/* Attribute name of obj of one value or, for numbers, n values: 0, or -1
 * (at closed) if there is none such. */
static int attr_open(hid_t obj, const char *name, hssize_t n, struct attr *at)
{
	at->a = H5Aexists(obj, name) > 0 ? H5Aopen(obj, name, H5P_DEFAULT) : -1;
	at->type = at->a >= 0 ? H5Aget_type(at->a) : -1;
	at->space = at->a >= 0 ? H5Aget_space(at->a) : -1;
	if (at->type >= 0 && at->space >= 0 && H5Sget_simple_extent_npoints(at->space) == n)
		return 0;
	attr_close(at);
	return -1;
}

/* A variable-length string value of attribute a (of file type ft) as a
 * new string. */
static int attr_read_vlen(hid_t a, hid_t ft, char **out)
{
	hid_t mt = H5Tcopy(H5T_C_S1);
	char *v = NULL;
	int err = SS_OK;
	/* in the file's character set: HDF5 converts none into another */
	if (mt >= 0 && H5Tset_size(mt, H5T_VARIABLE) >= 0 &&
	    H5Tset_cset(mt, H5Tget_cset(ft)) >= 0 && H5Aread(a, mt, &v) >= 0 && v) {
		if (!(*out = strdup(v)))
			err = ss_error_fail("out of memory");
	}
	if (v)
		H5free_memory(v);
	if (mt >= 0)
		H5Tclose(mt);
	return err;
}

int ss_h5_attr_read_text(const struct ss_h5_file *in, hid_t obj, const char *name,
                         char **out)
{
	*out = NULL;
	struct attr at;
	if (attr_open(obj, name, 1, &at))
		return SS_OK;
	int err = SS_OK;
	const size_t n = H5Tget_size(at.type);
	if (H5Tget_class(at.type) == H5T_STRING) {
		if (H5Tis_variable_str(at.type) > 0)
			err = attr_read_vlen(at.a, at.type, out);
		else if ((double)n > in->bytes)
			err = ss_h5_damaged(in, "attribute '%s' claims %zu characters, more than "
			                    "the file holds", name, n);
		else if (!(*out = calloc(1, n + 1)))
			err = ss_error_fail("out of memory");
		else if (H5Aread(at.a, at.type, *out) < 0) {
			free(*out);
			*out = NULL;
		}
	}
	attr_close(&at);
	return err;
}

int ss_h5_attr_read_string(const struct ss_h5_file *in, hid_t obj, const char *name,
                           char *out, size_t size)
{
	char *text;
	const int err = ss_h5_attr_read_text(in, obj, name, &text);
	snprintf(out, size, "%s", text ? text : "");
	free(text);
	return err;
}

/* IEEE floats and standard integers of either byte order. */
static int is_number_type(hid_t t)
{
	const hid_t known[] = {
		H5T_IEEE_F64LE, H5T_IEEE_F64BE, H5T_IEEE_F32LE, H5T_IEEE_F32BE,
		H5T_STD_U8LE, H5T_STD_U8BE, H5T_STD_I8LE, H5T_STD_I8BE,
		H5T_STD_U16LE, H5T_STD_U16BE, H5T_STD_I16LE, H5T_STD_I16BE,
		H5T_STD_U32LE, H5T_STD_U32BE, H5T_STD_I32LE, H5T_STD_I32BE,
		H5T_STD_U64LE, H5T_STD_U64BE, H5T_STD_I64LE, H5T_STD_I64BE,
	};
	for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
		if (H5Tequal(t, known[k]) > 0)
			return 1;
	return 0;
}

int ss_h5_attr_read_doubles(hid_t obj, const char *name, int n, double *v)
{
	struct attr at;
	double got[SS_SNAPSHOT_RESTART_VALUES];
	if (n > SS_SNAPSHOT_RESTART_VALUES || attr_open(obj, name, n, &at))
		return -1;
	const int ok = is_number_type(at.type) && H5Aread(at.a, H5T_NATIVE_DOUBLE, got) >= 0;
	if (ok)
		memcpy(v, got, (size_t)n * sizeof *v);
	attr_close(&at);
	return ok ? 0 : -1;
}

double ss_h5_attr_read_double(hid_t obj, const char *name)
{
	double v = NAN;
	ss_h5_attr_read_doubles(obj, name, 1, &v);
	return v;
}

int ss_h5_attr_write_string(hid_t obj, const char *name, const char *value)
{
	hid_t type = H5Tcopy(H5T_C_S1);
	size_t len = strlen(value);
	H5Tset_size(type, len ? len : 1);
	H5Tset_strpad(type, H5T_STR_NULLTERM);
	H5Tset_cset(type, H5T_CSET_UTF8);   /* the case text may hold any UTF-8 */
	hid_t space = H5Screate(H5S_SCALAR);
	hid_t a = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
	herr_t r = a < 0 ? -1 : H5Awrite(a, type, len ? value : "");
	if (a >= 0)
		H5Aclose(a);
	H5Sclose(space);
	H5Tclose(type);
	return r < 0 ? -1 : 0;
}

int ss_h5_attr_write_doubles(hid_t obj, const char *name, const double *v, hsize_t n)
{
	hid_t space = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, NULL);
	hid_t a = H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
	herr_t r = a < 0 ? -1 : H5Awrite(a, H5T_NATIVE_DOUBLE, v);
	if (a >= 0)
		H5Aclose(a);
	H5Sclose(space);
	return r < 0 ? -1 : 0;
}

int ss_h5_attr_update_doubles(hid_t obj, const char *name, const double *v, hsize_t n)
{
	if (H5Aexists(obj, name) > 0) {
		hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
		const hid_t space = a >= 0 ? H5Aget_space(a) : -1;
		const hssize_t count = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
		if (space >= 0)
			H5Sclose(space);
		/* one of another length (an older file's) is made again */
		const herr_t w = a < 0 ? -1 : (hsize_t)count == n ? H5Awrite(a, H5T_NATIVE_DOUBLE, v)
		                                                  : 1;
		if (a >= 0)
			H5Aclose(a);
		if (w <= 0)
			return w < 0 ? -1 : 0;
		if (H5Adelete(obj, name) < 0)
			return -1;
	}
	return ss_h5_attr_write_doubles(obj, name, v, n);
}

/* ---- datasets -------------------------------------------------------- */

void ss_h5_var_close(struct ss_h5_var *v)
{
	if (v->d >= 0)
		H5Dclose(v->d);
	v->d = -1;
}

/* The filters of dcpl and their largest packing ratio; 0 if a filter is
 * not one of deflate, shuffle, fletcher32. */
static double filters_ratio(hid_t dcpl)
{
	const int n = H5Pget_nfilters(dcpl);
	double ratio = n < 0 ? 0.0 : 1.0;
	for (int k = 0; k < n; k++) {
		unsigned flags, cd[8];
		size_t ncd = 8;
		const H5Z_filter_t id = H5Pget_filter2(dcpl, (unsigned)k, &flags, &ncd, cd, 0, NULL,
		                                       NULL);
		if (id == H5Z_FILTER_DEFLATE)
			ratio *= DEFLATE_MAX_RATIO;
		else if (id != H5Z_FILTER_SHUFFLE && id != H5Z_FILTER_FLETCHER32)
			return 0.0;
	}
	return ratio;
}

/* How v is stored (dcpl): the ratio, chunk sizes; SS_ERR_INPUT when the
 * storage is one this reader refuses or cannot be true. */
static int var_layout(const struct ss_h5_file *in, struct ss_h5_var *v, hid_t dcpl)
{
	const H5D_layout_t layout = H5Pget_layout(dcpl);
	if (layout == H5D_VIRTUAL || H5Pget_external_count(dcpl) != 0)
		return ss_error_input("'%s': /%s keeps its values in other files (external or "
		                      "virtual storage): not read", in->name, v->name);
	if (!(v->ratio = filters_ratio(dcpl)))
		return ss_error_input("'%s': /%s is stored with an HDF5 filter other than deflate, "
		                      "shuffle and fletcher32: not read", in->name, v->name);
	v->chunked = layout == H5D_CHUNKED;
	v->chunk_bytes = v->type_bytes;
	if (!v->chunked)
		return SS_OK;
	if (H5Pget_chunk(dcpl, v->rank, v->chunk) != v->rank)
		return ss_h5_damaged(in, "/%s has chunks of another rank than its own", v->name);
	for (int k = 0; k < v->rank; k++) {
		/* HDF5 creates no chunk larger than a dimension that cannot grow
		 * (and 1.10 reads past its buffers when a chunk is) */
		if (v->chunk[k] < 1 || (v->maxdims[k] != H5S_UNLIMITED && v->chunk[k] > v->maxdims[k]))
			return ss_h5_damaged(in, "/%s has chunks of %llu along a dimension of at "
			                     "most %llu", v->name, (unsigned long long)v->chunk[k],
			                     (unsigned long long)v->maxdims[k]);
		v->chunk_bytes *= (double)v->chunk[k];
	}
	if (v->chunk_bytes > in->bytes * v->ratio) {
		char b[32];
		return ss_h5_damaged(in, "/%s claims chunks of %.0f bytes, more than its %s can "
		                     "hold", v->name, v->chunk_bytes,
		                     ss_format_bytes(in->bytes, b));
	}
	return SS_OK;
}

/* Stored bytes that must hold the values of v, checked against the file. */
static int var_check_size(const struct ss_h5_file *in, const struct ss_h5_var *v)
{
	double values = v->type_bytes;
	for (int k = 0; k < v->rank; k++)
		values *= (double)v->dims[k];
	char b[32], d[96];
	const char *dims = ss_h5_format_dims(v->rank, v->dims, d, sizeof d);
	if (values > in->bytes * v->ratio)
		return ss_h5_damaged(in, "/%s claims %s values of %.0f bytes, more than its %s "
		                     "can hold", v->name, dims, v->type_bytes,
		                     ss_format_bytes(in->bytes, b));
	if (v->chunked || values == 0.0)
		return SS_OK;     /* chunks are checked where they are read */
	const haddr_t at = H5Dget_offset(v->d);
	const double stored = (double)H5Dget_storage_size(v->d);
	if (stored < values || (at != HADDR_UNDEF && (double)at + stored > in->bytes))
		return ss_h5_damaged(in, "/%s claims %s values of %.0f bytes but stores %.0f "
		                     "bytes%s", v->name, dims, v->type_bytes, stored,
		                     stored < values ? "" : " past the end of the file");
	return SS_OK;
}

int ss_h5_var_open(const struct ss_h5_file *in, const char *name, struct ss_h5_var *v)
{
	memset(v, 0, sizeof *v);
	v->d = -1;
	v->name = name[0] == '/' ? name + 1 : name;
	/* a hard link only: a soft or external one could lead to another file */
	H5L_info_t link;
	H5O_info_t obj;
	if (H5Lexists(in->file, name, H5P_DEFAULT) <= 0 ||
	    H5Lget_info(in->file, name, &link, H5P_DEFAULT) < 0 || link.type != H5L_TYPE_HARD)
		return SS_H5_VAR_MISSING;
	char what[300];
	snprintf(what, sizeof what, "/%s", v->name);
	if (H5Oget_info_by_name2(in->file, name, &obj, H5O_INFO_BASIC, H5P_DEFAULT) < 0)
		return ss_h5_read_failed(in, what);
	if (obj.type != H5O_TYPE_DATASET)
		return SS_H5_VAR_MISSING;
	if ((v->d = H5Dopen2(in->file, name, H5P_DEFAULT)) < 0)
		return ss_h5_read_failed(in, what);
	hid_t t = H5Dget_type(v->d), sp = H5Dget_space(v->d);
	v->rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
	const int numbers = t >= 0 && is_number_type(t) && v->rank >= 1 && v->rank <= 3 &&
	                    H5Sget_simple_extent_dims(sp, v->dims, v->maxdims) == v->rank;
	v->type_bytes = numbers ? (double)H5Tget_size(t) : 0.0;
	if (sp >= 0)
		H5Sclose(sp);
	if (t >= 0)
		H5Tclose(t);
	if (!numbers) {
		ss_h5_var_close(v);
		return SS_H5_VAR_NOT_NUMBERS;
	}
	hid_t dcpl = H5Dget_create_plist(v->d);
	int err = dcpl < 0 ? ss_h5_damaged(in, "cannot read how /%s is stored", v->name)
	                   : var_layout(in, v, dcpl);
	if (dcpl >= 0)
		H5Pclose(dcpl);
	if (!err)
		err = var_check_size(in, v);
	if (err)
		ss_h5_var_close(v);
	return err;
}

/* The chunk of v at offset is stored, inside the file, and large enough. */
static int check_chunk(const struct ss_h5_file *in, const struct ss_h5_var *v,
                       const hsize_t *offset)
{
	unsigned mask;
	haddr_t at;
	hsize_t size;
	char d[96], o[96];
	if (H5Dget_chunk_info_by_coord(v->d, offset, &mask, &at, &size) < 0) {
		char what[300];
		snprintf(what, sizeof what, "the chunk index of /%s", v->name);
		return ss_h5_read_failed(in, what);
	}
	if (at == HADDR_UNDEF)
		return ss_h5_damaged(in, "/%s declares %s values but stores no chunk at %s",
		                     v->name, ss_h5_format_dims(v->rank, v->dims, d, sizeof d),
		                     ss_h5_format_dims(v->rank, offset, o, sizeof o));
	if ((double)at + (double)size > in->bytes || (double)size * v->ratio < v->chunk_bytes)
		return ss_h5_damaged(in, "/%s has a chunk of %llu bytes at byte %llu, of a file of "
		                     "%.0f bytes, for %.0f bytes of values", v->name,
		                     (unsigned long long)size, (unsigned long long)at, in->bytes,
		                     v->chunk_bytes);
	return SS_OK;
}

int ss_h5_var_check_chunks(const struct ss_h5_file *in, const struct ss_h5_var *v,
                           const hsize_t *start, const hsize_t *count)
{
	if (!v->chunked)
		return SS_OK;
	hsize_t first[3], last[3], at[3];
	for (int k = 0; k < v->rank; k++) {
		first[k] = at[k] = start[k] / v->chunk[k] * v->chunk[k];
		last[k] = (start[k] + count[k] - 1) / v->chunk[k] * v->chunk[k];
	}
	for (;;) {
		const int err = check_chunk(in, v, at);
		if (err)
			return err;
		int k = v->rank - 1;
		while (k >= 0 && (at[k] += v->chunk[k]) > last[k]) {
			at[k] = first[k];
			k--;
		}
		if (k < 0)
			return SS_OK;
	}
}

int ss_h5_var_read(const struct ss_h5_file *in, const struct ss_h5_var *v,
                   const hsize_t *start, const hsize_t *count, hid_t mem_type, void *out,
                   const char *what)
{
	int err = ss_h5_var_check_chunks(in, v, start, count);
	if (err)
		return err;
	hid_t fs = H5Dget_space(v->d);
	hid_t ms = H5Screate_simple(v->rank, count, NULL);
	if (fs < 0 || ms < 0 ||
	    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
	    H5Dread(v->d, mem_type, ms, fs, H5P_DEFAULT, out) < 0)
		err = ss_h5_read_failed(in, what);
	if (ms >= 0)
		H5Sclose(ms);
	if (fs >= 0)
		H5Sclose(fs);
	return err;
}
