/*
 * Sliver repair inside the domain: edge removal, face removal (2-3 flips) and
 * vertex perturbation (see improve.h). The operations follow Shewchuk's edge
 * removal by dynamic programming ("Two discrete optimization algorithms for
 * the topological improvement of tetrahedral meshes", 2002) and Klingner and
 * Shewchuk's use of it with smoothing ("Aggressive tetrahedral mesh
 * improvement", IMR 2007), reduced to what the hybrid mesher needs: a few
 * hundred slivers left where nearly cospherical surface and grid nodes meet.
 *
 * Invariant kept by every operation: the new tetrahedra are positively
 * oriented (exact predicate) and fill exactly the cavity of the old ones, so
 * the mesh stays conforming, the domain and its boundary do not change, and
 * the worst tetrahedron of the cavity gets strictly better.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/improve.h"
#include "mesh/triset.h"
#include "thorax/mesh/mesh.h"
#include "thorax/geom/predicates.h"
#define MAX_RING 12    /* edges with more tetrahedra around them are not removed */
#define MAX_STAR 512   /* vertices with more tetrahedra around them are not moved */
#define EPS_GAIN 1e-9  /* an operation must raise the worst quality by more than this */
#define MAX_NEW 64     /* tetrahedra a replacement may take out or put in */
#define MAX_CAV 24     /* tetrahedra of a vertex insertion's cavity */
#define SELECT_RE 1.25
#define WIDE_N 16    /* the wide slide's samples: 2 WIDE_N + 1 a side of the star's reach */
/* sin(2 deg): the pocket pass's insertions may leave tetrahedra this flat (thorax check refuses
   dihedral angles below 1 deg) */
#define POCKET_FLOOR 0.034899496702500969
/* Quality is the smallest dihedral sine, or, for a tetrahedron whose radius-edge ratio RE exceeds
   the bound B (the refinement's), sin(target) * B / RE where that is smaller: such a needle counts
   as a sliver of the target angle or worse, so the repair takes it on, and no operation trades a
   sliver for a needle that is worse by this measure. (With the dihedral sine alone, the repair
   made needles of ratio 59 on the high phantom, where the refinement had left 16, and of 2.1 on
   OpenMEEG's Head1, where it had left none above 2.) */

/* ---- quality ---- */

static const int face_of[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}; /* outward for right-handed tets */

/* Smallest sine of the six dihedral angles of (p0, p1, p2, p3); 0 or less when flat or inverted
 * (floating point: the exact orientation is tested separately). */
static double quality(const double *p[4], double re_bound, double re_scale)
{
    double e[3][3]; /* p1 - p0, p2 - p0, p3 - p0 */
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) e[k][c] = p[k + 1][c] - p[0][c];
    double vol6 = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                  e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    if (!(vol6 > 0)) return 0;
    /* squared doubled face areas, face f opposite corner f */
    double nl2[4];
    for (int f = 0; f < 4; f++) {
        const int *v = face_of[f];
        double u[3], w[3];
        for (int c = 0; c < 3; c++) {
            u[c] = p[v[1]][c] - p[v[0]][c];
            w[c] = p[v[2]][c] - p[v[0]][c];
        }
        double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
        nl2[f] = x * x + y * y + z * z;
    }
    /* sin of the dihedral angle at edge (i, j) = 6V |e_ij| / (|n_k| |n_l|), k, l the other corners;
       compared squared, one square root at the end */
    static const int pair[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
    double best = INFINITY;
    for (int k = 0; k < 6; k++) {
        const int *q = pair[k];
        double d0 = p[q[1]][0] - p[q[0]][0], d1 = p[q[1]][1] - p[q[0]][1], d2 = p[q[1]][2] - p[q[0]][2];
        double s2 = (d0 * d0 + d1 * d1 + d2 * d2) / (nl2[q[2]] * nl2[q[3]]);
        if (s2 < best) best = s2;
    }
    double sine = vol6 * sqrt(best);
    /* radius-edge ratio R / l_min: the circumcentre is p0 + (|e0|^2 e1 x e2 + |e1|^2 e2 x e0 +
       |e2|^2 e0 x e1) / (2 * 6V) */
    double c[3] = {0, 0, 0}, l2[6];
    for (int k = 0; k < 3; k++) {
        const double *a = e[(k + 1) % 3], *b = e[(k + 2) % 3];
        double w = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
        l2[k] = w;
        c[0] += w * (a[1] * b[2] - a[2] * b[1]);
        c[1] += w * (a[2] * b[0] - a[0] * b[2]);
        c[2] += w * (a[0] * b[1] - a[1] * b[0]);
    }
    for (int k = 0; k < 3; k++) {
        const double *a = e[k], *b = e[(k + 1) % 3];
        l2[3 + k] = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
    }
    double lmin2 = l2[0];
    for (int k = 1; k < 6; k++) lmin2 = fmin(lmin2, l2[k]);
    double r2 = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (4 * vol6 * vol6);
    if (!(re_bound > 0) || r2 <= re_bound * re_bound * lmin2) return sine;
    double needle = re_scale * sqrt(lmin2 / r2);
    return needle < sine ? needle : sine;
}

double mesh_tet_quality(const double *p[4], double re_bound, double re_scale) { return quality(p, re_bound, re_scale); }

/* Radius-edge ratio of (p0, p1, p2, p3) (INFINITY when flat). */
static double radius_edge_of(const double *p[4])
{
    double e[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) e[k][c] = p[k + 1][c] - p[0][c];
    double vol6 = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                  e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    if (!(fabs(vol6) > 0)) return INFINITY;
    double c[3] = {0, 0, 0}, lmin2 = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double *a = e[(k + 1) % 3], *b = e[(k + 2) % 3];
        double w = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
        lmin2 = fmin(lmin2, w);
        c[0] += w * (a[1] * b[2] - a[2] * b[1]);
        c[1] += w * (a[2] * b[0] - a[0] * b[2]);
        c[2] += w * (a[0] * b[1] - a[1] * b[0]);
        const double *u = e[k], *v = e[(k + 1) % 3];
        lmin2 = fmin(lmin2, (u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]) + (u[2] - v[2]) * (u[2] - v[2]));
    }
    return sqrt((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (4 * vol6 * vol6) / lmin2);
}

double mesh_tet_min_dihedral(const double *xyz, const int32_t *q)
{
    thx_vec3 P[4], n[4];
    for (int k = 0; k < 4; k++) P[k] = thx_v3(xyz[3 * q[k]], xyz[3 * q[k] + 1], xyz[3 * q[k] + 2]);
    for (int f = 0; f < 4; f++) {
        const int *v = face_of[f];
        thx_vec3 c = thx_v3_cross(thx_v3_sub(P[v[1]], P[v[0]]), thx_v3_sub(P[v[2]], P[v[0]]));
        double l = thx_v3_norm(c);
        n[f] = l > 0 ? thx_v3_scale(c, 1.0 / l) : c;
        /* outward, whatever the orientation of the tetrahedron */
        if (thx_v3_dot(n[f], thx_v3_sub(P[f], P[v[0]])) > 0) n[f] = thx_v3_scale(n[f], -1.0);
    }
    double best = 180.0;
    for (int f = 0; f < 4; f++)
        for (int g = f + 1; g < 4; g++) {
            double c = -thx_v3_dot(n[f], n[g]);
            c = c > 1 ? 1 : c < -1 ? -1 : c;
            double a = acos(c) * (180.0 / M_PI);
            if (a < best) best = a;
        }
    return best;
}

/* ---- the mesh being improved ---- */
typedef struct {
    thx_ctx *ctx;
    double *xyz;
    size_t nn, nn_cap; /* nodes; room for them in xyz and the per-node arrays (insertion adds nodes) */
    int32_t *tet, *nbr, *reg; /* nbr[4t + f]: across the face opposite corner f, -1 on the boundary */
    unsigned char *dead;
    uint32_t *failed;  /* per slot: the clock when every operation failed on it (0: not tried) */
    size_t nt, cap;
    int32_t *freel;
    size_t n_free, free_cap;
    uint32_t clock, *node_clock; /* a counter of changes; per node, the last change touching it */
    int32_t *node_tet; /* some live tetrahedron at each node */
    const int32_t *node_surf;
    unsigned char *fixed; /* nodes that never move freely */
    int32_t *slide;       /* per node: its Steiner record if it may slide in its surface triangle, else -1 */
    thx_steiner *rec;     /* the volume's Steiner records (updated when a node slides) */
    const int32_t *corner; /* 3 volume nodes per record: its triangle's corners */
    tset prot;
    const improve_opts *o;
    double re_bound, re_scale; /* quality(): radius-edge bound and sin(target) * bound */
    size_t n_regions;
    int32_t star[MAX_STAR]; /* scratch: the star of the vertex being moved */
    int32_t star2[MAX_STAR];
    uint32_t *nmark, nstamp; /* node marks (recovery: the neighbours of an edge's far end) */
    uint32_t *tmark, tstamp; /* per slot: visited by the current star search */
    /* the pocket pass (NULL uf: off): an insertion's cavity must reach the main body of the nodes off
       surface pocket_surf (union-find roots uf, the main one pocket_root; nodes from pocket_nn on
       were inserted by the pass, next to it) */
    const int32_t *pocket_owner, *pocket_uf;
    int32_t pocket_surf, pocket_root;
    size_t pocket_nn;
} imesh;

static int in_main(const imesh *M, int32_t w)
{
    if ((size_t)w >= M->pocket_nn) return 1;
    return M->pocket_owner[w] != M->pocket_surf && M->pocket_uf[w] == M->pocket_root;
}

