/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * version.h - the library's version, for a program that links it to report
 * or check (the command line's --version prints it).
 */
#ifndef SANDSLIDE_VERSION_H
#define SANDSLIDE_VERSION_H

/* "MAJOR.MINOR.PATCH" of the library this program runs with (the shared
 * library may be newer than the headers it was built against). */
const char *ss_version(void);

#endif
