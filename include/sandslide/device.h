/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * device.h - where a command computes: the processor, or an NVIDIA GPU in
 * a build with CUDA (make CUDA=1; doc/gpu.md).
 *
 * `--device cpu|cuda[:N]` on run, relax, bench and fit, `device=` in
 * Python, `device` in a BMI config's [bmi] section.  cuda means cuda:0.
 * Asking for a GPU in a build without CUDA, or for one the machine does
 * not have, is bad input (SS_ERR_INPUT) with the reason, before any work.
 */
#ifndef SANDSLIDE_DEVICE_H
#define SANDSLIDE_DEVICE_H

#include <stddef.h>

enum ss_device_kind {
	SS_DEVICE_CPU = 0,     /* the default: OpenMP threads on this node */
	SS_DEVICE_CUDA = 1,    /* an NVIDIA GPU by the CUDA runtime's number */
};

struct ss_device {
	enum ss_device_kind kind;
	int index;             /* the GPU's number (cuda:N); 0 on the CPU */
};

/* "cpu", "cuda", "cuda:N" (N from 0 to 63) into *d; -1 for anything else,
 * *d unchanged. */
int ss_device_parse(const char *text, struct ss_device *d);

/* "cpu" or "cuda:N" into buf (at least 16 bytes); returns buf. */
char *ss_device_format(const struct ss_device *d, char *buf, size_t size);

/* 1 when this build can run on GPUs (make CUDA=1), else 0. */
int ss_device_cuda_built(void);

/* SS_OK when d can run here: the CPU always; a GPU when this build has
 * CUDA, the driver answers and device N exists.  Else SS_ERR_INPUT, its
 * message `what` ("--device cuda:1") and the reason: no CUDA in this
 * build, no driver or no GPU (the runtime's words), or how many GPUs
 * there are. */
int ss_device_check(const struct ss_device *d, const char *what);

/* The devices this program sees, one per line ("cpu: avx512, 2 threads",
 * "cuda:0: NVIDIA H200, 139.8 GiB, sm_90", or why there is none), into
 * buf; returns the length it needed (as snprintf). */
int ss_device_list(char *buf, size_t size);

#endif
