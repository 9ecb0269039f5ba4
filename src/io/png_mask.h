/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * png_mask.h - a case region's mask image (doc/case-file.md): any PNG,
 * read as 8-bit grey; a pixel that is not black is inside the region.
 */
#ifndef SANDSLIDE_IO_PNG_MASK_H
#define SANDSLIDE_IO_PNG_MASK_H

#include <stdint.h>

/* The PNG at path as nx x ny 8-bit grey pixels, top row first, into
 * *pixels (ss_free it).  SS_ERR_INPUT, naming where (the case's file:line)
 * and the path, when it cannot be opened, is not a readable PNG (its chunk
 * lengths are checked first: png_check.h) or has another size; SS_ERR_FAIL
 * out of memory. */
int ss_png_read_mask(const char *path, const char *where, long long nx, long long ny,
                     uint8_t **pixels);

#endif
