/*
 * The volume check's mesh topology and tables (see check_volume.c): faces (interior, boundary,
 * nonconforming, overlapping; the interface faces), duplicate tetrahedra and nodes, the boundary as
 * a surface (checked as one; its shells and cavities), the node tables between volume and surfaces,
 * and the Steiner records.
 */
#include "check_volume_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/union_find.h"

/* ------------------------------------------------------------------ */
/* Sorting helpers. */

typedef struct {
    int32_t b, c;  /* the two larger nodes of the face (the smallest is the bucket) */
    uint32_t tet;
    int8_t lf;     /* local face (opposite vertex lf) */
    int8_t par;    /* +1 if the outward face is an even permutation of (a, b, c), -1 if odd */
} face_rec;

static int cmp_face(const void *x, const void *y)
{
    const face_rec *a = x, *b = y;
    if (a->b != b->b) return a->b < b->b ? -1 : 1;
    if (a->c != b->c) return a->c < b->c ? -1 : 1;
    if (a->tet != b->tet) return a->tet < b->tet ? -1 : 1;
    return (a->lf > b->lf) - (a->lf < b->lf);
}

typedef struct {
    int32_t k[4];
    size_t t;
} tet_key;

static int cmp_tet_key(const void *x, const void *y)
{
    const tet_key *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a->k[i] != b->k[i]) return a->k[i] < b->k[i] ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

typedef struct {
    double x[3];
    int32_t i;
} node_key;

static int cmp_node_key(const void *x, const void *y)
{
    const node_key *a = x, *b = y;
    for (int k = 0; k < 3; k++)
        if (a->x[k] != b->x[k]) return a->x[k] < b->x[k] ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

/* ------------------------------------------------------------------ */
/* Faces, duplicates, the boundary, the tables. */

/* Counts the faces, marks the boundary faces in bmask (bit lf of tetrahedron
 * t) and, if iface is not NULL, lists the interface faces (boundary faces and
 * faces between two regions) as 4 t + lf, in the order of their sorted node
 * numbers. */
thx_status cv_faces_and_boundary(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, unsigned char *bmask,
                                 thx_volume_report *r, size_t **iface, size_t *n_iface)
{
    size_t cap_if = 0;
    if (iface) {
        *iface = NULL;
        *n_iface = 0;
    }
    thx_status st = THX_OK;
    size_t nv = v->n_nodes, nt = v->n_tets;
    size_t *start = thx_calloc(ctx, nv + 1, sizeof *start);
    size_t *fill = thx_malloc(ctx, (nv + 1) * sizeof *fill);
    face_rec *fr = thx_malloc(ctx, (4 * nt + 1) * sizeof *fr);
    if (!start || !fill || !fr) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        for (int f = 0; f < 4; f++) {
            int32_t k[3] = {v->tet[4 * t + vface[f][0]], v->tet[4 * t + vface[f][1]], v->tet[4 * t + vface[f][2]]};
            sort3(k);
            start[(size_t)k[0] + 1]++;
        }
    }
    for (size_t i = 0; i < nv; i++) start[i + 1] += start[i];
    memcpy(fill, start, nv * sizeof *fill);
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        for (int f = 0; f < 4; f++) {
            int32_t k[3] = {v->tet[4 * t + vface[f][0]], v->tet[4 * t + vface[f][1]], v->tet[4 * t + vface[f][2]]};
            int par = sort3(k);
            face_rec x = {k[1], k[2], (uint32_t)t, (int8_t)f, (int8_t)par};
            fr[fill[(size_t)k[0]]++] = x;
        }
    }
    for (size_t a = 0; a < nv; a++) {
        size_t b = start[a], e = start[a + 1];
        if (e - b > 1) qsort(fr + b, e - b, sizeof *fr, cmp_face);
        for (size_t g = b; g < e;) {
            size_t h = g;
            while (h < e && fr[h].b == fr[g].b && fr[h].c == fr[g].c) h++;
            size_t cnt = h - g;
            r->n_faces++;
            int inter = 0;
            if (cnt == 1) {
                r->n_boundary_faces++;
                bmask[fr[g].tet] |= (unsigned char)(1u << fr[g].lf);
                inter = 1;
            } else if (cnt == 2) {
                r->n_interior_faces++;
                inter = v->region && v->region[fr[g].tet] != v->region[fr[g + 1].tet];
                if (fr[g].par == fr[g + 1].par) {
                    if (!r->n_overlapping_faces) {
                        r->ex_overlapping_face[0] = (int32_t)a;
                        r->ex_overlapping_face[1] = fr[g].b;
                        r->ex_overlapping_face[2] = fr[g].c;
                    }
                    r->n_overlapping_faces++;
                }
            } else {
                if (!r->n_nonconforming_faces) {
                    r->ex_nonconforming_face[0] = (int32_t)a;
                    r->ex_nonconforming_face[1] = fr[g].b;
                    r->ex_nonconforming_face[2] = fr[g].c;
                }
                r->n_nonconforming_faces++;
            }
            if (inter && iface) {
                if (*n_iface + 1 > cap_if &&
                    (st = thx_grow(ctx, (void **)iface, &cap_if, *n_iface + 1, sizeof **iface)) != THX_OK)
                    goto done;
                (*iface)[(*n_iface)++] = 4 * (size_t)fr[g].tet + (size_t)fr[g].lf;
            }
            g = h;
        }
    }
