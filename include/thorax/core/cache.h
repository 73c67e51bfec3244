/*
 * thorax/core/cache.h — the user's cache directory: what a run computes from its inputs alone (a mesh's
 * fill-reducing ordering and symbolic factor, its stiffness matrix) kept for the next run on the same
 * inputs (docs/design/parallel.md, "The stiffness matrix kept"). Each file is named WHAT-KEY.bin, KEY
 * the SHA-256 of everything it depends on, and is written by its module to a temporary name and renamed;
 * a file that does not read back whole and right is ignored and computed again. The directory is kept
 * under a size (THORAX_CACHE_MAX): the files used least recently go first, and only files of thorax's
 * own names are ever removed. One small file more, blas-KEY.bin, holds the machine's choice of BLAS
 * kernels (thorax/core/blas_kernels.h); it is never trimmed.
 */
#ifndef THORAX_CORE_CACHE_H
#define THORAX_CORE_CACHE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* $THORAX_CACHE_DIR, else $XDG_CACHE_HOME/thorax, else $HOME/.cache/thorax; NULL when none can be named.
 * Written into buf (n bytes). */
const char *thx_cache_dir(char *buf, size_t n);

/* DIR/WHAT-KEY.bin, KEY as 64 lowercase hex digits. */
void thx_cache_path(char *buf, size_t n, const char *dir, const char *what, const unsigned char key[32]);

/* A cache file read and used: its time set to now, so the trim keeps it over older ones. */
void thx_cache_used(const char *path);

/* The size the directory is kept under: THORAX_CACHE_MAX in bytes (digits, then a K, M or G suffix
 * allowed), else 4 GiB. A value that does not parse (a sign, a space, other characters, more than 64 bits
 * of digits) gives the default; one whose suffix overflows 64 bits is the largest. */
uint64_t thx_cache_max_bytes(void);

/* A cache file being written: a temporary name beside path, renamed over it when whole. */
typedef struct {
    FILE *f;
    char tmp[4300];
} thx_cache_file;

/* Opens the temporary file for path (DIR/WHAT-KEY.bin) in dir, made if missing, for `bytes` bytes; 0 and a
 * note (naming `what`, e.g. "the ordering") when it cannot be kept: larger than THORAX_CACHE_MAX, no
 * directory, no file. */
int thx_cache_create(thx_cache_file *cf, const char *dir, const char *path, uint64_t bytes, const char *what, char *note,
                     size_t note_n);
/* Closes it; when ok and closed whole, renames it over path and trims the directory to its size (path
 * kept), else removes it and writes a note. */
void thx_cache_commit(thx_cache_file *cf, int ok, const char *dir, const char *path, const char *what, char *note,
                      size_t note_n);

/* Removes the least recently used of thorax's cache files (names WHAT-KEY.bin with WHAT one of
 * ordering, symbolic, stiffness and KEY 64 hex digits) until those left total at most max_bytes; never
 * `keep` (the file just written), never a file of another name. Returns how many were removed. */
int thx_cache_trim(const char *dir, uint64_t max_bytes, const char *keep);

#ifdef __cplusplus
}
#endif

#endif
