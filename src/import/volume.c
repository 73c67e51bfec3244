/*
 * Volume meshes made elsewhere, into a model (thorax/import/import.h): the region table, unused
 * nodes, orientation, the surfaces the regions are bounded by, and the checks. The file is read by
 * thx_volume_file_read (thorax/io/volume_read.h).
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Surfaces come from face counts only (a face in one tetrahedron is a
 *    boundary face; in two of different regions an interface face): a
 *    sort of the 4T faces, a union-find over their nodes, a sum of signed
 *    volumes, and the exact orientation of each tetrahedron.
 *
 *  - Model surfaces may not share nodes (a volume node is on at most one
 *    surface node: thorax/model/model.h), so an interface that touches the outer
 *    boundary or another interface cannot be a surface of its own; it is
 *    recorded in info->dropped, and the volume check judges the rest.
 */
#include "thorax/import/import.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"

void thx_volume_import_opts_default(thx_volume_import_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = THX_VOLFMT_NONE;
    o->scale = 1.0;
    thx_check_opts_default(&o->check);
    thx_volume_check_opts_default(&o->vcheck);
}

void thx_volume_import_info_free(thx_volume_import_info *info)
{
    if (!info) return;
    free(info->regions);
    free(info->surfaces);
    if (info->surface_reports)
        for (size_t s = 0; s < info->n_surfaces; s++) thx_surface_report_free(&info->surface_reports[s]);
    free(info->surface_reports);
    thx_volume_report_free(&info->volume_report);
    memset(info, 0, sizeof *info);
}

/* ------------------------------------------------------------- names */

/* A region or surface name from any text: [A-Za-z0-9_.-], other characters
 * as '_', at most 31 characters, not starting with '.'; "" if in is empty. */
static void clean_name(char *out, const char *in)
{
    size_t k = 0;
    for (const char *p = in; *p && k < 31; p++) {
        char c = *p;
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                 c == '.';
        out[k++] = ok ? c : '_';
    }
    out[k] = '\0';
    if (out[0] == '.') out[0] = '_';
}

static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > 31 || s[0] == '.') return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.'))
            return 0;
    }
    return 1;
}

/* Makes name unique among used[0..n) by appending "_2", "_3", ... */
static void unique_name(char *name, char (*used)[64], size_t n)
{
    char base[64];
    snprintf(base, sizeof base, "%s", name);
    for (int k = 1;; k++) {
        int clash = 0;
        for (size_t i = 0; i < n && !clash; i++) clash = !strcmp(used[i], name);
        if (!clash) return;
        char suffix[16];
        snprintf(suffix, sizeof suffix, "_%d", k + 1);
        size_t bl = strlen(base), sl = strlen(suffix);
        if (bl + sl > 31) bl = 31 - sl;
        snprintf(name, 64, "%.*s%s", (int)bl, base, suffix);
    }
}

/* ------------------------------------------------------------- faces */

/* The outward faces of a right-handed tetrahedron p0..p3, counterclockwise
 * seen from outside (thorax/check/check_volume.h). */
static const int tet_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

typedef struct { int32_t a, b, c, tf; } face_rec; /* sorted nodes; tf = 4 * tet + local face */

static int cmp_face(const void *x, const void *y)
{
    const face_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    if (p->c != q->c) return p->c < q->c ? -1 : 1;
    return (p->tf > q->tf) - (p->tf < q->tf);
}

/* Sorts faces by (a, b, c, tf). Below 2^21 nodes the three node numbers
 * pack into one 63-bit key and an LSD radix sort (stable, so ties stay in tf
 * order, as the input is) does it in 8 passes at most: about ten times faster
 * than qsort on the 4.8 M faces of 1.2 M tetrahedra. */
static thx_status sort_faces(thx_ctx *ctx, face_rec *fr, size_t n, size_t n_nodes)
{
    if (n_nodes >= ((size_t)1 << 21) || n < 1024) {
        qsort(fr, n, sizeof *fr, cmp_face);
        return THX_OK;
    }
    typedef struct { uint64_t key; int32_t tf; } fkey;
    fkey *a = thx_malloc(ctx, n * sizeof *a), *b = thx_malloc(ctx, n * sizeof *b);
    if (!a || !b) {
        free(a);
        free(b);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n; i++)
        a[i].key = (uint64_t)fr[i].a << 42 | (uint64_t)fr[i].b << 21 | (uint64_t)fr[i].c, a[i].tf = fr[i].tf;
    for (int shift = 0; shift < 64; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++) count[(a[i].key >> shift & 255) + 1]++;
        int all_one = 0;
        for (int k = 1; k <= 256; k++) all_one |= count[k] == n;
        if (all_one) continue; /* every key has the same byte here */
        for (int k = 1; k <= 256; k++) count[k] += count[k - 1];
        for (size_t i = 0; i < n; i++) b[count[a[i].key >> shift & 255]++] = a[i];
        fkey *t = a;
        a = b, b = t;
    }
    const uint64_t m21 = ((uint64_t)1 << 21) - 1;
    for (size_t i = 0; i < n; i++) {
        fr[i].a = (int32_t)(a[i].key >> 42), fr[i].b = (int32_t)(a[i].key >> 21 & m21), fr[i].c = (int32_t)(a[i].key & m21);
        fr[i].tf = a[i].tf;
    }
    free(a);
    free(b);
    return THX_OK;
}

