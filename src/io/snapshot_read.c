/*
 * snapshot_read.c - every read of an HDF5 file (snapshot.h): the one
 * definition of a sandslide file, and what `sandslide info` (the
 * summary), `run --restart`, the renderer, .h5 DEMs and
 * ss_snapshot_open_append's check read through it.
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
#include "sandslide/snapshot.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <hdf5.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "io/snapshot_layout.h"

#define DEFLATE_MAX_RATIO 1032.0    /* zlib: 1032:1 at most */
#define BLOCK_BYTES (8ll << 20)     /* rows per block read: about 8 MB */

int ss_snapshot_threadsafe(void)
{
	hbool_t safe = 0;
	return H5is_library_threadsafe(&safe) >= 0 && safe;
}

static void quiet_hdf5(void)
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

/* A file open for reading: the checks need its size. */
struct h5in {
	hid_t file;
	const char *name;           /* for messages */
	double bytes;               /* size of the file or image */
};

/* "'name' is damaged: ..." */
static int damaged(const struct h5in *in, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));
static int damaged(const struct h5in *in, const char *fmt, ...)
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

/* A read of what that failed: damage (a checksum, a chunk past the end). */
static int read_failed(const struct h5in *in, const char *what)
{
	struct h5why w;
	why_failed(&w);
	return damaged(in, "cannot read %s (HDF5: %s)", what, w.text);
}

/* "8 x 16 x 20" */
static const char *format_dims(int rank, const hsize_t *dims, char *out, size_t size)
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

/* Open name (a path, or an image when data is not NULL) read-only. */
static int h5in_open(struct h5in *in, const char *name, const void *data, size_t size)
{
	quiet_hdf5();
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
	return damaged(in, "HDF5 cannot open it (%s)", w.text);
}

static void h5in_close(struct h5in *in)
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

/*
 * A string attribute (one value, fixed or variable length) as a new
 * string in *out (free()); *out NULL if absent, not one string or
 * unreadable.  SS_ERR_INPUT if its stated length cannot be in the file.
 */
static int attr_text(const struct h5in *in, hid_t obj, const char *name, char **out)
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
			err = damaged(in, "attribute '%s' claims %zu characters, more than the file "
			              "holds", name, n);
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

/* attr_text into a buffer ("" if absent). */
static int attr_string(const struct h5in *in, hid_t obj, const char *name, char *out,
                       size_t size)
{
	char *text;
	const int err = attr_text(in, obj, name, &text);
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

/* n numbers of attribute name into v; -1 (v untouched) if absent or not
 * n numbers. */
static int attr_doubles(hid_t obj, const char *name, int n, double *v)
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

static double attr_double(hid_t obj, const char *name)
{
	double v = NAN;
	attr_doubles(obj, name, 1, &v);
	return v;
}

/* ---- datasets -------------------------------------------------------- */

/* An open dataset of numbers, rank 1 to 3, and how it is stored. */
struct var {
	hid_t d;
	const char *name;           /* for messages, without a leading '/' */
	int rank;
	hsize_t dims[3], maxdims[3];
	double type_bytes;          /* per value in the file */
	double ratio;               /* largest ratio of values to stored bytes */
	int chunked;
	hsize_t chunk[3];
	double chunk_bytes;
};

enum { VAR_MISSING = 1, VAR_NOT_NUMBERS = 2 };

static void var_close(struct var *v)
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
static int var_layout(const struct h5in *in, struct var *v, hid_t dcpl)
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
		return damaged(in, "/%s has chunks of another rank than its own", v->name);
	for (int k = 0; k < v->rank; k++) {
		/* HDF5 creates no chunk larger than a dimension that cannot grow
		 * (and 1.10 reads past its buffers when a chunk is) */
		if (v->chunk[k] < 1 || (v->maxdims[k] != H5S_UNLIMITED && v->chunk[k] > v->maxdims[k]))
			return damaged(in, "/%s has chunks of %llu along a dimension of at most %llu",
			               v->name, (unsigned long long)v->chunk[k],
			               (unsigned long long)v->maxdims[k]);
		v->chunk_bytes *= (double)v->chunk[k];
	}
	if (v->chunk_bytes > in->bytes * v->ratio) {
		char b[32];
		return damaged(in, "/%s claims chunks of %.0f bytes, more than its %s can hold",
		               v->name, v->chunk_bytes, ss_format_bytes(in->bytes, b));
	}
	return SS_OK;
}

/* Stored bytes that must hold the values of v, checked against the file. */
static int var_check_size(const struct h5in *in, const struct var *v)
{
	double values = v->type_bytes;
	for (int k = 0; k < v->rank; k++)
		values *= (double)v->dims[k];
	char b[32], d[96];
	if (values > in->bytes * v->ratio)
		return damaged(in, "/%s claims %s values of %.0f bytes, more than its %s can hold",
		               v->name, format_dims(v->rank, v->dims, d, sizeof d), v->type_bytes,
		               ss_format_bytes(in->bytes, b));
	if (v->chunked || values == 0.0)
		return SS_OK;     /* chunks are checked where they are read */
	const haddr_t at = H5Dget_offset(v->d);
	const double stored = (double)H5Dget_storage_size(v->d);
	if (stored < values || (at != HADDR_UNDEF && (double)at + stored > in->bytes))
		return damaged(in, "/%s claims %s values of %.0f bytes but stores %.0f bytes%s",
		               v->name, format_dims(v->rank, v->dims, d, sizeof d), v->type_bytes,
		               stored, stored < values ? "" : " past the end of the file");
	return SS_OK;
}

/*
 * Open dataset name as a var: SS_OK; VAR_MISSING (no such dataset) or
 * VAR_NOT_NUMBERS (not numbers of rank 1 to 3), with nothing printed, for
 * the caller to say what it needed; SS_ERR_INPUT if what it claims cannot
 * be in the file.
 */