static const double *X(const imesh *M, int32_t i) { return M->xyz + 3 * (size_t)i; }

static int right_handed(const double *a, const double *b, const double *c, const double *d)
{
    return thx_orient3d(a, b, c, d) < 0; /* predicates.h: < 0 iff ((b-a)x(c-a)).(d-a) > 0 */
}

/* Quality of (a, b, c, d) by node, -1 if not positively oriented (exact). */
static double q4(const imesh *M, int32_t a, int32_t b, int32_t c, int32_t d)
{
    const double *p[4] = {X(M, a), X(M, b), X(M, c), X(M, d)};
    if (!right_handed(p[0], p[1], p[2], p[3])) return -1;
    return quality(p, M->re_bound, M->re_scale);
}

static double qtet(const imesh *M, int32_t t)
{
    const int32_t *q = M->tet + 4 * (size_t)t;
    const double *p[4] = {X(M, q[0]), X(M, q[1]), X(M, q[2]), X(M, q[3])};
    return quality(p, M->re_bound, M->re_scale);
}

/* The smallest dihedral sine alone (no needle measure). */
static double dihedral_sine(const imesh *M, int32_t t)
{
    const int32_t *q = M->tet + 4 * (size_t)t;
    const double *p[4] = {X(M, q[0]), X(M, q[1]), X(M, q[2]), X(M, q[3])};
    return quality(p, 0, 0);
}

/* The measure that picks the tetrahedra to repair: dihedral angles below the target, or needles
 * above SELECT_RE times the bound (the ones just above it are many, and most are where the
 * refinement could not reach). */
static double qsel(const imesh *M, int32_t t)
{
    const int32_t *q = M->tet + 4 * (size_t)t;
    const double *p[4] = {X(M, q[0]), X(M, q[1]), X(M, q[2]), X(M, q[3])};
    return quality(p, SELECT_RE * M->re_bound, SELECT_RE * M->re_scale);
}

static double tet_volume6(const imesh *M, const int32_t *q)
{
    thx_vec3 P[4];
    for (int k = 0; k < 4; k++) P[k] = thx_v3(X(M, q[k])[0], X(M, q[k])[1], X(M, q[k])[2]);
    return thx_v3_dot(thx_v3_cross(thx_v3_sub(P[1], P[0]), thx_v3_sub(P[2], P[0])), thx_v3_sub(P[3], P[0]));
}

static int local_index(const int32_t *q, int32_t v)
{
    for (int k = 0; k < 4; k++)
        if (q[k] == v) return k;
    return -1;
}

/* Face-to-face adjacency through the tetrahedra around each node. */
static thx_status build_adjacency(imesh *M)
{
    size_t nn = M->nn, nt = M->nt;
    size_t *start = thx_calloc(M->ctx, nn + 1, sizeof *start);
    int32_t *inc = thx_malloc(M->ctx, 4 * (nt ? nt : 1) * sizeof *inc);
    if (!start || !inc) { free(start); free(inc); return THX_ENOMEM; }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) start[M->tet[4 * t + k] + 1]++;
    for (size_t i = 0; i < nn; i++) start[i + 1] += start[i];
    size_t *fill = thx_malloc(M->ctx, (nn ? nn : 1) * sizeof *fill);
    if (!fill) { free(start); free(inc); return THX_ENOMEM; }
    memcpy(fill, start, nn * sizeof *fill);
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) inc[fill[M->tet[4 * t + k]]++] = (int32_t)t;
    free(fill);
#pragma omp parallel for schedule(dynamic, 4096)
    for (long t = 0; t < (long)nt; t++) {
        const int32_t *q = M->tet + 4 * t;
        for (int f = 0; f < 4; f++) {
            int32_t a = q[face_of[f][0]], b = q[face_of[f][1]], c = q[face_of[f][2]];
            int32_t lo = a < b ? (a < c ? a : c) : (b < c ? b : c);
            int32_t found = -1, o1 = lo == a ? b : a, o2 = lo == c ? b : c; /* the two corners besides lo */
            for (size_t k = start[lo]; k < start[lo + 1] && found < 0; k++) {
                int32_t u = inc[k];
                if (u == t) continue;
                const int32_t *r = M->tet + 4 * (size_t)u;
                int hit = 0;
                for (int i = 0; i < 4; i++) hit += (r[i] == o1) + (r[i] == o2);
                if (hit == 2) found = u;
            }
            M->nbr[4 * t + f] = found;
        }
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) M->node_tet[M->tet[4 * t + k]] = (int32_t)t;
    free(start);
    free(inc);
    return THX_OK;
}

static thx_status grow(imesh *M, size_t need)
{
    if (need <= M->cap) return THX_OK;
    size_t cap = M->cap * 3 / 2 + 64;
    if (cap < need) cap = need;
    int32_t *t = realloc(M->tet, 4 * cap * sizeof *t);
    if (t) M->tet = t;
    int32_t *n = realloc(M->nbr, 4 * cap * sizeof *n);
    if (n) M->nbr = n;
    int32_t *r = realloc(M->reg, cap * sizeof *r);
    if (r) M->reg = r;
    unsigned char *d = realloc(M->dead, cap);
    if (d) M->dead = d;
    uint32_t *f = realloc(M->failed, cap * sizeof *f);
    if (f) M->failed = f;
    uint32_t *mk = realloc(M->tmark, cap * sizeof *mk);
    if (mk) M->tmark = mk;
    if (!t || !n || !r || !d || !f || !mk) return thx_error(M->ctx, THX_ENOMEM, "mesh: out of memory repairing slivers");
    memset(M->dead + M->cap, 1, cap - M->cap);
    memset(M->failed + M->cap, 0, (cap - M->cap) * sizeof *f);
    memset(M->tmark + M->cap, 0, (cap - M->cap) * sizeof *mk);
    M->cap = cap;
    return THX_OK;
}

/*
 * Replaces the tetrahedra old[0..n_old) by nw[0..n_new) (regions nreg) and
 * relinks the faces: each face of a new tetrahedron is either a face of the
 * cavity's boundary (linked to the tetrahedron outside) or shared with another
 * new one. Returns 0, or -1 if the faces do not match up (nothing changed).
 */
typedef struct { triple k; int32_t out; int fo; int used; } oface;

static int replace_any(imesh *M, const int32_t *old, int n_old, const int32_t (*nw)[4], const int32_t *nreg, int n_new,
                       int open)
{
    oface of[4 * MAX_NEW];
    int nof = 0;
    if (n_old > MAX_NEW || n_new > MAX_NEW) return -1;
    for (int i = 0; i < n_old; i++) {
        int32_t o = old[i];
        for (int f = 0; f < 4; f++) {
            int32_t u = M->nbr[4 * (size_t)o + f];
            int inside = 0;
            for (int j = 0; j < n_old && !inside; j++) inside = old[j] == u;
            if (inside) continue;
            const int32_t *q = M->tet + 4 * (size_t)o;
            of[nof].k = tri_sorted(q[face_of[f][0]], q[face_of[f][1]], q[face_of[f][2]]);
            of[nof].out = u;
            of[nof].fo = -1;
            if (u >= 0)
                for (int g = 0; g < 4; g++)
                    if (M->nbr[4 * (size_t)u + g] == o) of[nof].fo = g;
            of[nof].used = 0;
            nof++;
        }
    }
    /* match every new face before changing anything */
    int32_t link[MAX_NEW][4]; /* >= 0: outer face index; < 0: -(new tet * 4 + face) - 1 */
    for (int n = 0; n < n_new; n++)
        for (int g = 0; g < 4; g++) {
            triple k = tri_sorted(nw[n][face_of[g][0]], nw[n][face_of[g][1]], nw[n][face_of[g][2]]);
            int hit = -1;
            for (int i = 0; i < nof && hit < 0; i++)
                if (!of[i].used && of[i].k.a == k.a && of[i].k.b == k.b && of[i].k.c == k.c) hit = i;
            if (hit >= 0) { of[hit].used = 1; link[n][g] = hit; continue; }
            int other = -1;
            for (int m = 0; m < n_new && other < 0; m++) {
                if (m == n) continue;
                for (int h = 0; h < 4; h++) {
                    triple l = tri_sorted(nw[m][face_of[h][0]], nw[m][face_of[h][1]], nw[m][face_of[h][2]]);
                    if (l.a == k.a && l.b == k.b && l.c == k.c) { other = m * 4 + h; break; }
                }
            }
            if (other < 0 && !open) return -1;
            link[n][g] = other < 0 ? INT32_MIN : -other - 1; /* INT32_MIN: a new boundary face */
        }
    for (int i = 0; i < nof; i++)
        if (!of[i].used && !(open && of[i].out < 0)) return -1;
    if (grow(M, M->nt + (size_t)n_new) != THX_OK) return -1;
    if (M->n_free + (size_t)n_old > M->free_cap) {
        size_t fc = 2 * M->free_cap + 256;
        int32_t *fl = realloc(M->freel, fc * sizeof *fl);
        if (!fl) return -1;
        M->freel = fl;
        M->free_cap = fc;
    }
    M->clock++;
    /* slots: the old ones, then free ones, then new */
    int32_t slot[MAX_NEW];
    for (int n = 0; n < n_new; n++) {
        if (n < n_old) slot[n] = old[n];
        else if (M->n_free) slot[n] = M->freel[--M->n_free];
        else slot[n] = (int32_t)M->nt++;
    }
    for (int i = n_new; i < n_old; i++) {
        M->dead[old[i]] = 1;
        M->freel[M->n_free++] = old[i];
    }
    for (int n = 0; n < n_new; n++) {
        size_t s = (size_t)slot[n];
        memcpy(M->tet + 4 * s, nw[n], 4 * sizeof(int32_t));
        M->reg[s] = nreg[n];
        M->dead[s] = 0;
        M->failed[s] = 0;
    }
    for (int n = 0; n < n_new; n++) {
        size_t s = (size_t)slot[n];
        for (int g = 0; g < 4; g++) {
            if (link[n][g] == INT32_MIN) {
                M->nbr[4 * s + g] = -1;
            } else if (link[n][g] >= 0) {
                const oface *e = &of[link[n][g]];
                M->nbr[4 * s + g] = e->out;
                if (e->out >= 0) M->nbr[4 * (size_t)e->out + e->fo] = (int32_t)s;
            } else {
                int other = -link[n][g] - 1;
                M->nbr[4 * s + g] = slot[other / 4];
            }
        }
        for (int k = 0; k < 4; k++) {
            M->node_tet[nw[n][k]] = (int32_t)s;
            M->node_clock[nw[n][k]] = M->clock;
        }
    }
    return 0;
}

