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
#include "io/common/io_text.h"
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
/* regions_only: the region table alone (m->volume without nodes or tetrahedra; thx_model_read_regions_only) */
thx_status thx_io_volume_read(thx_ctx *ctx, const char *dir, const char *mpath, const cJSON *root, thx_model *m, int regions_only);

#endif
