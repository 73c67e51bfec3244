/*
 * Private interface between the model directory code (src/io/model.c) and
 * the volume mesh files (src/io/volume_io.c). Not installed, not public:
 * the public entry points are thx_model_write / thx_model_read and
 * thx_volume_export in thorax/io/model_dir.h.
 */
#ifndef THORAX_IO_VOLUME_IO_H
#define THORAX_IO_VOLUME_IO_H

#include <cjson/cJSON.h>
#include <stdio.h>

#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
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
/* Reads "x y z" lines (blank lines allowed); `what` prefixes the messages after FILE:LINE:. */
thx_status thx_io_read_xyz(thx_ctx *ctx, const char *path, const char *what, double **xyz_out, size_t *n_out);
/* Reads a .pts/.fac pair; want_base 0 or 1 requires that .fac base, -1 detects it (ptsfac.c). */
thx_status thx_io_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                              int want_base, thx_surface **out, int *base);
/* A manifest file name: non-empty, no '/', not "." or "..". */
int thx_io_file_name_ok(const char *s);
/* A count from a JSON object: o[key] a whole number in 0 .. INT32_MAX; 0, or -1 (missing or not
 * such a number; *out unchanged). */
int thx_io_json_count(const cJSON *o, const char *key, size_t *out);

/* Adds "vmap" to each surface object of root's "surfaces" array (in model
 * order) and the "volume" and "regions" members to root. m->volume != NULL
 * and validated. */
thx_status thx_io_volume_manifest(thx_ctx *ctx, const thx_model *m, cJSON *root);

/* Writes volume.pts, volume.tet and NAME.vmap into dir (validated volume). */
thx_status thx_io_volume_write_files(thx_ctx *ctx, const thx_model *m, const char *dir);

/* Reads the volume of the model directory dir whose manifest (path mpath)
 * is root, into m->volume; m already holds the surfaces in manifest order.
 * Does nothing when the manifest has no "volume" (and then refuses
 * "regions" or a surface "vmap" as inconsistent). */
thx_status thx_io_volume_read(thx_ctx *ctx, const char *dir, const char *mpath, const cJSON *root, thx_model *m);

#endif