/* Replaces a cavity whose boundary stays as it was. */
static int replace(imesh *M, const int32_t *old, int n_old, const int32_t (*nw)[4], const int32_t *nreg, int n_new)
{
    return replace_any(M, old, n_old, nw, nreg, n_new, 0);
}

/* Regions of new tetrahedra: the old one's when the cavity had one region, else by centroid. */
static void new_regions(const imesh *M, const int32_t *old, int n_old, const int32_t (*nw)[4], int n_new, int32_t *nreg)
{
    int32_t r0 = M->reg[old[0]];
    int mixed = 0;
    for (int i = 1; i < n_old; i++) mixed |= M->reg[old[i]] != r0;
    if (!mixed) {
        for (int n = 0; n < n_new; n++) nreg[n] = r0;
        return;
    }
    int32_t big = r0;
    double bigv = -1;
    for (int i = 0; i < n_old; i++) {
        double v6 = tet_volume6(M, M->tet + 4 * (size_t)old[i]);
        if (v6 > bigv) { bigv = v6; big = M->reg[old[i]]; }
    }
    for (int n = 0; n < n_new; n++) {
        if (!M->o->classify) { nreg[n] = big; continue; }
        thx_vec3 c = {0, 0, 0};
        for (int k = 0; k < 4; k++) c = thx_v3_add(c, thx_v3(X(M, nw[n][k])[0], X(M, nw[n][k])[1], X(M, nw[n][k])[2]));
        int r = M->o->classify(M->o->user, thx_v3_scale(c, 0.25));
        nreg[n] = r >= 0 && (size_t)r < M->n_regions ? r : big;
    }
}

/* ---- edge removal ---- */

/* The ring of vertices around edge (a, b) of tetrahedron t, ordered so that (a, b, r[i], r[i+1]) is
 * right-handed, and the tetrahedra between consecutive ring vertices. Returns the ring size, or 0
 * when the edge is on the boundary or has too many tetrahedra around it. */
static int edge_ring(const imesh *M, int32_t t, int32_t a, int32_t b, int32_t *ring, int32_t *tets)
{
    const int32_t *q = M->tet + 4 * (size_t)t;
    int ia = local_index(q, a), ib = local_index(q, b), ic = 0;
    while (ic == ia || ic == ib) ic++;
    int id = 6 - ia - ib - ic;
    /* orientation of (a, b, c, d): the parity of the permutation (ia, ib, ic, id) of the stored order */
    int perm[4] = {ia, ib, ic, id}, inv = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) inv += perm[i] > perm[j];
    int32_t c = q[ic], d = q[id];
    int n = 0;
    int32_t cur = t;
    for (;;) {
        if (n >= MAX_RING) return 0;
        ring[n] = c;
        tets[n] = cur;
        n++;
        /* cross the face (a, b, d), opposite c */
        const int32_t *r = M->tet + 4 * (size_t)cur;
        int32_t nx = M->nbr[4 * (size_t)cur + local_index(r, c)];
        if (nx < 0) return 0;
        const int32_t *s = M->tet + 4 * (size_t)nx;
        int32_t e = -1;
        for (int k = 0; k < 4; k++)
            if (s[k] != a && s[k] != b && s[k] != d) e = s[k];
        cur = nx;
        c = d;
        d = e;
        if (cur == t) break;
    }
    if (inv & 1) { /* (a, b, r0, r1) is left-handed: reverse the ring and its tetrahedra */
        for (int i = 0, j = n - 1; i < j; i++, j--) {
            int32_t x = ring[i]; ring[i] = ring[j]; ring[j] = x;
        }
        /* tets[i] lay between old ring[i] and ring[i+1]; after reversal between new ring[i] and ring[i+1] */
        int32_t tmp[MAX_RING];
        for (int i = 0; i < n; i++) tmp[i] = tets[(2 * n - 2 - i) % n];
        memcpy(tets, tmp, (size_t)n * sizeof *tets);
    }
    return n;
}

/* Does the ring diagonal (x, y) cross the chord (p, q) (ring indices, p < q)? */
static int crosses(int x, int y, int p, int q)
{
    if (x == p || x == q || y == p || y == q) return 0;
    return (p < x && x < q) != (p < y && y < q);
}

/* Best triangulation of the ring: returns its worst quality and fills nw (2(n-2) tetrahedra). With
 * cp < cq (ring indices), only triangulations holding the chord (r[cp], r[cq]) are considered. */
static double edge_removal_plan_chords(const imesh *M, int32_t a, int32_t b, const int32_t *r, int n, int32_t (*nw)[4],
                                       const int (*ch)[2], int nch);

static double edge_removal_plan(const imesh *M, int32_t a, int32_t b, const int32_t *r, int n, int32_t (*nw)[4],
                                int cp, int cq)
{
    const int ch[1][2] = {{cp, cq}};
    return edge_removal_plan_chords(M, a, b, r, n, nw, ch, cp >= 0 ? 1 : 0);
}

/* As edge_removal_plan, with every chord ch[k] = (p, q), p < q ring indices, held. */
static double edge_removal_plan_chords(const imesh *M, int32_t a, int32_t b, const int32_t *r, int n, int32_t (*nw)[4],
                                       const int (*ch)[2], int nch)
{
    double Q[MAX_RING][MAX_RING];
    int K[MAX_RING][MAX_RING];
    for (int i = 0; i + 1 < n; i++) Q[i][i + 1] = INFINITY;
    for (int len = 2; len < n; len++)
        for (int i = 0; i + len < n; i++) {
            int j = i + len;
            double best = -2;
            int bk = -1;
            for (int k = i + 1; k < j; k++) {
                double v = fmin(Q[i][k], Q[k][j]);
                if (v <= best) continue;
                int cut = 0;
                for (int c = 0; c < nch && !cut; c++)
                    cut = crosses(i, k, ch[c][0], ch[c][1]) || crosses(k, j, ch[c][0], ch[c][1]) || crosses(i, j, ch[c][0], ch[c][1]);
                if (cut) continue;
                /* with the ring counterclockwise seen from b: (ri, rk, rj, b) and (ri, rj, rk, a) */
                double qb = q4(M, r[i], r[k], r[j], b);
                if (qb <= best) continue;
                double qa = q4(M, r[i], r[j], r[k], a);
                v = fmin(v, fmin(qa, qb));
                if (v > best) { best = v; bk = k; }
            }
            Q[i][j] = best;
            K[i][j] = bk;
        }
    double res = Q[0][n - 1];
    if (res <= 0) return res;
    /* the triangles, by an explicit stack */
    int st[2 * MAX_RING][2], ns = 0, nt = 0;
    st[ns][0] = 0; st[ns][1] = n - 1; ns++;
    while (ns) {
        ns--;
        int i = st[ns][0], j = st[ns][1];
        if (j - i < 2) continue;
        int k = K[i][j];
        nw[nt][0] = r[i]; nw[nt][1] = r[k]; nw[nt][2] = r[j]; nw[nt][3] = b; nt++;
        nw[nt][0] = r[i]; nw[nt][1] = r[j]; nw[nt][2] = r[k]; nw[nt][3] = a; nt++;
        st[ns][0] = i; st[ns][1] = k; ns++;
        st[ns][0] = k; st[ns][1] = j; ns++;
    }
    return res;
}

static int try_edge_removal(imesh *M, int32_t t, double qt, size_t *count)
{
    static const int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    int32_t best_nw[2 * MAX_RING][4], best_old[MAX_RING];
    int best_n = 0;
    double best_gain = EPS_GAIN;
    for (int e = 0; e < 6; e++) {
        const int32_t *q = M->tet + 4 * (size_t)t;
        int32_t a = q[edges[e][0]], b = q[edges[e][1]];
        if (tset_has(&M->prot, edge_sorted(a, b))) continue;
        int32_t ring[MAX_RING], tets[MAX_RING];
        int n = edge_ring(M, t, a, b, ring, tets);
        if (n < 3) continue;
        double qold = qt;
        for (int i = 0; i < n; i++) qold = fmin(qold, qtet(M, tets[i]));
        int32_t nw[2 * MAX_RING][4];
        double qnew = edge_removal_plan(M, a, b, ring, n, nw, -1, -1);
        if (qnew - qold > best_gain) {
            best_gain = qnew - qold;
            best_n = n;
            memcpy(best_nw, nw, sizeof(int32_t[4]) * (size_t)(2 * (n - 2)));
            memcpy(best_old, tets, sizeof(int32_t) * (size_t)n);
        }
    }
    if (!best_n) return 0;
    int32_t nreg[2 * MAX_RING];
    new_regions(M, best_old, best_n, (const int32_t(*)[4])best_nw, 2 * (best_n - 2), nreg);
    if (replace(M, best_old, best_n, (const int32_t(*)[4])best_nw, nreg, 2 * (best_n - 2)) != 0) return 0;
    (*count)++;
    return 1;
}

