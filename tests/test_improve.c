/*
 * Sliver repair (src/mesh/improve.c): flips and vertex moves must keep the
 * mesh a conforming, positively oriented tetrahedralization of exactly the
 * same domain, never move fixed nodes, never remove protected surface
 * triangles, and must get rid of most flat tetrahedra.
 *
 * The test mesh is the Delaunay tetrahedralization of a lattice whose points
 * are jittered by a tiny amount: nearly cospherical groups of eight points
 * give the classic Delaunay slivers throughout the interior.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/improve.h"
#include "testlib.h"
#include "thorax/delaunay.h"
#include "thorax/predicates.h"

#define N 9 /* lattice points per side */

typedef struct { int32_t a, b, c, t; } face_rec;
static int cmp_face(const void *x, const void *y)
{
    const face_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->c > q->c) - (p->c < q->c);
}

static face_rec sorted_face(int32_t a, int32_t b, int32_t c, int32_t t)
{
    int32_t x;
    if (a > b) { x = a; a = b; b = x; }
    if (b > c) { x = b; b = c; c = x; }
    if (a > b) { x = a; a = b; b = x; }
    return (face_rec){a, b, c, t};
}

/* All faces of the volume, sorted. */
static face_rec *faces_of(const thx_volume *v)
{
    face_rec *f = malloc(4 * v->n_tets * sizeof *f);
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        f[4 * t] = sorted_face(q[1], q[2], q[3], (int32_t)t);
        f[4 * t + 1] = sorted_face(q[0], q[2], q[3], (int32_t)t);
        f[4 * t + 2] = sorted_face(q[0], q[1], q[3], (int32_t)t);
        f[4 * t + 3] = sorted_face(q[0], q[1], q[2], (int32_t)t);
    }
    qsort(f, 4 * v->n_tets, sizeof *f, cmp_face);
    return f;
}

/* Boundary faces (in exactly one tetrahedron) into *out; returns their number, or -1 if some face is
 * in more than two tetrahedra (not conforming). */
static long boundary_faces(const thx_volume *v, face_rec **out)
{
    face_rec *f = faces_of(v), *b = malloc(4 * v->n_tets * sizeof *b);
    size_t n = 4 * v->n_tets, nb = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && !cmp_face(&f[i], &f[j])) j++;
        if (j - i > 2) { free(f); free(b); return -1; }
        if (j - i == 1) b[nb++] = f[i];
        i = j;
    }
    free(f);
    for (size_t i = 0; i < nb; i++) b[i].t = 0;
    *out = b;
    return (long)nb;
}

static int has_face(const thx_volume *v, int32_t a, int32_t b, int32_t c)
{
    face_rec k = sorted_face(a, b, c, 0);
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        int hit = 0;
        for (int i = 0; i < 4; i++) hit += q[i] == k.a || q[i] == k.b || q[i] == k.c;
        if (hit == 3) return 1;
    }
    return 0;
}

static double total_volume(const thx_volume *v, int region)
{
    double s = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        if (region < 0 || v->region[t] == region) s += thx_volume_tet_volume(v, t);
    return s;
}

static size_t count_below(const thx_volume *v, double deg, double *mn)
{
    size_t c = 0;
    *mn = 180;
    for (size_t t = 0; t < v->n_tets; t++) {
        double d = mesh_tet_min_dihedral(v->xyz, v->tet + 4 * t);
        c += d < deg;
        if (d < *mn) *mn = d;
    }
    return c;
}

static int by_x(void *user, thx_vec3 c)
{
    (void)user;
    return c.x < 0.5 * (N - 1) ? 0 : 1;
}

