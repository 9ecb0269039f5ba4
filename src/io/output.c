/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * output.c - checks and claims of an output path (output.h), shared by run
 * and relax.
 */
#include "io/output.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

#include "sandslide/comm.h"
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

double ss_output_free_bytes(const char *path)
{
	char dir[4096];
	struct statvfs fs;
	folder_of(path, dir, sizeof dir);
	if (statvfs(dir, &fs) != 0 && statvfs(".", &fs) != 0)
		return -1.0;
	return (double)fs.f_bavail * (double)fs.f_frsize;
}

static int rank0_make_folder(const char *path)
{
	char dir[4096];
	folder_of(path, dir, sizeof dir);
	if (mkdir(dir, 0777) != 0 && errno != EEXIST)
		return ss_error_fail("cannot create output folder '%s': %s", dir, strerror(errno));
	return SS_OK;
}

static int rank0_check_absent(const char *path, int force, const char *hint)
{
	struct stat sb;
	if (!force && stat(path, &sb) == 0)
		return ss_error_input("'%s' exists: give --force to replace it%s", path,
		                      hint ? hint : "");
	return SS_OK;
}

/* ---- claims ------------------------------------------------------------ */

struct ss_output_claim {
	int fd;                 /* holds the flock */
	char *lock_path;
};

/* "dir/name.h5" and "dir/name.h5.partial" -> "dir/.name.h5.lock" */
static char *lock_path_of(const char *path)
{
	const char *slash = strrchr(path, '/');
	const int dir = slash ? (int)(slash - path) + 1 : 0;
	const char *name = path + dir;
	int len = (int)strlen(name);
	static const char partial[] = ".partial";
	const int plen = (int)sizeof partial - 1;
	if (len > plen && strcmp(name + len - plen, partial) == 0)
		len -= plen;
	const size_t size = strlen(path) + 8;
	char *lock = malloc(size);
	if (lock)
		snprintf(lock, size, "%.*s.%.*s.lock", dir, path, len, name);
	return lock;
}

/* The process that holds the lock file open in fd, as its text says; a run
 * that has just taken the lock writes it a moment later, so wait up to
 * 0.2 s for it (0: unknown). */
static long holder_of(int fd)
{
	for (int tries = 0; tries < 20; tries++) {
		char text[32] = "";
		const ssize_t n = pread(fd, text, sizeof text - 1, 0);
		const long pid = n > 0 ? strtol(text, NULL, 10) : 0;
		if (pid > 0)
			return pid;
		nanosleep(&(struct timespec){0, 10000000}, NULL);
	}
	return 0;
}

/* 1 when fd is still the file at path (a run that ends unlinks its lock
 * file: one opened just before that is no longer the lock). */
static int still_at(int fd, const char *path)
{
	struct stat a, b;
	return fstat(fd, &a) == 0 && stat(path, &b) == 0 && a.st_dev == b.st_dev &&
	       a.st_ino == b.st_ino;
}

/* Our process number into the lock file, for the message of a refused run
 * (which is all that a failed write costs). */
static int write_holder(int fd)
{
	char pid[32];
	const int n = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
	return ftruncate(fd, 0) == 0 && pwrite(fd, pid, (size_t)n, 0) == n ? 0 : -1;
}

static int refuse_held(const char *path, const char *lock, long holder)
{
	char who[48] = "";
	if (holder > 0)
		snprintf(who, sizeof who, " (process %ld)", holder);
	return ss_error_input("'%s' is being written by another sandslide run%s, which holds "
	                      "'%s': wait for it to end, or choose another output", path, who,
	                      lock);
}

static int rank0_claim(struct ss_output_claim **out, const char *path)
{
	*out = NULL;
	struct ss_output_claim *c = calloc(1, sizeof *c);
	if (!c || !(c->lock_path = lock_path_of(path))) {
		free(c);
		return ss_error_fail("out of memory");
	}
	int err = SS_OK;
	for (int attempt = 0;; attempt++) {
		c->fd = open(c->lock_path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
		if (c->fd < 0) {
			err = ss_error_fail("cannot create the lock file '%s': %s", c->lock_path,
			                    strerror(errno));
			break;
		}
		if (flock(c->fd, LOCK_EX | LOCK_NB) != 0) {
			err = errno == EWOULDBLOCK
			      ? refuse_held(path, c->lock_path, holder_of(c->fd))
			      : ss_error_fail("cannot lock '%s': %s", c->lock_path, strerror(errno));
			close(c->fd);
			break;
		}
		if (still_at(c->fd, c->lock_path)) {
			(void)write_holder(c->fd);
			*out = c;
			return SS_OK;
		}
		close(c->fd);
		if (attempt == 100) {
			err = ss_error_fail("cannot claim '%s': its lock file '%s' keeps being "
			                    "replaced", path, c->lock_path);
			break;
		}
	}
	free(c->lock_path);
	free(c);
	return err;
}

void ss_output_release(struct ss_output_claim *c)
{
	if (!c)
		return;
	/* unlinked while still locked, so that no other run can take this file
	 * as its lock and a waiting one sees it is gone (still_at) */
	unlink(c->lock_path);
	close(c->fd);
	free(c->lock_path);
	free(c);
}

/* In a run of several ranks (comm.h) rank 0 alone makes the folder, checks
 * and claims the output, and every rank learns the outcome. */
int ss_output_make_folder(const char *path)
{
	return ss_comm_agree(ss_comm_rank() == 0 ? rank0_make_folder(path) : SS_OK);
}

int ss_output_check_absent(const char *path, int force, const char *hint)
{
	return ss_comm_agree(ss_comm_rank() == 0 ? rank0_check_absent(path, force, hint) : SS_OK);
}

int ss_output_claim(struct ss_output_claim **out, const char *path)
{
	*out = NULL;
	return ss_comm_agree(ss_comm_rank() == 0 ? rank0_claim(out, path) : SS_OK);
}

int ss_output_write_text(const char *path, const char *text)
{
	const size_t n = strlen(path) + 16;
	char *tmp = malloc(n);
	if (!tmp)
		return ss_error_fail("out of memory");
	snprintf(tmp, n, "%s.tmpXXXXXX", path);
	const int fd = mkstemp(tmp);
	FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
	int bad = !f;
	if (f) {
		const size_t len = strlen(text);
		bad = fwrite(text, 1, len, f) != len;
		bad = fclose(f) != 0 || bad;
	} else if (fd >= 0) {
		close(fd);
	}
	const int e = errno;
	/* mkstemp made it 0600: the mode a plain fopen would give */
	const mode_t mask = umask(0);
	umask(mask);
	if (!bad && chmod(tmp, 0666 & ~mask) == 0 && rename(tmp, path) == 0) {
		free(tmp);
		return SS_OK;
	}
	const int why = bad ? e : errno;
	if (fd >= 0)
		remove(tmp);
	free(tmp);
	return ss_error_fail("cannot write '%s': %s", path, strerror(why));
}
