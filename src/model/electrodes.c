/*
 * Electrode sets (thorax/model/electrodes.h): create, destroy, their invariants and the check
 * against a model.
 *
 *  - The check against a model accepts a position within 1e-3 mm of its
 *    node: files written with "%.6f" agree to 5e-7 mm, and anything farther
 *    means the set belongs to another model (or another version of it).
 */
#include "thorax/model/electrodes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define POS_TOL_MM 1e-3

/* ------------------------------------------------------------ the object */

thx_status thx_electrodes_create(thx_ctx *ctx, size_t n, thx_electrodes **out)
{
    *out = NULL;
    if (n == 0) return thx_error(ctx, THX_EINPUT, "an electrode set needs at least one electrode");
    if (n > (size_t)INT32_MAX) return thx_error(ctx, THX_EINPUT, "%zu electrodes are too many", n);
    thx_electrodes *e = thx_calloc(ctx, 1, sizeof *e);
    if (!e) return THX_ENOMEM;
    e->name = thx_calloc(ctx, n, sizeof *e->name);
    e->node = thx_calloc(ctx, n, sizeof *e->node);
    e->xyz = thx_calloc(ctx, 3 * n, sizeof *e->xyz);
    e->corner = thx_malloc(ctx, 3 * n * sizeof *e->corner);
    e->weight = thx_calloc(ctx, 3 * n, sizeof *e->weight);
    if (!e->name || !e->node || !e->xyz || !e->corner || !e->weight) {
        thx_electrodes_destroy(&e);
        return THX_ENOMEM;
    }
    for (size_t k = 0; k < 3 * n; k++) e->corner[k] = -1;
    e->n = n;
    *out = e;
    return THX_OK;
}

void thx_electrodes_destroy(thx_electrodes **e)
{
    if (!e || !*e) return;
    free((*e)->name);
    free((*e)->node);
    free((*e)->xyz);
    free((*e)->corner);
    free((*e)->weight);
    free(*e);
    *e = NULL;
}

/* ------------------------------------------------------------ validation */

static int is_keyword(const char *s)
{
    return !strcmp(s, "end") || !strcmp(s, "surface") || !strcmp(s, "count") || !strcmp(s, "thorax-electrodes");
}

/* NULL if `s` is a valid electrode name, else why not. */
const char *thx_electrodes_name_why(const char *s, size_t cap)
{
    size_t n = strnlen(s, cap);
    if (n == 0) return "is empty";
    if (n >= cap) return "is longer than 31 characters";
    for (const char *c = s; *c; c++)
        if (!((*c >= 'A' && *c <= 'Z') || (*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '_' ||
              *c == '.' || *c == '+' || *c == '-'))
            return "has a character outside [A-Za-z0-9_.+-]";
    if (is_keyword(s)) return "is a keyword of the electrode file";
    return NULL;
}

/* NULL if `s` is a valid surface name (as thx_model_write accepts it), else why not. */
const char *thx_electrodes_surface_name_why(const char *s, size_t cap)
{
    size_t n = strnlen(s, cap);
    if (n == 0) return "is empty";
    if (n >= cap) return "is longer than 63 characters";
    if (s[0] == '.') return "starts with '.'";
    for (const char *c = s; *c; c++)
        if (!((*c >= 'A' && *c <= 'Z') || (*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '_' ||
              *c == '.' || *c == '-'))
            return "has a character outside [A-Za-z0-9_.-]";
    return NULL;
}

thx_status thx_electrodes_validate(thx_ctx *ctx, const thx_electrodes *e, const char *where)
{
    if (!e || e->n == 0) return thx_error(ctx, THX_EINPUT, "%san electrode set needs at least one electrode", where);
    const char *why = thx_electrodes_surface_name_why(e->surface, sizeof e->surface);
    if (why) return thx_error(ctx, THX_EINPUT, "%ssurface name \"%.63s\" %s", where, e->surface, why);
    for (size_t i = 0; i < e->n; i++) {
        if ((why = thx_electrodes_name_why(e->name[i], sizeof e->name[i])))
            return thx_error(ctx, THX_EINPUT, "%selectrode %zu: name \"%.31s\" %s", where, i + 1, e->name[i], why);
        if (e->node[i] < 0 && e->node[i] != THX_ELECTRODE_OFF_NODE)
            return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): node %d is negative (nodes are 0-based in memory)",
                             where, i + 1, e->name[i], (int)e->node[i]);
        if (e->node[i] == INT32_MAX)
            return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): node %d is too large", where, i + 1,
                             e->name[i], (int)e->node[i]);
        for (int k = 0; k < 3; k++)
            if (!isfinite(e->xyz[3 * i + k]))
                return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): position %c is not finite", where, i + 1,
                                 e->name[i], "xyz"[k]);
    }
    /* unique names: n is small (hundreds), a quadratic scan is fine */
    for (size_t i = 1; i < e->n; i++)
        for (size_t j = 0; j < i; j++)
            if (!strcmp(e->name[i], e->name[j]))
                return thx_error(ctx, THX_EINPUT, "%selectrode %zu: name \"%s\" already used by electrode %zu", where,
                                 i + 1, e->name[i], j + 1);
    return THX_OK;
}

