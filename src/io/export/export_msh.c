/*
 * The volume as Gmsh MSH 4.1 ASCII with tagged boundary surfaces and data views
 * (thx_volume_export_msh, thorax/io/export_data.h).
 *
 * Invariants:
 *  - Physical groups: dimension 3, tag = region id (1-based), the region's name; dimension 2,
 *    tag = surface index + 1, the surface's name. One entity per group, same tag.
 *  - Nodes: tag = volume node number (1-based), each in the block of the lowest region whose
 *    tetrahedra use it (Gmsh only needs every node once).
 *  - Elements: tetrahedra (type 4) tag = volume.tet line number, one block per non-empty region;
 *    then per surface the faces of tetrahedra lying on it (type 2), tags after the tetrahedra,
 *    counterclockwise seen from outside the surface (as the surface's own triangles).
 *  - A face lies on surface s when one triangle T of s holds its three nodes: a node of T's
 *    corners, or a Steiner node the mesher put inside T or on one of T's edges (v->steiner:
 *    triangle and barycentric weights; a zero weight puts it on the opposite edge, which it
 *    shares with the neighbouring triangle). This is exact: no coordinate is compared.
 *  - Second line of $Comments: "thorax volume mesh" (the claim signature of thx_export_claim).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/io/export_data.h"

typedef struct {
    int32_t s, tri;    /* surface, its triangle the face lies in */
    int32_t key[3];    /* sorted volume nodes */
    int32_t n[3];      /* oriented as the triangle */
} face;

static int face_cmp(const void *pa, const void *pb)
{
    const face *a = pa, *b = pb;
    if (a->s != b->s) return a->s < b->s ? -1 : 1;
    if (a->tri != b->tri) return a->tri < b->tri ? -1 : 1;
    for (int k = 0; k < 3; k++)
        if (a->key[k] != b->key[k]) return a->key[k] < b->key[k] ? -1 : 1;
    return 0;
}

/* Where a volume node lies on the surfaces: a corner of surface ns (node nn), or Steiner record st. */
typedef struct {
    const thx_model *m;
    const thx_volume *v;
    const int32_t *ns, *nn, *st; /* per volume node: surface or -1; its node there; Steiner record or -1 */
    int64_t **inc_start;          /* per surface: CSR of the triangles around each node */
    int32_t **inc;
} locator;

static int tri_has(const thx_surface *S, int32_t T, int32_t node)
{
    const int32_t *c = S->tri + 3 * (size_t)T;
    return c[0] == node || c[1] == node || c[2] == node;
}

/* Whether volume node w lies in triangle T of surface s. */
static int in_tri(const locator *L, int32_t w, int32_t s, int32_t T)
{
    const thx_surface *S = L->m->surf[s];
    if (L->ns[w] == s) return tri_has(S, T, L->nn[w]);
    if (L->st[w] < 0) return 0;
    const thx_steiner *k = &L->v->steiner[L->st[w]];
    if (k->surf != s) return 0;
    if (k->tri == T) return 1;
    const int32_t *c = S->tri + 3 * (size_t)k->tri;
    for (int j = 0; j < 3; j++)
        if (k->bary[j] == 0) return tri_has(S, T, c[(j + 1) % 3]) && tri_has(S, T, c[(j + 2) % 3]);
    return 0;
}

/* The surface a volume node lies on, or -1. */
static int32_t surf_of(const locator *L, int32_t w)
{
    if (L->ns[w] >= 0) return L->ns[w];
    if (L->st[w] >= 0) return L->v->steiner[L->st[w]].surf;
    return -1;
}

/* The triangle of surface s holding nodes a, b, c (a's candidates tried in order), or -1. */
static int32_t find_tri(const locator *L, int32_t s, int32_t a, int32_t b, int32_t c)
{
    const thx_surface *S = L->m->surf[s];
    int32_t corner = L->ns[a] == s ? L->nn[a] : -1;
    if (corner < 0) { /* a Steiner node: its triangle, or the triangles around its edge */
        const thx_steiner *k = &L->v->steiner[L->st[a]];
        if (in_tri(L, b, s, k->tri) && in_tri(L, c, s, k->tri)) return k->tri;
        const int32_t *q = S->tri + 3 * (size_t)k->tri;
        for (int j = 0; j < 3 && corner < 0; j++)
            if (k->bary[j] == 0) corner = q[(j + 1) % 3];
        if (corner < 0) return -1;
    }
    for (int64_t e = L->inc_start[s][corner]; e < L->inc_start[s][corner + 1]; e++) {
        int32_t T = L->inc[s][e];
        if (in_tri(L, a, s, T) && in_tri(L, b, s, T) && in_tri(L, c, s, T)) return T;
    }
    return -1;
}