static int var_open(const struct h5in *in, const char *name, struct var *v)
{
	memset(v, 0, sizeof *v);
	v->d = -1;
	v->name = name[0] == '/' ? name + 1 : name;
	/* a hard link only: a soft or external one could lead to another file */
	H5L_info_t link;
	H5O_info_t obj;
	if (H5Lexists(in->file, name, H5P_DEFAULT) <= 0 ||
	    H5Lget_info(in->file, name, &link, H5P_DEFAULT) < 0 || link.type != H5L_TYPE_HARD)
		return VAR_MISSING;
	char what[300];
	snprintf(what, sizeof what, "/%s", v->name);
	if (H5Oget_info_by_name2(in->file, name, &obj, H5O_INFO_BASIC, H5P_DEFAULT) < 0)
		return read_failed(in, what);
	if (obj.type != H5O_TYPE_DATASET)
		return VAR_MISSING;
	if ((v->d = H5Dopen2(in->file, name, H5P_DEFAULT)) < 0)
		return read_failed(in, what);
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
		var_close(v);
		return VAR_NOT_NUMBERS;
	}
	hid_t dcpl = H5Dget_create_plist(v->d);
	int err = dcpl < 0 ? damaged(in, "cannot read how /%s is stored", v->name)
	                   : var_layout(in, v, dcpl);
	if (dcpl >= 0)
		H5Pclose(dcpl);
	if (!err)
		err = var_check_size(in, v);
	if (err)
		var_close(v);
	return err;
}

/* The chunk of v at offset is stored, inside the file, and large enough. */
static int check_chunk(const struct h5in *in, const struct var *v, const hsize_t *offset)
{
	unsigned mask;
	haddr_t at;
	hsize_t size;
	char d[96], o[96];
	if (H5Dget_chunk_info_by_coord(v->d, offset, &mask, &at, &size) < 0) {
		char what[300];
		snprintf(what, sizeof what, "the chunk index of /%s", v->name);
		return read_failed(in, what);
	}
	if (at == HADDR_UNDEF)
		return damaged(in, "/%s declares %s values but stores no chunk at %s", v->name,
		               format_dims(v->rank, v->dims, d, sizeof d),
		               format_dims(v->rank, offset, o, sizeof o));
	if ((double)at + (double)size > in->bytes || (double)size * v->ratio < v->chunk_bytes)
		return damaged(in, "/%s has a chunk of %llu bytes at byte %llu, of a file of "
		               "%.0f bytes, for %.0f bytes of values", v->name,
		               (unsigned long long)size, (unsigned long long)at, in->bytes,
		               v->chunk_bytes);
	return SS_OK;
}

/* Every chunk of the block start .. start + count - 1 passes check_chunk. */
static int check_chunks(const struct h5in *in, const struct var *v, const hsize_t *start,
                        const hsize_t *count)
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

/* The block start .. start + count - 1 of v (rank values each) into out,
 * as mem_type; what names it in a message. */
static int var_read(const struct h5in *in, const struct var *v, const hsize_t *start,
                    const hsize_t *count, hid_t mem_type, void *out, const char *what)
{
	int err = check_chunks(in, v, start, count);
	if (err)
		return err;
	hid_t fs = H5Dget_space(v->d);
	hid_t ms = H5Screate_simple(v->rank, count, NULL);
	if (fs < 0 || ms < 0 ||
	    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
	    H5Dread(v->d, mem_type, ms, fs, H5P_DEFAULT, out) < 0)
		err = read_failed(in, what);
	if (ms >= 0)
		H5Sclose(ms);
	if (fs >= 0)
		H5Sclose(fs);
	return err;
}

/* The first n values of the 1-D series name into out; SS_ERR_INPUT naming
 * the series if it is missing or does not have n or n + 1 (the last one
 * unfinished: doc/output.md#written-as-the-run-goes) values. */
static int read_series(const struct h5in *in, const char *name, long long n, double *out)
{
	struct var v;
	int err = var_open(in, name, &v);
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] < (hsize_t)n ||
	                         v.dims[0] > (hsize_t)n + 1)))
		err = ss_error_input("'%s' is not a sandslide output file: no /%s (time) of %lld "
		                     "values", in->name, name, n);
	const hsize_t start = 0, count = (hsize_t)n;
	char what[80];
	snprintf(what, sizeof what, "/%s", name);
	if (!err && n > 0)
		err = var_read(in, &v, &start, &count, H5T_NATIVE_DOUBLE, out, what);
	var_close(&v);
	return err;
}

/* ---- a sandslide file ------------------------------------------------ */

struct ss_snapshot_file_h5 {
	struct h5in in;
	struct var height;          /* (time, y, x) */
	struct var cell_type;       /* (y, x) */
};

static int not_sandslide(const struct h5in *in, const char *why)
{
	return ss_error_input("'%s' is not a sandslide output file: %s", in->name, why);
}

/* /height (time, y, x) and /cell_type (y, x) of a grid of 1 .. 2^30 cells
 * a side, into f. */
static int check_grid(struct ss_snapshot_file *f)
{
	struct ss_snapshot_file_h5 *h = f->h5;
	int err = var_open(&h->in, "height", &h->height);
	if (err > 0 || (!err && h->height.rank != 3))
		return not_sandslide(&h->in, "no /height (time, y, x) of numbers (doc/output.md)");
	if (err)
		return err;
	const hsize_t *hd = h->height.dims;
	if (hd[1] < 1 || hd[2] < 1 || hd[1] > SS_SNAPSHOT_MAX_SIDE || hd[2] > SS_SNAPSHOT_MAX_SIDE)
		return ss_error_input("'%s' is not a sandslide output file: /height has %llu x %llu "
		                      "cells", h->in.name, (unsigned long long)hd[2],
		                      (unsigned long long)hd[1]);
	f->ny = (int)hd[1];
	f->nx = (int)hd[2];
	err = var_open(&h->in, "cell_type", &h->cell_type);
	const hsize_t *cd = h->cell_type.dims;
	if (err > 0 || (!err && (h->cell_type.rank != 2 || cd[0] != hd[1] || cd[1] != hd[2])))
		return not_sandslide(&h->in, "/cell_type (y, x) does not match /height");
	return err;
}