/* ---- face removal (2-3 flip) ---- */
static int try_face_removal(imesh *M, int32_t t, double qt, size_t *count)
{
    int32_t best_nw[3][4], best_old[2];
    double best_gain = EPS_GAIN;
    int found = 0;
    for (int f = 0; f < 4; f++) {
        int32_t u = M->nbr[4 * (size_t)t + f];
        if (u < 0) continue;
        const int32_t *q = M->tet + 4 * (size_t)t;
        if (tset_has(&M->prot, tri_sorted(q[face_of[f][0]], q[face_of[f][1]], q[face_of[f][2]]))) continue;
        const int32_t *s = M->tet + 4 * (size_t)u;
        int32_t apex = -1;
        for (int k = 0; k < 4; k++)
            if (local_index(q, s[k]) < 0) apex = s[k];
        double qold = fmin(qt, qtet(M, u));
        /* t with one corner of the shared face replaced by the other apex */
        int32_t nw[3][4];
        double qnew = INFINITY;
        for (int i = 0; i < 3 && qnew > 0; i++) {
            memcpy(nw[i], q, sizeof nw[i]);
            nw[i][face_of[f][i]] = apex;
            qnew = fmin(qnew, q4(M, nw[i][0], nw[i][1], nw[i][2], nw[i][3]));
        }
        if (qnew - qold > best_gain) {
            best_gain = qnew - qold;
            memcpy(best_nw, nw, sizeof nw);
            best_old[0] = t;
            best_old[1] = u;
            found = 1;
        }
    }
    if (!found) return 0;
    int32_t nreg[3];
    new_regions(M, best_old, 2, (const int32_t(*)[4])best_nw, 3, nreg);
    if (replace(M, best_old, 2, (const int32_t(*)[4])best_nw, nreg, 3) != 0) return 0;
    (*count)++;
    return 1;
}

/* ---- vertex perturbation ---- */

/* The tetrahedra around node v; 0 if its star is too large, or if v is on the boundary and open is 0. */
static int vertex_star(const imesh *M, int32_t v, int32_t *star, int open)
{
    int n = 0;
    star[n++] = M->node_tet[v];
    for (int i = 0; i < n; i++) {
        const int32_t *q = M->tet + 4 * (size_t)star[i];
        int lv = local_index(q, v);
        for (int f = 0; f < 4; f++) {
            if (f == lv) continue; /* the faces containing v */
            int32_t u = M->nbr[4 * (size_t)star[i] + f];
            if (u < 0) {
                if (!open) return 0;
                continue;
            }
            int seen = 0;
            for (int j = 0; j < n && !seen; j++) seen = star[j] == u;
            if (seen) continue;
            if (n >= MAX_STAR) return 0;
            star[n++] = u;
        }
    }
    return n;
}

static double stored(double x)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.6f", x);
    return strtod(buf, NULL);
}

/* Worst quality of the star with v at p (-1 if some tetrahedron inverts). */
static double star_quality(imesh *M, int32_t v, const int32_t *star, int n, const double *p, int *worst)
{
    double *x = M->xyz + 3 * (size_t)v, keep[3] = {x[0], x[1], x[2]};
    x[0] = p[0]; x[1] = p[1]; x[2] = p[2];
    double w = INFINITY;
    for (int i = 0; i < n && w > 0; i++) {
        const int32_t *q = M->tet + 4 * (size_t)star[i];
        double s = q4(M, q[0], q[1], q[2], q[3]);
        if (s < w) { w = s; if (worst) *worst = i; }
    }
    x[0] = keep[0]; x[1] = keep[1]; x[2] = keep[2];
    return w;
}

static int try_move(imesh *M, int32_t t, size_t *count)
{
    int32_t *star = M->star;
    int moved = 0;
    for (int k = 0; k < 4; k++) {
        int32_t v = M->tet[4 * (size_t)t + k];
        if (M->fixed[v]) continue;
        int n = vertex_star(M, v, star, 0);
        if (!n) continue;
        double *x = M->xyz + 3 * (size_t)v;
        int worst = 0;
        double q0 = star_quality(M, v, star, n, x, &worst), cur = q0;
        /* step scale: the shortest edge at v */
        double h = INFINITY;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < 4; j++) {
                int32_t w = M->tet[4 * (size_t)star[i] + j];
                if (w == v) continue;
                double d = thx_v3_norm(thx_v3_sub(thx_v3(X(M, w)[0], X(M, w)[1], X(M, w)[2]), thx_v3(x[0], x[1], x[2])));
                if (d < h) h = d;
            }
        double step = 0.25 * h;
        for (int it = 0; it < 40 && step > 1e-4 * h; it++) {
            /* directions: the axes, and the gradient of the worst tetrahedron's quality */
            double dir[8][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, 0, 0}, {0, 0, 0}};
            int nd = 6;
            {
                const int32_t *q = M->tet + 4 * (size_t)star[worst];
                double g[3], d = 1e-3 * h, base = q4(M, q[0], q[1], q[2], q[3]);
                for (int c = 0; c < 3; c++) {
                    double keep = x[c];
                    x[c] = keep + d;
                    double qp = q4(M, q[0], q[1], q[2], q[3]);
                    x[c] = keep;
                    g[c] = (fmax(qp, 0) - base) / d;
                }
                double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                if (gl > 0) { for (int c = 0; c < 3; c++) dir[nd][c] = g[c] / gl; nd++; }
            }
            double bestq = cur, bp[3] = {0};
            int bw = worst;
            for (int di = 0; di < nd; di++) {
                double p[3];
                for (int c = 0; c < 3; c++) p[c] = stored(x[c] + step * dir[di][c]);
                int w = 0;
                double qq = star_quality(M, v, star, n, p, &w);
                if (qq > bestq + EPS_GAIN) { bestq = qq; memcpy(bp, p, sizeof bp); bw = w; }
            }
            if (bestq > cur) {
                memcpy(x, bp, sizeof bp);
                cur = bestq;
                worst = bw;
            } else {
                step *= 0.5;
            }
        }
        if (cur > q0 + EPS_GAIN) {
            moved = 1;
            (*count)++;
            M->node_clock[v] = ++M->clock;
        }
    }
    return moved;
}

/* ---- Steiner nodes sliding on their surface triangle ---- */

/* The point of record r's triangle at barycentric coordinates w (w[k] = 0 for a corner the node's
 * edge leaves out). Exact, as the mesher's Steiner points are: the corners lie on the mesher's
 * binary grid and the coordinates are dyadic with few bits (2^-22 on an edge, 2^-20 inside). */
static void slide_point(const imesh *M, int32_t r, const double w[3], double p[3])
{
    const double *c[3] = {X(M, M->corner[3 * r]), X(M, M->corner[3 * r + 1]), X(M, M->corner[3 * r + 2])};
    int z = w[0] == 0 ? 0 : w[1] == 0 ? 1 : w[2] == 0 ? 2 : -1;
    if (z >= 0) { /* on the edge (a, b): a + w_b (b - a) */
        const double *a = c[(z + 1) % 3], *b = c[(z + 2) % 3];
        double t = w[(z + 2) % 3];
        for (int d = 0; d < 3; d++) p[d] = a[d] + t * (b[d] - a[d]);
    } else {
        for (int d = 0; d < 3; d++) p[d] = c[0][d] + w[1] * (c[1][d] - c[0][d]) + w[2] * (c[2][d] - c[0][d]);
    }
}

/*
 * A Steiner node of tetrahedron t slides within its surface triangle (a node on a triangle's
 * edge, along the edge): pattern search over its barycentric coordinates, rounded to the dyadic
 * grid the mesher uses, each position exactly in the triangle's plane (tested) and every
 * tetrahedron of its star positive (exact). The faces on the surfaces keep their nodes and stay
 * in the plane of their triangle, so the surfaces are still exactly unions of faces; the record
 * gets the new coordinates.
 */
static int try_slide_from(imesh *M, int32_t t, int wide, size_t *count);
static int try_slide(imesh *M, int32_t t, size_t *count) { return try_slide_from(M, t, 0, count); }

/* With wide set, the search starts from the best of a sample of the whole triangle (edge) on the
 * dyadic grid, WIDE_N steps a side, instead of from where the node is: a fallback for what the
 * other operations leave below the repair's floor. */