static void sort3(int32_t *v)
{
    int32_t t;
    if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
    if (v[1] > v[2]) t = v[1], v[1] = v[2], v[2] = t;
    if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
}

/* The outward triangle of face tf of a right-handed tetrahedron. */
static void face_tri(const int32_t *tet, int32_t tf, int32_t out[3])
{
    const int32_t *q = tet + 4 * (size_t)(tf / 4);
    for (int j = 0; j < 3; j++) out[j] = q[tet_face[tf % 4][j]];
}

static int32_t uf_find(int32_t *p, int32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static void uf_union(int32_t *p, int32_t a, int32_t b)
{
    a = uf_find(p, a), b = uf_find(p, b);
    if (a != b) p[a < b ? b : a] = a < b ? a : b;
}

/* Signed volume enclosed by triangles (3 volume nodes each), about ref. */
static double tris_volume(const double *xyz, const int32_t *tri, size_t n)
{
    if (!n) return 0;
    const double *o = xyz + 3 * (size_t)tri[0];
    double v = 0;
    for (size_t t = 0; t < n; t++) {
        const double *a = xyz + 3 * (size_t)tri[3 * t], *b = xyz + 3 * (size_t)tri[3 * t + 1], *c = xyz + 3 * (size_t)tri[3 * t + 2];
        double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2];
        double bx = b[0] - o[0], by = b[1] - o[1], bz = b[2] - o[2];
        double cx = c[0] - o[0], cy = c[1] - o[1], cz = c[2] - o[2];
        v += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    }
    return v / 6.0;
}

/* A candidate surface: triangles of volume nodes, its kind and regions. */
typedef struct {
    int32_t *tri;
    size_t n_tris;
    thx_volume_surface_kind kind;
    int inside, outside;
    char name[64];
    int named_by_file;
} cand;

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Builds a thx_surface from triangles of volume nodes: its nodes are the
 * distinct volume nodes, in increasing order (*vnodes, new). */
static thx_status make_surface(thx_ctx *ctx, const double *xyz, const cand *cd, thx_role role, thx_surface **out,
                               int32_t **vnodes, size_t *n_vnodes)
{
    thx_status st = THX_OK;
    thx_surface *s = NULL;
    int32_t *nodes = thx_malloc(ctx, (3 * cd->n_tris + 1) * sizeof *nodes);
    if (!nodes) return THX_ENOMEM;
    memcpy(nodes, cd->tri, 3 * cd->n_tris * sizeof *nodes);
    size_t n = 3 * cd->n_tris;
    qsort(nodes, n, sizeof *nodes, cmp_i32);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (!u || nodes[i] != nodes[u - 1]) nodes[u++] = nodes[i];
    THX_TRY(thx_surface_create(ctx, cd->name, role, &s));
    s->xyz = thx_malloc(ctx, 3 * (u ? u : 1) * sizeof *s->xyz);
    s->tri = thx_malloc(ctx, 3 * (cd->n_tris ? cd->n_tris : 1) * sizeof *s->tri);
    if (!s->xyz || !s->tri) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < u; i++) memcpy(s->xyz + 3 * i, xyz + 3 * (size_t)nodes[i], 3 * sizeof *xyz);
    s->n_nodes = u;
    for (size_t i = 0; i < 3 * cd->n_tris; i++) {
        const int32_t *f = bsearch(&cd->tri[i], nodes, u, sizeof *nodes, cmp_i32);
        s->tri[i] = (int32_t)(f - nodes);
    }
    s->n_tris = cd->n_tris;
    *out = s;
    s = NULL;
    *vnodes = nodes;
    *n_vnodes = u;
    nodes = NULL;
done:
    thx_surface_destroy(&s);
    free(nodes);
    return st;
}

/* ------------------------------------------------------------- the policy */

