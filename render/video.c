/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * video.c - frames to a video with ffmpeg, when it is installed.
 *
 * ffmpeg is found on PATH and started directly (posix_spawn, no shell, so
 * no quoting of file names).  H.264 in yuv420p, the format every player
 * takes; yuv420p needs even sizes, so odd pictures get one padding row or
 * column.  The exact number of frames is passed, so frames left in the
 * folder by an earlier, longer render are not taken.  The video is written
 * under a temporary name and renamed when ffmpeg succeeds.
 */
#include "internal.h"

#include <errno.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sandslide/error.h"

extern char **environ;

/* The first executable `name` on PATH into out; -1 if there is none. */
static int find_on_path(const char *name, char *out, size_t size)
{
	const char *path = getenv("PATH");
	if (!path || !*path)
		path = "/usr/bin:/bin";
	for (const char *p = path;; p++) {
		const size_t len = strcspn(p, ":");
		snprintf(out, size, "%.*s/%s", len ? (int)len : 1, len ? p : ".", name);
		struct stat sb;
		if (stat(out, &sb) == 0 && S_ISREG(sb.st_mode) && access(out, X_OK) == 0)
			return 0;
		p += len;
		if (!*p)
			return -1;
	}
}

/* ffmpeg's image-sequence pattern for dir: a '%' in the folder's name
 * must be doubled. */
static void frame_pattern(const char *dir, char *out, size_t size)
{
	size_t k = 0;
	for (const char *c = dir; *c && k + 2 < size; c++) {
		if (*c == '%')
			out[k++] = '%';
		out[k++] = *c;
	}
	out[k] = '\0';
	const int slash = k && out[k - 1] == '/';
	snprintf(out + k, size - k, "%sframe_%%05d.png", slash ? "" : "/");
}

/* "a/b.mp4" -> "a/b.partial.mp4": ffmpeg picks the container from the
 * extension, so the temporary name keeps it. */
static void partial_name(const char *video, char *out, size_t size)
{
	const char *slash = strrchr(video, '/'), *dot = strrchr(video, '.');
	if (dot && (!slash || dot > slash + 1))
		snprintf(out, size, "%.*s.partial%s", (int)(dot - video), video, dot);
	else
		snprintf(out, size, "%s.partial.mp4", video);
}

static int has_mp4_container(const char *video)
{
	const char *dot = strrchr(video, '.');
	return !dot || !strcmp(dot, ".mp4") || !strcmp(dot, ".mov") || !strcmp(dot, ".m4v");
}

/* A video of a few frames at 24 per second is over before it is seen (21
 * frames: 0.9 s): fewer frames play slower, a quarter of them per second,
 * down to one, so that the video lasts 4 s or more; from 96 frames on,
 * film speed. */
int ss_render_fps_for(long long frames)
{
	const long long fps = frames / 4;
	return fps < 1 ? 1 : fps > 24 ? 24 : (int)fps;
}

int ss_render_ffmpeg_found(void)
{
	char ffmpeg[4096];
	return find_on_path("ffmpeg", ffmpeg, sizeof ffmpeg) == 0;
}

int ss_render_video(const char *dir, long long count, int fps, const char *video,
                    enum ss_render_video_made *made)
{
	char ffmpeg[4096];
	*made = SS_RENDER_VIDEO_NO_FFMPEG;
	if (find_on_path("ffmpeg", ffmpeg, sizeof ffmpeg))
		return SS_OK;
	char pattern[8400], tmp[4200], rate[16], frames[32];
	frame_pattern(dir, pattern, sizeof pattern);
	partial_name(video, tmp, sizeof tmp);
	snprintf(rate, sizeof rate, "%d", fps);
	snprintf(frames, sizeof frames, "%lld", count);
	const char *argv[32];
	int n = 0;
	const char *fixed[] = {"ffmpeg", "-nostdin", "-hide_banner", "-loglevel", "error", "-y",
	                       "-framerate", rate, "-start_number", "0", "-i", pattern,
	                       "-frames:v", frames, "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
	                       "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"};
	for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; k++)
		argv[n++] = fixed[k];
	if (has_mp4_container(tmp)) {   /* index up front: plays while it downloads */
		argv[n++] = "-movflags";
		argv[n++] = "+faststart";
	}
	argv[n++] = tmp;
	argv[n] = NULL;

	fflush(stdout);
	fflush(stderr);
	pid_t pid;
	int rc = posix_spawn(&pid, ffmpeg, NULL, NULL, (char *const *)argv, environ);
	if (rc != 0)
		return ss_error_fail("cannot start '%s': %s", ffmpeg, strerror(rc));
	int status;
	while (waitpid(pid, &status, 0) < 0)
		if (errno != EINTR) {
			remove(tmp);
			return ss_error_fail("lost track of ffmpeg: %s", strerror(errno));
		}
	if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
		remove(tmp);
		if (WIFEXITED(status))
			return ss_error_fail("ffmpeg failed (exit status %d) making '%s' from the frames "
			                     "in '%s'", WEXITSTATUS(status), video, dir);
		return ss_error_fail("ffmpeg was stopped by signal %d making '%s'", WTERMSIG(status),
		                     video);
	}
	if (rename(tmp, video) != 0) {
		const int e = errno;
		remove(tmp);
		return ss_error_fail("cannot rename '%s' to '%s': %s", tmp, video, strerror(e));
	}
	*made = SS_RENDER_VIDEO_MADE;
	return SS_OK;
}
