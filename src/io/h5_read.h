/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * h5_read.h - what the summaries (h5_summary.c: `info`'s summary, the
 * restart state) read of an open sandslide file through the snapshot
 * reader (h5_read.c) besides snapshot.h.  Internal, with HDF5 types: only
 * the io/h5 files include it (make check-layering).
 */
#ifndef SANDSLIDE_H5_READ_H
#define SANDSLIDE_H5_READ_H

#include "io/h5_checked.h"

/* The HDF5 side of a struct ss_snapshot_file (its member h5). */
struct ss_snapshot_file_h5 {
	struct ss_h5_file in;
	struct ss_h5_var height;    /* (time, y, x) */
	struct ss_h5_var cell_type; /* (y, x) */
	struct ss_h5_var moving;    /* (time, y, x) of hysteresis; d < 0: none */
};

/* The first n values of the 1-D series name into out; SS_ERR_INPUT naming
 * the series if it is missing or does not have n or n + 1 (the last one
 * unfinished: doc/output.md#written-as-the-run-goes) values. */
int ss_h5_read_series(const struct ss_h5_file *in, const char *name, long long n, double *out);

#endif