static int cmp_ll(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Policy step 3: the region table, and each tetrahedron's region index. */
static thx_status build_regions(thx_volume_file *r, const thx_volume_import_opts *o, thx_region **table_out, size_t *n_out,
                                int32_t **region_out, thx_volume_import_region **info_out)
{
    thx_status st = THX_OK;
    long long *tags = thx_malloc(r->ctx, r->n_tets * sizeof *tags);
    thx_region *table = NULL;
    thx_volume_import_region *ri = NULL;
    int32_t *region = NULL;
    char(*used)[64] = NULL;
    if (!tags) return THX_ENOMEM;
    for (size_t t = 0; t < r->n_tets; t++) tags[t] = r->has_tags ? r->tag[t] : 1;
    qsort(tags, r->n_tets, sizeof *tags, cmp_ll);
    size_t n = 0;
    for (size_t t = 0; t < r->n_tets; t++)
        if (!n || tags[t] != tags[n - 1]) tags[n++] = tags[t];
    for (size_t k = 0; k < o->n_region_maps; k++) {
        const thx_region_map *mp = &o->region_maps[k];
        if (!bsearch(&mp->tag, tags, n, sizeof *tags, cmp_ll)) {
            char list[200] = "";
            for (size_t i = 0; i < n && strlen(list) < sizeof list - 24; i++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%lld", i ? ", " : "", tags[i]);
            if (n > 0 && strlen(list) >= sizeof list - 24) snprintf(list + strlen(list), sizeof list - strlen(list), ", ...");
            st = thx_error(r->ctx, THX_EINPUT, "%s: --region %lld: the mesh has no region %lld (its regions: %s)", r->path,
                           mp->tag, mp->tag, list);
            goto done;
        }
        for (size_t j = 0; j < k; j++)
            if (o->region_maps[j].tag == mp->tag) {
                st = thx_error(r->ctx, THX_EINPUT, "--region %lld given twice", mp->tag);
                goto done;
            }
        if (mp->name[0] && !valid_name(mp->name)) {
            st = thx_error(r->ctx, THX_EINPUT, "--region %lld=%s: a region name is 1-31 characters of A-Z a-z 0-9 _ . - "
                           "(not starting with '.')", mp->tag, mp->name);
            goto done;
        }
        if (mp->has_sigma && !(mp->sigma > 0 && isfinite(mp->sigma))) {
            st = thx_error(r->ctx, THX_EINPUT, "--region %lld: conductivity %g must be a finite number > 0 (S/m)", mp->tag,
                           mp->sigma);
            goto done;
        }
    }
    table = thx_calloc(r->ctx, n, sizeof *table);
    ri = thx_calloc(r->ctx, n, sizeof *ri);
    used = thx_calloc(r->ctx, n + 1, sizeof *used);
    region = thx_malloc(r->ctx, r->n_tets * sizeof *region);
    if (!table || !ri || !used || !region) {
        st = THX_ENOMEM;
        goto done;
    }
    /* names given by options first, so that a default name yields to them */
    for (int pass = 0; pass < 2; pass++)
        for (size_t k = 0; k < n; k++) {
            const thx_region_map *mp = NULL;
            for (size_t j = 0; j < o->n_region_maps; j++)
                if (o->region_maps[j].tag == tags[k]) mp = &o->region_maps[j];
            int by_option = mp && mp->name[0];
            if (by_option != (pass == 0)) continue;
            thx_region *g = &table[k];
            ri[k].tag = tags[k];
            const char *fname = thx_volume_file_name_of(r, 3, tags[k]);
            if (fname) snprintf(ri[k].file_name, sizeof ri[k].file_name, "%s", fname);
            if (by_option) {
                snprintf(g->name, sizeof g->name, "%s", mp->name);
                for (size_t j = 0; j < k; j++)
                    if (table[j].name[0] && !strcmp(table[j].name, g->name)) {
                        st = thx_error(r->ctx, THX_EINPUT, "--region: regions %lld and %lld are both named \"%s\"",
                                       tags[j], tags[k], g->name);
                        goto done;
                    }
                ri[k].name_from = THX_RNAME_OPTION;
            } else {
                char nm[64] = "";
                if (fname) clean_name(nm, fname);
                ri[k].name_from = nm[0] ? THX_RNAME_FILE : THX_RNAME_DEFAULT;
                if (!nm[0]) snprintf(nm, sizeof nm, "region_%lld", tags[k]);
                size_t nu = 0;
                for (size_t j = 0; j < n; j++)
                    if (table[j].name[0]) snprintf(used[nu++], 64, "%s", table[j].name);
                unique_name(nm, used, nu);
                snprintf(g->name, sizeof g->name, "%s", nm);
            }
            if (mp && mp->has_sigma) {
                g->sigma[0] = g->sigma[4] = g->sigma[8] = mp->sigma;
                snprintf(g->source, sizeof g->source, "thorax import --region (isotropic, S/m)");
            } else if (o->default_region.sigma[0] > 0) {
                memcpy(g->sigma, o->default_region.sigma, sizeof g->sigma);
                g->anisotropic = o->default_region.anisotropic;
                snprintf(g->source, sizeof g->source, "%s", o->default_region.source);
                ri[k].sigma_defaulted = 1;
            } else {
                st = thx_error(r->ctx, THX_EINPUT, "%s: region %lld (\"%s\") has no conductivity: give --region %lld=NAME:SIGMA",
                               r->path, tags[k], g->name, tags[k]);
                goto done;
            }
        }
    for (size_t t = 0; t < r->n_tets; t++) {
        long long tg = r->has_tags ? r->tag[t] : 1;
        const long long *f = bsearch(&tg, tags, n, sizeof *tags, cmp_ll);
        region[t] = (int32_t)(f - tags);
        ri[region[t]].n_tets++;
    }
    *table_out = table, *n_out = n, *region_out = region, *info_out = ri;
    table = NULL, ri = NULL, region = NULL;
done:
    free(tags);
    free(table);
    free(ri);
    free(region);
    free(used);
    return st;
}

/* Policy step 4: removes nodes in no tetrahedron (and tagged triangles on them). */
static thx_status drop_unused(thx_volume_file *r, size_t *removed, long long *first)
{
    int32_t *map = thx_malloc(r->ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < r->n_nodes; i++) map[i] = -1;
    for (size_t i = 0; i < 4 * r->n_tets; i++) map[r->tet[i]] = 0;
    size_t k = 0;
    *first = -1;
    for (size_t i = 0; i < r->n_nodes; i++) {
        if (map[i] < 0) {
            if (*first < 0) *first = r->node_tag ? r->node_tag[i] : (long long)i + r->index_base;
            continue;
        }
        map[i] = (int32_t)k;
        if (k != i) memmove(r->xyz + 3 * k, r->xyz + 3 * i, 3 * sizeof *r->xyz);
        k++;
    }
    *removed = r->n_nodes - k;
    for (size_t i = 0; i < 4 * r->n_tets; i++) r->tet[i] = map[r->tet[i]];
    size_t kt = 0;
    for (size_t t = 0; t < r->n_tris; t++) {
        int32_t a = map[r->tri[3 * t]], b = map[r->tri[3 * t + 1]], c = map[r->tri[3 * t + 2]];
        if (a < 0 || b < 0 || c < 0) continue;
        r->tri[3 * kt] = a, r->tri[3 * kt + 1] = b, r->tri[3 * kt + 2] = c;
        r->tri_tag[kt++] = r->tri_tag[t];
    }
    r->n_tris = kt;
    r->n_nodes = k;
    free(map);
    return THX_OK;
}

/* Policy step 5: left-handed tetrahedra get their last two nodes swapped;
 * a flat one refuses the file. */
static thx_status orient_tets(thx_volume_file *r, size_t *flipped)
{
    size_t n_flat = 0, ex = 0;
    *flipped = 0;
    for (size_t t = 0; t < r->n_tets; t++) {
        int32_t *q = r->tet + 4 * t;
        double o = thx_orient3d(r->xyz + 3 * (size_t)q[0], r->xyz + 3 * (size_t)q[1], r->xyz + 3 * (size_t)q[2],
                                r->xyz + 3 * (size_t)q[3]);
        if (o > 0) {
            int32_t s = q[2];
            q[2] = q[3], q[3] = s;
            (*flipped)++;
        } else if (o == 0) {
            if (!n_flat) ex = t;
            n_flat++;
        }
    }
    if (n_flat)
        return thx_error(r->ctx, THX_EGEOM,
                         "%s: %zu flat tetrahedr%s (four nodes in one plane, or a node twice; first: the one at %s %lld): "
                         "refused, a flat tetrahedron cannot be made right-handed", r->path, n_flat, n_flat == 1 ? "on" : "a",
                         r->ref_kind, r->ref[ex]);
    return THX_OK;
}

/* A Gmsh physical surface that holds every triangle of cd, if there is one. */
static const char *file_surface_name(const thx_volume_file *r, const face_rec *named, size_t n_named, const cand *cd)
{
    if (!n_named || !cd->n_tris) return NULL;
    long long tag = LLONG_MIN;
    for (size_t t = 0; t < cd->n_tris; t++) {
        face_rec key;
        int32_t v[3] = {cd->tri[3 * t], cd->tri[3 * t + 1], cd->tri[3 * t + 2]};
        sort3(v);
        key.a = v[0], key.b = v[1], key.c = v[2], key.tf = INT32_MIN;
        /* the first record with this key */
        size_t lo = 0, hi = n_named;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (cmp_face(&named[mid], &key) < 0) lo = mid + 1;
            else hi = mid;
        }
        if (lo == n_named || named[lo].a != v[0] || named[lo].b != v[1] || named[lo].c != v[2]) return NULL;
        long long tg = r->tri_tag[named[lo].tf];
        if (tag != LLONG_MIN && tg != tag) return NULL;
        tag = tg;
    }
    return thx_volume_file_name_of(r, 2, tag);
}

/* Collects faces [begin, end) of kind into components by node-connectivity
 * (a union-find over the nodes of those faces). comp[i] = component of face
 * i (in order of first appearance); returns the component count. */
static size_t components(const int32_t *tet, const int32_t *faces, size_t n_faces, int32_t *parent, size_t n_nodes,
                         int32_t *cid, int32_t *comp)
{
    for (size_t i = 0; i < n_nodes; i++) parent[i] = (int32_t)i, cid[i] = -1;
    for (size_t i = 0; i < n_faces; i++) {
        int32_t v[3];
        face_tri(tet, faces[i], v);
        uf_union(parent, v[0], v[1]);
        uf_union(parent, v[0], v[2]);
    }
    size_t nc = 0;
    for (size_t i = 0; i < n_faces; i++) {
        int32_t v[3];
        face_tri(tet, faces[i], v);
        int32_t root = uf_find(parent, v[0]);
        if (cid[root] < 0) cid[root] = (int32_t)nc++;
        comp[i] = cid[root];
    }
    return nc;
}

/* Face indices grouped by component, in order within each (a counting
 * sort): component k's are order[start[k] .. start[k + 1]). */
static thx_status group_faces(thx_ctx *ctx, const int32_t *comp, size_t n, size_t nc, int32_t **order, size_t **start)
{
    *order = thx_malloc(ctx, (n ? n : 1) * sizeof **order);
    *start = thx_calloc(ctx, nc + 2, sizeof **start);
    if (!*order || !*start) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) (*start)[comp[i] + 2]++;
    for (size_t k = 0; k < nc; k++) (*start)[k + 2] += (*start)[k + 1];
    for (size_t i = 0; i < n; i++) (*order)[(*start)[comp[i] + 1]++] = (int32_t)i;
    return THX_OK;
}