static int try_slide_from(imesh *M, int32_t t, int wide, size_t *count)
{
    int32_t *star = M->star;
    int slid = 0;
    for (int k = 0; k < 4; k++) {
        int32_t v = M->tet[4 * (size_t)t + k];
        int32_t r = M->slide ? M->slide[v] : -1;
        if (r < 0) continue;
        int n = vertex_star(M, v, star, 1);
        if (!n) continue;
        double *x = M->xyz + 3 * (size_t)v;
        double w[3] = {M->rec[r].bary[0], M->rec[r].bary[1], M->rec[r].bary[2]};
        int z = w[0] == 0 ? 0 : w[1] == 0 ? 1 : w[2] == 0 ? 2 : -1;
        double bits = z >= 0 ? 22 : 20;
        const double *c[3] = {X(M, M->corner[3 * r]), X(M, M->corner[3 * r + 1]), X(M, M->corner[3 * r + 2])};
        double L = fmax(thx_v3_norm(thx_v3_sub(thx_v3(c[1][0], c[1][1], c[1][2]), thx_v3(c[0][0], c[0][1], c[0][2]))),
                        thx_v3_norm(thx_v3_sub(thx_v3(c[2][0], c[2][1], c[2][2]), thx_v3(c[0][0], c[0][1], c[0][2]))));
        double h = INFINITY;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < 4; j++) {
                int32_t u = M->tet[4 * (size_t)star[i] + j];
                if (u == v) continue;
                double d = thx_v3_norm(thx_v3_sub(thx_v3(X(M, u)[0], X(M, u)[1], X(M, u)[2]), thx_v3(x[0], x[1], x[2])));
                if (d < h) h = d;
            }
        double q0 = star_quality(M, v, star, n, x, NULL), cur = q0;
        double step = 0.25 * h / L, keep[3] = {x[0], x[1], x[2]};
        if (wide) {
            /* the star's reach: its farthest node, in the coordinates */
            double R = 0;
            for (int i = 0; i < n; i++)
                for (int j = 0; j < 4; j++) {
                    int32_t u = M->tet[4 * (size_t)star[i] + j];
                    double d = thx_v3_norm(thx_v3_sub(thx_v3(X(M, u)[0], X(M, u)[1], X(M, u)[2]), thx_v3(x[0], x[1], x[2])));
                    if (d > R) R = d;
                }
            double span = R / L, bestq = cur, bw[3] = {0};
            for (int i = -WIDE_N; i <= WIDE_N; i++)
                for (int j = z >= 0 ? 0 : -WIDE_N; j <= (z >= 0 ? 0 : WIDE_N); j++) {
                    double ww[3];
                    if (z >= 0) {
                        ww[z] = 0;
                        ww[(z + 2) % 3] = ldexp(nearbyint(ldexp(w[(z + 2) % 3] + span * i / WIDE_N, (int)bits)), -(int)bits);
                        ww[(z + 1) % 3] = 1 - ww[(z + 2) % 3];
                    } else {
                        ww[1] = ldexp(nearbyint(ldexp(w[1] + span * i / WIDE_N, (int)bits)), -(int)bits);
                        ww[2] = ldexp(nearbyint(ldexp(w[2] + span * j / WIDE_N, (int)bits)), -(int)bits);
                        ww[0] = 1 - ww[1] - ww[2];
                    }
                    int ok = 1;
                    for (int k2 = 0; k2 < 3; k2++)
                        if (k2 != z && !(ww[k2] > 0 && ww[k2] < 1)) ok = 0;
                    if (!ok) continue;
                    double p[3];
                    slide_point(M, r, ww, p);
                    if (thx_orient3d(c[0], c[1], c[2], p) != 0) continue;
                    double qq = star_quality(M, v, star, n, p, NULL);
                    if (qq > bestq + EPS_GAIN) { bestq = qq; memcpy(bw, ww, sizeof bw); }
                }
            if (bestq > cur) {
                memcpy(w, bw, sizeof w);
                slide_point(M, r, w, x);
                cur = bestq;
            }
        }
        for (int it = 0; it < 30 && step * L > 1e-4 * h; it++) {
            /* directions in the coordinates: along the edge, or the three edge directions inside */
            double dir[6][3];
            int nd = 0;
            if (z >= 0) {
                int a = (z + 1) % 3, b = (z + 2) % 3;
                for (int sgn = -1; sgn <= 1; sgn += 2) { dir[nd][z] = 0; dir[nd][a] = -sgn; dir[nd][b] = sgn; nd++; }
            } else {
                for (int a = 0; a < 3; a++)
                    for (int sgn = -1; sgn <= 1; sgn += 2) {
                        int b = (a + 1) % 3, cc = (a + 2) % 3;
                        dir[nd][a] = sgn; dir[nd][b] = -0.5 * sgn; dir[nd][cc] = -0.5 * sgn; nd++;
                    }
            }
            double bestq = cur, bw[3] = {0};
            for (int di = 0; di < nd; di++) {
                double ww[3];
                for (int j = 0; j < 3; j++) ww[j] = w[j] + step * dir[di][j];
                /* on the dyadic grid; the corner weight left out stays exactly zero */
                int ok = 1;
                for (int j = 0; j < 3; j++) {
                    if (j == z || j == (z >= 0 ? (z + 1) % 3 : 0)) continue;
                    ww[j] = ldexp(nearbyint(ldexp(ww[j], (int)bits)), -(int)bits);
                }
                if (z >= 0) { ww[z] = 0; ww[(z + 1) % 3] = 1 - ww[(z + 2) % 3]; }
                else ww[0] = 1 - ww[1] - ww[2];
                for (int j = 0; j < 3; j++)
                    if (j != z && !(ww[j] > 0 && ww[j] < 1)) ok = 0;
                if (!ok) continue;
                double p[3];
                slide_point(M, r, ww, p);
                if (thx_orient3d(c[0], c[1], c[2], p) != 0) continue; /* not exactly in the plane */
                double qq = star_quality(M, v, star, n, p, NULL);
                if (qq > bestq + EPS_GAIN) { bestq = qq; memcpy(bw, ww, sizeof bw); }
            }
            if (bestq > cur) {
                memcpy(w, bw, sizeof w);
                slide_point(M, r, w, x);
                cur = bestq;
            } else
                step *= 0.5;
        }
        if (cur > q0 + EPS_GAIN) {
            memcpy(M->rec[r].bary, w, sizeof w);
            (*count)++;
            M->node_clock[v] = ++M->clock;
            if (!wide) return 1;
            slid = 1;
            continue;
        }
        x[0] = keep[0]; x[1] = keep[1]; x[2] = keep[2];
    }
    return slid;
}

/* ---- edge collapse ---- */

/* Removes a movable node v of tetrahedron t by collapsing it onto a neighbour w: the tetrahedra
 * around edge (v, w) vanish, the others of v's star get w for v. Applied when every new
 * tetrahedron is positive (exact), the new ones fill the star exactly (faces matched, same
 * volume) and the worst one is better than the star's worst. v is left in no tetrahedron (the
 * mesher drops such nodes). Nodes on the surfaces never go (they are fixed). */
static int try_collapse(imesh *M, int32_t t, size_t *count)
{
    int32_t *star = M->star;
    for (int k = 0; k < 4; k++) {
        int32_t v = M->tet[4 * (size_t)t + k];
        if (M->fixed[v]) continue;
        int n = vertex_star(M, v, star, 0);
        if (!n || n > 2 * MAX_RING) continue;
        double q_old = INFINITY, vol_old = 0;
        for (int i = 0; i < n; i++) {
            double q = qtet(M, star[i]);
            if (q < q_old) q_old = q;
            vol_old += tet_volume6(M, M->tet + 4 * (size_t)star[i]);
        }
        /* candidates: the star's other nodes, nearest first */
        int32_t cand[3 * 2 * MAX_RING + 4];
        int nc = 0;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < 4; j++) {
                int32_t w = M->tet[4 * (size_t)star[i] + j];
                int seen = w == v;
                for (int c = 0; c < nc && !seen; c++) seen = cand[c] == w;
                if (!seen && nc < (int)(sizeof cand / sizeof *cand)) cand[nc++] = w;
            }
        double best_q = q_old + EPS_GAIN;
        int32_t best_w = -1;
        int32_t nw[2 * MAX_RING][4], nreg[2 * MAX_RING];
        for (int c = 0; c < nc; c++) {
            int32_t w = cand[c];
            int m = 0, okc = 1;
            double q_new = INFINITY, vol_new = 0;
            for (int i = 0; i < n && okc; i++) {
                const int32_t *q = M->tet + 4 * (size_t)star[i];
                int has_w = q[0] == w || q[1] == w || q[2] == w || q[3] == w;
                if (has_w) continue;
                int32_t r[4];
                for (int j = 0; j < 4; j++) r[j] = q[j] == v ? w : q[j];
                double qq = q4(M, r[0], r[1], r[2], r[3]);
                if (qq <= 0) { okc = 0; break; }
                if (qq < q_new) q_new = qq;
                vol_new += tet_volume6(M, r);
                m++;
            }
            if (!okc || m == 0 || !(q_new > best_q)) continue;
            if (fabs(vol_new - vol_old) > 1e-9 * fabs(vol_old)) continue; /* the new ones overlap: not the star */
            best_q = q_new;
            best_w = w;
        }
        if (best_w < 0) continue;
        int m = 0;
        for (int i = 0; i < n; i++) {
            const int32_t *q = M->tet + 4 * (size_t)star[i];
            if (q[0] == best_w || q[1] == best_w || q[2] == best_w || q[3] == best_w) continue;
            for (int j = 0; j < 4; j++) nw[m][j] = q[j] == v ? best_w : q[j];
            nreg[m] = M->reg[star[i]];
            m++;
        }
        int32_t old[2 * MAX_RING];
        memcpy(old, star, (size_t)n * sizeof *old);
        if (replace(M, old, n, (const int32_t (*)[4])nw, nreg, m) != 0) continue;
        M->node_tet[v] = -1;
        (*count)++;
        return 1;
    }
    return 0;
}


