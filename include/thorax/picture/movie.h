/*
 * thorax/picture/movie.h — an MP4 (H.264) from numbered frames DIR/frame_%05d.png, through ffmpeg
 * (run as a program, argv without a shell). Used by thorax animate and by the viewer's recording.
 */
#ifndef THORAX_PICTURE_MOVIE_H
#define THORAX_PICTURE_MOVIE_H
#include "thorax/core/fileio.h"
#ifdef __cplusplus
extern "C" {
#endif

/* The movie's signature: its metadata comment, which +faststart puts in the header before the
 * frames' data, within the first THX_MOVIE_WINDOW bytes (thorax/core/fileio.h). */
#define THX_MOVIE_MARKER "thorax-movie"
#define THX_MOVIE_WINDOW (4u << 20)

/* Claims path for a movie before any frame is drawn: a file there that is not thorax's own movie
 * stops the run (thx_output_claim_in). */
thx_status thx_movie_claim(thx_ctx *ctx, const char *path, thx_atomic_file *af);
/* Runs ffmpeg on frames first .. first + count - 1 of dir at fps frames per second into a fresh
 * temporary file beside the claimed path, and moves it in under the claim. Errors name ffmpeg's
 * exit status, or that ffmpeg is not installed. */
thx_status thx_movie_make(thx_ctx *ctx, thx_atomic_file *af, const char *dir, int first, int count, int fps);

#ifdef __cplusplus
}
#endif
#endif