static void add_dropped(thx_volume_import_info *info, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add_dropped(thx_volume_import_info *info, const char *fmt, ...)
{
    if (info->n_dropped < THX_VIMPORT_MAX_DROPPED) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(info->dropped[info->n_dropped], sizeof info->dropped[0], fmt, ap);
        va_end(ap);
    }
    info->n_dropped++;
}

static void free_cands(cand *c, size_t n)
{
    for (size_t i = 0; c && i < n; i++) free(c[i].tri);
    free(c);
}

/* Policy step 6: the candidate surfaces (boundary components first, then
 * interface components that can be surfaces of their own). */
static thx_status find_surfaces(thx_volume_file *r, const int32_t *region, const thx_region *table, const thx_volume_import_opts *o,
                                thx_volume_import_info *info, cand **out, size_t *n_out)
{
    thx_status st = THX_OK;
    thx_ctx *ctx = r->ctx;
    size_t nt = r->n_tets, nf = 4 * nt;
    face_rec *fr = thx_malloc(ctx, (nf ? nf : 1) * sizeof *fr);
    int32_t *nb = thx_malloc(ctx, (nf ? nf : 1) * sizeof *nb);
    int32_t *parent = thx_malloc(ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *parent);
    int32_t *cid = thx_malloc(ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *cid);
    unsigned char *on_boundary = thx_calloc(ctx, r->n_nodes ? r->n_nodes : 1, 1);
    int32_t *bf = NULL, *ifc = NULL, *comp = NULL, *tri = NULL, *order = NULL;
    size_t *start = NULL;
    face_rec *named = NULL;
    cand *cands = NULL;
    size_t n_cands = 0, n_bf = 0, n_if = 0;
    if (!fr || !nb || !parent || !cid || !on_boundary) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++) {
            int32_t v[3];
            face_tri(r->tet, (int32_t)(4 * t + (size_t)f), v);
            sort3(v);
            face_rec *e = &fr[4 * t + (size_t)f];
            e->a = v[0], e->b = v[1], e->c = v[2], e->tf = (int32_t)(4 * t + (size_t)f);
        }
    THX_TRY(sort_faces(ctx, fr, nf, r->n_nodes));
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && fr[j].a == fr[i].a && fr[j].b == fr[i].b && fr[j].c == fr[i].c) j++;
        for (size_t k = i; k < j; k++)
            nb[fr[k].tf] = j - i == 1 ? -1 : j - i == 2 ? fr[i + (k == i)].tf : -2;
        if (j - i > 2) info->n_nonconforming_faces++;
        i = j;
    }
    /* boundary and interface faces, in tetrahedron order */
    bf = thx_malloc(ctx, (nf ? nf : 1) * sizeof *bf);
    ifc = thx_malloc(ctx, (nf ? nf : 1) * sizeof *ifc);
    comp = thx_malloc(ctx, (nf ? nf : 1) * sizeof *comp);
    if (!bf || !ifc || !comp) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t tf = 0; tf < nf; tf++) {
        if (nb[tf] == -1) bf[n_bf++] = (int32_t)tf;
        else if (nb[tf] >= 0 && (int32_t)tf < nb[tf] && region[tf / 4] != region[nb[tf] / 4]) ifc[n_if++] = (int32_t)tf;
    }
    for (size_t i = 0; i < n_bf; i++) {
        int32_t v[3];
        face_tri(r->tet, bf[i], v);
        on_boundary[v[0]] = on_boundary[v[1]] = on_boundary[v[2]] = 1;
    }
    /* Gmsh's named triangles, sorted by their nodes (tf holds the triangle's index) */
    if (r->n_tris) {
        named = thx_malloc(ctx, r->n_tris * sizeof *named);
        if (!named) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t t = 0; t < r->n_tris; t++) {
            int32_t v[3] = {r->tri[3 * t], r->tri[3 * t + 1], r->tri[3 * t + 2]};
            sort3(v);
            named[t].a = v[0], named[t].b = v[1], named[t].c = v[2], named[t].tf = (int32_t)t;
        }
        qsort(named, r->n_tris, sizeof *named, cmp_face);
    }
    size_t n_bc = components(r->tet, bf, n_bf, parent, r->n_nodes, cid, comp);
    THX_TRY(group_faces(ctx, comp, n_bf, n_bc, &order, &start));
    size_t n_tri_total = n_bf + n_if;
    tri = thx_malloc(ctx, 3 * (n_tri_total ? n_tri_total : 1) * sizeof *tri);
    if (!tri) {
        st = THX_ENOMEM;
        goto done;
    }
    cands = thx_calloc(ctx, n_bc + n_if + 1, sizeof *cands);
    if (!cands) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t k = 0; k < n_bc; k++) {
        cand *cd = &cands[n_cands];
        size_t m = 0;
        int reg = -2;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            face_tri(r->tet, bf[i], tri + 3 * m++);
            int rg = region[bf[i] / 4];
            reg = reg == -2 ? rg : reg == rg ? reg : -1;
        }
        cd->tri = thx_malloc(ctx, 3 * m * sizeof *cd->tri);
        if (!cd->tri) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(cd->tri, tri, 3 * m * sizeof *tri);
        cd->n_tris = m;
        n_cands++;
        double vol = tris_volume(r->xyz, cd->tri, m);
        if (vol < 0) { /* a hole in the mesh: faces out of the hole */
            for (size_t t = 0; t < m; t++) {
                int32_t s = cd->tri[3 * t + 1];
                cd->tri[3 * t + 1] = cd->tri[3 * t + 2], cd->tri[3 * t + 2] = s;
            }
            cd->kind = THX_VSURF_CAVITY;
            cd->inside = -1, cd->outside = reg >= 0 ? reg : -1;
            snprintf(cd->name, sizeof cd->name, "cavity");
        } else {
            cd->kind = THX_VSURF_BOUNDARY;
            cd->inside = reg >= 0 ? reg : -1, cd->outside = -1;
            snprintf(cd->name, sizeof cd->name, "%s", reg >= 0 ? table[reg].name : "outer");
        }
    }
    size_t n_ic = components(r->tet, ifc, n_if, parent, r->n_nodes, cid, comp);
    free(order);
    free(start);
    order = NULL, start = NULL;
    THX_TRY(group_faces(ctx, comp, n_if, n_ic, &order, &start));
    for (size_t k = 0; k < n_ic; k++) {
        size_t m = 0, first = (size_t)order[start[k]];
        int touches = 0;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int32_t v[3];
            face_tri(r->tet, ifc[i], v);
            touches |= on_boundary[v[0]] | on_boundary[v[1]] | on_boundary[v[2]];
            m++;
        }
        int ra = region[ifc[first] / 4], rb = region[nb[ifc[first]] / 4];
        int ok_a = 1, ok_b = 1;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int r1 = region[ifc[i] / 4], r2 = region[nb[ifc[i]] / 4];
            ok_a &= r1 == ra || r2 == ra;
            ok_b &= r1 == rb || r2 == rb;
        }
        if (touches) {
            add_dropped(info, "%zu faces between regions \"%s\" and \"%s\"%s touch the boundary of the mesh: not a surface "
                        "of their own", m, table[ra].name, table[rb].name, ok_a && ok_b ? "" : " (and others)");
            continue;
        }
        if (!ok_a && !ok_b) {
            add_dropped(info, "%zu faces between regions \"%s\", \"%s\" and others meet where three or more regions do: not a "
                        "surface of their own", m, table[ra].name, table[rb].name);
            continue;
        }
        /* oriented outward of region c: the face as its tetrahedron in c has it */
        int c = ok_a ? ra : rb;
        m = 0;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int32_t tf = region[ifc[i] / 4] == c ? ifc[i] : nb[ifc[i]];
            face_tri(r->tet, tf, tri + 3 * m++);
        }
        double vol = tris_volume(r->xyz, tri, m);
        int inside = c, outside = ok_a && ok_b ? rb : -1;
        if (vol < 0) {
            for (size_t t = 0; t < m; t++) {
                int32_t s = tri[3 * t + 1];
                tri[3 * t + 1] = tri[3 * t + 2], tri[3 * t + 2] = s;
            }
            outside = c;
            inside = ok_a && ok_b ? rb : -1;
        }
        cand *cd = &cands[n_cands];
        cd->tri = thx_malloc(ctx, 3 * m * sizeof *cd->tri);
        if (!cd->tri) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(cd->tri, tri, 3 * m * sizeof *tri);
        cd->n_tris = m;
        cd->kind = THX_VSURF_INTERFACE;
        cd->inside = inside, cd->outside = outside;
        snprintf(cd->name, sizeof cd->name, "%s", inside >= 0 ? table[inside].name : "interface");
        n_cands++;
    }
    /* names: a Gmsh physical surface holding every face; then unique */
    {
        char(*used)[64] = thx_calloc(ctx, n_cands + 1, sizeof *used);
        if (!used) {
            st = THX_ENOMEM;
            goto done;
        }
        snprintf(used[0], 64, "volume");
        for (size_t k = 0; k < n_cands; k++) {
            const char *fname = file_surface_name(r, named, r->n_tris, &cands[k]);
            char nm[64] = "";
            if (fname) clean_name(nm, fname);
            if (nm[0] && strcmp(nm, "model.json") != 0) {
                snprintf(cands[k].name, sizeof cands[k].name, "%s", nm);
                cands[k].named_by_file = 1;
            }
            unique_name(cands[k].name, used, k + 1);
            snprintf(used[k + 1], 64, "%s", cands[k].name);
        }
        free(used);
    }
    (void)o;
    *out = cands, *n_out = n_cands;
    cands = NULL;