/* /time (time) into f->time; its length is the count of complete
 * snapshots.  /height holds as many, or one more that a killed run did not
 * finish (the writer's append). */
static int read_times(struct ss_snapshot_file *f)
{
	const struct ss_snapshot_file_h5 *h = f->h5;
	const struct h5in *in = &h->in;
	struct var v;
	int err = var_open(in, "time", &v);
	const hsize_t stored = h->height.dims[0];
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] > stored || v.dims[0] + 1 < stored))) {
		char why[96];
		snprintf(why, sizeof why, "/time does not match /height (%llu snapshots)",
		         (unsigned long long)stored);
		err = not_sandslide(in, why);
	}
	if (!err)
		f->count = (long long)v.dims[0];
	var_close(&v);
	/* snapshots are written in order: the last one stored, all are */
	const hsize_t last[3] = {(hsize_t)f->count - 1, 0, 0},
	              one[3] = {1, h->height.dims[1], h->height.dims[2]};
	if (!err && f->count > 0)
		err = check_chunks(in, &h->height, last, one);
	if (!err && !(f->time = malloc((size_t)(f->count ? f->count : 1) * sizeof *f->time)))
		err = ss_error_fail("out of memory");
	return err ? err : read_series(in, "time", f->count, f->time);
}

/* The first value of the optional 1-D variable name into *v (NAN if it is
 * absent or empty). */
static int first_value(const struct h5in *in, const char *name, double *v)
{
	struct var x;
	*v = NAN;
	int err = var_open(in, name, &x);
	if (err > 0)
		return SS_OK;
	if (!err && x.rank == 1 && x.dims[0] >= 1) {
		const hsize_t start = 0, one = 1;
		err = var_read(in, &x, &start, &one, H5T_NATIVE_DOUBLE, v, name);
	}
	var_close(&x);
	return err;
}

/* The wall sides from the root attribute boundary ("west=wall east=open
 * ..."); none when it is missing.  A word that is not side=kind makes the
 * file damaged. */
static int read_wall_sides(struct ss_snapshot_file *f)
{
	const struct h5in *in = &f->h5->in;
	char text[256], *save = NULL;
	int err = attr_string(in, in->file, SS_SNAPSHOT_BOUNDARY, text, sizeof text);
	for (char *w = strtok_r(text, " ", &save); w && !err; w = strtok_r(NULL, " ", &save)) {
		char *eq = strchr(w, '=');
		enum ss_side_kind kind;
		int side = -1;
		for (int k = 0; eq && k < 4; k++)
			if ((size_t)(eq - w) == strlen(ss_side_name(k)) &&
			    !strncmp(w, ss_side_name(k), (size_t)(eq - w)))
				side = k;
		if (side < 0 || ss_side_kind_parse(eq + 1, &kind))
			err = damaged(in, "root attribute %s has '%s': expected SIDE=KIND, SIDE west, "
			              "east, south or north and KIND wall, open or periodic",
			              SS_SNAPSHOT_BOUNDARY, w);
		else if (kind == SS_SIDE_WALL)
			f->wall_sides |= 1u << side;
	}
	return err;
}

/* The definition of snapshot.h, the sizes and geometry into f. */
static int check_definition(struct ss_snapshot_file *f)
{
	const struct h5in *in = &f->h5->in;
	char source[256];
	int err = attr_string(in, in->file, "source", source, sizeof source);
	if (err)
		return err;
	if (strncmp(source, SS_SNAPSHOT_SOURCE, strlen(SS_SNAPSHOT_SOURCE)))
		return not_sandslide(in, "no root attribute source = \"sandslide ...\" "
		                         "(doc/output.md#the-one-reader)");
	if ((err = check_grid(f)) || (err = read_times(f)))
		return err;
	f->dx = attr_double(in->file, "dx");
	f->dy = attr_double(in->file, "dy");
	if (!(f->dx > 0.0) || !(f->dy > 0.0) || !isfinite(f->dx) || !isfinite(f->dy))
		return not_sandslide(in, "no positive dx, dy attributes");
	double x0, y0;
	if ((err = first_value(in, "x", &x0)) || (err = first_value(in, "y", &y0)))
		return err;
	/* the corner from the first cell centres */
	f->origin_x = x0 - 0.5 * f->dx;
	f->origin_y = y0 - 0.5 * f->dy;
	f->origin_x = isfinite(f->origin_x) ? f->origin_x : NAN;
	f->origin_y = isfinite(f->origin_y) ? f->origin_y : NAN;
	if ((err = read_wall_sides(f)))
		return err;
	/* the optional CF grid mapping variable /crs of a georeferenced run */
	if (H5Lexists(in->file, "crs", H5P_DEFAULT) > 0) {
		hid_t crs = H5Oopen(in->file, "crs", H5P_DEFAULT);
		if (crs >= 0) {
			err = attr_text(in, crs, "crs_wkt", &f->crs_wkt);
			H5Oclose(crs);
		}
	}
	return err;
}

void ss_snapshot_file_close(struct ss_snapshot_file *f)
{
	if (f->h5) {
		var_close(&f->h5->height);
		var_close(&f->h5->cell_type);
		h5in_close(&f->h5->in);
		free(f->h5);
	}
	free(f->time);
	free(f->name);
	free(f->crs_wkt);
	memset(f, 0, sizeof *f);
}

