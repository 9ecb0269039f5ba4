/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * png_check.c - chunk lengths of a PNG checked against its file's size
 * before libpng reads it (see png_check.h).
 */
#include "io/png_check.h"

#include <ctype.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "sandslide/error.h"

int ss_png_check_chunks(FILE *f, char type[5], unsigned long *length)
{
	struct stat st;
	const off_t start = ftello(f);
	if (start < 0 || fstat(fileno(f), &st) || !S_ISREG(st.st_mode))
		return SS_OK;
	const off_t size = st.st_size;
	int err = SS_OK;
	unsigned char head[8];   /* length (big-endian), type */
	for (off_t at = 8; at + 8 <= size;) {
		if (fseeko(f, at, SEEK_SET) || fread(head, 1, 8, f) != 8)
			break;
		const unsigned long n = (unsigned long)head[0] << 24 | (unsigned long)head[1] << 16 |
		                        (unsigned long)head[2] << 8 | head[3];
		if ((off_t)n > size - at - 8) {
			for (int k = 0; k < 4; k++)
				type[k] = isalpha(head[4 + k]) ? (char)head[4 + k] : '?';
			type[4] = '\0';
			*length = n;
			err = -1;
			break;
		}
		at += 12 + (off_t)n;   /* length, type, data, CRC */
	}
	fseeko(f, start, SEEK_SET);
	return err;
}
