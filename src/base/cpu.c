/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * cpu.c - the processor check and the kernel path in use (see cpu.h).
 *
 * The path is one integer read for every row of faces by every thread, and
 * written once (or by ss_cpu_select between runs): a relaxed atomic, which
 * costs a plain load, so that a first use from several threads at once is
 * not a data race.
 */
#include "sandslide/cpu.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sandslide/comm.h"
#include "sandslide/error.h"

/* -1 until a path is chosen, then an enum ss_cpu_path */
static atomic_int path_in_use = -1;

int ss_cpu_path_supported(enum ss_cpu_path path)
{
	if (path == SS_CPU_GENERIC)
		return 1;
#if defined(SS_KERNEL_PATHS) && defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
	/* the processor's CPUID bits and, for AVX and AVX-512, the operating
	 * system's saving of the ymm, zmm and mask registers (XCR0): the
	 * compiler's run-time library checks both.  The features each copy
	 * is compiled with (Makefile, PATHFLAGS_*): AVX2 implies POPCNT to
	 * gcc, and every processor with AVX2 has it. */
	__builtin_cpu_init();
	const int avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
	if (path == SS_CPU_AVX2)
		return avx2;
	if (path == SS_CPU_AVX512)
		return avx2 && __builtin_cpu_supports("avx512f") &&
		       __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512vl") &&
		       __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq");
#endif
	return 0;
}

const char *ss_cpu_path_name(enum ss_cpu_path path)
{
	return path == SS_CPU_AVX512 ? "avx512" : path == SS_CPU_AVX2 ? "avx2" : "generic";
}

static enum ss_cpu_path best_path(void)
{
	return ss_cpu_path_supported(SS_CPU_AVX512) ? SS_CPU_AVX512
	     : ss_cpu_path_supported(SS_CPU_AVX2) ? SS_CPU_AVX2 : SS_CPU_GENERIC;
}

/* The path a name asks for into *path: 0, or -1 for an unknown name. */
static int path_of_name(const char *name, enum ss_cpu_path *path)
{
	if (!name || !*name || !strcmp(name, "auto"))
		*path = best_path();
	else if (!strcmp(name, "generic"))
		*path = SS_CPU_GENERIC;
	else if (!strcmp(name, "avx2"))
		*path = SS_CPU_AVX2;
	else if (!strcmp(name, "avx512"))
		*path = SS_CPU_AVX512;
	else
		return -1;
	return 0;
}

/* The paths this processor runs, "generic, avx2" */
static const char *supported_names(char *buf, size_t size)
{
	snprintf(buf, size, "generic%s%s", ss_cpu_path_supported(SS_CPU_AVX2) ? ", avx2" : "",
	         ss_cpu_path_supported(SS_CPU_AVX512) ? ", avx512" : "");
	return buf;
}

/* The path `name` asks for, checked; `what` names it in a message
 * ("SANDSLIDE_CPU=x" or "kernel path 'x'"). */
static int checked_path(const char *name, const char *what, enum ss_cpu_path *path)
{
	char names[64];
	if (path_of_name(name, path))
		return ss_error_input("%s: unknown kernel path: expected auto, generic, avx2 or "
		                      "avx512", what);
	if (!ss_cpu_path_supported(*path))
		return ss_error_input("%s: this processor (or this build) cannot run the %s path: "
		                      "it runs %s (or auto, the best of them)", what,
		                      ss_cpu_path_name(*path), supported_names(names, sizeof names));
	return SS_OK;
}

enum ss_cpu_path ss_cpu_path(void)
{
	int p = atomic_load_explicit(&path_in_use, memory_order_relaxed);
	if (p < 0) {
		/* first use before ss_cpu_init: SANDSLIDE_CPU if it names a path
		 * this processor runs, else the best one (every thread that gets
		 * here finds the same) */
		enum ss_cpu_path q;
		if (path_of_name(getenv("SANDSLIDE_CPU"), &q) || !ss_cpu_path_supported(q))
			q = best_path();
		p = (int)q;
		atomic_store_explicit(&path_in_use, p, memory_order_relaxed);
	}
	return (enum ss_cpu_path)p;
}

int ss_cpu_select(const char *name)
{
	char what[96];
	enum ss_cpu_path p;
	snprintf(what, sizeof what, "kernel path '%.60s'", name ? name : "");
	const int err = checked_path(name, what, &p);
	if (err)
		return err;
	atomic_store_explicit(&path_in_use, (int)p, memory_order_relaxed);
	return SS_OK;
}

int ss_cpu_init(void)
{
	if (atomic_load_explicit(&path_in_use, memory_order_relaxed) >= 0)
		return SS_OK;
	const char *env = getenv("SANDSLIDE_CPU");
	char what[96];
	enum ss_cpu_path p = SS_CPU_GENERIC;
	snprintf(what, sizeof what, "SANDSLIDE_CPU=%.60s", env ? env : "");
	/* a refusal on any rank is every rank's (and printed once) */
	const int err = ss_comm_agree(checked_path(env, what, &p));
	if (err)
		return err;
	if (ss_comm_size() > 1) {
		/* the lowest path of any rank, so that a job over unlike
		 * processors gives one path's bits: the paths are ordered, and a
		 * processor that runs one runs every lower one */
		double lowest = -(double)p, none = 0.0;
		ss_comm_reduce(&lowest, 1, &none, 0);
		p = (enum ss_cpu_path)(int)-lowest;
	}
	atomic_store_explicit(&path_in_use, (int)p, memory_order_relaxed);
	return SS_OK;
}