static int file_open(struct ss_snapshot_file *f, const char *name, const void *data,
                     size_t size)
{
	memset(f, 0, sizeof *f);
	f->origin_x = f->origin_y = NAN;
	f->name = strdup(name);
	f->h5 = calloc(1, sizeof *f->h5);
	if (!f->name || !f->h5) {
		ss_snapshot_file_close(f);
		return ss_error_fail("out of memory");
	}
	f->h5->height.d = f->h5->cell_type.d = f->h5->in.file = -1;
	int err = h5in_open(&f->h5->in, f->name, data, size);
	if (!err)
		err = check_definition(f);
	if (err)
		ss_snapshot_file_close(f);
	return err;
}

int ss_snapshot_file_open(struct ss_snapshot_file *f, const char *path)
{
	return file_open(f, path, NULL, 0);
}

int ss_snapshot_file_open_image(struct ss_snapshot_file *f, const char *name,
                                const void *data, size_t size)
{
	static const char none;
	return file_open(f, name, size ? data : &none, size);
}

int ss_snapshot_file_block_rows(const struct ss_snapshot_file *f)
{
	/* whole chunks, so that each chunk is read once */
	long long rows = BLOCK_BYTES / (8ll * f->nx);
	rows = rows < SS_SNAPSHOT_CHUNK_SIDE ? SS_SNAPSHOT_CHUNK_SIDE
	                                     : rows / SS_SNAPSHOT_CHUNK_SIDE * SS_SNAPSHOT_CHUNK_SIDE;
	return rows > f->ny ? f->ny : (int)rows;
}

static void check_rows(const struct ss_snapshot_file *f, int j0, int rows)
{
	if (j0 < 0 || rows < 1 || rows > f->ny - j0)
		SS_BUG("rows %d .. %d of a grid of %d rows", j0, j0 + rows - 1, f->ny);
}

/* Walls are stored as NaN (the _FillValue, snapshot_write.c) and held at
 * 0 m by the stepper: give them 0 m again, so that a restart, a frame or a
 * DEM read from the file sees what the run had; so are cells without data
 * (read as walls), and a DEM read from the file has them as nodata, whose
 * value is 0 (dem.h).  A NaN anywhere else is left for the caller's checks
 * to find. */
static int walls_to_zero(struct ss_snapshot_file *f, int j0, int rows, double *out)
{
	const size_t n = (size_t)rows * (size_t)f->nx;
	size_t k = 0;
	while (k < n && !isnan(out[k]))
		k++;
	if (k == n)
		return SS_OK;
	uint8_t *types = ss_alloc(n, 1, "cell type rows");
	if (!types)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_cell_types(f, j0, rows, types);
	for (; k < n && !err; k++)
		if (types[k] == SS_CELL_WALL && isnan(out[k]))
			out[k] = 0.0;
	ss_free(types);
	return err;
}

int ss_snapshot_file_read_rows(struct ss_snapshot_file *f, long long t, int j0, int rows,
                               double *out)
{
	check_rows(f, j0, rows);
	if (t < 0 || t >= f->count)
		SS_BUG("snapshot %lld of %lld", t, f->count);
	const hsize_t start[3] = {(hsize_t)t, (hsize_t)j0, 0};
	const hsize_t count[3] = {1, (hsize_t)rows, (hsize_t)f->nx};
	char what[96];
	snprintf(what, sizeof what, "snapshot %lld of /height, rows %d .. %d", t, j0,
	         j0 + rows - 1);
	int err;
	#pragma omp critical(ss_snapshot_hdf5)
	{
		quiet_hdf5();
		err = var_read(&f->h5->in, &f->h5->height, start, count, H5T_NATIVE_DOUBLE, out,
		               what);
	}
	return err ? err : walls_to_zero(f, j0, rows, out);
}

int ss_snapshot_file_read_cell_flags(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out)
{
	check_rows(f, j0, rows);
	const hsize_t start[2] = {(hsize_t)j0, 0}, count[2] = {(hsize_t)rows, (hsize_t)f->nx};
	char what[96];
	snprintf(what, sizeof what, "/cell_type, rows %d .. %d", j0, j0 + rows - 1);
	int err;
	#pragma omp critical(ss_snapshot_hdf5)
	{
		quiet_hdf5();
		err = var_read(&f->h5->in, &f->h5->cell_type, start, count, H5T_NATIVE_UINT8, out,
		               what);
	}
	const size_t n = (size_t)rows * (size_t)f->nx;
	for (size_t k = 0; k < n && !err; k++)
		if (out[k] > SS_SNAPSHOT_CELL_NODATA)
			err = damaged(&f->h5->in, "/cell_type holds %d at column %zu, row %zu (from the "
			              "south): expected 0 (flow), 1 (wall), 2 (open) or 3 (no data)",
			              out[k], k % (size_t)f->nx + 1, j0 + k / (size_t)f->nx + 1);
	return err;
}

/* A cell without data is a wall to every reader but the renderer's: the
 * stepper held it as one (or as open, which left it at the open level),
 * and its height is stored as NaN like a wall's. */
int ss_snapshot_file_read_cell_types(struct ss_snapshot_file *f, int j0, int rows,
                                     uint8_t *out)
{
	const int err = ss_snapshot_file_read_cell_flags(f, j0, rows, out);
	const size_t n = (size_t)rows * (size_t)f->nx;
	for (size_t k = 0; k < n && !err; k++)
		if (out[k] == SS_SNAPSHOT_CELL_NODATA)
			out[k] = SS_CELL_WALL;
	return err;
}

/* Snapshot t as a new array (nx * ny, south row first; ss_free). */
static int read_snapshot(struct ss_snapshot_file *f, long long t, double **out)
{
	*out = ss_alloc((size_t)f->nx * (size_t)f->ny, sizeof **out, "snapshot heights");
	if (!*out)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_rows(f, t, 0, f->ny, *out);
	if (err) {
		ss_free(*out);
		*out = NULL;
	}
	return err;
}

