/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * replay.c - runs a fuzz harness over files without libFuzzer, so any
 * compiler can replay the corpora and the regression inputs (`make
 * fuzz-replay`, part of `make test`).
 *
 *   fuzz_NAME-replay PATH...    each PATH a file or a folder of files
 *
 * A folder's files are fed in name order.  A harness reports a failure by
 * crashing (a sanitizer report or abort()), so reaching the end means every
 * input passed.
 */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz.h"

/* Under AddressSanitizer an allocation over 256 MB is an error, as it is
 * when fuzzing with -malloc_limit_mb=256: the inputs are a few KB, and a
 * reader must not allocate far more than its file could hold (a 4 KB PNG
 * holds at most 4 MB of pixels). */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
	return "max_allocation_size_mb=256";
}

static long inputs;
static size_t bytes;

static int run_file(const char *path)
{
	FILE *f = fopen(path, "rb");
	if (!f) {
		fprintf(stderr, "replay: cannot open '%s': %s\n", path, strerror(errno));
		return -1;
	}
	uint8_t *data = NULL;
	size_t size = 0, cap = 0;
	for (;;) {
		if (size == cap) {
			cap = cap ? 2 * cap : 4096;
			uint8_t *grown = realloc(data, cap);
			if (!grown) {
				fprintf(stderr, "replay: out of memory reading '%s'\n", path);
				free(data);
				fclose(f);
				return -1;
			}
			data = grown;
		}
		const size_t got = fread(data + size, 1, cap - size, f);
		size += got;
		if (got == 0)
			break;
	}
	const int bad = ferror(f);
	fclose(f);
	if (bad) {
		fprintf(stderr, "replay: cannot read '%s'\n", path);
		free(data);
		return -1;
	}
	/* an exactly sized copy, as libFuzzer gives, so that a read past the
	 * input is caught */
	uint8_t *input = malloc(size ? size : 1);
	if (!input) {
		free(data);
		return -1;
	}
	if (size)
		memcpy(input, data, size);
	free(data);
	if (getenv("SANDSLIDE_FUZZ_VERBOSE"))
		fprintf(stderr, "replay: %s (%zu bytes)\n", path, size);
	LLVMFuzzerTestOneInput(input, size);
	free(input);
	inputs++;
	bytes += size;
	return 0;
}

static int by_name(const struct dirent **a, const struct dirent **b)
{
	return strcmp((*a)->d_name, (*b)->d_name);
}

static int run_path(const char *path)
{
	struct stat st;
	if (stat(path, &st)) {
		fprintf(stderr, "replay: cannot open '%s': %s\n", path, strerror(errno));
		return -1;
	}
	if (!S_ISDIR(st.st_mode))
		return run_file(path);
	struct dirent **names;
	const int count = scandir(path, &names, NULL, by_name);
	if (count < 0) {
		fprintf(stderr, "replay: cannot list '%s': %s\n", path, strerror(errno));
		return -1;
	}
	int err = 0;
	for (int k = 0; k < count; k++) {
		char file[4096];
		snprintf(file, sizeof file, "%s/%s", path, names[k]->d_name);
		if (names[k]->d_name[0] != '.' && stat(file, &st) == 0 && S_ISREG(st.st_mode) &&
		    run_file(file))
			err = -1;
		free(names[k]);
	}
	free(names);
	return err;
}

int main(int argc, char **argv)
{
	if (argc < 2) {
		fprintf(stderr, "usage: %s PATH...  (files, or folders of files, to replay)\n",
		        argv[0]);
		return 2;
	}
	int err = 0;
	for (int a = 1; a < argc; a++)
		if (run_path(argv[a]))
			err = 1;
	printf("%s: %ld inputs, %zu bytes replayed\n", argv[0], inputs, bytes);
	return err;
}
