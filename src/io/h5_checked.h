/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_checked.h - the HDF5 calls the files of src/io/h5_* share
 * (h5_checked.c): the reader (h5_read.c, h5_summary.c) opens files, reads
 * attributes and datasets through them, every size a file states checked
 * against the file before anything of that size is allocated; the writer
 * (h5_write.c) writes its attributes through them.  Internal: it holds
 * HDF5 types, so only the io/h5 files include it (make check-layering).
 *
 * Every function that fails prints one message (error.h) and returns its
 * status, unless it says otherwise.
 */
#ifndef SANDSLIDE_H5_CHECKED_H
#define SANDSLIDE_H5_CHECKED_H

#include <stddef.h>

#include <hdf5.h>

/* Turn HDF5's own error printing off for the calling thread: each failure
 * prints one sandslide message instead.  Per thread, so every entry point
 * calls it, and so does each OpenMP thread that reads. */
void ss_h5_quiet(void);

/* ---- a file open for reading ------------------------------------------ */

/* A file open for reading: the checks need its size. */
struct ss_h5_file {
	hid_t file;
	const char *name;           /* for messages */
	double bytes;               /* size of the file or image */
};

/* Open name (a path, or an image of size bytes in memory when data is not
 * NULL) read-only, quietly: SS_ERR_INPUT when it is missing, not HDF5,
 * damaged or locked by a writer; SS_ERR_FAIL when HDF5 cannot be set up to
 * read an image.  The file's size is kept for the checks. */
int ss_h5_file_open(struct ss_h5_file *in, const char *name, const void *data, size_t size);
void ss_h5_file_close(struct ss_h5_file *in);

/* "'name' is damaged: ...": SS_ERR_INPUT. */
int ss_h5_damaged(const struct ss_h5_file *in, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

/* A read of what that failed: damage (a checksum, a chunk past the end),
 * with what HDF5's error stack says. */
int ss_h5_read_failed(const struct ss_h5_file *in, const char *what);

/* "8 x 16 x 20" into out. */
const char *ss_h5_format_dims(int rank, const hsize_t *dims, char *out, size_t size);

/* ---- attributes ---------------------------------------------------------- */

/*
 * A string attribute (one value, fixed or variable length) as a new
 * string in *out (free()); *out NULL if absent, not one string or
 * unreadable.  SS_ERR_INPUT if its stated length cannot be in the file.
 */
int ss_h5_attr_read_text(const struct ss_h5_file *in, hid_t obj, const char *name, char **out);

/* ss_h5_attr_read_text into a buffer ("" if absent). */
int ss_h5_attr_read_string(const struct ss_h5_file *in, hid_t obj, const char *name,
                           char *out, size_t size);

/* n numbers (at most SS_SNAPSHOT_RESTART_VALUES) of attribute name into v;
 * -1 (v untouched, nothing printed) if absent or not n numbers. */
int ss_h5_attr_read_doubles(hid_t obj, const char *name, int n, double *v);

/* One number of attribute name; NAN if absent or not one number. */
double ss_h5_attr_read_double(hid_t obj, const char *name);

/* Attribute name of obj, created: a scalar UTF-8 string, or n float64
 * (a scalar when n is 1); 0, or -1 on failure with nothing printed (the
 * writer says which file). */
int ss_h5_attr_write_string(hid_t obj, const char *name, const char *value);
int ss_h5_attr_write_doubles(hid_t obj, const char *name, const double *v, hsize_t n);

/* The n float64 of attribute name of obj: written over an existing one's
 * values, else created as by ss_h5_attr_write_doubles; 0 or -1, nothing
 * printed. */
int ss_h5_attr_update_doubles(hid_t obj, const char *name, const double *v, hsize_t n);

/* ---- datasets ------------------------------------------------------------ */

/* An open dataset of numbers, rank 1 to 3, and how it is stored. */
struct ss_h5_var {
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

enum { SS_H5_VAR_MISSING = 1, SS_H5_VAR_NOT_NUMBERS = 2 };

/*
 * Open dataset name as a var: SS_OK; SS_H5_VAR_MISSING (no such dataset)
 * or SS_H5_VAR_NOT_NUMBERS (not numbers of rank 1 to 3), with nothing
 * printed, for the caller to say what it needed; SS_ERR_INPUT if what it
 * claims cannot be in the file.  Close it in any case.
 */
int ss_h5_var_open(const struct ss_h5_file *in, const char *name, struct ss_h5_var *v);
void ss_h5_var_close(struct ss_h5_var *v);

/* Every chunk of the block start .. start + count - 1 is stored, inside
 * the file, and large enough for its values. */
int ss_h5_var_check_chunks(const struct ss_h5_file *in, const struct ss_h5_var *v,
                           const hsize_t *start, const hsize_t *count);

/* The block start .. start + count - 1 of v (rank values each) into out,
 * as mem_type, its chunks checked first; what names it in a message. */
int ss_h5_var_read(const struct ss_h5_file *in, const struct ss_h5_var *v,
                   const hsize_t *start, const hsize_t *count, hid_t mem_type, void *out,
                   const char *what);

#endif
