/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * device.c - a device's name read and written (device.h); whether one is
 * there is src/cuda/device.c's to say.
 */
#include "sandslide/device.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { DEVICE_INDEX_MAX = 63 };

int ss_device_parse(const char *text, struct ss_device *d)
{
	if (!text)
		return -1;
	if (strcmp(text, "cpu") == 0) {
		d->kind = SS_DEVICE_CPU;
		d->index = 0;
		return 0;
	}
	if (strncmp(text, "cuda", 4) != 0)
		return -1;
	int index = 0;
	if (text[4] == ':') {
		/* digits only: no sign, no space, no leading zeros but "0" */
		const char *p = text + 5;
		if (p[0] < '0' || p[0] > '9' || (p[0] == '0' && p[1] != '\0') || strlen(p) > 2)
			return -1;
		for (; *p; p++) {
			if (*p < '0' || *p > '9')
				return -1;
			index = 10 * index + (*p - '0');
		}
		if (index > DEVICE_INDEX_MAX)
			return -1;
	} else if (text[4] != '\0') {
		return -1;
	}
	d->kind = SS_DEVICE_CUDA;
	d->index = index;
	return 0;
}

char *ss_device_format(const struct ss_device *d, char *buf, size_t size)
{
	if (d->kind == SS_DEVICE_CUDA)
		snprintf(buf, size, "cuda:%d", d->index);
	else
		snprintf(buf, size, "cpu");
	return buf;
}
