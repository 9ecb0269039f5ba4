/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * cpu.h - which instruction-set path the kernel runs, chosen at run time.
 *
 * The library is built for the baseline instruction set of x86-64 (SSE2),
 * so that it runs on any x86-64 machine; the kernel's hot loops (the face
 * flux and the fast sweep, src/core/face.c and sweep_fast.c) are compiled
 * in two more copies, for AVX2 and for AVX-512, and the best copy this
 * processor runs is chosen when the library first needs one.  `make
 * NATIVE=1` builds the rest for the machine it is built on; the choice is
 * the same.
 *
 * The paths and their bits.  The AVX-512 path computes the reciprocal
 * square roots of a face as vrsqrt14pd refined by two Newton steps, the
 * generic and AVX2 paths as 1/sqrt (doc/model.md#the-face-function): the
 * AVX-512 path gives bits of its own, the generic and AVX2 paths the same
 * bits as each other.  Every other operation is the same in every path.
 * Each path gives the same bits for any thread count and tile size, in the
 * fast and the reference sweep.
 *
 * The environment variable SANDSLIDE_CPU chooses a path:
 *   unset, "" or "auto"   the best path this processor runs (the default)
 *   "generic"             the baseline path, on any processor
 *   "avx2"                AVX2; refused on a processor without it
 *   "avx512"              AVX-512 F, CD, VL, BW and DQ; refused on a
 *                         processor (or operating system) without them
 * A build for another processor than x86-64 has the generic path only.
 */
#ifndef SANDSLIDE_CPU_H
#define SANDSLIDE_CPU_H

enum ss_cpu_path {
	SS_CPU_GENERIC = 0,   /* baseline (x86-64: SSE2); faces by 1/sqrt */
	SS_CPU_AVX2 = 1,      /* AVX2; faces by 1/sqrt: the generic path's bits */
	SS_CPU_AVX512 = 2,    /* AVX-512; faces by vrsqrt14pd + 2 Newton steps */
};

/* 1 when this build has the path and this processor and its operating
 * system can run it. */
int ss_cpu_path_supported(enum ss_cpu_path path);

/* "generic", "avx2" or "avx512". */
const char *ss_cpu_path_name(enum ss_cpu_path path);

/* The path in use.  Until ss_cpu_init or ss_cpu_select chose one: the path
 * SANDSLIDE_CPU names if this processor runs it, else the best one it
 * runs.  Cheap enough to call for every row of faces. */
enum ss_cpu_path ss_cpu_path(void);

/* Use the path `name` from now on ("auto", "generic", "avx2" or "avx512";
 * NULL or "" is "auto"), whatever SANDSLIDE_CPU says: for programs and
 * tests that choose.  SS_ERR_INPUT, with a message, for an unknown name or
 * a path this processor cannot run; the path in use is then unchanged.
 * Not while a sweep runs: the faces of one sweep must take one path. */
int ss_cpu_select(const char *name);

/* The path SANDSLIDE_CPU names, checked: SS_ERR_INPUT, with a message
 * naming the variable, for an unknown value or a path this processor
 * cannot run.  Chooses once: after a path is in use (chosen by an earlier
 * call, by ss_cpu_select or by a first ss_cpu_path) it returns SS_OK and
 * changes nothing.  In a distributed run (comm.h) it is collective: every
 * rank calls it, a refusal on one is every rank's, and every rank takes
 * the lowest path any rank chose (generic < avx2 < avx512), so that ranks
 * on unlike processors give one path's bits.  The command line calls it on
 * every rank before any command; the stepper (ss_stepper_init) calls it in
 * a run of one process, for a program that did not. */
int ss_cpu_init(void);

#endif