done:
    free(start);
    free(fill);
    free(fr);
    return st;
}

thx_status cv_duplicates(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, thx_volume_report *r)
{
    size_t nt = v->n_tets, nv = v->n_nodes;
    tet_key *keys = thx_malloc(ctx, (nt + 1) * sizeof *keys);
    node_key *nk = thx_malloc(ctx, (nv + 1) * sizeof *nk);
    size_t *start = thx_calloc(ctx, nv + 2, sizeof *start);
    if (!keys || !nk || !start) {
        free(keys);
        free(nk);
        free(start);
        return THX_ENOMEM;
    }
    /* sorted node quadruples, bucketed by the smallest node (counting sort
     * keeps tetrahedron order), then sorted inside each small bucket */
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        const int32_t *q = v->tet + 4 * t;
        int32_t mn = q[0];
        for (int i = 1; i < 4; i++) mn = q[i] < mn ? q[i] : mn;
        start[(size_t)mn + 1]++;
    }
    for (size_t i = 0; i < nv; i++) start[i + 1] += start[i];
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        int32_t k[4];
        memcpy(k, v->tet + 4 * t, sizeof k);
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
                int32_t x = k[j];
                k[j] = k[j - 1];
                k[j - 1] = x;
            }
        tet_key *dst = &keys[start[(size_t)k[0]]++];
        memcpy(dst->k, k, sizeof k);
        dst->t = t;
    }
    /* start[a] now ends bucket a; bucket a begins at start[a - 1] (0 for a = 0) */
    for (size_t a = 0; a < nv; a++) {
        size_t b = a ? start[a - 1] : 0, e = start[a];
        if (e - b > 1) qsort(keys + b, e - b, sizeof *keys, cmp_tet_key);
        for (size_t i = b + 1; i < e; i++)
            if (!memcmp(keys[i].k, keys[i - 1].k, sizeof keys[i].k)) {
                if (!r->n_duplicate_tets || keys[i].t < r->ex_duplicate_tet[1]) {
                    /* the earliest pair by the later tetrahedron's index */
                    size_t g = i - 1;
                    while (g > b && !memcmp(keys[g - 1].k, keys[i].k, sizeof keys[i].k)) g--;
                    r->ex_duplicate_tet[0] = keys[g].t;
                    r->ex_duplicate_tet[1] = keys[i].t;
                }
                r->n_duplicate_tets++;
            }
    }
    free(start);
    for (size_t i = 0; i < nv; i++) {
        memcpy(nk[i].x, v->xyz + 3 * i, 3 * sizeof(double));
        nk[i].i = (int32_t)i;
    }
    qsort(nk, nv, sizeof *nk, cmp_node_key);
    for (size_t i = 1; i < nv; i++)
        if (nk[i].x[0] == nk[i - 1].x[0] && nk[i].x[1] == nk[i - 1].x[1] && nk[i].x[2] == nk[i - 1].x[2]) {
            if (!r->n_duplicate_nodes) {
                size_t g = i - 1;
                while (g > 0 && nk[g - 1].x[0] == nk[i].x[0] && nk[g - 1].x[1] == nk[i].x[1] &&
                       nk[g - 1].x[2] == nk[i].x[2])
                    g--;
                r->ex_duplicate_node[0] = nk[g].i;
                r->ex_duplicate_node[1] = nk[i].i;
            }
            r->n_duplicate_nodes++;
        }
    free(keys);
    free(nk);
    return THX_OK;
}

/* Builds the boundary as a surface (faces in tet order), checks it, counts
 * shells and cavities. */
