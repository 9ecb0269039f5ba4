/*
 * strings.c - string helpers (see strings.h).
 */
#include "base/strings.h"

#include <stdlib.h>
#include <string.h>

#include "sandslide/error.h"

char *ss_strings_join(const char *const *v, int n, const char *separator, int terminate)
{
	const size_t sep = strlen(separator);
	size_t len = 1;
	for (int k = 0; k < n; k++)
		len += strlen(v[k]) + sep;
	char *s = malloc(len), *end = s;
	if (!s) {
		ss_error_fail("out of memory");
		return NULL;
	}
	for (int k = 0; k < n; k++) {
		const size_t m = strlen(v[k]);
		memcpy(end, v[k], m);
		end += m;
		if (k + 1 < n || terminate) {
			memcpy(end, separator, sep);
			end += sep;
		}
	}
	*end = '\0';
	return s;
}
