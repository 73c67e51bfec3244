/*
 * thorax/io/channels_file.h — map3d's channel maps and lead links (io layer;
 * docs/formats.md, "Channels and lead links").
 *
 *   .channels   `N leads`, then N lines `NODE CHANNEL` (1-based): node NODE of the surface takes
 *               its signal from the recording's row CHANNEL; CHANNEL 0 or negative = none
 *               (map3d's "unused"). Nodes 1..N in any order, each exactly once (N lines,
 *               none twice).
 *   .leadlinks  `N leads`, then N lines `LABEL NODE`: lead LABEL (a name, often its number)
 *               sits on node NODE of the surface, 1-based (a file holding a node 0 is read as
 *               0-based, as map3d does; the log says so).
 * The first line's word is free ("leads", "nodes"); blank lines are skipped; anything but blank
 * lines after the N pairs is an error. Errors name the file, the line and the lead.
 */
#ifndef THORAX_IO_CHANNELS_FILE_H
#define THORAX_IO_CHANNELS_FILE_H

#include "thorax/model/channels.h"
#include "thorax/model/electrodes.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a .channels file. Caller destroys *out. */
thx_status thx_channels_read(thx_ctx *ctx, const char *path, thx_channels **out);

/* Reads a .leadlinks file as an electrode set on surface s (names = the labels, positions = the
 * nodes'; placed). Caller destroys *out. */
thx_status thx_leadlinks_read(thx_ctx *ctx, const char *path, const thx_surface *s, thx_electrodes **out);

#ifdef __cplusplus
}
#endif
#endif
