/* Volumes (thorax/model/volume.h): lifecycle, tetrahedron volumes and the invariants of a volume in
 * its model. */
#include "thorax/model/volume.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/model/model.h"

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

int thx_name_ok(const char *s, size_t cap)
{
    size_t n = strnlen(s, cap);
    if (n == 0 || n == cap || s[0] == '.') return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
              c == '.'))
            return 0;
    }
    return 1;
}

/* A surface node and its volume node: the mesher snaps volume nodes to a binary grid finer than
 * the surfaces' 6 decimals (so that points it adds on a surface triangle are exactly in its
 * plane); they agree to within NODE_TOL mm. */
#define NODE_TOL 1e-6
int thx_volume_same_node(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (!(fabs(a[k] - b[k]) <= NODE_TOL)) return 0;
    return 1;
}

/* Whether a 3x3 row-major tensor is symmetric positive definite; if not,
 * why[] says how. */
int thx_tensor_spd(const double *a, char *why, size_t size)
{
    double amax = 0;
    for (int k = 0; k < 9; k++) {
        if (!isfinite(a[k])) {
            snprintf(why, size, "entry [%d][%d] is not a finite number", k / 3 + 1, k % 3 + 1);
            return 0;
        }
        if (fabs(a[k]) > amax) amax = fabs(a[k]);
    }
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (fabs(a[3 * i + j] - a[3 * j + i]) > 1e-12 * amax) {
                snprintf(why, size, "not symmetric: [%d][%d] = %.17g but [%d][%d] = %.17g", i + 1, j + 1, a[3 * i + j],
                         j + 1, i + 1, a[3 * j + i]);
                return 0;
            }
    /* Cholesky of the symmetric part: all three pivots must be positive. */
    double s00 = a[0], s11 = a[4], s22 = a[8];
    double s01 = 0.5 * (a[1] + a[3]), s02 = 0.5 * (a[2] + a[6]), s12 = 0.5 * (a[5] + a[7]);
    double d = s00;
    int pivot = 1;
    if (d > 0) {
        double l00 = sqrt(d), l10 = s01 / l00, l20 = s02 / l00;
        d = s11 - l10 * l10;
        pivot = 2;
        if (d > 0) {
            double l11 = sqrt(d), l21 = (s12 - l20 * l10) / l11;
            d = s22 - l20 * l20 - l21 * l21;
            pivot = 3;
        }
    }
    if (!(d > 0)) {
        snprintf(why, size, "not positive definite (Cholesky pivot %d is %.6g)", pivot, d);
        return 0;
    }
    return 1;
}

/* Checks one region of the table (k 0-based); `where` prefixes messages. */
static thx_status check_region(thx_ctx *ctx, const char *where, size_t k, const thx_region *r)
{
    if (!thx_name_ok(r->name, sizeof r->name))
        return thx_error(ctx, THX_EINPUT,
                         "%s: region %zu: name is empty, too long (31 characters at most) or not made of letters, "
                         "digits, '_', '-', '.'",
                         where, k + 1);
    if (!memchr(r->source, '\0', sizeof r->source))
        return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): source is not terminated", where, k + 1, r->name);
    char why[160];
    if (!r->anisotropic) {
        double s = r->sigma[0];
        if (!isfinite(s) || !(s > 0))
            return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): conductivity %g S/m is not positive", where, k + 1,
                             r->name, s);
        for (int i = 0; i < 9; i++)
            if (r->sigma[i] != (i % 4 == 0 ? s : 0.0))
                return thx_error(ctx, THX_EINPUT,
                                 "%s: region %zu (\"%s\"): marked isotropic but sigma is not sigma[0] times the identity",
                                 where, k + 1, r->name);
    } else if (!thx_tensor_spd(r->sigma, why, sizeof why)) {
        return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): conductivity tensor %s", where, k + 1, r->name, why);
    }
    return THX_OK;
}

