/*
 * thorax/fileio.h — atomic file and directory output.
 *
 * Every file thorax writes goes first to a temporary name in the same
 * directory and is renamed over the target only when complete, so a failed
 * run leaves no partial output. Model directories are built in a temporary
 * sibling directory and renamed as a whole.
 */
#ifndef THORAX_FILEIO_H
#define THORAX_FILEIO_H

#include <stdio.h>

#include "thorax/core.h"

typedef struct {
    FILE *f;            /* write here */
    char path[1024];    /* final name */
    char tmp[1040];     /* temporary name */
} thx_atomic_file;

/* Opens a temporary file next to `path` for writing. */
thx_status thx_atomic_open(thx_ctx *ctx, const char *path, thx_atomic_file *af);
/* Flushes, checks for write errors, closes and renames over the final name. */
thx_status thx_atomic_commit(thx_ctx *ctx, thx_atomic_file *af);
/* Closes and removes the temporary file (safe after a failed commit or none). */
void thx_atomic_abort(thx_atomic_file *af);

/* Creates a fresh temporary directory beside `final_dir` ("final_dir.tmpXXXXXX"). */
thx_status thx_tmpdir_create(thx_ctx *ctx, const char *final_dir, char *tmp, size_t tmp_size);
/* Replaces final_dir by tmp (an existing final_dir is removed first, recursively). */
thx_status thx_tmpdir_commit(thx_ctx *ctx, const char *tmp, const char *final_dir);
/* Removes a temporary directory and its files (one level). */
void thx_tmpdir_abort(const char *tmp);

/* Reads a whole file into a NUL-terminated buffer (caller frees). */
thx_status thx_read_file(thx_ctx *ctx, const char *path, char **text, size_t *len);
#endif
