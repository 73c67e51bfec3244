/* Surfaces (thorax/model/surface.h): roles, lifecycle, enclosed volume. */
#include "thorax/model/surface.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const role_names[THX_ROLE_COUNT] = {"outer", "fat", "muscle", "lung", "heart", "other"};

const char *thx_role_name(thx_role r)
{
    return (r >= 0 && r < THX_ROLE_COUNT) ? role_names[r] : "?";
}

int thx_role_parse(const char *s, thx_role *out)
{
    for (int r = 0; r < THX_ROLE_COUNT; r++)
        if (strcmp(s, role_names[r]) == 0) { *out = (thx_role)r; return 0; }
    return -1;
}

thx_status thx_surface_create(thx_ctx *ctx, const char *name, thx_role role, thx_surface **out)
{
    thx_surface *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    snprintf(s->name, sizeof s->name, "%s", name);
    s->role = role;
    *out = s;
    return THX_OK;
}

void thx_surface_destroy(thx_surface **s)
{
    if (!s || !*s) return;
    free((*s)->xyz);
    free((*s)->tri);
    free(*s);
    *s = NULL;
}

double thx_surface_volume(const thx_surface *s)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], s->xyz[3 * i + d]);
            hi[d] = fmax(hi[d], s->xyz[3 * i + d]);
        }
    thx_vec3 o = thx_v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    double v = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        thx_vec3 a = thx_v3_sub(thx_surface_node(s, (size_t)s->tri[3 * t]), o);
        thx_vec3 b = thx_v3_sub(thx_surface_node(s, (size_t)s->tri[3 * t + 1]), o);
        thx_vec3 c = thx_v3_sub(thx_surface_node(s, (size_t)s->tri[3 * t + 2]), o);
        v += thx_v3_dot(a, thx_v3_cross(b, c));
    }
    return v / 6.0;
}

void thx_surface_normal_sums(const thx_surface *s, double *out)
{
    memset(out, 0, 3 * s->n_nodes * sizeof *out);
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        const double *a = s->xyz + 3 * (size_t)v[0], *b = s->xyz + 3 * (size_t)v[1], *c = s->xyz + 3 * (size_t)v[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) out[3 * (size_t)v[k] + (size_t)j] += n[j];
    }
}

thx_status thx_surface_validate(thx_ctx *ctx, const thx_surface *s)
{
    if ((s->n_nodes && !s->xyz) || (s->n_tris && !s->tri))
        return thx_error(ctx, THX_EINTERNAL, "surface \"%s\": counts set but arrays missing", s->name);
    for (size_t i = 0; i < 3 * s->n_nodes; i++)
        if (!isfinite(s->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": node %zu has a non-finite coordinate", s->name, i / 3 + 1);
    if (s->n_nodes > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "surface \"%s\": too many nodes (%zu)", s->name, s->n_nodes);
    for (size_t i = 0; i < 3 * s->n_tris; i++)
        if (s->tri[i] < 0 || (size_t)s->tri[i] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": triangle %zu has node index %ld out of range 0..%zu (0-based)",
                             s->name, i / 3 + 1, (long)s->tri[i], s->n_nodes - 1);
    return THX_OK;
}