/* ---- info: the summary ----------------------------------------------- */

/* Count the cell types a block of rows at a time. */
static int count_cells(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	const int block = ss_snapshot_file_block_rows(f);
	uint8_t *types = ss_alloc((size_t)block * (size_t)f->nx, 1, "cell type rows");
	if (!types)
		return SS_ERR_FAIL;
	int err = SS_OK;
	for (int j0 = 0; j0 < f->ny && !err; j0 += block) {
		const int rows = f->ny - j0 < block ? f->ny - j0 : block;
		err = ss_snapshot_file_read_cell_flags(f, j0, rows, types);
		for (size_t k = 0; k < (size_t)rows * (size_t)f->nx && !err; k++) {
			sum->flow_cells += types[k] == SS_CELL_FLOW;
			sum->wall_cells += types[k] == SS_CELL_WALL;
			sum->open_cells += types[k] == SS_CELL_OPEN;
			sum->nodata_cells += types[k] == SS_SNAPSHOT_CELL_NODATA;
		}
	}
	ss_free(types);
	return err;
}

/* The diagnostic series into sum->diag. */
static int read_diagnostics(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	const long long n = f->count;
	double *col = malloc((size_t)(n ? n : 1) * sizeof *col);
	if (!col)
		return ss_error_fail("out of memory");
	int err = SS_OK;
	for (int k = 0; k < SS_SNAPSHOT_DIAG_COUNT && !err; k++) {
		struct var v;
		const int opened = var_open(&f->h5->in, ss_snapshot_diag_name(k), &v);
		var_close(&v);
		if (opened < 0) {   /* damaged: said so already (read_series would again) */
			err = opened;
			break;
		}
		if (k == SS_SNAPSHOT_DIAG_EVALUATIONS && opened == VAR_MISSING) {
			/* written before RKL2: one evaluation per step */
			for (long long m = 0; m < n; m++)
				sum->diag[m].evaluations = sum->diag[m].steps;
			continue;
		}
		err = read_series(&f->h5->in, ss_snapshot_diag_name(k), n, col);
		for (long long m = 0; m < n && !err; m++)
			*ss_snapshot_diag_field(&sum->diag[m], k) = col[m];
	}
	free(col);
	return err;
}

int ss_snapshot_file_summary(struct ss_snapshot_file *f, struct ss_snapshot_summary *sum)
{
	memset(sum, 0, sizeof *sum);
	const struct h5in *in = &f->h5->in;
	sum->nx = f->nx;
	sum->ny = f->ny;
	sum->count = f->count;
	sum->dx = f->dx;
	sum->dy = f->dy;
	sum->origin_x = f->origin_x;
	sum->origin_y = f->origin_y;
	int err;
	if ((err = attr_string(in, in->file, "source", sum->source, sizeof sum->source)) ||
	    (err = attr_string(in, in->file, "closure", sum->closure, sizeof sum->closure)) ||
	    (err = attr_string(in, in->file, "integrator", sum->integrator,
	                       sizeof sum->integrator)) ||
	    (err = attr_string(in, in->file, "title", sum->title, sizeof sum->title)))
		return err;
	sum->repose_angle_deg = attr_double(in->file, "repose_angle_deg");
	sum->nu = attr_double(in->file, "nu");
	sum->gamma = attr_double(in->file, "gamma");

	const size_t n = (size_t)(f->count ? f->count : 1);
	sum->time = malloc(n * sizeof *sum->time);
	sum->diag = calloc(n, sizeof *sum->diag);
	if (!sum->time || !sum->diag)
		err = ss_error_fail("out of memory");
	else
		memcpy(sum->time, f->time, (size_t)f->count * sizeof *sum->time);
	if (!err)
		err = read_diagnostics(f, sum);
	if (!err)
		err = count_cells(f, sum);
	if (err)
		ss_snapshot_summary_release(sum);
	return err;
}

/* Open path, read its summary (sum) or restart information (r), close it. */
static int read_path(const char *path, struct ss_snapshot_summary *sum,
                     struct ss_restart_info *r)
{
	struct ss_snapshot_file f;
	if (sum)
		memset(sum, 0, sizeof *sum);
	if (r)
		memset(r, 0, sizeof *r);
	int err = ss_snapshot_file_open(&f, path);
	if (!err)
		err = sum ? ss_snapshot_file_summary(&f, sum) : ss_snapshot_file_restart(&f, r);
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_summary(const char *path, struct ss_snapshot_summary *sum)
{
	return read_path(path, sum, NULL);
}

void ss_snapshot_summary_release(struct ss_snapshot_summary *sum)
{
	free(sum->time);
	free(sum->diag);
	sum->time = NULL;
	sum->diag = NULL;
}

/* ---- restarts -------------------------------------------------------- */

void ss_restart_info_release(struct ss_restart_info *r)
{
	free(r->case_text);
	free(r->case_path);
	free(r->case_overrides);
	ss_free(r->height);
	memset(r, 0, sizeof *r);
}

/* The case a restart continues: its text, path and --set values. */
static int read_case(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	const struct h5in *in = &f->h5->in;
	int err;
	if ((err = attr_text(in, in->file, "case", &r->case_text)) ||
	    (err = attr_text(in, in->file, "title", &r->case_path)) ||
	    (err = attr_text(in, in->file, "case_overrides", &r->case_overrides)))
		return err;
	if (!r->case_text || !r->case_path || !r->case_overrides || !*r->case_text)
		return ss_error_input("cannot restart from '%s': it does not hold the case it was "
		                      "run from (written by sandslide run?)", f->name);
	return SS_OK;
}

/* The restart state of the last snapshot, checked. */
static int read_state(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	const struct h5in *in = &f->h5->in;
	double v[SS_SNAPSHOT_RESTART_VALUES] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN};
	/* the last snapshot's by its parity; one restart_state in older files */
	const char *name = ss_snapshot_restart_attribute(f->count - 1);
	if (H5Aexists(in->file, name) <= 0)
		name = "restart_state";
	if (attr_doubles(in->file, name, SS_SNAPSHOT_RESTART_VALUES, v) &&
	    !attr_doubles(in->file, name, SS_SNAPSHOT_RESTART_VALUES_OLD, v)) {
		/* before RKL2: Euler's evaluations are its steps */
		v[5] = v[0];
		v[6] = INFINITY;
	}
	/* the counts are stored as doubles: below 2^63 to be ones; the
	 * super-step limit is a positive time or infinity */
	if (!(v[0] >= 0.0 && v[0] < 0x1p63) || !(v[5] >= 0.0 && v[5] < 0x1p63) ||
	    !(v[6] > 0.0) || !isfinite(v[1] + v[2] + v[3] + v[4]))
		return ss_error_input("cannot restart from '%s': its restart state is missing or "
		                      "damaged (written by an older sandslide?)", f->name);
	r->state.steps = (long long)v[0];
	r->state.inflow.sum = v[1];
	r->state.inflow.carry = v[2];
	r->state.outflow.sum = v[3];
	r->state.outflow.carry = v[4];
	r->state.evaluations = (long long)v[5];
	r->state.rkl2_tau = v[6];
	return SS_OK;
}

