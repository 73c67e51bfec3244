/*
 * thorax/model/channels.h — which recording channel feeds each node (model layer; the file is
 * map3d's `.channels`, read by thorax/io/channels_file.h; docs/formats.md, "Channels").
 *
 * A recording's rows are its channels (the Utah tank's 512: 1-192 the tank's electrodes,
 * 193-320 the epicardial sock, ...). A channel map says, for each node i of a surface (a "lead"
 * in map3d's words), the channel its signal is in, or none. Applying it to a recording gives a
 * series whose row i is node i: the recording's row channel[i], or NaN for a node with no
 * channel (a lost or unconnected electrode; callers that cannot use NaN refuse it).
 * Indices are 0-based in memory, 1-based in the file.
 */
#ifndef THORAX_MODEL_CHANNELS_H
#define THORAX_MODEL_CHANNELS_H

#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t n;           /* nodes (leads) the map describes: the rows of a mapped series */
    int32_t *channel;   /* n: the channel of node i, 0-based; -1 = none */
    int32_t *line;      /* n: the file's line that gave it (0 = none): messages name it */
    char path[512];     /* the file it was read from ("" otherwise) */
} thx_channels;

/* n nodes, none with a channel yet. Caller destroys. */
thx_status thx_channels_create(thx_ctx *ctx, size_t n, thx_channels **out);
void thx_channels_destroy(thx_channels **c);

/*
 * The recording `in` (rows = channels) as a series on the nodes: row i = in's row
 * channel[i], NaN where a node has no channel; time axis, units and label carried over.
 * A channel beyond in's rows is an error naming the file, line, node and channel.
 * *out is new (caller destroys); `in` is not changed.
 */
thx_status thx_channels_apply(thx_ctx *ctx, const thx_channels *c, const thx_series *in, thx_series **out);

/* Nodes with no channel (rows a mapped series fills with NaN). */
size_t thx_channels_unmapped(const thx_channels *c);

#ifdef __cplusplus
}
#endif
#endif
