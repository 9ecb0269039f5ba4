/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * png_check.h - what libpng does not check before it reads a PNG.
 *
 * libpng allocates (and clears) a chunk's stated length before it reads the
 * chunk's data, and a reader takes a length over its limit (8 MB for
 * ancillary chunks) as a benign error, that is a warning (libpng 1.6.39,
 * Debian 12): a PNG of 150 bytes whose zTXt chunk claims 1.7 GB made it
 * allocate and clear 1.7 GB before failing at the end of the file (found by
 * tests/fuzz/fuzz_png.c and fuzz_mask.c).  The mask reader (shape.c) and the
 * heightmap reader (dem_png.c) therefore walk the chunk headers first.
 */
#ifndef SANDSLIDE_PNG_CHECK_H
#define SANDSLIDE_PNG_CHECK_H

#include <stdio.h>

/*
 * SS_OK when the data of every chunk of the PNG open in f fits in the file
 * (or the file's size is unknown); otherwise -1 with the chunk's type
 * (printable, '?' for other bytes) and stated length.  Chunks are counted
 * from byte 8, after the signature; f is left where it was.  Prints nothing.
 */
int ss_png_check_chunks(FILE *f, char type[5], unsigned long *length);

#endif
