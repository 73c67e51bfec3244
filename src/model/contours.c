/*
 * Digitized contours in memory (paper 3.1): building them, and the walk that checks their
 * structure (the loops' geometry is thorax/geom/contours_valid.h's; the file, thorax/io/
 * contours_file.h's).
 */
#include "thorax/model/contours.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Grows an array of n elements by one: arrays grown only here have capacity n rounded up to a
 * power of two, so a file of many small loops costs O(total) copying, not O(n^2). */
static void *grow_one(thx_ctx *ctx, void *a, size_t n, size_t size)
{
    if (n && (n & (n - 1))) return a; /* not a power of two: room left */
    size_t cap = n ? 2 * n : 1;
    return thx_realloc(ctx, a, cap * size);
}

/* ---- builders ---------------------------------------------------------- */

thx_status thx_contours_create(thx_ctx *ctx, thx_contours **out)
{
    *out = thx_calloc(ctx, 1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

void thx_contours_destroy(thx_contours **c)
{
    if (!c || !*c) return;
    thx_contours *k = *c;
    for (size_t s = 0; s < k->n_surfaces; s++) {
        thx_contour_surface *cs = &k->surf[s];
        for (size_t l = 0; l < cs->n_layers; l++) {
            for (size_t i = 0; i < cs->layers[l].n_loops; i++) {
                free(cs->layers[l].loops[i].p);
                free(cs->layers[l].loops[i].lines);
            }
            free(cs->layers[l].loops);
        }
        free(cs->layers);
    }
    free(k->surf);
    free(k);
    *c = NULL;
}

int thx_contours_find_surface(const thx_contours *c, const char *name)
{
    for (size_t s = 0; s < c->n_surfaces; s++)
        if (strcmp(c->surf[s].name, name) == 0) return (int)s;
    return -1;
}

thx_status thx_contours_add_surface(thx_ctx *ctx, thx_contours *c, const char *name, thx_role role,
                                    thx_cap_method cap, double cap_grid, size_t *idx)
{
    if (strlen(name) == 0 || strlen(name) >= sizeof c->surf[0].name)
        return thx_error(ctx, THX_EINPUT, "surface name '%s' is empty or longer than 63 characters", name);
    if (thx_contours_find_surface(c, name) >= 0) return thx_error(ctx, THX_EINPUT, "surface \"%s\" declared twice", name);
    thx_contour_surface *ns = grow_one(ctx, c->surf, c->n_surfaces, sizeof *ns);
    if (!ns) return THX_ENOMEM;
    c->surf = ns;
    thx_contour_surface *cs = &c->surf[c->n_surfaces];
    memset(cs, 0, sizeof *cs);
    snprintf(cs->name, sizeof cs->name, "%s", name);
    cs->role = role;
    cs->cap = cap;
    cs->cap_grid = cap_grid;
    if (idx) *idx = c->n_surfaces;
    c->n_surfaces++;
    return THX_OK;
}

thx_status thx_contours_layer(thx_ctx *ctx, thx_contour_surface *cs, double z, int index, int line,
                              thx_contour_layer **out)
{
    if (cs->n_layers && cs->layers[cs->n_layers - 1].z == z) {
        *out = &cs->layers[cs->n_layers - 1];
        return THX_OK;
    }
    thx_contour_layer *nl = grow_one(ctx, cs->layers, cs->n_layers, sizeof *nl);
    if (!nl) return THX_ENOMEM;
    cs->layers = nl;
    thx_contour_layer *L = &cs->layers[cs->n_layers++];
    memset(L, 0, sizeof *L);
    L->z = z;
    L->index = index;
    L->line = line;
    *out = L;
    return THX_OK;
}

thx_status thx_contours_layer_add_loop(thx_ctx *ctx, thx_contour_layer *L, int line, thx_loop **out)
{
    thx_loop *nl = grow_one(ctx, L->loops, L->n_loops, sizeof *nl);
    if (!nl) return THX_ENOMEM;
    L->loops = nl;
    thx_loop *lp = &L->loops[L->n_loops++];
    memset(lp, 0, sizeof *lp);
    lp->line = line;
    *out = lp;
    return THX_OK;
}

thx_status thx_contours_add_loop(thx_ctx *ctx, thx_contours *c, size_t s, double z, const thx_vec2 *pts, size_t n)
{
    if (s >= c->n_surfaces) return thx_error(ctx, THX_EINPUT, "no surface %zu", s);
    thx_contour_surface *cs = &c->surf[s];
    if (cs->n_layers && z < cs->layers[cs->n_layers - 1].z)
        return thx_error(ctx, THX_EINPUT, "surface \"%s\": layer z=%g added after z=%g", cs->name, z,
                         cs->layers[cs->n_layers - 1].z);
    /* The file-wide layer index: count distinct z over all surfaces lazily at write time. */
    thx_contour_layer *L;
    THX_CHECK(thx_contours_layer(ctx, cs, z, -1, 0, &L));
    thx_loop *lp;
    THX_CHECK(thx_contours_layer_add_loop(ctx, L, 0, &lp));
    lp->p = thx_malloc(ctx, (n ? n : 1) * sizeof *lp->p);
    if (!lp->p) return THX_ENOMEM;
    memcpy(lp->p, pts, n * sizeof *pts);
    lp->n = n;
    return THX_OK;
}

/* ---- validation -------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

thx_status thx_contours_layer_z(thx_ctx *ctx, const thx_contours *c, double **zs, size_t *nz)
{
    size_t total = 0;
    for (size_t s = 0; s < c->n_surfaces; s++) total += c->surf[s].n_layers;
    double *z = thx_malloc(ctx, (total ? total : 1) * sizeof *z);
    if (!z) return THX_ENOMEM;
    size_t k = 0;
    for (size_t s = 0; s < c->n_surfaces; s++)
        for (size_t l = 0; l < c->surf[s].n_layers; l++) z[k++] = c->surf[s].layers[l].z;
    qsort(z, k, sizeof *z, cmp_double);
    size_t m = 0;
    for (size_t i = 0; i < k; i++)
        if (m == 0 || z[i] != z[m - 1]) z[m++] = z[i];
    *zs = z;
    *nz = m;
    return THX_OK;
}

static size_t z_index(const double *zs, size_t nz, double z)
{
    size_t lo = 0, hi = nz;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (zs[mid] <= z) lo = mid; else hi = mid;
    }
    return lo;
}


/* Layer number for messages: the file's, or the surface's own for contours built in memory. */
static int layer_no(const double *zs, size_t nz, const thx_contour_layer *L)
{
    return L->index >= 0 ? L->index + 1 : (int)z_index(zs, nz, L->z) + 1;
}

thx_status thx_contours_validate_with(thx_ctx *ctx, const thx_contours *c, thx_contours_check_fn fn, void *user)
{
    const char *path = c->path[0] ? c->path : "<contours>";
    if (c->n_surfaces == 0) return thx_error(ctx, THX_EINPUT, "%s: no surfaces declared", path);
    double *zs = NULL;
    size_t nz = 0;
    THX_CHECK(thx_contours_layer_z(ctx, c, &zs, &nz));
    thx_status st = THX_OK;
    for (size_t s = 0; s < c->n_surfaces && st == THX_OK; s++) {
        const thx_contour_surface *cs = &c->surf[s];
        if (cs->n_layers == 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" has no loops", path, cs->line, cs->name);
            break;
        }
        for (size_t l = 0; l < cs->n_layers && st == THX_OK; l++) {
            const thx_contour_layer *L = &cs->layers[l];
            int lno = layer_no(zs, nz, L);
            if (!isfinite(L->z)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d: z is not finite", path, L->line,
                               cs->name, lno);
                break;
            }
            if (l > 0) {
                const thx_contour_layer *P = &cs->layers[l - 1];
                if (!(L->z > P->z)) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": layer z=%g is out of order after z=%g",
                                   path, L->line, cs->name, L->z, P->z);
                    break;
                }
                size_t ip = z_index(zs, nz, P->z), il = z_index(zs, nz, L->z);
                if (il != ip + 1) {
                    st = thx_error(ctx, THX_EINPUT,
                                   "%s:%d: surface \"%s\" vanishes at z=%g and reappears at z=%g "
                                   "(a surface must be digitized on consecutive layers)",
                                   path, L->line, cs->name, zs[ip + 1], L->z);
                    break;
                }
            }
            for (size_t i = 0; i < L->n_loops && st == THX_OK; i++) {
                const thx_loop *lp = &L->loops[i];
                int where = lp->line ? lp->line : L->line;
                if (lp->n < 3) {
                    st = thx_error(ctx, THX_EINPUT,
                                   "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: loop has %zu point%s (at least 3 needed)",
                                   path, where, cs->name, lno, L->z, i + 1, lp->n, lp->n == 1 ? "" : "s");
                    break;
                }
                for (size_t k = 0; k < lp->n; k++) {
                    thx_vec2 a = lp->p[k];
                    int line = lp->lines ? lp->lines[k] : where;
                    if (!isfinite(a.x) || !isfinite(a.y)) {
                        st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: point %zu is not finite",
                                       path, line, cs->name, lno, L->z, i + 1, k + 1);
                        break;
                    }
                    if (fn) {
                        thx_contours_at at = {path, cs, L, i, lno, k};
                        st = fn(ctx, &at, user);
                        if (st != THX_OK) break;
                    }
                }
                if (st != THX_OK || !fn) continue;
                thx_contours_at at = {path, cs, L, i, lno, SIZE_MAX};
                st = fn(ctx, &at, user);
            }
        }
    }
    free(zs);
    return st;
}

thx_status thx_contours_validate_structure(thx_ctx *ctx, const thx_contours *c)
{
    return thx_contours_validate_with(ctx, c, NULL, NULL);
}