thx_status cv_boundary(thx_ctx *ctx, const thx_volume *v, const unsigned char *bmask,
                       const thx_volume_check_opts *o, thx_volume_report *r, int32_t **bnode_out,
                       size_t *n_bnodes)
{
    thx_status st = THX_OK;
    size_t nv = v->n_nodes, nt = v->n_tets, nf = r->n_boundary_faces;
    int32_t *map = thx_malloc(ctx, (nv + 1) * sizeof *map);
    int32_t *back = thx_malloc(ctx, (nv + 1) * sizeof *back);
    size_t *parent = thx_malloc(ctx, (nv + 1) * sizeof *parent);
    thx_surface *s = NULL;
    double *cvol = NULL;
    if (!map || !back || !parent) {
        st = THX_ENOMEM;
        goto done;
    }
    THX_TRY(thx_surface_create(ctx, "boundary", THX_ROLE_OTHER, &s));
    s->tri = thx_malloc(ctx, (3 * nf + 1) * sizeof *s->tri);
    if (!s->tri) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < nv; i++) {
        map[i] = -1;
        parent[i] = i;
    }
    size_t nb = 0, k = 0;
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++) {
            if (!(bmask[t] & (1u << f))) continue;
            for (int j = 0; j < 3; j++) {
                int32_t g = v->tet[4 * t + vface[f][j]];
                if (map[g] < 0) {
                    back[nb] = g;
                    map[g] = (int32_t)nb++;
                }
                s->tri[k++] = map[g];
            }
            uf_union(parent, (size_t)v->tet[4 * t + vface[f][0]], (size_t)v->tet[4 * t + vface[f][1]]);
            uf_union(parent, (size_t)v->tet[4 * t + vface[f][0]], (size_t)v->tet[4 * t + vface[f][2]]);
        }
    s->n_tris = nf;
    s->n_nodes = nb;
    s->xyz = thx_malloc(ctx, (3 * nb + 1) * sizeof *s->xyz);
    if (!s->xyz) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < nb; i++) memcpy(s->xyz + 3 * i, v->xyz + 3 * (size_t)back[i], 3 * sizeof(double));

    thx_check_opts so;
    thx_check_opts_default(&so);
    so.check_intersections = o->check_intersections;
    so.min_angle_deg = 0.0; /* reported only: the tetrahedra's own dihedral floor decides (check.md) */
    st = thx_surface_check(ctx, s, NULL, &so, &r->boundary);
    if (st == THX_ECHECK) {
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    if (st != THX_OK) goto done;
    r->boundary_checked = 1;
    /* node numbers back to volume nodes */
    thx_surface_report *b = &r->boundary;
#define BACK(x) ((x) = ((x) >= 0 && (size_t)(x) < nb) ? back[(x)] : (x))
    if (b->n_boundary_edges) { BACK(b->ex_boundary_edge[0]); BACK(b->ex_boundary_edge[1]); }
    if (b->n_nonmanifold_edges) { BACK(b->ex_nonmanifold_edge[0]); BACK(b->ex_nonmanifold_edge[1]); }
    if (b->n_inconsistent_edges) { BACK(b->ex_inconsistent_edge[0]); BACK(b->ex_inconsistent_edge[1]); }
    if (b->n_nonmanifold_vertices) BACK(b->ex_nonmanifold_vertex);
    if (b->n_unused_nodes) BACK(b->ex_unused_node);
#undef BACK

    /* components: node-connected; signed volume about the centre of the node box */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nb; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], s->xyz[3 * i + a]);
            hi[a] = fmax(hi[a], s->xyz[3 * i + a]);
        }
    thx_vec3 c0 = thx_v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    /* component index per root, in order of first appearance */
    for (size_t i = 0; i < nb; i++) map[back[i]] = -1;
    size_t nc = 0;
    for (size_t i = 0; i < nb; i++) {
        size_t root = uf_find(parent, (size_t)back[i]);
        if (map[root] < 0) map[root] = (int32_t)nc++;
    }
    cvol = thx_calloc(ctx, nc + 1, sizeof *cvol);
    if (!cvol) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t f = 0; f < nf; f++) {
        int32_t g0 = back[s->tri[3 * f]];
        size_t cidx = (size_t)map[uf_find(parent, (size_t)g0)];
        thx_vec3 a = thx_v3_sub(node3(s->xyz, s->tri[3 * f]), c0);
        thx_vec3 bb = thx_v3_sub(node3(s->xyz, s->tri[3 * f + 1]), c0);
        thx_vec3 cc = thx_v3_sub(node3(s->xyz, s->tri[3 * f + 2]), c0);
        cvol[cidx] += thx_v3_dot(a, thx_v3_cross(bb, cc)) / 6.0;
    }
    r->n_boundary_components = nc;
    for (size_t c = 0; c < nc; c++) {
        if (cvol[c] > 0.0) r->n_shells++;
        else r->n_cavities++;
    }
    *bnode_out = back;
    *n_bnodes = nb;
    back = NULL;
done:
    free(map);
    free(back);
    free(parent);
    free(cvol);
    thx_surface_destroy(&s);
    return st;
}