/* Rows first_row .. first_row + rows - 1 of snapshot t as a new array
 * (south row first; ss_free); rows < 0: every row, 0: none. */
static int read_snapshot_rows(struct ss_snapshot_file *f, long long t, long long first_row,
                              int rows, double **out)
{
	if (rows < 0)
		return read_snapshot(f, t, out);
	if (rows == 0)
		return SS_OK;
	if (first_row < 0 || first_row + rows > f->ny)
		return ss_error_input("cannot restart from '%s': its snapshots have %d rows, not "
		                      "the %lld this grid needs", f->name, f->ny, first_row + rows);
	*out = ss_alloc((size_t)f->nx * (size_t)rows, sizeof **out, "snapshot heights");
	if (!*out)
		return SS_ERR_FAIL;
	const int err = ss_snapshot_file_read_rows(f, t, (int)first_row, rows, *out);
	if (err) {
		ss_free(*out);
		*out = NULL;
	}
	return err;
}

/* The last snapshot (its rows first_row .. + rows - 1, all for rows < 0)
 * with its restart state, and with the case when with_case. */
static int read_last(struct ss_snapshot_file *f, struct ss_restart_info *r, int with_case,
                     long long first_row, int rows)
{
	memset(r, 0, sizeof *r);
	r->count = f->count;
	r->nx = f->nx;
	r->ny = f->ny;
	r->first_row = rows < 0 ? 0 : first_row;
	r->rows = rows < 0 ? f->ny : rows;
	if (f->count < 1)
		return ss_error_input("cannot restart from '%s': it holds no snapshot", f->name);
	r->time = f->time[f->count - 1];
	int err = with_case ? read_case(f, r) : SS_OK;
	if (!err)
		err = read_state(f, r);
	if (!err)
		err = read_snapshot_rows(f, f->count - 1, first_row, rows, &r->height);
	if (err)
		ss_restart_info_release(r);
	return err;
}

int ss_snapshot_file_restart(struct ss_snapshot_file *f, struct ss_restart_info *r)
{
	return read_last(f, r, 1, 0, -1);
}

