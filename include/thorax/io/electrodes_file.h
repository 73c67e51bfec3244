/*
 * thorax/io/electrodes_file.h — the electrode file (docs/formats.md, "Electrodes"; io layer).
 */
#ifndef THORAX_IO_ELECTRODES_FILE_H
#define THORAX_IO_ELECTRODES_FILE_H

#include "thorax/model/electrodes.h"

#ifdef __cplusplus
extern "C" {
#endif

thx_status thx_electrodes_read(thx_ctx *ctx, const char *path, thx_electrodes **out);
/* Atomic; nothing half-written on failure. */
thx_status thx_electrodes_write(thx_ctx *ctx, const thx_electrodes *e, const char *path);

#ifdef __cplusplus
}
#endif
#endif