/* Node tables (paper 3.3). */
void cv_node_tables(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r)
{
    int has = v->surf_node || v->node_surf || v->node_snode || v->n_surfaces;
    if (!has && !(m && m->n_surfaces)) return;
    r->node_tables_checked = 1;
    r->n_table_surfaces = v->n_surfaces;
    r->table_max_distance = NAN;
    size_t ns = v->n_surfaces;
    int first_bad = 1;
#define NOTE_BAD(s_, i_)                \
    do {                                \
        if (first_bad) {                \
            r->ex_table_surface = (s_); \
            r->ex_table_node = (i_);    \
            first_bad = 0;              \
        }                               \
    } while (0)
    if (m && m->n_surfaces != ns)
        r->n_table_size_errors += m->n_surfaces > ns ? m->n_surfaces - ns : ns - m->n_surfaces;
    if (!v->node_surf || !v->node_snode) r->n_table_size_errors++;
    if (ns && (!v->surf_node || !v->surf_n_nodes)) {
        r->n_table_size_errors += ns;
        return;
    }
    double maxd = -1.0, tol2 = o->node_tol * o->node_tol;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *ms = (m && s < m->n_surfaces) ? m->surf[s] : NULL;
        if (!v->surf_node[s] || (ms && v->surf_n_nodes[s] != ms->n_nodes)) {
            r->n_table_size_errors++;
            continue;
        }
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            int32_t g = v->surf_node[s][i];
            if (g < 0 || (size_t)g >= v->n_nodes) {
                NOTE_BAD(s, i);
                r->n_table_bad_entries++;
                continue;
            }
            if (ms) {
                double d2 = 0.0;
                for (int a = 0; a < 3; a++) {
                    double dd = v->xyz[3 * (size_t)g + a] - ms->xyz[3 * i + a];
                    d2 += dd * dd;
                }
                if (d2 > maxd) maxd = d2;
                if (!(d2 <= tol2)) {
                    NOTE_BAD(s, i);
                    r->n_table_mismatches++;
                }
            }
            if (v->node_surf && v->node_snode &&
                (v->node_surf[g] < 0 || ((size_t)v->node_surf[g] == s && (size_t)v->node_snode[g] != i))) {
                if (!r->n_table_backlink_errors) r->ex_backlink_node = g;
                r->n_table_backlink_errors++;
            }
        }
    }
    if (maxd >= 0.0) r->table_max_distance = sqrt(maxd);
    if (v->node_surf && v->node_snode)
        for (size_t g = 0; g < v->n_nodes; g++) {
            int32_t s = v->node_surf[g];
            if (s < 0) continue;
            int32_t i = v->node_snode[g];
            int ok = (size_t)s < ns && v->surf_node && v->surf_node[s] && v->surf_n_nodes && i >= 0 &&
                     (size_t)i < v->surf_n_nodes[s] && v->surf_node[s][i] == (int32_t)g;
            if (!ok) {
                if (!r->n_table_backlink_errors) r->ex_backlink_node = (int32_t)g;
                r->n_table_backlink_errors++;
            }
        }
#undef NOTE_BAD
}

/* Steiner records (with a model): in range, not on a surface node, and on
 * the point their barycentric coordinates give. */
void cv_steiner_table(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r)
{
    r->n_steiner = v->n_steiner;
    r->steiner_max_distance = NAN;
    if (!v->n_steiner || !m) return;
    if (!v->steiner) {
        r->n_steiner_bad = v->n_steiner;
        r->ex_steiner = 0;
        return;
    }
    double maxd = -1.0, tol2 = o->node_tol * o->node_tol;
    int first = 1;
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *sr = &v->steiner[k];
        const thx_surface *su = (sr->surf >= 0 && (size_t)sr->surf < m->n_surfaces) ? m->surf[sr->surf] : NULL;
        int ok = su && sr->node >= 0 && (size_t)sr->node < v->n_nodes && sr->tri >= 0 && (size_t)sr->tri < su->n_tris &&
                 (!v->node_surf || v->node_surf[sr->node] < 0);
        for (int c = 0; c < 3 && ok; c++) {
            int32_t i = su->tri[3 * (size_t)sr->tri + c];
            ok = i >= 0 && (size_t)i < su->n_nodes && isfinite(sr->bary[c]);
        }
        if (!ok) {
            if (first) r->ex_steiner = k;
            first = 0;
            r->n_steiner_bad++;
            continue;
        }
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double x = 0.0;
            for (int c = 0; c < 3; c++) x += sr->bary[c] * su->xyz[3 * (size_t)su->tri[3 * (size_t)sr->tri + c] + a];
            double dd = v->xyz[3 * (size_t)sr->node + a] - x;
            d2 += dd * dd;
        }
        if (d2 > maxd) maxd = d2;
        if (!(d2 <= tol2)) {
            if (first) r->ex_steiner = k;
            first = 0;
            r->n_steiner_mismatches++;
        }
    }
    if (maxd >= 0.0) r->steiner_max_distance = sqrt(maxd);
}