/* ---- vertex insertion ---- */

/* Room for one more node: xyz and the per-node arrays grow; returns the new node (free, at p), or -1
 * when out of memory. */
static int32_t add_node(imesh *M, const double p[3])
{
    if (M->nn >= (size_t)INT32_MAX) return -1;
    if (M->nn + 1 > M->nn_cap) {
        size_t cap = M->nn_cap * 5 / 4 + 256;
        double *x = realloc(M->xyz, 3 * cap * sizeof *x);
        if (x) M->xyz = x;
        int32_t *nt = realloc(M->node_tet, cap * sizeof *nt);
        if (nt) M->node_tet = nt;
        uint32_t *nc = realloc(M->node_clock, cap * sizeof *nc);
        if (nc) M->node_clock = nc;
        unsigned char *fx = realloc(M->fixed, cap);
        if (fx) M->fixed = fx;
        int32_t *sl = M->slide ? realloc(M->slide, cap * sizeof *sl) : NULL;
        if (sl) M->slide = sl;
        if (!x || !nt || !nc || !fx || (M->slide && !sl)) return -1;
        M->nn_cap = cap;
    }
    int32_t v = (int32_t)M->nn++;
    memcpy(M->xyz + 3 * (size_t)v, p, 3 * sizeof *p);
    M->node_tet[v] = -1;
    M->node_clock[v] = 0;
    M->fixed[v] = 0;
    if (M->slide) M->slide[v] = -1;
    return v;
}

/* Worst quality of the tetrahedra joining p to the faces f[0..n) (each outward from the cavity);
 * below -1 when one is not positive, the more so the farther p lies on the wrong side of a face
 * (h: a length scale), so that a search can walk into the cavity's kernel. */
static double fan_quality(const imesh *M, const int32_t (*f)[3], int n, const double *p, double h)
{
    double w = INFINITY, wrong = 0;
    for (int i = 0; i < n; i++) {
        const double *a = X(M, f[i][0]), *b = X(M, f[i][1]), *c = X(M, f[i][2]);
        if (!right_handed(a, c, b, p)) {
            /* signed distance of p from the face's plane, positive outside */
            double u[3], v[3], nrm[3];
            for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; v[k] = c[k] - a[k]; }
            nrm[0] = u[1] * v[2] - u[2] * v[1];
            nrm[1] = u[2] * v[0] - u[0] * v[2];
            nrm[2] = u[0] * v[1] - u[1] * v[0];
            double l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
            double d = l > 0 ? (nrm[0] * (p[0] - a[0]) + nrm[1] * (p[1] - a[1]) + nrm[2] * (p[2] - a[2])) / l : h;
            wrong = fmax(wrong, fmax(d, 0) / h + 1e-3);
            continue;
        }
        const double *q[4] = {a, c, b, p};
        double s = quality(q, M->re_bound, M->re_scale);
        if (s < w) w = s;
    }
    return wrong > 0 ? -1 - fmin(wrong, 1) : w;
}

/*
 * A new free node inside the domain replaces sliver t and its neighbours (the cavity: t, then the
 * tetrahedra across its faces that are not on a surface, then theirs): it is joined to every face
 * of the cavity's boundary, at the position (pattern search, rounded to the stored precision) where
 * the worst of those tetrahedra is best, and kept when that betters the cavity's worst. What flips
 * and moves cannot do: a sliver whose four nodes lie on the surfaces (two of its faces on a nearly
 * flat surface, the edge between them with no other tetrahedron around it), or in a pocket no free
 * node reaches. The cavity holds no face or edge of a surface inside it (those stay), every node
 * of it stays, and the new tetrahedra fill it exactly (all positive, exact test; volumes summed).
 */
static int try_insert_to(imesh *M, int32_t t, double qt, double need, size_t *count);
static int try_insert(imesh *M, int32_t t, double qt, size_t *count) { return try_insert_to(M, t, qt, INFINITY, count); }

/* As try_insert; the new tetrahedra's worst must beat the cavity's worst, or reach `need`. */
static int try_insert_to(imesh *M, int32_t t, double qt, double need, size_t *count)
{
    for (int level = 1; level <= (M->pocket_uf ? 3 : 2); level++) {
        int32_t cav[MAX_CAV];
        int nc = 0, ok = 1;
        cav[nc++] = t;
        for (int l = 0; l < level && ok; l++) {
            int n0 = nc;
            for (int i = 0; i < n0 && ok; i++)
                for (int f = 0; f < 4 && ok; f++) {
                    int32_t u = M->nbr[4 * (size_t)cav[i] + f];
                    if (u < 0) continue;
                    const int32_t *q = M->tet + 4 * (size_t)cav[i];
                    if (tset_has(&M->prot, tri_sorted(q[face_of[f][0]], q[face_of[f][1]], q[face_of[f][2]]))) continue;
                    int seen = 0;
                    for (int j = 0; j < nc && !seen; j++) seen = cav[j] == u;
                    if (seen) continue;
                    if (nc >= MAX_CAV || M->reg[u] != M->reg[t]) { ok = 0; break; }
                    cav[nc++] = u;
                }
        }
        if (!ok) continue;
        /* the boundary faces (outward), the old quality and volume; no surface face inside */
        int32_t F[4 * MAX_CAV][3];
        int nf = 0;
        double q_old = qt, vol_old = 0, re_old = M->re_bound;
        for (int i = 0; i < nc && ok; i++) {
            const int32_t *q = M->tet + 4 * (size_t)cav[i];
            q_old = fmin(q_old, qtet(M, cav[i]));
            const double *pq[4] = {X(M, q[0]), X(M, q[1]), X(M, q[2]), X(M, q[3])};
            re_old = fmax(re_old, radius_edge_of(pq));
            vol_old += tet_volume6(M, q);
            for (int f = 0; f < 4; f++) {
                int32_t u = M->nbr[4 * (size_t)cav[i] + f];
                int inside = 0;
                for (int j = 0; j < nc && !inside; j++) inside = cav[j] == u;
                int32_t a = q[face_of[f][0]], b = q[face_of[f][1]], c = q[face_of[f][2]];
                if (inside) {
                    if (tset_has(&M->prot, tri_sorted(a, b, c))) { ok = 0; break; }
                    continue;
                }
                F[nf][0] = a; F[nf][1] = b; F[nf][2] = c; nf++;
            }
        }
        if (!ok || nf > MAX_NEW) continue;
        /* every node and every surface edge of the cavity stays on its boundary */
        for (int i = 0; i < nc && ok; i++) {
            const int32_t *q = M->tet + 4 * (size_t)cav[i];
            for (int a = 0; a < 4 && ok; a++)
                for (int b = a; b < 4 && ok; b++) {
                    int on = 0;
                    for (int j = 0; j < nf && !on; j++) {
                        int ha = F[j][0] == q[a] || F[j][1] == q[a] || F[j][2] == q[a];
                        int hb = F[j][0] == q[b] || F[j][1] == q[b] || F[j][2] == q[b];
                        on = ha && hb;
                    }
                    if (!on && (a == b || tset_has(&M->prot, edge_sorted(q[a], q[b])))) ok = 0;
                }
        }
        if (!ok) continue;
        if (M->pocket_uf) { /* the pocket pass: the new node must join the main body */
            int reach = 0;
            for (int j = 0; j < nf && !reach; j++)
                for (int k = 0; k < 3 && !reach; k++) reach = in_main(M, F[j][k]);
            if (!reach) continue;
        }
        /* length scale: the mean edge of the sliver */
        const int32_t *qt4 = M->tet + 4 * (size_t)t;
        double h = 0;
        for (int a = 0; a < 4; a++)
            for (int b = a + 1; b < 4; b++) {
                const double *x = X(M, qt4[a]), *y = X(M, qt4[b]);
                h += sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2])) / 6;
            }
        if (!(h > 0)) continue;
        /* starting points: the centroids of the cavity's tetrahedra; the best one searched from */
        double p[3] = {0, 0, 0}, cur = -INFINITY;
        for (int i = 0; i < nc; i++) {
            const int32_t *q = M->tet + 4 * (size_t)cav[i];
            double c[3];
            for (int k = 0; k < 3; k++) c[k] = stored(0.25 * (X(M, q[0])[k] + X(M, q[1])[k] + X(M, q[2])[k] + X(M, q[3])[k]));
            double w = fan_quality(M, (const int32_t (*)[3])F, nf, c, h);
            if (w > cur) { cur = w; memcpy(p, c, sizeof p); }
        }
        /* ... and points off each boundary face, inward, at heights of a fifth to the whole of its size
           (a sliver flat on a surface wants its node above the surface) */
        for (int j = 0; j < nf; j++) {
            const double *a = X(M, F[j][0]), *b = X(M, F[j][1]), *c = X(M, F[j][2]);
            double u[3], w[3], nrm[3], m[3];
            for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; w[k] = c[k] - a[k]; m[k] = (a[k] + b[k] + c[k]) / 3; }
            nrm[0] = u[1] * w[2] - u[2] * w[1];
            nrm[1] = u[2] * w[0] - u[0] * w[2];
            nrm[2] = u[0] * w[1] - u[1] * w[0];
            double l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
            if (!(l > 0)) continue;
            double size = sqrt(0.5 * l);
            for (int hk = 1; hk <= 5; hk++) {
                double c2[3];
                for (int k = 0; k < 3; k++) c2[k] = stored(m[k] - nrm[k] / l * size * 0.2 * hk); /* outward normal: inward is minus */
                double wq = fan_quality(M, (const int32_t (*)[3])F, nf, c2, h);
                if (wq > cur) { cur = wq; memcpy(p, c2, sizeof p); }
            }
        }
        double step = 0.25 * h;
        for (int it = 0; it < 100 && step > 1e-4 * h; it++) {
            static const double dir[14][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
                                              {1, 1, 1}, {-1, -1, -1}, {1, -1, 1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1},
                                              {-1, 1, 1}, {1, -1, -1}};
            double bestq = cur, bp[3] = {0, 0, 0};
            for (int di = 0; di < 14; di++) {
                double r = di < 6 ? 1 : 0.57735026918962573, x[3];
                for (int k = 0; k < 3; k++) x[k] = stored(p[k] + step * r * dir[di][k]);
                double w = fan_quality(M, (const int32_t (*)[3])F, nf, x, h);
                if (w > bestq + EPS_GAIN) { bestq = w; memcpy(bp, x, sizeof bp); }
            }
            if (bestq > cur) { cur = bestq; memcpy(p, bp, sizeof p); }
            else step *= 0.5;
        }
        if (!(cur > q_old + EPS_GAIN) && !(cur >= need)) continue;
        /* no needle longer than the cavity had, or than the bound (a sliver is not traded for one) */
        double re_new = 0;
        for (int j = 0; j < nf; j++) {
            const double *pq[4] = {X(M, F[j][0]), X(M, F[j][2]), X(M, F[j][1]), p};
            re_new = fmax(re_new, radius_edge_of(pq));
        }
        if (re_new > re_old) continue;
        int32_t nw[MAX_NEW][4], nreg[MAX_NEW];
        int32_t v = add_node(M, p);
        if (v < 0) return 0;
        double vol_new = 0;
        for (int j = 0; j < nf; j++) {
            nw[j][0] = F[j][0]; nw[j][1] = F[j][2]; nw[j][2] = F[j][1]; nw[j][3] = v;
            nreg[j] = M->reg[t];
            vol_new += tet_volume6(M, nw[j]);
        }
        if (fabs(vol_new - vol_old) > 1e-9 * fabs(vol_old) ||
            replace(M, cav, nc, (const int32_t (*)[4])nw, nreg, nf) != 0) {
            M->nn--; /* not used: given back */
            continue;
        }
        M->node_clock[v] = M->clock;
        (*count)++;
        return 1;
    }
    return 0;
}

