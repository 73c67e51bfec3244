/* thx_volume lifecycle and small helpers (see thorax/volume.h). */
#include "thorax/model/volume.h"
#include <stdlib.h>

thx_status thx_volume_create(thx_ctx *ctx, thx_volume **out)
{
    *out = thx_calloc(ctx, 1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

void thx_volume_destroy(thx_volume **v)
{
    if (!v || !*v) return;
    thx_volume *w = *v;
    free(w->xyz);
    free(w->tet);
    free(w->region);
    free(w->regions);
    if (w->surf_node)
        for (size_t s = 0; s < w->n_surfaces; s++) free(w->surf_node[s]);
    free(w->surf_node);
    free(w->surf_n_nodes);
    free(w->node_surf);
    free(w->node_snode);
    free(w->steiner);
    free(w);
    *v = NULL;
}

double thx_volume_tet_volume(const thx_volume *v, size_t t)
{
    const int32_t *q = v->tet + 4 * t;
    thx_vec3 p0 = thx_v3(v->xyz[3 * q[0]], v->xyz[3 * q[0] + 1], v->xyz[3 * q[0] + 2]);
    thx_vec3 a = thx_v3_sub(thx_v3(v->xyz[3 * q[1]], v->xyz[3 * q[1] + 1], v->xyz[3 * q[1] + 2]), p0);
    thx_vec3 b = thx_v3_sub(thx_v3(v->xyz[3 * q[2]], v->xyz[3 * q[2] + 1], v->xyz[3 * q[2] + 2]), p0);
    thx_vec3 c = thx_v3_sub(thx_v3(v->xyz[3 * q[3]], v->xyz[3 * q[3] + 1], v->xyz[3 * q[3] + 2]), p0);
    return thx_v3_dot(thx_v3_cross(a, b), c) / 6.0;
}
