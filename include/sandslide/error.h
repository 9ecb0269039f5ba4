/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * error.h - status codes, the one error printer, programmer-error aborts and
 * checked aligned allocation.
 *
 * Library functions return an int status: SS_OK, SS_ERR_INPUT (the user gave
 * something we cannot accept: the CLI exits 2) or SS_ERR_FAIL (a failure while
 * running: the CLI exits 1).  The function that detects the error prints one
 * message through ss_error_*() and returns the code; callers only propagate
 * it, so every error is printed exactly once (git usage.c).
 */
#ifndef SANDSLIDE_ERROR_H
#define SANDSLIDE_ERROR_H

#include <stddef.h>

enum ss_status {
	SS_OK = 0,
	SS_ERR_FAIL = -1,   /* runtime failure: exit status 1 */
	SS_ERR_INPUT = -2,  /* bad usage or bad input: exit status 2 */
};

/* Print "sandslide: <message>" on stderr (after flushing stdout) and return
 * SS_ERR_INPUT or SS_ERR_FAIL respectively. */
int ss_error_input(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
int ss_error_fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* ss_error_input with a location first: "sandslide: <where>: <message>"
 * (no location when where is NULL or ""), e.g. where = "case.ini:12". */
int ss_error_input_at(const char *where, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

/* Exit status of the CLI for a status code: 0, 1 or 2. */
int ss_status_exit_code(int status);

/* Longest message kept, bytes (a longer one is cut). */
#define SS_ERROR_MESSAGE_MAX 8192
/* Print "sandslide: <message>" to stderr (stdout flushed first). */
void ss_error_print(const char *message);
/* The last message the calling thread reported ("" for none): calls in
 * different threads each read their own.  In a run of several ranks only
 * rank 0 prints as it reports; comm.h says how the message of another rank
 * reaches it. */
const char *ss_error_last_message(void);
/* Make message the calling thread's last, without printing it, and return
 * status: for a message reported (and printed) in another thread, an
 * OpenMP worker, handed to the thread that returns the status. */
int ss_error_adopt(int status, const char *message);
/* on != 0: report without printing, for a program that shows
 * ss_error_last_message() its own way (the Python module raises it as an
 * exception).  Off by default. */
void ss_error_set_quiet(int on);

_Noreturn void ss_bug_at(const char *file, int line, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
#define SS_BUG(...) ss_bug_at(__FILE__, __LINE__, __VA_ARGS__)

/* 64-byte aligned, zero-filled array of count elements of size bytes.  On
 * overflow or exhaustion prints "cannot allocate <what>: N bytes" and returns
 * NULL; the caller propagates SS_ERR_FAIL.  Free with ss_free(). */
void *ss_alloc(size_t count, size_t size, const char *what);
void ss_free(void *p);

/* Human-readable byte count ("1.5 GiB") into buf; returns buf. */
const char *ss_format_bytes(double bytes, char buf[32]);

/* Memory this machine can give a new allocation now (MemAvailable), in
 * bytes; 0 when unknown. */
double ss_memory_available_bytes(void);

/* The largest resident memory this process has had (getrusage's
 * ru_maxrss), in bytes; 0 when unknown. */
double ss_memory_peak_bytes(void);

#endif