static thx_vec3 node_at(const double *xyz, int32_t w)
{
    return thx_v3(xyz[3 * (size_t)w], xyz[3 * (size_t)w + 1], xyz[3 * (size_t)w + 2]);
}

/* The faces of the tetrahedra on the surfaces, sorted, each once; *out malloc'ed. */
static thx_status boundary_faces(thx_ctx *ctx, const locator *L, face **out, size_t *n_out)
{
    const thx_volume *v = L->v;
    static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}; /* outward faces */
    face *F = NULL;
    size_t n = 0, cap = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        for (int f = 0; f < 4; f++) {
            const int32_t *q = v->tet + 4 * t;
            int32_t a = q[fv[f][0]], b = q[fv[f][1]], c = q[fv[f][2]];
            int32_t s = surf_of(L, a);
            if (s < 0 || surf_of(L, b) != s || surf_of(L, c) != s) continue;
            int32_t k[3] = {a, b, c}; /* sorted */
            for (int i = 0; i < 2; i++)
                for (int j = 0; j < 2 - i; j++)
                    if (k[j] > k[j + 1]) {
                        int32_t x = k[j];
                        k[j] = k[j + 1];
                        k[j + 1] = x;
                    }
            int32_t T = find_tri(L, s, k[0], k[1], k[2]);
            if (T < 0) continue; /* three nodes of one surface, not in one of its triangles: a chord */
            if (thx_grow(ctx, (void **)&F, &cap, n + 1, sizeof *F) != THX_OK) {
                free(F);
                return THX_ENOMEM;
            }
            face *g = &F[n++];
            g->s = s;
            g->tri = T;
            memcpy(g->key, k, sizeof k);
            /* orient as T: the normals agree */
            const thx_surface *S = L->m->surf[s];
            thx_vec3 p0 = thx_surface_node(S, (size_t)S->tri[3 * (size_t)T]);
            thx_vec3 p1 = thx_surface_node(S, (size_t)S->tri[3 * (size_t)T + 1]);
            thx_vec3 p2 = thx_surface_node(S, (size_t)S->tri[3 * (size_t)T + 2]);
            thx_vec3 nt = thx_v3_cross(thx_v3_sub(p1, p0), thx_v3_sub(p2, p0));
            thx_vec3 A = node_at(v->xyz, a), B = node_at(v->xyz, b), C = node_at(v->xyz, c);
            thx_vec3 nf = thx_v3_cross(thx_v3_sub(B, A), thx_v3_sub(C, A));
            int flip = thx_v3_dot(nt, nf) < 0;
            g->n[0] = a;
            g->n[1] = flip ? c : b;
            g->n[2] = flip ? b : c;
        }
    if (n) qsort(F, n, sizeof *F, face_cmp);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (u == 0 || face_cmp(&F[u - 1], &F[i]) != 0) F[u++] = F[i];
    *out = F;
    *n_out = u;
    return THX_OK;
}

/* A surface some of whose triangles no face of the mesh lies on (a mesh that does not conform to
 * it: made elsewhere, or regions assigned without the surfaces) is written as its own triangles
 * on their volume nodes (the node table), with a warning: the group then names the surface, not
 * faces of the tetrahedra. F stays sorted. */
