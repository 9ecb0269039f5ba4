/*
 * strings.h - the few string helpers more than one tier needs.
 */
#ifndef SANDSLIDE_BASE_STRINGS_H
#define SANDSLIDE_BASE_STRINGS_H

/* The n strings of v joined into one new string (free it), separator
 * between them, and after the last one too when terminate is set; NULL
 * (after a message) when out of memory. */
char *ss_strings_join(const char *const *v, int n, const char *separator, int terminate);

#endif
