/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * integrator.c - integrators by name, and auto's rule (integrator.h).
 */
#include "sandslide/integrator.h"

#include <string.h>

static const char *const integrator_names[] = {
	[SS_INTEGRATOR_EULER] = "euler", [SS_INTEGRATOR_RKL2] = "rkl2",
	[SS_INTEGRATOR_AUTO] = "auto",
};

const char *ss_integrator_name(enum ss_integrator integrator)
{
	return integrator_names[integrator];
}

int ss_integrator_parse(const char *name, enum ss_integrator *out)
{
	for (int k = 0; k < 3; k++) {
		if (strcmp(name, integrator_names[k]) == 0) {
			*out = (enum ss_integrator)k;
			return 0;
		}
	}
	return -1;
}

enum ss_integrator ss_integrator_resolve(enum ss_integrator asked, int has_bedrock,
                                         int relaxing)
{
	if (asked != SS_INTEGRATOR_AUTO)
		return asked;
	return has_bedrock || relaxing ? SS_INTEGRATOR_EULER : SS_INTEGRATOR_RKL2;
}

static const char *const rest_names[] = {
	[SS_REST_OFF] = "off", [SS_REST_CHEBYSHEV] = "chebyshev",
};

const char *ss_rest_mode_name(enum ss_rest_mode rest)
{
	return rest_names[rest];
}

int ss_rest_mode_parse(const char *name, enum ss_rest_mode *out)
{
	for (int k = 0; k < 2; k++) {
		if (strcmp(name, rest_names[k]) == 0) {
			*out = (enum ss_rest_mode)k;
			return 0;
		}
	}
	return -1;
}