done:
    free_cands(cands, n_cands);
    free(fr);
    free(nb);
    free(parent);
    free(cid);
    free(on_boundary);
    free(bf);
    free(ifc);
    free(comp);
    free(tri);
    free(named);
    free(order);
    free(start);
    return st;
}

thx_status thx_volume_import(thx_ctx *ctx, const char *path, const thx_volume_import_opts *opts, thx_model **out,
                             thx_volume_import_info *info)
{
    thx_volume_import_opts def;
    if (!opts) {
        thx_volume_import_opts_default(&def);
        opts = &def;
    }
    *out = NULL;
    thx_volume_import_info local;
    if (!info) info = &local;
    memset(info, 0, sizeof *info);
    info->first_unused = -1;
    info->scale = opts->scale;
    thx_status st = THX_OK;
    thx_volume_file r;
    memset(&r, 0, sizeof r);
    thx_model *m = NULL;
    thx_volume *v = NULL;
    thx_region *table = NULL;
    int32_t *region = NULL;
    cand *cands = NULL;
    size_t n_reg = 0, n_cands = 0;
    if (!(opts->scale > 0) || !isfinite(opts->scale)) {
        st = thx_error(ctx, THX_EINPUT, "%s: scale %g must be a finite positive number", path, opts->scale);
        goto done;
    }
    thx_volume_format fmt = opts->format != THX_VOLFMT_NONE ? opts->format : thx_volume_format_from_path(path);
    info->format = fmt;
    if (fmt == THX_VOLFMT_NONE) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a volume mesh format (.pts + .tet/.elem, .vtk unstructured grid, .vtu, .msh)",
                       path);
        goto done;
    }
    /* 1. read */
    THX_TRY(thx_volume_file_read(ctx, path, fmt, opts->elem_path, opts->region_array, &r));
    snprintf(info->format_detail, sizeof info->format_detail, "%s", r.detail);
    snprintf(info->path2, sizeof info->path2, "%s", r.path2);
    snprintf(info->region_source, sizeof info->region_source, "%s", r.region_source);
    info->index_base = r.index_base;
    info->index_base_detected = r.index_base_detected;
    info->n_nodes_read = r.n_nodes;
    info->n_tets_read = r.n_tets;
    info->n_cells_ignored = r.n_ignored;
    info->n_tris_named = r.n_tris;
    if (r.n_tets == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: no tetrahedra%s", path, r.n_ignored ? " (only cells of dimension 0-2)" : "");
        goto done;
    }
    /* 2. scale */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < r.n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            double *x = &r.xyz[3 * i + (size_t)k];
            *x *= opts->scale;
            if (!isfinite(*x)) {
                st = thx_error(ctx, THX_EINPUT, "%s: node %zu is not finite after scaling by %g", path, i + 1, opts->scale);
                goto done;
            }
            lo[k] = fmin(lo[k], *x), hi[k] = fmax(hi[k], *x);
        }
    info->extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    /* 3. regions */
    THX_TRY(build_regions(&r, opts, &table, &n_reg, &region, &info->regions));
    info->n_regions = n_reg;
    /* 4. unused nodes; 5. orientation */
    THX_TRY(drop_unused(&r, &info->n_unused_removed, &info->first_unused));
    THX_TRY(orient_tets(&r, &info->n_flipped));
    /* 6. surfaces */
    THX_TRY(find_surfaces(&r, region, table, opts, info, &cands, &n_cands));

    /* the model: its volume first (the surfaces' node tables point into it) */
    THX_TRY(thx_model_create(ctx, &m));
    THX_TRY(thx_volume_create(ctx, &v));
    m->volume = v;
    v->n_nodes = r.n_nodes;
    v->xyz = r.xyz, r.xyz = NULL;
    v->n_tets = r.n_tets;
    v->tet = r.tet, r.tet = NULL;
    v->region = region, region = NULL;
    v->n_regions = n_reg;
    v->regions = table, table = NULL;
    for (size_t t = 0; t < v->n_tets; t++) info->regions[v->region[t]].volume += thx_volume_tet_volume(v, t);
    v->node_surf = thx_malloc(ctx, v->n_nodes * sizeof *v->node_surf);
    v->node_snode = thx_malloc(ctx, v->n_nodes * sizeof *v->node_snode);
    v->surf_node = thx_calloc(ctx, n_cands + 1, sizeof *v->surf_node);
    v->surf_n_nodes = thx_calloc(ctx, n_cands + 1, sizeof *v->surf_n_nodes);
    info->surfaces = thx_calloc(ctx, n_cands + 1, sizeof *info->surfaces);
    info->surface_reports = thx_calloc(ctx, n_cands + 1, sizeof *info->surface_reports);
    if (!v->node_surf || !v->node_snode || !v->surf_node || !v->surf_n_nodes || !info->surfaces || !info->surface_reports) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < v->n_nodes; i++) v->node_surf[i] = v->node_snode[i] = -1;
    /* 7a. each surface checked; interfaces that fail are not stored */
    char first_reason[400] = "";
    for (size_t k = 0; k < n_cands; k++) {
        const cand *cd = &cands[k];
        thx_role role = cd->kind == THX_VSURF_BOUNDARY ? THX_ROLE_OUTER : cd->kind == THX_VSURF_CAVITY ? THX_ROLE_HEART : THX_ROLE_OTHER;
        thx_surface *s = NULL;
        int32_t *vn = NULL;
        size_t nvn = 0;
        THX_TRY(make_surface(ctx, v->xyz, cd, role, &s, &vn, &nvn));
        thx_surface_report rep;
        memset(&rep, 0, sizeof rep);
        st = thx_surface_check(ctx, s, NULL, &opts->check, &rep);
        if (st != THX_OK && st != THX_ECHECK) {
            thx_surface_destroy(&s);
            free(vn);
            goto done;
        }
        if (st == THX_ECHECK && cd->kind == THX_VSURF_INTERFACE) {
            add_dropped(info, "interface \"%s\" (%zu triangles) is not a valid surface: %s", cd->name, cd->n_tris,
                        rep.n_reasons ? rep.reasons[0] : "failed its checks");
            thx_surface_report_free(&rep);
            thx_surface_destroy(&s);
            free(vn);
            st = THX_OK;
            thx_ctx_clear(ctx);
            continue;
        }
        if (st == THX_ECHECK) {
            info->check_failed = 1;
            if (!first_reason[0])
                snprintf(first_reason, sizeof first_reason, "surface \"%s\": %s", cd->name,
                         rep.n_reasons ? rep.reasons[0] : "failed its checks");
            st = THX_OK;
            thx_ctx_clear(ctx);
        }
        size_t si = m->n_surfaces;
        st = thx_model_add_surface(ctx, m, &s);
        if (st) {
            thx_surface_report_free(&rep);
            free(vn);
            goto done;
        }
        if (rep.interior_source != THX_INTERIOR_NONE && !(rep.failures & THX_CHECKF_SOLID_ANGLE)) {
            m->has_interior[si] = 1;
            m->interior[si] = rep.interior;
        }
        info->surface_reports[si] = rep;
        info->surfaces[si].kind = cd->kind;
        info->surfaces[si].inside = cd->inside;
        info->surfaces[si].outside = cd->outside;
        info->surfaces[si].named_by_file = cd->named_by_file;
        v->surf_node[si] = vn;
        v->surf_n_nodes[si] = nvn;
        for (size_t i = 0; i < nvn; i++) v->node_surf[vn[i]] = (int32_t)si, v->node_snode[vn[i]] = (int32_t)i;
        v->n_surfaces = m->n_surfaces;
        info->n_surfaces = m->n_surfaces;
    }
    /* 7b. the volume against its surfaces */
    st = thx_volume_check(ctx, v, m, &opts->vcheck, &info->volume_report);
    info->volume_checked = 1;
    if (st != THX_OK && st != THX_ECHECK) goto done;
    if (st == THX_ECHECK) {
        info->check_failed = 1;
        if (!first_reason[0])
            snprintf(first_reason, sizeof first_reason, "volume: %s",
                     info->volume_report.n_reasons ? info->volume_report.reasons[0] : "failed its checks");
    }
    st = THX_OK;
    thx_ctx_clear(ctx);
    if (info->check_failed && !opts->force) {
        st = thx_error(ctx, THX_ECHECK, "%s: refused: %s", path, first_reason);
        goto done;
    }
    *out = m;
    m = NULL;
done:
    thx_volume_file_free(&r);
    free(table);
    free(region);
    free_cands(cands, n_cands);
    thx_model_destroy(&m);
    if (info == &local) thx_volume_import_info_free(&local);
    return st;
}
