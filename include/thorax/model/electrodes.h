/*
 * thorax/model/electrodes.h — electrodes on the torso surface (model layer; the file is
 * thorax/io/electrodes_file.h, the ECG leads thorax/leads/leads.h).
 *
 * An electrode set names nodes of one surface of a model (normally the outer
 * one): each electrode is a surface node, so its signal is that node's row
 * of a surface series. File (docs/formats.md, "Electrodes"): a first line
 * `thorax-electrodes 1`, `surface NAME`, `count N`, then N lines
 * `NAME NODE X Y Z` (NODE 1-based on that surface; X Y Z, mm, its position,
 * checked against the model when one is given), then `end`.
 */
#ifndef THORAX_MODEL_ELECTRODES_H
#define THORAX_MODEL_ELECTRODES_H

#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char surface[64];   /* the surface the nodes belong to */
    size_t n;
    char (*name)[32];   /* electrode names: "RA", "LA", "LL", "V1".."V6", "A001".. */
    int32_t *node;      /* node on that surface, 0-based */
    double *xyz;        /* 3 n: the node's position, mm */
    char path[512];     /* the file it was read from (thx_electrodes_read; "" otherwise): checks name it */
} thx_electrodes;

thx_status thx_electrodes_create(thx_ctx *ctx, size_t n, thx_electrodes **out);
void thx_electrodes_destroy(thx_electrodes **e);
/* The invariants every set holds (checked before it is written, after it is read and before it
 * is checked against a model): at least one electrode, a surface name a model accepts, electrode
 * names of 1-31 characters from [A-Za-z0-9_.+-] that are not keywords of the electrode file,
 * unique; nodes >= 0; finite positions. `where` prefixes the messages. */
thx_status thx_electrodes_validate(thx_ctx *ctx, const thx_electrodes *e, const char *where);
/* NULL when s (at most cap bytes) is a valid electrode name / surface name of a set, else why not
 * ("is empty", "has a character outside [A-Za-z0-9_.+-]", ...). */
const char *thx_electrodes_name_why(const char *s, size_t cap);
const char *thx_electrodes_surface_name_why(const char *s, size_t cap);
/* Checks the set against the model: the surface exists, every node is on it, positions agree within
 * 1e-3 mm; errors name the electrode. */
thx_status thx_electrodes_check(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m);

#ifdef __cplusplus
}
#endif
#endif