static thx_status fall_back(thx_ctx *ctx, const thx_model *m, face **F, size_t *nF, const char *path)
{
    const thx_volume *v = m->volume;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const thx_surface *S = m->surf[s];
        size_t lo = 0, hi, covered = 0;
        while (lo < *nF && (size_t)(*F)[lo].s < s) lo++;
        for (hi = lo; hi < *nF && (size_t)(*F)[hi].s == s; hi++)
            covered += hi == lo || (*F)[hi].tri != (*F)[hi - 1].tri;
        if (covered == S->n_tris) continue;
        thx_log(ctx, THX_LOG_WARN, "%s: surface \"%s\": the tetrahedra's faces cover %zu of its %zu triangles (the mesh "
                "does not conform to it): its own triangles are written", path, S->name, covered, S->n_tris);
        size_t n_new = *nF - (hi - lo) + S->n_tris;
        face *G = thx_malloc(ctx, (n_new ? n_new : 1) * sizeof *G);
        if (!G) return THX_ENOMEM;
        memcpy(G, *F, lo * sizeof *G);
        for (size_t t = 0; t < S->n_tris; t++) {
            face *g = &G[lo + t];
            g->s = (int32_t)s;
            g->tri = (int32_t)t;
            for (int k = 0; k < 3; k++) g->key[k] = g->n[k] = v->surf_node[s][S->tri[3 * t + (size_t)k]];
        }
        memcpy(G + lo + S->n_tris, *F + hi, (*nF - hi) * sizeof *G);
        free(*F);
        *F = G;
        *nF = n_new;
    }
    return THX_OK;
}

static void put_xyz(FILE *f, const double *p, const char *eol)
{
    fprintf(f, "%.17g %.17g %.17g%s", p[0] + 0.0, p[1] + 0.0, p[2] + 0.0, eol);
}

static int view_name_ok(const char *s)
{
    if (!s || !*s || strlen(s) > 200) return 0;
    for (; *s; s++)
        if (*s < 0x20 || *s > 0x7e || *s == '"') return 0;
    return 1;
}

