/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * batch_step.c - the test hook of the outflow batch (src/core/ledger.h:
 * on several ranks with open faces each rank keeps its faces' fluxes, and
 * the ranks fold them when ss_stepper_advance returns or the batch is
 * full), linked into a fourth sandslide, build/tests/sandslide-batch, and
 * never into the real one.
 *
 * The batch holds 4 MiB a rank: a test case of a few thousand evaluations
 * never fills it, so the fold before an evaluation that might not fit
 * would go untested.  This program is linked with
 * -Wl,--wrap=ss_stepper_prepare, so every stepper the library's commands
 * prepare (run, relax, the guard's fresh one) comes here first.  With
 * SANDSLIDE_TEST_OUTFLOW_BATCH_BYTES=N in the environment the ledger's
 * batch_bytes becomes N (a few kB fill it every few evaluations);
 * without it the program is sandslide.  The bytes change when the ranks
 * fold, never what they add up, so every output keeps its bits.
 */
#include <stdlib.h>

#include "core/ledger.h"
#include "sandslide/stepper.h"

int __real_ss_stepper_prepare(struct ss_stepper *st);
int __wrap_ss_stepper_prepare(struct ss_stepper *st);

int __wrap_ss_stepper_prepare(struct ss_stepper *st)
{
	const char *env = getenv("SANDSLIDE_TEST_OUTFLOW_BATCH_BYTES");
	if (env && *env)
		st->ledger->batch_bytes = (size_t)strtoull(env, NULL, 10);
	return __real_ss_stepper_prepare(st);
}
