/* An MP4 from numbered PNG frames through ffmpeg (thorax/picture/movie.h). */
#include <errno.h>
#include <limits.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "thorax/picture/movie.h"

extern char **environ;

thx_status thx_movie_claim(thx_ctx *ctx, const char *path, thx_atomic_file *af)
{
    return thx_output_claim_in(ctx, path, THX_MOVIE_MARKER, strlen(THX_MOVIE_MARKER), THX_MOVIE_WINDOW, NULL, 0, af);
}

/* Runs ffmpeg on the frames (argv, no shell: any path works); its exit status, 127 if it cannot run. */
static int run_ffmpeg(int fps, int first, int count, const char *dir, const char *out)
{
    char rate[32], start[32], nframes[32], pattern[PATH_MAX + 32];
    snprintf(rate, sizeof rate, "%d", fps);
    snprintf(start, sizeof start, "%d", first);
    snprintf(nframes, sizeof nframes, "%d", count);
    snprintf(pattern, sizeof pattern, "%s/frame_%%05d.png", dir);
    /* the encoder's threads fixed (-threads 4): x264 picks its count from the cores it may use (one
       under mpirun's binding, two here, more elsewhere), records it in the stream, and its frame
       threads shape the rate control; fixed, the same frames give the same movie on any machine and
       any number of ranks */
    char *args[] = {"ffmpeg", "-nostdin", "-loglevel", "error", "-y", "-framerate", rate, "-start_number", start,
                    "-i", pattern, "-frames:v", nframes, "-c:v", "libx264", "-threads", "4", "-pix_fmt", "yuv420p", "-vf",
                    "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-metadata", "comment=" THX_MOVIE_MARKER, "-movflags", "+faststart",
                    "-f", "mp4", (char *)out, NULL};
    pid_t pid;
    if (posix_spawnp(&pid, "ffmpeg", NULL, NULL, args, environ) != 0) return 127;
    int status = 0;
    if (waitpid(pid, &status, 0) < 0) return 127;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

thx_status thx_movie_make(thx_ctx *ctx, thx_atomic_file *af, const char *dir, int first, int count, int fps)
{
    /* a fresh temporary name beside the movie (never a file that is there), moved in under the claim */
    char tmpm[PATH_MAX + 80];
    snprintf(tmpm, sizeof tmpm, "%s.tmpXXXXXX", af->path);
    int fd = mkstemp(tmpm);
    if (fd < 0) return thx_error(ctx, THX_EIO, "%s: cannot create a temporary file beside it: %s", af->path, strerror(errno));
    close(fd);
    int r = run_ffmpeg(fps, first, count, dir, tmpm);
    if (r != 0) {
        remove(tmpm);
        return thx_error(ctx, THX_EIO, "ffmpeg failed (exit %d) making %s%s", r, af->path,
                         r == 127 ? ": ffmpeg is not installed (Debian package ffmpeg)" : "");
    }
    return thx_output_place(ctx, af, tmpm);
}
