/*
 * thorax/core/fileio.h — atomic file and directory output.
 *
 * Every file thorax writes goes first to a temporary name in the same
 * directory and is renamed over the target only when complete, so a failed
 * run leaves no partial output. Model and solution directories are built in
 * a temporary sibling directory and renamed as a whole (thx_outdir).
 */
#ifndef THORAX_FILEIO_H
#define THORAX_FILEIO_H

#include <stdio.h>
#include <sys/types.h>

#include "thorax/core/core.h"
typedef struct {
    FILE *f;            /* write here */
    char path[1024];    /* final name */
    char tmp[1040];     /* temporary name */
    int claimed;        /* opened by thx_atomic_open_output: the commit checks the claim */
    int existed;        /* ... and path existed then, as this file: */
    unsigned long long dev, ino;
} thx_atomic_file;

/* Opens a temporary file next to `path` for writing. */
thx_status thx_atomic_open(thx_ctx *ctx, const char *path, thx_atomic_file *af);
/* Flushes, checks for write errors, closes and renames over the final name. */
thx_status thx_atomic_commit(thx_ctx *ctx, thx_atomic_file *af);
/* Closes and removes the temporary file (safe after a failed commit or none). */
void thx_atomic_abort(thx_atomic_file *af);

/*
 * Single-file outputs a user names (-o FILE: contours, series, images,
 * exports, movies). An existing path is replaced only when it is a regular
 * file (never through a symbolic link, never a directory), not one of the
 * command's inputs, and empty or thorax's own output of the same kind: its first
 * 4096 bytes hold `marker` (marker_len bytes; every such writer puts its
 * marker there: "thorax-contours", "thorax-series", the .mat header text,
 * a PNG tEXt chunk, ...). Otherwise the command stops, before anything is
 * written, with a message saying what is there.
 *
 * Two commands writing the same file at once: if it was absent, the commit
 * links the finished file into place and fails if another got there first;
 * if it existed, the commit replaces it only if it is still the file the
 * claim saw. The loser exits with an error and leaves nothing behind.
 */
thx_status thx_atomic_open_output(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len,
                                  const char *const *inputs, size_t n_inputs, thx_atomic_file *af);
/* The claim alone (no temporary file): for writers that go through another library
 * (libpng, libmatio, ffmpeg) and commit by thx_output_place. */
thx_status thx_output_claim(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len,
                            const char *const *inputs, size_t n_inputs, thx_atomic_file *af);
/* The same with the signature looked for in the first `window` bytes (a movie's metadata). */
thx_status thx_output_claim_in(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len, size_t window,
                               const char *const *inputs, size_t n_inputs, thx_atomic_file *af);
/* Moves the finished temporary file tmp into af->path under the claim (rules above); tmp is
 * removed whatever happens. */
thx_status thx_output_place(thx_ctx *ctx, thx_atomic_file *af, const char *tmp);

/*
 * Directory outputs (a model, a solution). A directory is replaced only when it
 * is thorax's own output of the same kind: it holds `manifest` (model.json,
 * solution.json) with "format": `format`, and nothing that manifest does not
 * name (no other file, no folder, no link). It is never followed through a
 * symbolic link and never replaced when it holds an input of the command.
 * Otherwise the command stops with a message saying what is there, before
 * anything is written.
 *
 * Two commands writing the same directory at once: the claim records what
 * was there when the command started; the commit replaces it only if it is
 * still that (the same directory, or still absent), so the first to commit
 * wins whole and the other fails with nothing left behind.
 */
typedef struct {
    char dir[4096];
    char tmp[4200];          /* the temporary sibling the output is built in ("" until begun) */
    const char *manifest, *format;
    int existed;             /* dir existed when claimed */
    unsigned long long dev, ino; /* ... as this directory */
} thx_outdir;

/* Checks that dir may be written (above) by a command reading the files or
 * directories inputs[0..n_inputs-1] (NULL entries skipped) and records what
 * is there now. Nothing is created. */
thx_status thx_outdir_claim(thx_ctx *ctx, thx_outdir *od, const char *dir, const char *manifest, const char *format,
                            const char *const *inputs, size_t n_inputs);
/* Creates the temporary sibling directory od->tmp to write the output into. */
thx_status thx_outdir_begin(thx_ctx *ctx, thx_outdir *od);
/* Replaces (or creates) od->dir by od->tmp, if dir is still what the claim
 * saw and still thorax's own; else removes od->tmp and fails. */
thx_status thx_outdir_commit(thx_ctx *ctx, thx_outdir *od);
/* Removes od->tmp and everything in it, if begun. */
void thx_outdir_abort(thx_outdir *od);

/* count bytes of fd from offset off (off < 0: from where it stands, as a pipe is read) into p, retried
 * until all came: fewer only at the end of the file; -1 on an error (errno set). */
ssize_t thx_read_at(int fd, void *p, size_t count, off_t off);
/* The same into fresh memory whose pages are first asked for at once (thorax/core/pages.h); 1 when all
 * count bytes came, else 0 (an error, or the file ended first). */
int thx_read_exact(int fd, void *p, size_t count, off_t off);
/* Reads a whole file into a NUL-terminated buffer (caller frees). A regular file of THX_READ_SPLIT bytes or
 * more is read as two halves side by side (two threads); a file that changes size meanwhile is read to its
 * end all the same; a pipe is read as it comes. */
#define THX_READ_SPLIT ((size_t)8 << 20)
thx_status thx_read_file(thx_ctx *ctx, const char *path, char **text, size_t *len);
/* mkdir -p: dir and the directories above it that are missing (mode 0755); 0, or -1 with errno set
 * (a path of 4096 bytes or more: ENAMETOOLONG). */
int thx_make_dirs(const char *dir);
#endif
