/*
 * output.h - checks of an output path, made before a command computes
 * anything, so that a long run does not end unable to write its result.
 */
#ifndef SANDSLIDE_OUTPUT_H
#define SANDSLIDE_OUTPUT_H

/* The folder of path must exist and be writable, and path must not be a
 * folder.  With default_folder (a default output such as out/NAME.h5) the
 * folder may be missing if the working folder is writable: it is made by
 * ss_output_make_folder when the writing starts.  SS_ERR_INPUT says why
 * not. */
int ss_output_check_folder(const char *path, int default_folder);

/* Make the folder of path if it is missing (one level); SS_ERR_FAIL says
 * why it cannot be. */
int ss_output_make_folder(const char *path);

#endif
