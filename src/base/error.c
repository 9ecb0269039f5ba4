/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * error.c - one message per error, programmer-error aborts, checked
 * allocation.  See error.h for the conventions.
 */
#include "sandslide/error.h"

#include "sandslide/comm.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* The last message of the calling thread: calls on different data may run
 * at the same time in different threads (the Python module), and each
 * caller reads its own call's message.  In a distributed run only rank 0
 * prints, and ss_comm_agree has it printed there when another rank failed
 * first (comm.h).  OpenMP's worker threads report nothing: errors are
 * raised outside the parallel regions. */
static _Thread_local char last_message[SS_ERROR_MESSAGE_MAX];
/* Set by a program that shows the messages itself (the Python module):
 * once, before any call, for the whole process. */
static int quiet;

void ss_error_set_quiet(int on)
{
	quiet = on != 0;
}

static int vreport(int status, const char *fmt, va_list ap)
{
	vsnprintf(last_message, sizeof last_message, fmt, ap);
	if (ss_comm_rank() == 0 && !quiet)
		ss_error_print(last_message);
	return status;
}

void ss_error_print(const char *message)
{
	fflush(stdout);
	fprintf(stderr, "sandslide: %s\n", message);
}

const char *ss_error_last_message(void)
{
	return last_message;
}

int ss_error_adopt(int status, const char *message)
{
	if (message != last_message)
		snprintf(last_message, sizeof last_message, "%s", message);
	return status;
}

int ss_error_input(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = vreport(SS_ERR_INPUT, fmt, ap);
	va_end(ap);
	return r;
}

int ss_error_fail(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int r = vreport(SS_ERR_FAIL, fmt, ap);
	va_end(ap);
	return r;
}

int ss_error_input_at(const char *where, const char *fmt, ...)
{
	char msg[1024];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	if (where && *where)
		return ss_error_input("%s: %s", where, msg);
	return ss_error_input("%s", msg);
}

int ss_status_exit_code(int status)
{
	if (status == SS_OK)
		return 0;
	return status == SS_ERR_INPUT ? 2 : 1;
}

_Noreturn void ss_bug_at(const char *file, int line, const char *fmt, ...)
{
	va_list ap;
	fflush(stdout);
	fprintf(stderr, "sandslide: BUG at %s:%d: ", file, line);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fputc('\n', stderr);
	abort();
}

void *ss_alloc(size_t count, size_t size, const char *what)
{
	char buf[32];
	if (size != 0 && count > (SIZE_MAX - 63) / size) {
		ss_error_fail("cannot allocate %s: size overflows", what);
		return NULL;
	}
	size_t bytes = count * size;
	bytes = (bytes + 63) / 64 * 64;   /* aligned_alloc wants a multiple */
	if (bytes == 0)
		bytes = 64;
	void *p = aligned_alloc(64, bytes);
	if (!p) {
		ss_error_fail("cannot allocate %s: %s", what,
		              ss_format_bytes((double)bytes, buf));
		return NULL;
	}
	memset(p, 0, bytes);
	return p;
}

void ss_free(void *p)
{
	free(p);
}

const char *ss_format_bytes(double bytes, char buf[32])
{
	static const char *const unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
	int u = 0;
	while (bytes >= 1024.0 && u < 5) {
		bytes /= 1024.0;
		u++;
	}
	snprintf(buf, 32, u ? "%.1f %s" : "%.0f %s", bytes, unit[u]);
	return buf;
}

double ss_memory_peak_bytes(void)
{
	struct rusage u;
	return getrusage(RUSAGE_SELF, &u) == 0 ? (double)u.ru_maxrss * 1024.0 : 0.0;
}

double ss_memory_available_bytes(void)
{
	FILE *f = fopen("/proc/meminfo", "r");
	if (!f)
		return 0.0;
	char line[256];
	double kib = 0.0;
	while (fgets(line, sizeof line, f)) {
		if (sscanf(line, "MemAvailable: %lf kB", &kib) == 1)
			break;
	}
	fclose(f);
	return kib * 1024.0;
}
