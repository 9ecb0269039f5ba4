/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * integrator.c - integrators by name, and auto's rule (integrator.h).
 */
#include "sandslide/integrator.h"

#include "base/strings.h"

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
	const int k = ss_parse_name(name, integrator_names, 3);
	if (k >= 0)
		*out = (enum ss_integrator)k;
	return k < 0 ? -1 : 0;
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
	const int k = ss_parse_name(name, rest_names, 2);
	if (k >= 0)
		*out = (enum ss_rest_mode)k;
	return k < 0 ? -1 : 0;
}