/* Open path, read_last, close. */
static int read_last_of(const char *path, struct ss_restart_info *r, int with_case,
                        long long first_row, int rows)
{
	struct ss_snapshot_file f;
	memset(r, 0, sizeof *r);
	int err = ss_snapshot_file_open(&f, path);
	if (!err)
		err = read_last(&f, r, with_case, first_row, rows);
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_last_state(const char *path, struct ss_restart_info *r)
{
	return read_last_of(path, r, 0, 0, -1);
}

int ss_snapshot_read_last_rows(const char *path, long long first_row, int rows,
                               struct ss_restart_info *r)
{
	return read_last_of(path, r, 0, first_row, rows);
}

int ss_snapshot_read_restart(const char *path, struct ss_restart_info *r)
{
	return read_path(path, NULL, r);
}

int ss_snapshot_read_restart_case(const char *path, struct ss_restart_info *r)
{
	return read_last_of(path, r, 1, 0, 0);
}

/* ---- a 2-D field of any file ----------------------------------------- */

/* Snapshot index (negative: from the end) of a (time, y, x) v, or the
 * (y, x) v, as a new array. */
static int read_field_var(const struct h5in *in, const struct var *v, long long index,
                          int *nx, int *ny, double **values)
{
	hsize_t dims[3] = {1, 0, 0};
	memcpy(v->rank == 3 ? dims : dims + 1, v->dims, (size_t)v->rank * sizeof *dims);
	if ((v->rank != 2 && v->rank != 3) || dims[0] < 1 || dims[1] < 1 || dims[2] < 1 ||
	    dims[1] > SS_SNAPSHOT_MAX_SIDE || dims[2] > SS_SNAPSHOT_MAX_SIDE)
		return ss_error_input("'%s:/%s' is not a (y, x) or non-empty (time, y, x) variable",
		                      in->name, v->name);
	const long long t = index < 0 ? (long long)dims[0] + index : index;
	if (t < 0 || t >= (long long)dims[0])
		return ss_error_input("'%s:/%s' has %llu snapshots: index %lld is out of range",
		                      in->name, v->name, (unsigned long long)dims[0], index);
	*ny = (int)dims[1];
	*nx = (int)dims[2];
	*values = ss_alloc((size_t)dims[1] * dims[2], sizeof(double), "input heights");
	if (!*values)
		return SS_ERR_FAIL;
	const hsize_t start[3] = {(hsize_t)t, 0, 0}, count[3] = {1, dims[1], dims[2]};
	char what[300];
	snprintf(what, sizeof what, "/%s", v->name);
	const int skip = 3 - v->rank;   /* (y, x): no time */
	const int err = var_read(in, v, start + skip, count + skip, H5T_NATIVE_DOUBLE, *values,
	                         what);
	if (err) {
		ss_free(*values);
		*values = NULL;
	}
	return err;
}

/* Snapshot index of /height of a sandslide file. */
static int read_snapshot_field(const char *path, long long index, int *nx, int *ny,
                               double **values)
{
	struct ss_snapshot_file f;
	int err = ss_snapshot_file_open(&f, path);
	const long long t = index < 0 ? f.count + index : index;
	if (!err && (t < 0 || t >= f.count))
		err = ss_error_input("'%s' has %lld snapshots: index %lld is out of range", path,
		                     f.count, index);
	if (!err && !(err = read_snapshot(&f, t, values))) {
		*nx = f.nx;
		*ny = f.ny;
	}
	ss_snapshot_file_close(&f);
	return err;
}

int ss_snapshot_read_field(const char *path, const char *dataset, long long index,
                           int *nx, int *ny, double **values)
{
	*values = NULL;
	if (!dataset || !*dataset)
		return read_snapshot_field(path, index, nx, ny, values);
	struct h5in in;
	int err = h5in_open(&in, path, NULL, 0);
	struct var v = {.d = -1};
	if (!err)
		err = var_open(&in, dataset, &v);
	if (err == VAR_MISSING)
		err = ss_error_input("'%s' has no dataset '%s'", path, dataset);
	else if (err == VAR_NOT_NUMBERS)
		err = ss_error_input("'%s:%s' is not a (y, x) or non-empty (time, y, x) variable "
		                     "of numbers", path, dataset);
	if (!err)
		err = read_field_var(&in, &v, index, nx, ny, values);
	var_close(&v);
	h5in_close(&in);
	return err;
}

/* ---- a series of heights of any file ---------------------------------- */

void ss_height_series_release(struct ss_height_series *s)
{
	ss_free(s->time);
	ss_free(s->height);
	memset(s, 0, sizeof *s);
	s->dx = s->dy = s->origin_x = s->origin_y = NAN;
}

/* "'obs.h5' is not a height series: ..., the layout it needs" */
static int not_series(const struct h5in *in, const char *why)
{
	return ss_error_input("'%s' is not a height series: %s (expected /time (time) in s and "
	                      "/height (time, y, x) in m, doc/output.md)", in->name, why);
}

/*
 * The optional cell centres name (/x or /y) of n cells into *d and
 * *origin: the spacing and the corner, NAN without them.  They must be
 * finite, increasing and evenly spaced, as a grid's are: a /y from north
 * to south would flip every snapshot without a word.
 */
static int read_centres(const struct h5in *in, const char *name, int n, double *d,
                        double *origin)
{
	struct var v;
	*d = *origin = NAN;
	int err = var_open(in, name, &v);
	if (err == VAR_MISSING)
		return SS_OK;
	if (err > 0 || (!err && (v.rank != 1 || v.dims[0] != (hsize_t)n))) {
		var_close(&v);
		return ss_error_input("'%s': /%s is not %d numbers, one per %s of /height", in->name,
		                      name, n, name[0] == 'x' ? "column" : "row");
	}
	double *c = err ? NULL : ss_alloc((size_t)n, sizeof *c, "cell centres");
	if (!err && !c)
		err = SS_ERR_FAIL;
	const hsize_t start = 0, count = (hsize_t)n;
	if (!err)
		err = var_read(in, &v, &start, &count, H5T_NATIVE_DOUBLE, c, name);
	var_close(&v);
	if (!err && n >= 2) {
		const double step = c[1] - c[0];
		if (!(step > 0.0) || !isfinite(step))
			err = ss_error_input("'%s': /%s does not increase (%s[0] = %g, %s[1] = %g): "
			                     "cell centres in m, %s", in->name, name, name, c[0], name,
			                     c[1], name[0] == 'x' ? "west to east"
			                                          : "south to north (row 0 the south row)");
		for (int k = 2; k < n && !err; k++) {
			const double want = c[0] + k * step;
			if (!isfinite(c[k]) || fabs(c[k] - want) > 1e-6 * step + 1e-12 * fabs(want))
				err = ss_error_input("'%s': /%s is not increasing evenly (%s %d is %g, "
				                     "%g expected): cell centres in m, %s", in->name,
				                     name, name, k, c[k], want,
				                     name[0] == 'x' ? "west to east"
				                                    : "south to north (row 0 the south row)");
		}
		*d = step;
	}
	if (!err && !isfinite(c[0]))
		err = ss_error_input("'%s': /%s[0] is %g: cell centres in m", in->name, name, c[0]);
	if (!err)
		*origin = c[0];     /* a centre: the caller takes half a cell off */
	ss_free(c);
	return err;
}

/* The cell size along name (/x or /y) and the corner: from the centres,
 * else (one cell, or none given) the root attribute of a sandslide file. */
static int series_geometry(const struct h5in *in, const char *name, int n, double *d,
                           double *origin)
{
	double first;
	const int err = read_centres(in, name, n, d, &first);
	if (err)
		return err;
	if (isnan(*d)) {
		const double a = attr_double(in->file, name[0] == 'x' ? "dx" : "dy");
		*d = a > 0.0 && isfinite(a) ? a : NAN;
	}
	*origin = first - 0.5 * *d;
	if (!isfinite(*origin))
		*origin = NAN;
	return SS_OK;
}

/* /cell_type, when the file has one: its walls and cells without data
 * as NaN in every snapshot. */
static int series_walls(const struct h5in *in, struct ss_height_series *s)
{
	struct var v;
	int err = var_open(in, "cell_type", &v);
	if (err == VAR_MISSING)
		return SS_OK;
	if (err > 0 || (!err && (v.rank != 2 || v.dims[0] != (hsize_t)s->ny ||
	                         v.dims[1] != (hsize_t)s->nx))) {
		var_close(&v);
		return ss_error_input("'%s': /cell_type is not %d x %d numbers (y, x) as /height's "
		                      "snapshots", in->name, s->nx, s->ny);
	}
	const size_t cells = (size_t)s->nx * (size_t)s->ny;
	uint8_t *types = err ? NULL : ss_alloc(cells, 1, "cell types");
	if (!err && !types)
		err = SS_ERR_FAIL;
	const hsize_t start[2] = {0, 0}, count[2] = {(hsize_t)s->ny, (hsize_t)s->nx};
	if (!err)
		err = var_read(in, &v, start, count, H5T_NATIVE_UINT8, types, "/cell_type");
	var_close(&v);
	for (size_t k = 0; k < cells && !err; k++) {
		if (types[k] > SS_SNAPSHOT_CELL_NODATA)
			err = ss_error_input("'%s': /cell_type holds %d at column %zu, row %zu (from "
			                     "the south): expected 0 (flow), 1 (wall), 2 (open) or 3 "
			                     "(no data)", in->name, types[k], k % (size_t)s->nx + 1,
			                     k / (size_t)s->nx + 1);
		if (types[k] != SS_CELL_WALL && types[k] != SS_SNAPSHOT_CELL_NODATA)
			continue;
		for (long long t = 0; t < s->count; t++)
			s->height[(size_t)t * cells + k] = NAN;
	}
	ss_free(types);
	return err;
}

/* /time and /height: their sizes, then (memory allowing) their values. */
static int series_values(const struct h5in *in, struct ss_height_series *s)
{
	struct var h, t;
	int err = var_open(in, "height", &h);
	if (err > 0 || (!err && h.rank != 3)) {
		var_close(&h);
		return not_series(in, err == VAR_MISSING ? "no /height"
		                                         : "/height is not (time, y, x) numbers");
	}
	if (err)
		return err;
	if ((err = var_open(in, "time", &t)) > 0 || (!err && t.rank != 1)) {
		var_close(&h);
		var_close(&t);
		return not_series(in, err == VAR_MISSING ? "no /time" : "/time is not (time) numbers");
	}
	const hsize_t *hd = h.dims;
	char d[96];
	/* a sandslide output killed while it wrote a snapshot has one more
	 * /height than /time (doc/output.md#written-as-the-run-goes): /time
	 * counts the complete ones */
	if (!err && t.dims[0] != hd[0] && t.dims[0] + 1 != hd[0]) {
		char why[96];
		snprintf(why, sizeof why, "/time has %llu values, /height %llu snapshots",
		         (unsigned long long)t.dims[0], (unsigned long long)hd[0]);
		err = not_series(in, why);
	}
	else if (!err && (hd[1] < 1 || hd[2] < 1 || hd[1] > SS_SNAPSHOT_MAX_SIDE ||
	                  hd[2] > SS_SNAPSHOT_MAX_SIDE))
		err = ss_error_input("'%s': /height is %s (time, y, x): expected 1 to %d cells a "
		                     "side", in->name, format_dims(3, hd, d, sizeof d),
		                     SS_SNAPSHOT_MAX_SIDE);
	s->count = (long long)(err ? hd[0] : t.dims[0]);
	s->ny = (int)hd[1];
	s->nx = (int)hd[2];
	const size_t cells = (size_t)s->nx * (size_t)s->ny;
	/* the file has been found to hold them; memory need not */
	const double need = 8.0 * (double)s->count * ((double)cells + 1.0);
	const double have = ss_memory_available_bytes();
	if (!err && s->count > 0 && (need > (double)SIZE_MAX / 2 || (have > 0.0 && need > have))) {
		char b[32], a[32];
		err = ss_error_input("'%s' holds %lld snapshots of %d x %d cells: they need %s of "
		                     "memory, more than the %s available", in->name, s->count,
		                     s->nx, s->ny, ss_format_bytes(need, b),
		                     ss_format_bytes(have, a));
	}
	if (!err && s->count > 0) {
		s->time = ss_alloc((size_t)s->count, sizeof *s->time, "observation times");
		s->height = s->time ? ss_alloc((size_t)s->count * cells, sizeof *s->height,
		                               "observed heights")
		                    : NULL;
		if (!s->height)
			err = SS_ERR_FAIL;
	}
	const hsize_t t0 = 0, tn = (hsize_t)s->count;
	if (!err && s->count > 0)
		err = var_read(in, &t, &t0, &tn, H5T_NATIVE_DOUBLE, s->time, "/time");
	for (long long k = 0; k < s->count && !err; k++) {
		const hsize_t start[3] = {(hsize_t)k, 0, 0}, count[3] = {1, hd[1], hd[2]};
		char what[64];
		snprintf(what, sizeof what, "snapshot %lld of /height", k);
		err = var_read(in, &h, start, count, H5T_NATIVE_DOUBLE,
		               s->height + (size_t)k * cells, what);
	}
	var_close(&t);
	var_close(&h);
	return err;
}

int ss_snapshot_read_height_series(const char *path, struct ss_height_series *s)
{
	memset(s, 0, sizeof *s);
	s->dx = s->dy = s->origin_x = s->origin_y = NAN;
	struct h5in in;
	int err = h5in_open(&in, path, NULL, 0);
	if (!err)
		err = series_values(&in, s);
	if (!err)
		err = series_geometry(&in, "x", s->nx, &s->dx, &s->origin_x);
	if (!err)
		err = series_geometry(&in, "y", s->ny, &s->dy, &s->origin_y);
	if (!err)
		err = series_walls(&in, s);
	h5in_close(&in);
	if (err)
		ss_height_series_release(s);
	return err;
}