thx_status thx_model_volume_validate(thx_ctx *ctx, const thx_model *m, const char *where)
{
    const thx_volume *v = m->volume;
    if (!v) return thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh", where);
    if (v->n_nodes == 0 || !v->xyz) return thx_error(ctx, THX_EINPUT, "%s: volume: no nodes", where);
    if (v->n_tets == 0 || !v->tet || !v->region) return thx_error(ctx, THX_EINPUT, "%s: volume: no tetrahedra", where);
    if (v->n_regions == 0 || !v->regions) return thx_error(ctx, THX_EINPUT, "%s: volume: no region table", where);
    if (v->n_nodes > (size_t)INT32_MAX || v->n_tets > (size_t)INT32_MAX || v->n_regions > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "%s: volume: too many nodes, tetrahedra or regions", where);
    /* the first value at fault found by the threads together (the smallest index: the same message whatever the
       threads), then named below */
    size_t bad_x = SIZE_MAX, bad_t = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad_x)
    for (size_t i = 0; i < 3 * v->n_nodes; i++)
        if (!isfinite(v->xyz[i]) && i < bad_x) bad_x = i;
    if (bad_x != SIZE_MAX)
        return thx_error(ctx, THX_EINPUT, "%s: volume node %zu has a non-finite coordinate", where, bad_x / 3 + 1);
