/*
 * output.c - checks of an output path (output.h), shared by run and relax.
 */
#include "io/output.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sandslide/error.h"

/* The folder of path: "." for a bare name, "/" for a file in the root. */
static void folder_of(const char *path, char *dir, size_t size)
{
	const char *slash = strrchr(path, '/');
	if (slash)
		snprintf(dir, size, "%.*s", (int)(slash - path) + (slash == path), path);
	else
		snprintf(dir, size, ".");
}

int ss_output_check_folder(const char *path, int default_folder)
{
	char dir[4096];
	folder_of(path, dir, sizeof dir);
	struct stat sb;
	if (default_folder && stat(dir, &sb) != 0) {
		if (access(".", W_OK) != 0)
			return ss_error_input("cannot create output folder '%s': the working folder "
			                      "is not writable", dir);
		return SS_OK;
	}
	if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
		return ss_error_input("cannot write '%s': folder '%s' does not exist", path, dir);
	if (access(dir, W_OK) != 0)
		return ss_error_input("cannot write '%s': folder '%s' is not writable", path, dir);
	if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
		return ss_error_input("cannot write '%s': it is a folder", path);
	return SS_OK;
}

int ss_output_make_folder(const char *path)
{
	char dir[4096];
	folder_of(path, dir, sizeof dir);
	if (mkdir(dir, 0777) != 0 && errno != EEXIST)
		return ss_error_fail("cannot create output folder '%s': %s", dir, strerror(errno));
	return SS_OK;
}