/* The lattice volume: nodes on the cube's faces are "surface" nodes (fixed). */
static thx_volume *lattice(thx_ctx *ctx, unsigned seed, int32_t **adj)
{
    thx_volume *v = NULL;
    if (thx_volume_create(ctx, &v) != THX_OK) return NULL;
    size_t n = N * N * N;
    v->n_nodes = n;
    v->xyz = malloc(3 * n * sizeof *v->xyz);
    v->node_surf = malloc(n * sizeof *v->node_surf);
    v->node_snode = malloc(n * sizeof *v->node_snode);
    srand(seed);
    size_t k = 0;
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            for (int l = 0; l < N; l++, k++) {
                int on = i == 0 || j == 0 || l == 0 || i == N - 1 || j == N - 1 || l == N - 1;
                double jit = on ? 0 : 1e-3;
                v->xyz[3 * k] = i + jit * (rand() / (double)RAND_MAX - 0.5);
                v->xyz[3 * k + 1] = j + jit * (rand() / (double)RAND_MAX - 0.5);
                v->xyz[3 * k + 2] = l + jit * (rand() / (double)RAND_MAX - 0.5);
                /* stored precision, as the mesher does */
                for (int c = 0; c < 3; c++) v->xyz[3 * k + c] = round(v->xyz[3 * k + c] * 1e6) / 1e6;
                v->node_surf[k] = on ? 0 : -1;
                v->node_snode[k] = on ? (int32_t)k : -1;
            }
    int32_t *tets = NULL, *nbrs = NULL;
    size_t nt = 0;
    if (thx_delaunay3d(ctx, v->xyz, n, &tets, &nbrs, &nt, NULL) != THX_OK) { thx_volume_destroy(&v); return NULL; }
    /* Delaunay output is left-handed in the volume's convention: swap two corners (and their faces) */
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = x;
        x = nbrs[4 * t + 2];
        nbrs[4 * t + 2] = nbrs[4 * t + 3];
        nbrs[4 * t + 3] = x;
    }
    if (adj) *adj = nbrs;
    else free(nbrs);
    v->tet = tets;
    v->n_tets = nt;
    v->region = malloc(nt * sizeof *v->region);
    v->n_regions = 2;
    v->regions = calloc(2, sizeof *v->regions);
    for (size_t t = 0; t < nt; t++) {
        const int32_t *q = tets + 4 * t;
        double cx = 0.25 * (v->xyz[3 * q[0]] + v->xyz[3 * q[1]] + v->xyz[3 * q[2]] + v->xyz[3 * q[3]]);
        v->region[t] = cx < 0.5 * (N - 1) ? 0 : 1;
    }
    return v;
}

/* The lattice with its interior nodes jittered by up to 0.15 (rounded to 1e-6; the nodes of the
 * plane z = 3 too unless keep_plane), tetrahedralized afresh by the Delaunay step (right-handed, as
 * the mesher hands them over), regions 0; *nbrs its adjacency. */
static thx_volume *jittered_delaunay(thx_ctx *ctx, unsigned seed, int keep_plane, int32_t **nbrs)
{
    thx_volume *v = lattice(ctx, 3, NULL);
    if (!v) return NULL;
    srand(seed);
    for (size_t k = 0; k < v->n_nodes; k++)
        for (int c = 0; c < 3; c++) {
            double x = round(v->xyz[3 * k + c]);
            int on = v->node_surf[k] >= 0 || (keep_plane && round(v->xyz[3 * k + 2]) == 3);
            v->xyz[3 * k + c] = on ? x : round((x + 0.3 * (rand() / (double)RAND_MAX - 0.5)) * 1e6) / 1e6;
        }
    int32_t *tets = NULL;
    size_t nt = 0;
    if (thx_delaunay3d(ctx, v->xyz, v->n_nodes, &tets, nbrs, &nt, NULL) != THX_OK) {
        thx_volume_destroy(&v);
        return NULL;
    }
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2]; tets[4 * t + 2] = tets[4 * t + 3]; tets[4 * t + 3] = x;
        x = (*nbrs)[4 * t + 2]; (*nbrs)[4 * t + 2] = (*nbrs)[4 * t + 3]; (*nbrs)[4 * t + 3] = x;
    }
    free(v->tet);
    free(v->region);
    v->tet = tets;
    v->n_tets = nt;
    v->region = calloc(nt, sizeof *v->region);
    return v;
}

/* Every tetrahedron positive (exact), the boundary the same face for face as b0 (nb0 faces; freed
 * here) and the total volume vol0 (to 1e-9). */