thx_status thx_volume_export_msh(thx_ctx *ctx, const thx_model *m, const thx_msh_view *views, size_t n_views,
                                 const char *path)
{
    if (!m->volume) return thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh to export", path);
    THX_CHECK(thx_model_volume_validate(ctx, m, path));
    const thx_volume *v = m->volume;
    size_t nr = v->n_regions, nsu = m->n_surfaces, maxn = 0;
    for (size_t k = 0; k < n_views; k++) {
        const thx_msh_view *w = &views[k];
        size_t lim = w->on_cells ? v->n_tets : v->n_nodes;
        if (!view_name_ok(w->name))
            return thx_error(ctx, THX_EINPUT, "%s: view name \"%s\" cannot be written", path, w->name ? w->name : "");
        if ((w->n_comp != 1 && w->n_comp != 3) || !w->values || !w->time || !w->n_frames || !w->n || w->n > lim)
            return thx_error(ctx, THX_EINTERNAL, "%s: view \"%s\": bad description", path, w->name);
        for (size_t i = 0; w->ids && i < w->n; i++)
            if (w->ids[i] < 0 || (size_t)w->ids[i] >= lim)
                return thx_error(ctx, THX_EINTERNAL, "%s: view \"%s\": entry %zu out of range", path, w->name, i + 1);
        for (size_t f = 0; f < w->n_frames; f++)
            if (!isfinite(w->time[f]))
                return thx_error(ctx, THX_EINPUT, "%s: view \"%s\": frame %zu has no finite time", path, w->name, f + 1);
        if (w->n * (size_t)w->n_comp > maxn) maxn = w->n * (size_t)w->n_comp;
    }
    thx_status st = THX_OK;
    face *F = NULL;
    size_t nF = 0;
    int32_t *ns = thx_malloc(ctx, v->n_nodes * sizeof *ns), *nn = thx_malloc(ctx, v->n_nodes * sizeof *nn);
    int32_t *stn = thx_malloc(ctx, v->n_nodes * sizeof *stn), *ent = thx_malloc(ctx, v->n_nodes * sizeof *ent);
    int64_t **inc_start = thx_calloc(ctx, nsu ? nsu : 1, sizeof *inc_start);
    int32_t **inc = thx_calloc(ctx, nsu ? nsu : 1, sizeof *inc);
    size_t *n_in = thx_calloc(ctx, nr ? nr : 1, sizeof *n_in), *nodes_in = thx_calloc(ctx, nr ? nr : 1, sizeof *nodes_in);
    size_t *f_in = thx_calloc(ctx, nsu ? nsu : 1, sizeof *f_in);
    double *box = thx_malloc(ctx, 6 * (nr + nsu) * sizeof *box + 1), *val = thx_malloc(ctx, (maxn ? maxn : 1) * sizeof *val);
    if (!ns || !nn || !stn || !ent || !inc_start || !inc || !n_in || !nodes_in || !f_in || !box || !val) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t w = 0; w < v->n_nodes; w++) ns[w] = nn[w] = stn[w] = -1;
    for (size_t s = 0; s < v->n_surfaces; s++)
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            ns[v->surf_node[s][i]] = (int32_t)s;
            nn[v->surf_node[s][i]] = (int32_t)i;
        }
    for (size_t k = 0; k < v->n_steiner; k++) stn[v->steiner[k].node] = (int32_t)k;
    /* triangles around each node, per surface */
    for (size_t s = 0; s < nsu; s++) {
        const thx_surface *S = m->surf[s];
        inc_start[s] = thx_calloc(ctx, S->n_nodes + 1, sizeof **inc_start);
        inc[s] = thx_malloc(ctx, (3 * S->n_tris + 1) * sizeof **inc);
        if (!inc_start[s] || !inc[s]) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t i = 0; i < 3 * S->n_tris; i++) inc_start[s][S->tri[i] + 1]++;
        for (size_t i = 0; i < S->n_nodes; i++) inc_start[s][i + 1] += inc_start[s][i];
        int64_t *fill = thx_malloc(ctx, (S->n_nodes + 1) * sizeof *fill);
        if (!fill) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(fill, inc_start[s], (S->n_nodes + 1) * sizeof *fill);
        for (size_t t = 0; t < S->n_tris; t++)
            for (int k = 0; k < 3; k++) inc[s][fill[S->tri[3 * t + k]]++] = (int32_t)t;
        free(fill);
    }
    locator L = {m, v, ns, nn, stn, inc_start, inc};
    THX_TRY(boundary_faces(ctx, &L, &F, &nF));
    THX_TRY(fall_back(ctx, m, &F, &nF, path));
    for (size_t i = 0; i < nF; i++) f_in[F[i].s]++;
    /* entities: node classification and bounding boxes */
    for (size_t w = 0; w < v->n_nodes; w++) ent[w] = INT32_MAX;
    for (size_t b = 0; b < nr + nsu; b++)
        for (int k = 0; k < 3; k++) box[6 * b + k] = INFINITY, box[6 * b + 3 + k] = -INFINITY;
    for (size_t t = 0; t < v->n_tets; t++) {
        int32_t r = v->region[t];
        n_in[r]++;
        for (int a = 0; a < 4; a++) {
            int32_t w = v->tet[4 * t + a];
            if (r < ent[w]) ent[w] = r;
            for (int k = 0; k < 3; k++) {
                double c = v->xyz[3 * (size_t)w + (size_t)k];
                box[6 * r + k] = fmin(box[6 * r + k], c);
                box[6 * r + 3 + k] = fmax(box[6 * r + 3 + k], c);
            }
        }
    }
    for (size_t i = 0; i < nF; i++)
        for (int a = 0; a < 3; a++)
            for (int k = 0; k < 3; k++) {
                size_t b = nr + (size_t)F[i].s;
                double c = v->xyz[3 * (size_t)F[i].n[a] + (size_t)k];
                box[6 * b + k] = fmin(box[6 * b + k], c);
                box[6 * b + 3 + k] = fmax(box[6 * b + 3 + k], c);
            }
    for (size_t w = 0; w < v->n_nodes; w++) {
        if (ent[w] == INT32_MAX) ent[w] = 0; /* a node no tetrahedron uses */
        nodes_in[ent[w]]++;
    }
    for (size_t r = 0; r < nr; r++)
        if (!n_in[r])
            for (int k = 0; k < 6; k++) box[6 * r + k] = 0; /* a region with no tetrahedra */

    thx_atomic_file af;
    THX_TRY(thx_export_claim(ctx, THX_EXPORT_MSH, path));
    THX_TRY(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    /* a section Gmsh does not know is skipped by its reader: it carries thorax's signature */
    fputs("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nthorax volume mesh, mm, tagged surfaces", f);
    fprintf(f, "%s\n$EndComments\n", n_views ? ", data views" : "");
    fprintf(f, "$PhysicalNames\n%zu\n", nsu + nr);
    for (size_t s = 0; s < nsu; s++) fprintf(f, "2 %zu \"%s\"\n", s + 1, m->surf[s]->name);
    for (size_t r = 0; r < nr; r++) fprintf(f, "3 %zu \"%s\"\n", r + 1, v->regions[r].name);
    fputs("$EndPhysicalNames\n", f);
    fprintf(f, "$Entities\n0 0 %zu %zu\n", nsu, nr);
    for (size_t s = 0; s < nsu; s++) {
        fprintf(f, "%zu ", s + 1);
        put_xyz(f, box + 6 * (nr + s), " ");
        put_xyz(f, box + 6 * (nr + s) + 3, "");
        fprintf(f, " 1 %zu 0\n", s + 1);
    }
    for (size_t r = 0; r < nr; r++) {
        fprintf(f, "%zu ", r + 1);
        put_xyz(f, box + 6 * r, " ");
        put_xyz(f, box + 6 * r + 3, "");
        fprintf(f, " 1 %zu 0\n", r + 1);
    }
    fputs("$EndEntities\n", f);
    size_t blocks = 0;
    for (size_t r = 0; r < nr; r++) blocks += nodes_in[r] > 0;
    fprintf(f, "$Nodes\n%zu %zu 1 %zu\n", blocks, v->n_nodes, v->n_nodes);
    for (size_t r = 0; r < nr; r++) {
        if (!nodes_in[r]) continue;
        fprintf(f, "3 %zu 0 %zu\n", r + 1, nodes_in[r]);
        for (size_t w = 0; w < v->n_nodes; w++)
            if ((size_t)ent[w] == r) fprintf(f, "%zu\n", w + 1);
        for (size_t w = 0; w < v->n_nodes; w++)
            if ((size_t)ent[w] == r) put_xyz(f, v->xyz + 3 * w, "\n");
    }
    fputs("$EndNodes\n", f);
    blocks = nsu;
    for (size_t r = 0; r < nr; r++) blocks += n_in[r] > 0;
    fprintf(f, "$Elements\n%zu %zu 1 %zu\n", blocks, v->n_tets + nF, v->n_tets + nF);
    for (size_t r = 0; r < nr; r++) {
        if (!n_in[r]) continue;
        fprintf(f, "3 %zu 4 %zu\n", r + 1, n_in[r]);
        for (size_t t = 0; t < v->n_tets; t++) {
            if ((size_t)v->region[t] != r) continue;
            const int32_t *q = v->tet + 4 * t;
            fprintf(f, "%zu %ld %ld %ld %ld\n", t + 1, (long)q[0] + 1, (long)q[1] + 1, (long)q[2] + 1, (long)q[3] + 1);
        }
    }
    for (size_t s = 0, i = 0; s < nsu; s++) {
        fprintf(f, "2 %zu 2 %zu\n", s + 1, f_in[s]);
        for (; i < nF && (size_t)F[i].s == s; i++)
            fprintf(f, "%zu %ld %ld %ld\n", v->n_tets + i + 1, (long)F[i].n[0] + 1, (long)F[i].n[1] + 1,
                    (long)F[i].n[2] + 1);
    }
    fputs("$EndElements\n", f);
    for (size_t k = 0; k < n_views; k++) {
        const thx_msh_view *w = &views[k];
        const char *sec = w->on_cells ? "ElementData" : "NodeData";
        for (size_t fr = 0; fr < w->n_frames; fr++) {
            w->values(w->user, fr, val);
            fprintf(f, "$%s\n1\n\"%s\"\n1\n%.17g\n3\n%zu\n%d\n%zu\n", sec, w->name, w->time[fr] + 0.0, fr, w->n_comp, w->n);
            for (size_t i = 0; i < w->n; i++) {
                fprintf(f, "%ld", (long)(w->ids ? w->ids[i] : (int32_t)i) + 1);
                for (int c = 0; c < w->n_comp; c++) fprintf(f, " %.17g", val[i * (size_t)w->n_comp + (size_t)c] + 0.0);
                fputc('\n', f);
            }
            fprintf(f, "$End%s\n", sec);
        }
    }
    st = thx_atomic_commit(ctx, &af); /* checks ferror: a short write fails here */
done:
    for (size_t s = 0; inc_start && inc && s < nsu; s++) {
        free(inc_start[s]);
        free(inc[s]);
    }
    free(inc_start);
    free(inc);
    free(F);
    free(ns);
    free(nn);
    free(stn);
    free(ent);
    free(n_in);
    free(nodes_in);
    free(f_in);
    free(box);
    free(val);
    return st;
}
