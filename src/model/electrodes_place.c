/*
 * Electrodes placed on their surface (thorax/model/electrodes.h): an electrode on a node, or one
 * anywhere on the surface, projected to the nearest surface point and weighed on its triangle.
 *
 *  - Linear interpolation on the triangle (barycentric weights) is what the finite-element
 *    solution is on a surface of linear elements, so an electrode between nodes reads the same
 *    field the solver computed, and a field linear in space is reproduced exactly (tested in
 *    tests/test_electrodes.c). docs/decisions.md, "Electrodes anywhere on the surface".
 *  - A projection within 1e-3 mm of a corner (the tolerance thx_electrodes_check gives a node's
 *    position) is that node: a set of positions that are nodes (the Utah tank's 192 leads are
 *    nodes of the full tank) becomes a set of nodes, byte-for-byte what a node list gives.
 */
#include "thorax/model/electrodes.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NODE_TOL_MM 1e-3

thx_status thx_electrodes_place(thx_ctx *ctx, thx_electrodes *e, const thx_model *m, double max_offset,
                                double *max_moved)
{
    if (max_moved) *max_moved = 0;
    char fp[sizeof e->path + 2] = "";
    if (e->path[0]) snprintf(fp, sizeof fp, "%s: ", e->path);
    THX_CHECK(thx_electrodes_validate(ctx, e, fp));
    const thx_surface *s = thx_electrodes_surface(ctx, e, m);
    if (!s) return THX_EINPUT;
    /* the nodes first, as thx_electrodes_check has them */
    for (size_t i = 0; i < e->n; i++)
        if (e->node[i] >= 0 && (size_t)e->node[i] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): node %d is not on surface \"%s\" (nodes 1..%zu)",
                             fp, i + 1, e->name[i], (int)e->node[i] + 1, s->name, s->n_nodes);
    if (s->n_tris == 0)
        for (size_t i = 0; i < e->n; i++)
            if (e->node[i] < 0)
                return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): surface \"%s\" has no triangles to place it on",
                                 fp, i + 1, e->name[i], s->name);
    double moved = 0;
    for (size_t i = 0; i < e->n; i++) {
        double *x = e->xyz + 3 * i;
        int32_t *c = e->corner + 3 * i;
        double *w = e->weight + 3 * i;
        if (e->node[i] >= 0) {
            const double *b = s->xyz + 3 * (size_t)e->node[i];
            double d = sqrt((x[0] - b[0]) * (x[0] - b[0]) + (x[1] - b[1]) * (x[1] - b[1]) + (x[2] - b[2]) * (x[2] - b[2]));
            if (!(d <= NODE_TOL_MM))
                return thx_error(ctx, THX_EINPUT,
                                 "%selectrode %zu (\"%s\"): position (%.6f, %.6f, %.6f) is %.3g mm from node %d of surface "
                                 "\"%s\" (tolerance %g mm; write the node as '-' for an electrode between nodes)",
                                 fp, i + 1, e->name[i], x[0], x[1], x[2], d, (int)e->node[i] + 1, s->name, NODE_TOL_MM);
            c[0] = c[1] = c[2] = e->node[i];
            w[0] = 1;
            w[1] = w[2] = 0;
            continue;
        }
        size_t t = 0;
        double q[3], wt[3];
        double d = thx_surface_nearest(s, x, &t, wt, q);
        if (!(d >= 0 && d <= max_offset))
            return thx_error(ctx, THX_EINPUT,
                             "%selectrode %zu (\"%s\"): position (%.6f, %.6f, %.6f) is %.3g mm from surface \"%s\" (at most "
                             "%g mm)",
                             fp, i + 1, e->name[i], x[0], x[1], x[2], d, s->name, max_offset);
        moved = fmax(moved, d);
        const int32_t *T = s->tri + 3 * t;
        /* on a corner (within the node tolerance): that node's electrode */
        int at = -1;
        for (int k = 0; k < 3 && at < 0; k++) {
            const double *b = s->xyz + 3 * (size_t)T[k];
            double dn = sqrt((q[0] - b[0]) * (q[0] - b[0]) + (q[1] - b[1]) * (q[1] - b[1]) + (q[2] - b[2]) * (q[2] - b[2]));
            if (dn <= NODE_TOL_MM) at = k;
        }
        if (at >= 0) {
            e->node[i] = T[at];
            memcpy(x, s->xyz + 3 * (size_t)T[at], 3 * sizeof *x);
            c[0] = c[1] = c[2] = T[at];
            w[0] = 1;
            w[1] = w[2] = 0;
            continue;
        }
        memcpy(x, q, sizeof q);
        for (int k = 0; k < 3; k++) {
            c[k] = T[k];
            w[k] = wt[k];
        }
    }
    e->placed = 1;
    if (max_moved) *max_moved = moved;
    return THX_OK;
}

thx_status thx_electrodes_from_nodes(thx_ctx *ctx, const thx_surface *s, const int32_t *nodes, const char (*names)[32],
                                     size_t n, thx_electrodes **out)
{
    *out = NULL;
    thx_electrodes *e = NULL;
    THX_CHECK(thx_electrodes_create(ctx, n, &e));
    snprintf(e->surface, sizeof e->surface, "%s", s->name);
    for (size_t i = 0; i < n; i++) {
        if (nodes[i] < 0 || (size_t)nodes[i] >= s->n_nodes) {
            thx_electrodes_destroy(&e);
            return thx_error(ctx, THX_EINPUT, "electrode %zu: node %d is not on surface \"%s\" (nodes 1..%zu)", i + 1,
                             (int)nodes[i] + 1, s->name, s->n_nodes);
        }
        if (names) snprintf(e->name[i], sizeof e->name[i], "%s", names[i]);
        else snprintf(e->name[i], sizeof e->name[i], "N%d", (int)nodes[i] + 1);
        e->node[i] = nodes[i];
        memcpy(e->xyz + 3 * i, s->xyz + 3 * (size_t)nodes[i], 3 * sizeof(double));
        e->corner[3 * i] = e->corner[3 * i + 1] = e->corner[3 * i + 2] = nodes[i];
        e->weight[3 * i] = 1;
    }
    e->placed = 1;
    thx_status st = thx_electrodes_validate(ctx, e, "");
    if (st != THX_OK) thx_electrodes_destroy(&e);
    *out = e;
    return st;
}
