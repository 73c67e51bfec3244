/*
 * Fuzz harness: map3d's .channels and .leadlinks (thx_channels_read, thx_leadlinks_read on a
 * 4-node surface). Properties of an accepted map: 1..(size / 4) nodes, each channel -1 or >= 0
 * with its line recorded, and the mapping of a recording of 8 channels either refused or giving
 * a row per node: the recording's row, or NaN. Of an accepted lead-link set: names
 * NUL-terminated and unique, nodes on the surface, positions the nodes', placed with weight 1.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/io/channels_file.h"
#include "thorax/model/electrodes.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("f.channels", data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_channels *c = NULL;
    if (thx_channels_read(ctx, path, &c) == THX_OK) {
        FUZZ_ASSERT(c->n >= 1 && c->n <= size / 4);
        for (size_t i = 0; i < c->n; i++) FUZZ_ASSERT(c->channel[i] >= -1 && c->line[i] >= 2);
        thx_series *rec = NULL, *out = NULL;
        FUZZ_ASSERT(thx_series_create(ctx, 8, 2, &rec) == THX_OK);
        for (size_t k = 0; k < 16; k++) rec->v[k] = (double)k;
        if (thx_channels_apply(ctx, c, rec, &out) == THX_OK) {
            FUZZ_ASSERT(out->n_rows == c->n && out->n_frames == 2);
            for (size_t f = 0; f < 2; f++)
                for (size_t i = 0; i < c->n; i++) {
                    double v = out->v[f * c->n + i];
                    FUZZ_ASSERT(c->channel[i] < 0 ? isnan(v) : v == (double)(f * 8 + (size_t)c->channel[i]));
                }
        } else {
            int beyond = 0;
            for (size_t i = 0; i < c->n; i++) beyond |= c->channel[i] >= 8;
            FUZZ_ASSERT(beyond && out == NULL);
        }
        thx_series_destroy(&out);
        thx_series_destroy(&rec);
        thx_channels_destroy(&c);
    }
    /* the same bytes as lead links on a 4-node surface */
    thx_surface s = {.name = "torso", .role = THX_ROLE_OUTER, .n_nodes = 4};
    double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    s.xyz = xyz;
    thx_electrodes *e = NULL;
    if (thx_leadlinks_read(ctx, path, &s, &e) == THX_OK) {
        FUZZ_ASSERT(e->n >= 1 && e->n <= size / 4 && e->placed);
        for (size_t i = 0; i < e->n; i++) {
            FUZZ_ASSERT(memchr(e->name[i], 0, sizeof e->name[i]) && e->name[i][0]);
            FUZZ_ASSERT(e->node[i] >= 0 && e->node[i] < 4 && e->corner[3 * i] == e->node[i] && e->weight[3 * i] == 1);
            FUZZ_ASSERT(!memcmp(e->xyz + 3 * i, xyz + 3 * e->node[i], 3 * sizeof(double)));
            for (size_t j = 0; j < i; j++) FUZZ_ASSERT(strcmp(e->name[i], e->name[j]) != 0);
        }
        thx_electrodes_destroy(&e);
    }
    thx_ctx_destroy(&ctx);
    return 0;
}
