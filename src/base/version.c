/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * version.c - the version the Makefile gives (VERSION), compiled into the
 * library rather than the headers, so that a program linked against the
 * shared library reports the one it runs with.
 */
#include "sandslide/version.h"

const char *ss_version(void)
{
	return SS_VERSION;
}