/* ------------------------------------------------------------ the check */

const thx_surface *thx_electrodes_surface(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m)
{
    char fp[sizeof e->path + 2] = "";
    if (e->path[0]) snprintf(fp, sizeof fp, "%s: ", e->path);
    if (!m) {
        thx_error(ctx, THX_EINPUT, "%selectrodes: no model to check them against", fp);
        return NULL;
    }
    for (size_t k = 0; k < m->n_surfaces; k++)
        if (!strcmp(m->surf[k]->name, e->surface)) return m->surf[k];
    char list[600] = "";
    size_t off = 0;
    for (size_t k = 0; k < m->n_surfaces && off < sizeof list; k++)
        off += (size_t)snprintf(list + off, sizeof list - off, "%s%s", k ? ", " : "", m->surf[k]->name);
    thx_error(ctx, THX_EINPUT, "%sthe electrodes' surface \"%s\" is not in the model (surfaces: %s)", fp, e->surface,
              m->n_surfaces ? list : "none");
    return NULL;
}

thx_status thx_electrodes_check(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m)
{
    /* messages name the file the set came from, when it came from one */
    char fp[sizeof e->path + 2] = "";
    if (e->path[0]) snprintf(fp, sizeof fp, "%s: ", e->path);
    THX_CHECK(thx_electrodes_validate(ctx, e, fp));
    const thx_surface *s = thx_electrodes_surface(ctx, e, m);
    if (!s) return THX_EINPUT;
    for (size_t i = 0; i < e->n; i++) {
        const double *a = e->xyz + 3 * i;
        if (e->node[i] == THX_ELECTRODE_OFF_NODE) {
            double q[3], d = thx_surface_nearest(s, a, NULL, NULL, q);
            if (!(d >= 0 && d <= THX_ELECTRODE_MAX_OFFSET_MM))
                return thx_error(ctx, THX_EINPUT,
                                 "%selectrode %zu (\"%s\"): position (%.6f, %.6f, %.6f) is %.3g mm from surface \"%s\" "
                                 "(at most %g mm)",
                                 fp, i + 1, e->name[i], a[0], a[1], a[2], d, s->name, THX_ELECTRODE_MAX_OFFSET_MM);
            continue;
        }
        if ((size_t)e->node[i] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "%selectrode %zu (\"%s\"): node %d is not on surface \"%s\" (nodes 1..%zu)",
                             fp, i + 1, e->name[i], (int)e->node[i] + 1, s->name, s->n_nodes);
        const double *b = s->xyz + 3 * (size_t)e->node[i];
        double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        if (!(d <= POS_TOL_MM))
            return thx_error(ctx, THX_EINPUT,
                             "%selectrode %zu (\"%s\"): position (%.6f, %.6f, %.6f) is %.3g mm from node %d of surface "
                             "\"%s\" at (%.6f, %.6f, %.6f) (tolerance %g mm)",
                             fp, i + 1, e->name[i], a[0], a[1], a[2], d, (int)e->node[i] + 1, s->name, b[0], b[1], b[2],
                             POS_TOL_MM);
    }
    return THX_OK;
}