/* ---- driver ---- */
typedef struct { double q; int32_t t; } qrec;
static int cmp_qrec(const void *x, const void *y)
{
    double a = ((const qrec *)x)->q, b = ((const qrec *)y)->q;
    return (a > b) - (a < b);
}

static double min_dihedral_and_count(const imesh *M, double below, size_t *n_below)
{
    double mn = 180;
    size_t cnt = 0;
#pragma omp parallel for schedule(static) reduction(min : mn) reduction(+ : cnt)
    for (long t = 0; t < (long)M->nt; t++) {
        if (M->dead[t]) continue;
        double d = mesh_tet_min_dihedral(M->xyz, M->tet + 4 * t);
        if (d < mn) mn = d;
        cnt += d < below;
    }
    *n_below = cnt;
    return mn;
}

/* Takes over tet (4 nt), reg (nt; NULL: all 0) and nbr (NULL: searched for). */
static thx_status imesh_open(imesh *M, thx_ctx *ctx, double *xyz, size_t nn, int32_t *tet, int32_t *reg, size_t nt,
                             int32_t *nbr, const int32_t *node_surf, size_t n_regions, const improve_opts *o)
{
    memset(M, 0, sizeof *M);
    M->ctx = ctx;
    M->xyz = xyz;
    M->nn = M->nn_cap = nn;
    M->nt = nt;
    M->node_surf = node_surf;
    M->o = o;
    M->n_regions = n_regions;
    M->tet = tet;
    M->reg = reg ? reg : thx_calloc(ctx, nt ? nt : 1, sizeof *M->reg);
    M->nbr = nbr ? nbr : thx_malloc(ctx, 4 * (nt ? nt : 1) * sizeof *M->nbr);
    M->dead = thx_calloc(ctx, nt ? nt : 1, 1);
    M->failed = thx_calloc(ctx, nt ? nt : 1, sizeof *M->failed);
    M->tmark = thx_calloc(ctx, nt ? nt : 1, sizeof *M->tmark);
    M->node_tet = thx_malloc(ctx, (nn ? nn : 1) * sizeof *M->node_tet);
    M->node_clock = thx_calloc(ctx, nn ? nn : 1, sizeof *M->node_clock);
    if (!M->reg || !M->nbr || !M->dead || !M->failed || !M->tmark || !M->node_tet || !M->node_clock) return THX_ENOMEM;
    M->cap = nt;
    thx_status st = grow(M, nt + 64);
    if (st != THX_OK) return st;
    if (nbr) {
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 4; k++) M->node_tet[M->tet[4 * t + k]] = (int32_t)t;
        return THX_OK;
    }
    return build_adjacency(M);
}

/* The protected set: the given faces (node triples) and their edges. */
static thx_status build_prot(imesh *M, const int32_t *prot, size_t n_prot)
{
    THX_CHECK(tset_init(M->ctx, &M->prot, 4 * n_prot));
    for (size_t i = 0; i < n_prot; i++) {
        int32_t a = prot[3 * i], b = prot[3 * i + 1], c = prot[3 * i + 2];
        tset_add(&M->prot, tri_sorted(a, b, c));
        tset_add(&M->prot, edge_sorted(a, b));
        tset_add(&M->prot, edge_sorted(b, c));
        tset_add(&M->prot, edge_sorted(c, a));
    }
    return THX_OK;
}

/* Compacts the live tetrahedra and hands the arrays back (nbr renumbered when wanted). */
static thx_status imesh_close(imesh *M, int32_t **tet, int32_t **reg, int32_t **nbr, size_t *nt)
{
    int32_t *idx = NULL;
    if (nbr) {
        idx = thx_malloc(M->ctx, (M->nt ? M->nt : 1) * sizeof *idx);
        if (!idx) return THX_ENOMEM;
    }
    size_t live = 0;
    for (size_t t = 0; t < M->nt; t++) {
        if (idx) idx[t] = M->dead[t] ? -1 : (int32_t)live;
        if (M->dead[t]) continue;
        memmove(M->tet + 4 * live, M->tet + 4 * t, 4 * sizeof *M->tet);
        if (nbr) memmove(M->nbr + 4 * live, M->nbr + 4 * t, 4 * sizeof *M->nbr);
        M->reg[live] = M->reg[t];
        live++;
    }
    if (idx) {
        for (size_t k = 0; k < 4 * live; k++)
            if (M->nbr[k] >= 0) M->nbr[k] = idx[M->nbr[k]];
        free(idx);
    }
    int32_t *t = realloc(M->tet, 4 * (live ? live : 1) * sizeof *t);
    if (t) M->tet = t; /* a failed shrink keeps the larger block */
    *tet = M->tet;
    M->tet = NULL;
    if (reg) {
        int32_t *r = realloc(M->reg, (live ? live : 1) * sizeof *r);
        if (r) M->reg = r;
        *reg = M->reg;
        M->reg = NULL;
    }
    if (nbr) {
        int32_t *n = realloc(M->nbr, 4 * (live ? live : 1) * sizeof *n);
        if (n) M->nbr = n;
        *nbr = M->nbr;
        M->nbr = NULL;
    }
    *nt = live;
    return THX_OK;
}

static void imesh_free(imesh *M)
{
    free(M->tet);
    free(M->nbr);
    free(M->reg);
    free(M->dead);
    free(M->freel);
    free(M->failed);
    free(M->node_clock);
    free(M->node_tet);
    free(M->prot.slot);
    free(M->fixed);
    free(M->slide);
    free(M->nmark);
    free(M->tmark);
    memset(M, 0, sizeof *M);
}

