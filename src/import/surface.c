/*
 * Surfaces made elsewhere, into a model (thorax/import/import.h): read (thorax/io/surface_read.h),
 * scaled, unused nodes removed, checked, reversed when every triangle faces inward.
 */
#include "thorax/import/import.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void thx_import_opts_default(thx_import_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = THX_IMPORT_AUTO;
    o->scale = 1.0;
    o->force = 0;
    thx_check_opts_default(&o->check);
}

void thx_import_info_free(thx_import_info *info)
{
    if (!info) return;
    thx_surface_report_free(&info->report);
    memset(info, 0, sizeof *info);
}


/* Removes nodes used by no triangle, keeping the order of the rest. */
static thx_status remove_unused(thx_ctx *ctx, thx_surface *s, size_t *removed, long *first)
{
    *removed = 0;
    *first = -1;
    int32_t *map = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < s->n_nodes; i++) map[i] = -1;
    for (size_t i = 0; i < 3 * s->n_tris; i++) map[s->tri[i]] = 0;
    size_t k = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        if (map[i] < 0) {
            if (*first < 0) *first = (long)i;
            continue;
        }
        map[i] = (int32_t)k;
        if (k != i) memmove(s->xyz + 3 * k, s->xyz + 3 * i, 3 * sizeof *s->xyz);
        k++;
    }
    for (size_t i = 0; i < 3 * s->n_tris; i++) s->tri[i] = map[s->tri[i]];
    *removed = s->n_nodes - k;
    s->n_nodes = k;
    free(map);
    return THX_OK;
}

/* Closed, manifold and consistently oriented, but enclosing a negative volume:
 * every triangle is clockwise seen from outside (policy step 5). */
static int inward_only(const thx_surface_report *r)
{
    return !(r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX)) && r->n_boundary_edges == 0 &&
           r->n_nonmanifold_edges == 0 && r->n_nonmanifold_vertices == 0 && r->n_inconsistent_edges == 0 &&
           r->volume < 0;
}

thx_status thx_surface_import(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              const thx_import_opts *opts, thx_surface **out, thx_import_info *info)
{
    thx_import_opts def;
    if (!opts) {
        thx_import_opts_default(&def);
        opts = &def;
    }
    *out = NULL;
    thx_import_info local;
    if (!info) {
        memset(&local, 0, sizeof local);
        info = &local;
    }
    if (!(opts->scale > 0) || !isfinite(opts->scale))
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": scale %g must be a finite positive number", path, name,
                         opts->scale);
    thx_surface *s = NULL;
    thx_status st;
    memset(info, 0, sizeof *info); /* overwritten, not freed */
    info->scale = 1.0;
    THX_TRY(thx_surface_read_file(ctx, path, path2, opts->format, name, role, &s, &info->read));
    info->scale = opts->scale;
    if (opts->scale != 1.0)
        for (size_t i = 0; i < 3 * s->n_nodes; i++) {
            s->xyz[i] *= opts->scale;
            if (!isfinite(s->xyz[i])) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": node %zu is not finite after scaling by %g", path,
                               name, i / 3 + 1, opts->scale);
                goto done;
            }
        }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], s->xyz[3 * i + (size_t)k]);
            hi[k] = fmax(hi[k], s->xyz[3 * i + (size_t)k]);
        }
    info->extent = s->n_nodes ? fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2])) : 0;
    THX_TRY(remove_unused(ctx, s, &info->n_unused_removed, &info->first_unused));
    if (info->first_unused >= 0 && info->read.index_base > 0) info->first_unused += info->read.index_base;

    st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
    if (st != THX_OK && st != THX_ECHECK) goto done;
    if (inward_only(&info->report)) {
        for (size_t t = 0; t < s->n_tris; t++) {
            int32_t tmp = s->tri[3 * t + 1];
            s->tri[3 * t + 1] = s->tri[3 * t + 2];
            s->tri[3 * t + 2] = tmp;
        }
        info->reversed = 1;
        info->omega_before = info->report.solid_angle;
        thx_surface_report_free(&info->report);
        st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
        if (st != THX_OK && st != THX_ECHECK) goto done;
    }
    if (st == THX_ECHECK) {
        info->check_failed = 1;
        const thx_surface_report *r = &info->report;
        if (!opts->force) {
            char more[48] = "";
            if (r->n_reasons > 1) snprintf(more, sizeof more, " (and %zu more)", r->n_reasons - 1);
            st = thx_error(ctx, THX_ECHECK, "%s: surface \"%s\": refused: %s%s", path, name,
                           r->n_reasons ? r->reasons[0] : "failed its checks", more);
            goto done;
        }
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    if (info == &local) thx_import_info_free(&local);
    return st;
}