#pragma omp parallel for schedule(static) reduction(min : bad_t)
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        int bad = v->region[t] < 0 || (size_t)v->region[t] >= v->n_regions;
        for (int a = 0; a < 4; a++) {
            bad |= q[a] < 0 || (size_t)q[a] >= v->n_nodes;
            for (int b = 0; b < a; b++) bad |= q[a] == q[b];
        }
        if (bad && t < bad_t) bad_t = t;
    }
    for (size_t t = bad_t; t < v->n_tets; t++) { /* (none when bad_t is SIZE_MAX) */
        const int32_t *q = v->tet + 4 * t;
        for (int a = 0; a < 4; a++) {
            if (q[a] < 0 || (size_t)q[a] >= v->n_nodes)
                return thx_error(ctx, THX_EINPUT, "%s: volume tetrahedron %zu: node index %ld out of range 0..%zu (0-based)",
                                 where, t + 1, (long)q[a], v->n_nodes - 1);
            for (int b = 0; b < a; b++)
                if (q[a] == q[b])
                    return thx_error(ctx, THX_EINPUT, "%s: volume tetrahedron %zu: node %ld appears twice (1-based)", where,
                                     t + 1, (long)q[a] + 1);
        }
        if (v->region[t] < 0 || (size_t)v->region[t] >= v->n_regions)
            return thx_error(ctx, THX_EINPUT, "%s: volume tetrahedron %zu: region index %ld out of range 0..%zu (0-based)",
                             where, t + 1, (long)v->region[t], v->n_regions - 1);
    }
    for (size_t k = 0; k < v->n_regions; k++) {
        THX_CHECK(check_region(ctx, where, k, &v->regions[k]));
        for (size_t j = 0; j < k; j++)
            if (strcmp(v->regions[j].name, v->regions[k].name) == 0)
                return thx_error(ctx, THX_EINPUT, "%s: regions %zu and %zu are both named \"%s\"", where, j + 1, k + 1,
                                 v->regions[k].name);
    }

    /* Node tables: one per surface of the model, consistent, injective. */
    if (v->n_surfaces != m->n_surfaces)
        return thx_error(ctx, THX_EINPUT, "%s: the volume has node tables for %zu surfaces but the model has %zu", where,
                         v->n_surfaces, m->n_surfaces);
    if (m->n_surfaces == 0) return THX_OK;
    if (!v->surf_n_nodes || !v->surf_node)
        return thx_error(ctx, THX_EINPUT, "%s: the volume has no node tables", where);
    /* owner[v] = (surface index << 32 | node) + 1 of the surface node on v, 0 if none. */
    uint64_t *owner = thx_calloc(ctx, v->n_nodes, sizeof *owner);
    if (!owner) return THX_ENOMEM;
    thx_status st = THX_OK;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const thx_surface *sf = m->surf[s];
        if (v->surf_n_nodes[s] != sf->n_nodes || (sf->n_nodes && !v->surf_node[s])) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": the volume's node table has %zu nodes, the surface %zu",
                           where, sf->name, v->surf_n_nodes[s], sf->n_nodes);
            goto done;
        }
        for (size_t i = 0; i < sf->n_nodes; i++) {
            int32_t w = v->surf_node[s][i];
            if (w < 0 || (size_t)w >= v->n_nodes) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\" node %zu: volume node index %ld out of range 0..%zu",
                               where, sf->name, i + 1, (long)w, v->n_nodes - 1);
                goto done;
            }
            if (!thx_volume_same_node(sf->xyz + 3 * i, v->xyz + 3 * (size_t)w)) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s: surface \"%s\" node %zu is volume node %ld but the coordinates differ: "
                               "(%.6f, %.6f, %.6f) vs (%.6f, %.6f, %.6f)",
                               where, sf->name, i + 1, (long)w + 1, sf->xyz[3 * i], sf->xyz[3 * i + 1], sf->xyz[3 * i + 2],
                               v->xyz[3 * w], v->xyz[3 * w + 1], v->xyz[3 * w + 2]);
                goto done;
            }
            if (owner[w]) {
                size_t s2 = (size_t)((owner[w] - 1) >> 32), i2 = (size_t)((owner[w] - 1) & 0xffffffffu);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: surface \"%s\" node %zu and surface \"%s\" node %zu are both volume node %ld "
                               "(a volume node lies on one surface node at most)",
                               where, m->surf[s2]->name, i2 + 1, sf->name, i + 1, (long)w + 1);
                goto done;
            }
            owner[w] = (((uint64_t)s << 32) | (uint64_t)i) + 1;
        }
    }
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *r = &v->steiner[k];
        if (r->node < 0 || (size_t)r->node >= v->n_nodes || r->surf < 0 || (size_t)r->surf >= m->n_surfaces ||
            r->tri < 0 || (size_t)r->tri >= m->surf[r->surf]->n_tris) {
            st = thx_error(ctx, THX_EINPUT, "%s: Steiner node record %zu: node, surface or triangle out of range", where, k + 1);
            goto done;
        }
        double sum = r->bary[0] + r->bary[1] + r->bary[2];
        if (!(r->bary[0] >= -1e-12 && r->bary[1] >= -1e-12 && r->bary[2] >= -1e-12 && fabs(sum - 1) <= 1e-9)) {
            st = thx_error(ctx, THX_EINPUT, "%s: Steiner node record %zu (volume node %ld): barycentric coordinates "
                           "(%g, %g, %g) are not in the triangle", where, k + 1, (long)r->node + 1, r->bary[0], r->bary[1], r->bary[2]);
            goto done;
        }
        if (owner[r->node]) {
            st = thx_error(ctx, THX_EINPUT, "%s: volume node %ld is a surface node and a Steiner node (record %zu), or "
                           "two Steiner records name it", where, (long)r->node + 1, k + 1);
            goto done;
        }
        owner[r->node] = UINT64_MAX; /* taken */
    }
    for (size_t k = 0; k < v->n_steiner; k++) owner[v->steiner[k].node] = 0;
    if (v->node_surf && v->node_snode)
        for (size_t w = 0; w < v->n_nodes; w++) {
            long ws = owner[w] ? (long)((owner[w] - 1) >> 32) : -1;
            long wi = owner[w] ? (long)((owner[w] - 1) & 0xffffffffu) : -1;
            if (v->node_surf[w] != ws || v->node_snode[w] != wi) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s: volume node %zu: reverse node table says surface %ld node %ld, the surfaces' tables "
                               "say surface %ld node %ld (0-based, -1 = none)",
                               where, w + 1, (long)v->node_surf[w], (long)v->node_snode[w], ws, wi);
                goto done;
            }
        }
done:
    free(owner);
    return st;
}