thx_status mesh_improve(thx_ctx *ctx, thx_volume *v, int32_t *nbr, const int32_t *prot, size_t n_prot,
                        const improve_opts *o, improve_stats *stats)
{
    double t0 = thx_wtime();
    thx_status st = THX_OK;
    improve_stats S;
    memset(&S, 0, sizeof S);
    imesh M;
    qrec *bad = NULL;
    /* the volume's arrays are taken over (no copy) and given back compacted; on failure the volume is
       left without tetrahedra */
    int32_t *tet = v->tet, *reg = v->region;
    size_t nt = v->n_tets;
    v->tet = NULL;
    v->region = NULL;
    v->n_tets = 0;
    if (!reg) reg = thx_calloc(ctx, nt ? nt : 1, sizeof *reg);
    st = imesh_open(&M, ctx, v->xyz, v->n_nodes, tet, reg, nt, nbr, v->node_surf, v->n_regions, o);
    if (st != THX_OK) goto done;
    THX_TRY(build_prot(&M, prot, n_prot));
    /* nodes that never move: surface nodes and the Steiner points on the surfaces */
    M.fixed = thx_calloc(ctx, v->n_nodes ? v->n_nodes : 1, 1);
    if (!M.fixed) { st = THX_ENOMEM; goto done; }
    if (v->node_surf)
        for (size_t i = 0; i < v->n_nodes; i++) M.fixed[i] = v->node_surf[i] >= 0;
    for (size_t i = 0; i < v->n_steiner; i++) M.fixed[v->steiner[i].node] = 1;
    if (o->steiner_corners && v->n_steiner) {
        /* Steiner nodes that may slide: those whose record gives back their position exactly */
        M.slide = thx_malloc(ctx, v->n_nodes * sizeof *M.slide);
        if (!M.slide) { st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < v->n_nodes; i++) M.slide[i] = -1;
        M.rec = v->steiner;
        M.corner = o->steiner_corners;
        for (size_t i = 0; i < v->n_steiner; i++) {
            double p[3];
            slide_point(&M, (int32_t)i, v->steiner[i].bary, p);
            const double *x = X(&M, v->steiner[i].node);
            if (p[0] == x[0] && p[1] == x[1] && p[2] == x[2]) M.slide[v->steiner[i].node] = (int32_t)i;
        }
    }
    S.tets_before = M.nt;
    S.min_before = min_dihedral_and_count(&M, o->target_deg, &S.below_before);
    double sin_target = sin(o->target_deg * M_PI / 180.0);
    M.re_bound = o->radius_edge;
    M.re_scale = sin_target * o->radius_edge;
    unsigned ops = o->ops ? o->ops : IMPROVE_EDGE | IMPROVE_FACE | IMPROVE_MOVE | IMPROVE_SLIDE | IMPROVE_COLLAPSE | IMPROVE_INSERT;
    for (int round = 0; round < 2; round++) {
    for (int pass = 0; pass < (round ? 1 : o->max_passes); pass++) {
        size_t nb = 0;
        free(bad);
        bad = thx_malloc(ctx, (M.nt ? M.nt : 1) * sizeof *bad);
        if (!bad) { st = THX_ENOMEM; goto done; }
#pragma omp parallel for schedule(static)
        for (long t = 0; t < (long)M.nt; t++) bad[t].q = M.dead[t] ? INFINITY : qsel(&M, (int32_t)t);
        for (size_t t = 0; t < M.nt; t++)
            if (bad[t].q < sin_target) bad[nb++] = (qrec){bad[t].q, (int32_t)t};
        if (!nb) break;
        qsort(bad, nb, sizeof *bad, cmp_qrec);
        size_t changed = 0;
        for (size_t i = 0; i < nb; i++) {
            int32_t t = bad[i].t;
            if (M.dead[t]) continue;
            if (qsel(&M, t) >= sin_target) continue;
            double q = qtet(&M, t);
            if (M.failed[t]) { /* tried before: again only if something changed at its corners since */
                uint32_t last = 0;
                for (int k = 0; k < 4; k++) {
                    uint32_t c = M.node_clock[M.tet[4 * (size_t)t + k]];
                    if (c > last) last = c;
                }
                if (last <= M.failed[t]) continue;
            }
            if (((ops & IMPROVE_EDGE) && try_edge_removal(&M, t, q, &S.n_edge_removals)) ||
                ((ops & IMPROVE_FACE) && try_face_removal(&M, t, q, &S.n_face_removals)) ||
                ((ops & IMPROVE_MOVE) && try_move(&M, t, &S.n_moves)) ||
                ((ops & IMPROVE_SLIDE) && try_slide(&M, t, &S.n_slides)) ||
                ((ops & IMPROVE_COLLAPSE) && try_collapse(&M, t, &S.n_collapses)) ||
                ((ops & IMPROVE_INSERT) && try_insert(&M, t, q, &S.n_inserts)))
                changed++;
            else
                M.failed[t] = M.clock;
        }
        if (!changed) break;
    }
    /* What the passes leave with a dihedral angle below 2 deg (thorax check refuses 1 deg; needles
       are not taken: at --grid 8 that made 2.46 deg 1.90): a Steiner node of it may do
       better far from where the pattern search got stuck, so its slide starts from the best of a
       sample of its star's reach (ECGSim, --quality 0 --repair 0: a point inside heart triangle 213
       slid from 21 to 41 deg off a 16 deg fold, 0.78 -> 0.79 deg, where 8-16 deg gives 1.4-2.7);
       if one moves, one more pass follows (the passes may stop at max_passes, not converged: a
       whole second round doubled the repair's time for no better result). */
    size_t wide = 0;
    if (round == 0 && (ops & IMPROVE_SLIDE) && M.slide) {
        for (size_t t = 0; t < M.nt; t++)
            if (!M.dead[t] && dihedral_sine(&M, (int32_t)t) < POCKET_FLOOR && try_slide_from(&M, (int32_t)t, 1, &S.n_slides))
                wide++;
    }
    if (!wide) break;
    }
    /* Pockets: a surface node none of whose neighbours is a node of the main body of the rest (the
       largest connected set of nodes not on its surface, Steiner nodes included) gets a free node
       joined to both. Where a surface's potentials are given (the heart's), such a node's value
       reaches no free node that reaches the torso: its transfer column would be zero (a narrow
       cavity pocket of ECGSim's right ventricle, no grid node in it). Accepted when the new
       tetrahedra are no worse than the cavity's worst, or than a 2 deg sliver. */
    if ((ops & IMPROVE_INSERT) && v->node_surf && o->pocket_surface >= -1) {
        size_t nv = v->n_nodes; /* nodes the volume's tables cover; later ones were inserted (free) */
        int32_t *owner = NULL, *uf = NULL;
        for (int32_t s = 0; (size_t)s < v->n_surfaces; s++) {
            if (o->pocket_surface >= 0 && s != o->pocket_surface) continue;
            size_t nn0 = M.nn; /* the nodes now, insertions for earlier surfaces included */
            int32_t *o2 = realloc(owner, (nn0 ? nn0 : 1) * sizeof *o2);
            if (o2) owner = o2;
            int32_t *u2 = realloc(uf, (nn0 ? nn0 : 1) * sizeof *u2);
            if (u2) uf = u2;
            if (!o2 || !u2) { free(owner); free(uf); st = thx_error(ctx, THX_ENOMEM, "mesh: out of memory repairing slivers"); goto done; }
            for (size_t i = 0; i < nn0; i++) owner[i] = i < nv ? v->node_surf[i] : -1;
            for (size_t i = 0; i < v->n_steiner; i++) owner[v->steiner[i].node] = v->steiner[i].surf;
            /* components of the nodes off surface s (union-find over the tetrahedra's edges) */
            for (size_t i = 0; i < nn0; i++) uf[i] = (int32_t)i;
            for (size_t t = 0; t < M.nt; t++) {
                if (M.dead[t]) continue;
                const int32_t *q = M.tet + 4 * t;
                int32_t first = -1;
                for (int c = 0; c < 4; c++) {
                    if (owner[q[c]] == s) continue;
                    int32_t r = q[c];
                    while (uf[r] != r) r = uf[r] = uf[uf[r]];
                    if (first < 0) first = r;
                    else if (r != first) { if (r < first) { uf[first] = r; first = r; } else uf[r] = first; }
                }
            }
            size_t *cnt = thx_calloc(ctx, nn0 ? nn0 : 1, sizeof *cnt);
            if (!cnt) { free(owner); free(uf); st = THX_ENOMEM; goto done; }
            int32_t root = -1;
            for (size_t i = 0; i < nn0; i++) {
                if (owner[i] == s || M.node_tet[i] < 0) continue;
                int32_t r = (int32_t)i;
                while (uf[r] != r) r = uf[r] = uf[uf[r]];
                uf[i] = r;
                if (++cnt[r] > (root >= 0 ? cnt[root] : 0)) root = r;
            }
            free(cnt);
            if (root < 0) continue;
            M.pocket_owner = owner;
            M.pocket_uf = uf;
            M.pocket_surf = s;
            M.pocket_root = root;
            M.pocket_nn = nn0;
            for (size_t i = 0; i < nn0 && i < nv; i++) {
                if (owner[i] != s || v->node_surf[i] != s || M.node_tet[i] < 0) continue;
                int32_t *star = M.star2;
                int n = vertex_star(&M, (int32_t)i, star, 1);
                int reach = 0;
                for (int k = 0; k < n && !reach; k++)
                    for (int c = 0; c < 4 && !reach; c++) reach = in_main(&M, M.tet[4 * (size_t)star[k] + c]);
                if (!n || reach) continue;
                S.n_pockets++;
                for (int k = 0; k < n; k++)
                    if (!M.dead[star[k]] && try_insert_to(&M, star[k], qtet(&M, star[k]), POCKET_FLOOR, &S.n_inserts)) {
                        S.n_pocket_nodes++;
                        break;
                    }
            }
            M.pocket_uf = NULL;
        }
        free(owner);
        free(uf);
    }
    S.min_after = min_dihedral_and_count(&M, o->target_deg, &S.below_after);
    if (M.nn > v->n_nodes) { /* inserted nodes: free, on no surface */
        int32_t *ns = realloc(v->node_surf, M.nn * sizeof *ns);
        if (ns) v->node_surf = ns;
        int32_t *nd = realloc(v->node_snode, M.nn * sizeof *nd);
        if (nd) v->node_snode = nd;
        if (!ns || !nd) { st = thx_error(ctx, THX_ENOMEM, "mesh: out of memory repairing slivers"); goto done; }
        for (size_t i = v->n_nodes; i < M.nn; i++) v->node_surf[i] = v->node_snode[i] = -1;
        v->n_nodes = M.nn;
    }
    THX_TRY(imesh_close(&M, &v->tet, &v->region, NULL, &v->n_tets));
    S.tets_after = v->n_tets;
    S.seconds = thx_wtime() - t0;
    if (stats) *stats = S;
done:
    v->xyz = M.xyz; /* insertions may have moved it */
    free(bad);
    imesh_free(&M);
    return st;
}
