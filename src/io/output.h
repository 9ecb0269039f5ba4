/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * output.h - what a command checks and claims before it writes an output:
 * its folder (before anything is computed, so that a long run does not end
 * unable to write its result), that it is not already there unless it may
 * be replaced, and that no other run is writing it.
 *
 * One run owns its output.  A claim is an exclusive flock(2) on a lock file
 * beside the output, "DIR/.NAME.lock", taken without waiting: a second run
 * aimed at the same output is refused at once, --force or not, and of two
 * runs started together exactly one gets it.  NAME is the output's name
 * without a trailing ".partial", so a run aimed at another run's temporary
 * file is refused as well.  The kernel drops the lock when the process ends,
 * however it ends; a lock file left by a killed run is taken over.  The
 * claim comes after every input check, so bad input leaves no lock file.
 */
#ifndef SANDSLIDE_IO_OUTPUT_H
#define SANDSLIDE_IO_OUTPUT_H

/* The folder of path must exist and be writable, and path must not be a
 * folder.  With default_folder (a default output such as out/NAME.h5) the
 * folder may be missing if the working folder is writable: it is made by
 * ss_output_make_folder when the writing starts.  SS_ERR_INPUT says why
 * not. */
int ss_output_check_folder(const char *path, int default_folder);

/* The bytes free to this user on the file system that will hold path (that
 * of its folder, or of the working folder while a default folder is still
 * to be made); a negative value when it cannot be told. */
double ss_output_free_bytes(const char *path);

/* Make the folder of path if it is missing (one level); SS_ERR_FAIL says
 * why it cannot be. */
int ss_output_make_folder(const char *path);

/* SS_ERR_INPUT when path exists and force is 0: "'PATH' exists: give
 * --force to replace it" followed by hint (may be NULL). */
int ss_output_check_absent(const char *path, int force, const char *hint);

/* The whole of text as the file path, written to a temporary file beside
 * it and renamed over it, so that a reader sees the old file or the new
 * one, never half of one.  SS_ERR_FAIL names the path and the reason. */
int ss_output_write_text(const char *path, const char *text);

struct ss_output_claim;

/* Claim path for this process (its folder must exist).  SS_ERR_INPUT when a
 * live run holds it, naming that process; SS_ERR_FAIL when the lock file
 * cannot be made. */
int ss_output_claim(struct ss_output_claim **out, const char *path);

/* Give the claim up and remove the lock file.  NULL is a no-op. */
void ss_output_release(struct ss_output_claim *claim);

#endif
