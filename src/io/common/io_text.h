/*
 * The text helpers of src/io/map3d/ptsfac.c that several io families share (io common, docs/design/io.md,
 * "io by family"): the model directory (src/io/model/), the exports (src/io/export/) and the .pts/.fac
 * reader itself. Not installed, not public. Moved unchanged from volume_io.h, which keeps the model
 * directory's own private interface (src/io/model/volume_io.h).
 */
#ifndef THORAX_IO_COMMON_IO_TEXT_H
#define THORAX_IO_COMMON_IO_TEXT_H

#include <stdio.h>

#include "thorax/model/model.h"

/* Shared text helpers (defined in ptsfac.c). */
/* Writes one coordinate "%.6f", a value that rounds to zero as "0.000000". */
void thx_io_put_coord(FILE *f, double v);
/* Reads a whole text file (thx_read_file), refusing one with a NUL byte (naming its line):
 * the line parsers stop at a NUL, which would cut the file short without a word. */
thx_status thx_io_read_text(thx_ctx *ctx, const char *path, char **text);
/* Splits the line at p into at most max whitespace-separated tokens
 * (NUL-terminated in place); returns the count (max + 1 = "more than max");
 * *next = start of the following line or NULL. */
int thx_io_split_line(char *p, char **tok, int max, char **next);
/* A run of whole lines of a text, [begin, end) (end the next piece's begin or the text's NUL), and what its
 * parser made of it: the lines it read (all of them unless it failed), the records it kept, and its first
 * fault (bad_line: its own line number, 0 none, -1 out of memory; why: the text after FILE:LINE:). */
typedef struct {
    char *begin, *end;
    int lines;
    int bad_line;
    size_t n;
    char why[200];
} thx_io_piece;
/* Cuts the NUL-terminated text of len bytes into at most max pieces of whole lines, each at least min_bytes
 * long but the last, for readers that parse the pieces in parallel (each line's tokens are its own). Returns
 * the count (1 for a short text); the outcomes are zero. */
size_t thx_io_cut_lines(char *text, size_t len, size_t max, size_t min_bytes, thx_io_piece *pieces);
/* The pieces for this machine: as many as OpenMP's threads, at most 8, from 1 MB a piece. */
#define THX_IO_PIECES_MAX 8
#define THX_IO_PIECE_BYTES ((size_t)1 << 20)
size_t thx_io_cut_for_threads(char *text, thx_io_piece *pieces);
/* After the pieces were parsed: the first fault in the file's order as THX_EINPUT ("PATH:LINE: why", the
 * line counted over the pieces before it, which are whole) or THX_ENOMEM; else THX_OK and *n the records. */
thx_status thx_io_pieces_verdict(thx_ctx *ctx, const char *path, const thx_io_piece *pc, size_t np, size_t *n);
/* Reads "x y z" lines (blank lines allowed); `what` prefixes the messages after FILE:LINE:. Files above a
 * megabyte are parsed in pieces, one thread each. */
thx_status thx_io_read_xyz(thx_ctx *ctx, const char *path, const char *what, double **xyz_out, size_t *n_out);
/* Reads a .pts/.fac pair; want_base 0 or 1 requires that .fac base, -1 detects it (ptsfac.c). */
thx_status thx_io_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                              int want_base, thx_surface **out, int *base);

#endif