static void same_domain(const thx_volume *v, face_rec *b0, long nb0, double vol0)
{
    size_t wrong = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        wrong += !(thx_orient3d(v->xyz + 3 * q[0], v->xyz + 3 * q[1], v->xyz + 3 * q[2], v->xyz + 3 * q[3]) < 0);
    }
    CHECK(wrong == 0);
    face_rec *b1 = NULL;
    long nb1 = boundary_faces(v, &b1);
    CHECK(nb1 == nb0 && !memcmp(b0, b1, (size_t)nb0 * sizeof *b0));
    CHECK_NEAR(total_volume(v, -1), vol0, 1e-9 * vol0);
    free(b0);
    free(b1);
}

/* mesh_recover on v's tetrahedra (nbrs their adjacency, taken over) for the triangles tri of v's
 * nodes; v gets the result, regions 0. */
static thx_status recover_in(thx_ctx *ctx, thx_volume *v, int32_t *nbrs, int32_t *tri, size_t ntri, recover_stats *R)
{
    thx_surface surf;
    memset(&surf, 0, sizeof surf);
    surf.n_nodes = v->n_nodes;
    surf.n_tris = ntri;
    surf.tri = tri;
    const thx_surface *sp[1] = {&surf};
    size_t offset[2] = {0, v->n_nodes}, nt = v->n_tets;
    int32_t *tets = v->tet;
    v->tet = NULL;
    thx_status st = mesh_recover(ctx, v->xyz, v->n_nodes, &tets, &nbrs, &nt, sp, offset, 1, R);
    v->tet = tets;
    v->n_tets = nt;
    free(v->region);
    v->region = calloc(nt ? nt : 1, sizeof *v->region);
    free(nbrs);
    return st;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);

    /* 1. conforming, same domain, fixed nodes stay, most slivers gone */
    {
        thx_volume *v = lattice(ctx, 7, NULL);
        CHECK(v != NULL);
        size_t n = v->n_nodes;
        double *xyz0 = malloc(3 * n * sizeof *xyz0);
        memcpy(xyz0, v->xyz, 3 * n * sizeof *xyz0);
        face_rec *b0 = NULL, *b1 = NULL;
        long nb0 = boundary_faces(v, &b0);
        CHECK(nb0 == 6 * 2 * (N - 1) * (N - 1));
        double vol0 = total_volume(v, -1), mn0, mn1;
        size_t below0 = count_below(v, 10, &mn0);
        CHECK(below0 > 100); /* the test mesh really has slivers */
        CHECK(mn0 < 1);
        /* a surface made of interior faces of the mesh: they must survive */
        thx_surface prot;
        memset(&prot, 0, sizeof prot);
        int32_t tri[3 * 64];
        size_t np = 0;
        for (size_t t = 0; t < v->n_tets && np < 64; t += 97) {
            const int32_t *q = v->tet + 4 * t;
            tri[3 * np] = q[0]; tri[3 * np + 1] = q[1]; tri[3 * np + 2] = q[2];
            np++;
        }
        prot.n_tris = np;
        prot.tri = tri;
        prot.n_nodes = n;
        int32_t *ident = malloc(n * sizeof *ident);
        for (size_t i = 0; i < n; i++) ident[i] = (int32_t)i;
        v->n_surfaces = 1;
        v->surf_node = malloc(sizeof *v->surf_node);
        v->surf_node[0] = ident;
        v->surf_n_nodes = malloc(sizeof *v->surf_n_nodes);
        v->surf_n_nodes[0] = n;
        const thx_surface *surfs[1] = {&prot};
        improve_opts o = {10.0, 6, 0, by_x, NULL};
        improve_stats S;
        CHECK_OK(ctx, mesh_improve(ctx, v, NULL, surfs, 1, &o, &S));
        size_t below1 = count_below(v, 10, &mn1);
        printf("lattice %d^3: %zu -> %zu tetrahedra; below 10 deg %zu -> %zu; min dihedral %.3f -> %.3f deg; "
               "%zu edge removals, %zu face removals, %zu moves\n",
               N, S.tets_before, S.tets_after, below0, below1, mn0, mn1, S.n_edge_removals, S.n_face_removals, S.n_moves);
        CHECK(S.below_before == below0);
        CHECK(S.below_after == below1);
        CHECK(S.tets_after == v->n_tets);
        CHECK(below1 * 5 < below0);
        CHECK(mn1 > mn0);
        /* every tetrahedron right-handed, exactly */
        size_t wrong = 0;
        for (size_t t = 0; t < v->n_tets; t++) {
            const int32_t *q = v->tet + 4 * t;
            wrong += !(thx_orient3d(v->xyz + 3 * q[0], v->xyz + 3 * q[1], v->xyz + 3 * q[2], v->xyz + 3 * q[3]) < 0);
        }
        CHECK(wrong == 0);
        /* the same boundary, face for face; conforming inside */
        long nb1 = boundary_faces(v, &b1);
        CHECK(nb1 == nb0);
        CHECK(nb1 == nb0 && !memcmp(b0, b1, (size_t)nb0 * sizeof *b0));
        CHECK_NEAR(total_volume(v, -1), vol0, 1e-9 * vol0);
        /* fixed (surface) nodes did not move */
        size_t moved_fixed = 0;
        for (size_t i = 0; i < n; i++)
            if (v->node_surf[i] >= 0) moved_fixed += memcmp(v->xyz + 3 * i, xyz0 + 3 * i, 3 * sizeof(double)) != 0;
        CHECK(moved_fixed == 0);
        /* the protected triangles are still faces */
        size_t kept = 0;
        for (size_t i = 0; i < np; i++) kept += has_face(v, tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
        CHECK(kept == np);
        /* regions by centroid: each half keeps its volume closely */
        double half = vol0 / 2;
        CHECK_NEAR(total_volume(v, 0), half, 0.01 * half);
        CHECK_NEAR(total_volume(v, 1), half, 0.01 * half);
        v->n_surfaces = 0; /* the surface arrays are freed here, not by the volume */
        free(v->surf_node[0]);
        free(v->surf_node);
        v->surf_node = NULL;
        free(v->surf_n_nodes);
        v->surf_n_nodes = NULL;
        free(b0);
        free(b1);
        free(xyz0);
        thx_volume_destroy(&v);
    }

    /* 2. all nodes fixed: only flips; still conforming and better */
    {
        thx_volume *v = lattice(ctx, 11, NULL);
        CHECK(v != NULL);
        for (size_t i = 0; i < v->n_nodes; i++) v->node_surf[i] = 0;
        face_rec *b0 = NULL, *b1 = NULL;
        long nb0 = boundary_faces(v, &b0);
        double mn0, mn1;
        size_t below0 = count_below(v, 10, &mn0);
        improve_opts o = {10.0, 6, 0, NULL, NULL};
        improve_stats S;
        CHECK_OK(ctx, mesh_improve(ctx, v, NULL, NULL, 0, &o, &S));
        size_t below1 = count_below(v, 10, &mn1);
        printf("flips only: below 10 deg %zu -> %zu; min %.3f -> %.3f deg; %zu moves\n", below0, below1, mn0, mn1, S.n_moves);
        CHECK(S.n_moves == 0);
        CHECK(below1 < below0);
        long nb1 = boundary_faces(v, &b1);
        CHECK(nb1 == nb0 && !memcmp(b0, b1, (size_t)nb0 * sizeof *b0));
        /* regions: a cavity within one region keeps it; mixed ones take the largest old tetrahedron's */
        CHECK_NEAR(total_volume(v, 0) + total_volume(v, 1), total_volume(v, -1), 1e-9);
        free(b0);
        free(b1);
        thx_volume_destroy(&v);
    }
    /* 3. each operation alone keeps the mesh valid and helps */
    for (unsigned op = IMPROVE_EDGE; op <= IMPROVE_MOVE; op <<= 1) {
        thx_volume *v = lattice(ctx, 13, NULL);
        CHECK(v != NULL);
        face_rec *b0 = NULL;
        long nb0 = boundary_faces(v, &b0);
        double vol0 = total_volume(v, -1), mn0, mn1;
        size_t below0 = count_below(v, 10, &mn0);
        improve_opts o = {10.0, 6, op, NULL, NULL};
        improve_stats S;
        CHECK_OK(ctx, mesh_improve(ctx, v, NULL, NULL, 0, &o, &S));
        size_t below1 = count_below(v, 10, &mn1);
        size_t applied = op == IMPROVE_EDGE ? S.n_edge_removals : op == IMPROVE_FACE ? S.n_face_removals : S.n_moves;
        size_t others = S.n_edge_removals + S.n_face_removals + S.n_moves - applied;
        printf("operation %u alone: %zu applied; below 10 deg %zu -> %zu; min %.3f -> %.3f deg\n", op, applied, below0,
               below1, mn0, mn1);
        CHECK(others == 0);
        if (op != IMPROVE_FACE) { /* 2-3 flips do not help lattice slivers (a flat quadrilateral); see case 4 */
            CHECK(applied > 10);
            CHECK(below1 < below0);
        }
        same_domain(v, b0, nb0, vol0);
        thx_volume_destroy(&v);
    }
    /* 5. the adjacency handed over (as the mesher does) gives the same result as the one searched for */
    {
        int32_t *adj = NULL;
        thx_volume *a = lattice(ctx, 7, &adj), *b = lattice(ctx, 7, NULL);
        CHECK(a && b && adj);
        improve_opts o = {10.0, 6, 0, by_x, NULL};
        improve_stats Sa, Sb;
        CHECK_OK(ctx, mesh_improve(ctx, a, adj, NULL, 0, &o, &Sa));
        CHECK_OK(ctx, mesh_improve(ctx, b, NULL, NULL, 0, &o, &Sb));
        CHECK(a->n_tets == b->n_tets && !memcmp(a->tet, b->tet, 4 * a->n_tets * sizeof *a->tet));
        CHECK(!memcmp(a->xyz, b->xyz, 3 * a->n_nodes * sizeof *a->xyz));
        thx_volume_destroy(&a);
        thx_volume_destroy(&b);
    }
    /* 6. recovery: triangles using the other diagonal of lattice squares (inside and on the hull)
          become faces, the tetrahedralization stays valid, and the domain does not change */
    {
        /* nodes off the hull and off the plane z = 3 jittered (generic position there); the hull and
           the plane exact, so their squares are flat */
        int32_t *nbrs = NULL;
        thx_volume *v = jittered_delaunay(ctx, 5, 1, &nbrs);
        CHECK(v != NULL);
        face_rec *b0 = NULL, *b1 = NULL;
        long nb0 = boundary_faces(v, &b0);
        double vol0 = total_volume(v, -1);
        /* the squares of the plane z = 3 (inside) and of the face x = 0 (on the hull) */
#define NODE(i, j, l) ((int32_t)(((i) * N + (j)) * N + (l)))
        int32_t tri[3 * 2 * 2 * (N - 1) * (N - 1)];
        size_t ntri = 0, inside = 0;
        for (int side = 0; side < 2; side++)
            for (int i = 0; i + 1 < N; i++)
                for (int j = 0; j + 1 < N; j++) {
                    int32_t a, b, c, d; /* the square a b c d */
                    if (side == 0) { a = NODE(i, j, 3); b = NODE(i + 1, j, 3); c = NODE(i + 1, j + 1, 3); d = NODE(i, j + 1, 3); }
                    else { a = NODE(0, i, j); b = NODE(0, i + 1, j); c = NODE(0, i + 1, j + 1); d = NODE(0, i, j + 1); }
                    /* the diagonal the tetrahedralization does not have */
                    int ac = has_face(v, a, b, c) && has_face(v, a, c, d);
                    int bd = has_face(v, a, b, d) && has_face(v, b, c, d);
                    CHECK(ac != bd);
                    if (ac) {
                        tri[3 * ntri] = a; tri[3 * ntri + 1] = b; tri[3 * ntri + 2] = d; ntri++;
                        tri[3 * ntri] = b; tri[3 * ntri + 1] = c; tri[3 * ntri + 2] = d; ntri++;
                    } else {
                        tri[3 * ntri] = a; tri[3 * ntri + 1] = b; tri[3 * ntri + 2] = c; ntri++;
                        tri[3 * ntri] = a; tri[3 * ntri + 1] = c; tri[3 * ntri + 2] = d; ntri++;
                    }
                    if (side == 0) inside += 2;
                }
#undef NODE
        recover_stats R;
        CHECK_OK(ctx, recover_in(ctx, v, nbrs, tri, ntri, &R));
        printf("recovery: %zu of %zu triangles missing -> %zu (%zu 2-3 flips, %zu edge removals, %zu on the hull)\n",
               R.missing_before, R.n_triangles, R.missing_after, R.n_flip23, R.n_edge_removals, R.n_boundary);
        CHECK(R.missing_before == ntri);
        CHECK(R.missing_after * 5 < R.missing_before); /* the rest need more than one flip per edge */
        CHECK(R.n_boundary > 0 && R.n_edge_removals > 0);
        size_t present = 0, wrong = 0;
        for (size_t i = 0; i < ntri; i++) present += has_face(v, tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
        CHECK(present == ntri - R.missing_after);
        for (size_t t = 0; t < v->n_tets; t++) {
            const int32_t *q = v->tet + 4 * t;
            wrong += !(thx_orient3d(v->xyz + 3 * q[0], v->xyz + 3 * q[1], v->xyz + 3 * q[2], v->xyz + 3 * q[3]) < 0);
        }
        CHECK(wrong == 0);
        /* conforming; the boundary has as many faces (the hull squares only changed diagonals) and the
           same volume (the squares are flat: the wedge between the diagonals is empty) */
        long nb1 = boundary_faces(v, &b1);
        CHECK(nb1 == nb0);
        CHECK_NEAR(total_volume(v, -1), vol0, 1e-9 * vol0);
        (void)inside;
        free(b0);
        free(b1);
        thx_volume_destroy(&v);
    }
    /* 7. recovery of edges that cross several tetrahedra (walks of flips): isolated triangles on
          body diagonals of the jittered lattice's cubes; the walks recover some that single
          operations could not, every tetrahedron stays positive, the boundary and the volume stay
          exactly as they were */
    {
        int32_t *nbrs = NULL;
        thx_volume *v = jittered_delaunay(ctx, 11, 0, &nbrs);
        CHECK(v != NULL);
        face_rec *b0 = NULL;
        long nb0 = boundary_faces(v, &b0);
        double vol0 = total_volume(v, -1);
#define NODE(i, j, l) ((int32_t)(((i) * N + (j)) * N + (l)))
        int32_t tri[3 * 64];
        size_t ntri = 0;
        for (int i = 1; i + 2 < N - 1; i += 3)
            for (int j = 1; j + 2 < N - 1; j += 3)
                for (int l = 1; l + 1 < N - 1; l += 3) {
                    /* a body diagonal of a lattice cube and two cube edges' worth apart: the
                       Delaunay step has the diagonal or not, and the jitter decides */
                    tri[3 * ntri] = NODE(i, j, l);
                    tri[3 * ntri + 1] = NODE(i + 1, j + 1, l + 1);
                    tri[3 * ntri + 2] = NODE(i + 1, j, l);
                    ntri++;
                }
#undef NODE
        size_t missing0 = 0;
        for (size_t i = 0; i < ntri; i++) missing0 += !has_face(v, tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
        recover_stats R;
        CHECK_OK(ctx, recover_in(ctx, v, nbrs, tri, ntri, &R));
        printf("walks: %zu of %zu long triangles missing -> %zu after single operations -> %zu after walks (%zu walk steps)\n",
               R.missing_before, ntri, R.missing_before_walk, R.missing_after, R.n_walk);
        CHECK(R.missing_before == missing0 && missing0 * 2 > ntri);
        CHECK(R.missing_before_walk > 0 && R.n_walk > 0);
        CHECK(R.missing_after < R.missing_before_walk);
        size_t present = 0;
        for (size_t i = 0; i < ntri; i++) present += has_face(v, tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
        CHECK(present == ntri - R.missing_after);
        same_domain(v, b0, nb0, vol0);
        thx_volume_destroy(&v);
    }
    /* 8. face recovery: a triangle whose three edges are mesh edges but which an edge pierces (the
          Delaunay step joins two low apexes across it) becomes a face by the 3-2 flip */
    {
        double h = 0.2;
        double xyz[15] = {1, 0, 0, -0.5, 0.8660254037844386, 0, -0.5, -0.8660254037844386, 0, 0.01, 0.02, h, -0.02, 0.01, -h};
        int32_t *tets = NULL, *nbrs = NULL;
        size_t nt = 0;
        CHECK_OK(ctx, thx_delaunay3d(ctx, xyz, 5, &tets, &nbrs, &nt, NULL));
        for (size_t t = 0; t < nt; t++) {
            int32_t x = tets[4 * t + 2]; tets[4 * t + 2] = tets[4 * t + 3]; tets[4 * t + 3] = x;
            x = nbrs[4 * t + 2]; nbrs[4 * t + 2] = nbrs[4 * t + 3]; nbrs[4 * t + 3] = x;
        }
        CHECK(nt == 3); /* around the edge (3, 4) through the triangle */
        int32_t tri[3] = {0, 1, 2};
        thx_surface surf;
        memset(&surf, 0, sizeof surf);
        surf.n_nodes = 5;
        surf.n_tris = 1;
        surf.tri = tri;
        const thx_surface *sp[1] = {&surf};
        size_t offset[2] = {0, 5};
        recover_stats R;
        CHECK_OK(ctx, mesh_recover(ctx, xyz, 5, &tets, &nbrs, &nt, sp, offset, 1, &R));
        printf("face recovery: %zu missing -> %zu, %zu tetrahedra, %zu operations on piercing edges\n", R.missing_before,
               R.missing_after, nt, R.n_face_ops);
        CHECK(R.missing_before == 1 && R.missing_after == 0 && R.n_face_ops == 1 && nt == 2);
        double vol = 0;
        int has = 0;
        for (size_t t = 0; t < nt; t++) {
            const int32_t *q = tets + 4 * t;
            double o = thx_orient3d(xyz + 3 * q[0], xyz + 3 * q[1], xyz + 3 * q[2], xyz + 3 * q[3]);
            CHECK(o < 0);
            vol += -o / 6;
            int k = 0;
            for (int c = 0; c < 4; c++) k += q[c] <= 2;
            has += k == 3;
        }
        CHECK(has == 2);
        /* the two tetrahedra on the triangle: area 3 sqrt(3) / 4 times (2 h) / 3 */
        CHECK_NEAR(vol, 3 * sqrt(3) / 4 * 2 * h / 3, 1e-12);
        free(tets);
        free(nbrs);
    }
    /* 4. two flat caps on one triangle become three good tetrahedra (2-3 flip) */
    {
        thx_volume *v = NULL;
        CHECK_OK(ctx, thx_volume_create(ctx, &v));
        double h = 0.3 * 0.5; /* apexes at 0.3 times the inradius (0.5 for circumradius 1) */
        double xyz[15] = {1, 0, 0, -0.5, 0.8660254037844386, 0, -0.5, -0.8660254037844386, 0, 0, 0, h, 0, 0, -h};
        int32_t tet[8] = {0, 1, 2, 3, 0, 2, 1, 4};
        v->n_nodes = 5;
        v->xyz = malloc(sizeof xyz);
        memcpy(v->xyz, xyz, sizeof xyz);
        v->n_tets = 2;
        v->tet = malloc(sizeof tet);
        memcpy(v->tet, tet, sizeof tet);
        v->region = calloc(2, sizeof *v->region);
        v->n_regions = 1;
        v->regions = calloc(1, sizeof *v->regions);
        v->node_surf = malloc(5 * sizeof *v->node_surf);
        v->node_snode = malloc(5 * sizeof *v->node_snode);
        for (int i = 0; i < 5; i++) v->node_surf[i] = v->node_snode[i] = -1;
        CHECK(thx_volume_tet_volume(v, 0) > 0 && thx_volume_tet_volume(v, 1) > 0);
        double vol0 = total_volume(v, -1), mn0, mn1;
        count_below(v, 40, &mn0);
        improve_opts o = {40.0, 6, IMPROVE_FACE, NULL, NULL};
        improve_stats S;
        CHECK_OK(ctx, mesh_improve(ctx, v, NULL, NULL, 0, &o, &S));
        count_below(v, 40, &mn1);
        printf("2-3 flip: %zu -> %zu tetrahedra, min dihedral %.2f -> %.2f deg\n", S.tets_before, S.tets_after, mn0, mn1);
        CHECK(S.n_face_removals == 1);
        CHECK(v->n_tets == 3);
        CHECK(mn1 > mn0 + 5);
        CHECK_NEAR(total_volume(v, -1), vol0, 1e-12);
        for (size_t t = 0; t < v->n_tets; t++) CHECK(thx_volume_tet_volume(v, t) > 0);
        thx_volume_destroy(&v);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
