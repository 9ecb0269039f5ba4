/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * fuzz.h - what the fuzz harnesses (tests/fuzz/fuzz_*.c) share.
 *
 * Each harness defines LLVMFuzzerTestOneInput and is linked either with
 * libFuzzer (clang -fsanitize=fuzzer, `make fuzz`) or with replay.c, a
 * plain main() that feeds it the files of the corpus and regression
 * folders (`make fuzz-replay`, any compiler).
 *
 *   fuzz_temp_path(name)     name in a per-process temporary folder (made
 *                            on first use in $TMPDIR, else /dev/shm, else
 *                            /tmp; emptied and removed at exit), for the
 *                            readers that take a path
 *   fuzz_write_file(p, d, n) the input as that file
 *   fuzz_png_fix_crcs(d, n)  give every whole chunk of a PNG its right
 *                            CRC, so that mutations reach past libpng's
 *                            check (libpng itself is not instrumented)
 *   fuzz_quiet_begin/end()   library messages to /dev/null in between
 *                            (SANDSLIDE_FUZZ_VERBOSE=1 keeps them)
 *   FUZZ_CHECK(expr)         an invariant of a successful read: abort()
 *                            with file:line, which libFuzzer reports as a
 *                            crash
 *
 * Quieting swaps glibc's `stderr` FILE pointer, not file descriptor 2:
 * libFuzzer and the sanitizers keep writing their reports to descriptor 2.
 */
#ifndef SANDSLIDE_TESTS_FUZZ_H
#define SANDSLIDE_TESTS_FUZZ_H

#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FUZZ_CHECK(expr)                                                        \
	do {                                                                    \
		if (!(expr)) {                                                  \
			fuzz_quiet_end();                                       \
			fprintf(stderr, "fuzz: %s:%d: check failed: %s\n",      \
			        __FILE__, __LINE__, #expr);                     \
			abort();                                                \
		}                                                               \
	} while (0)

static char fuzz_dir[256];

static inline void fuzz_remove_dir(void)
{
	DIR *d = opendir(fuzz_dir);
	if (d) {
		char path[512];
		for (struct dirent *e; (e = readdir(d));) {
			if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
				snprintf(path, sizeof path, "%s/%s", fuzz_dir, e->d_name);
				unlink(path);
			}
		}
		closedir(d);
	}
	rmdir(fuzz_dir);
}

static inline const char *fuzz_temp_path(const char *name)
{
	static char path[2][512];
	static int turn;
	if (!fuzz_dir[0]) {
		const char *base = getenv("TMPDIR");
		struct stat st;
		if (!base || !*base)
			base = stat("/dev/shm", &st) == 0 && S_ISDIR(st.st_mode) &&
			       access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
		snprintf(fuzz_dir, sizeof fuzz_dir, "%s/sandslide-fuzz-XXXXXX", base);
		if (!mkdtemp(fuzz_dir)) {
			perror("fuzz: cannot create a temporary folder");
			abort();
		}
		atexit(fuzz_remove_dir);
	}
	turn ^= 1;
	snprintf(path[turn], sizeof path[turn], "%s/%s", fuzz_dir, name);
	return path[turn];
}

static inline void fuzz_write_file(const char *path, const uint8_t *data, size_t size)
{
	FILE *f = fopen(path, "wb");
	if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f)) {
		perror("fuzz: cannot write the input file");
		abort();
	}
}

static inline void fuzz_png_fix_crcs(uint8_t *data, size_t size)
{
	for (size_t at = 8; at + 12 <= size;) {
		const size_t n = (size_t)data[at] << 24 | (size_t)data[at + 1] << 16 |
		                 (size_t)data[at + 2] << 8 | data[at + 3];
		if (n > size - at - 12)
			break;
		uint32_t c = 0xffffffffu;   /* CRC-32 of type and data */
		for (size_t k = at + 4; k < at + 8 + n; k++) {
			c ^= data[k];
			for (int b = 0; b < 8; b++)
				c = c & 1 ? 0xedb88320u ^ (c >> 1) : c >> 1;
		}
		c ^= 0xffffffffu;
		data[at + 8 + n] = (uint8_t)(c >> 24);
		data[at + 9 + n] = (uint8_t)(c >> 16);
		data[at + 10 + n] = (uint8_t)(c >> 8);
		data[at + 11 + n] = (uint8_t)c;
		at += 12 + n;
	}
}

static FILE *fuzz_saved_stderr;

static inline void fuzz_quiet_begin(void)
{
	static FILE *null;
	static int verbose = -1;
	if (verbose < 0)
		verbose = getenv("SANDSLIDE_FUZZ_VERBOSE") != NULL;
	if (verbose || (!null && !(null = fopen("/dev/null", "w"))))
		return;
	fuzz_saved_stderr = stderr;
	stderr = null;
}

static inline void fuzz_quiet_end(void)
{
	if (fuzz_saved_stderr)
		stderr = fuzz_saved_stderr;
	fuzz_saved_stderr = NULL;
}

#endif
