/*
 * Verification geometry and closed-form solutions for the volume-conductor
 * solvers (thorax/geom/verify.h, docs/validation.md "Verification geometry").
 *
 * 1. Concentric spherical shells.
 *
 *    Radii a < b < c, conductivity s1 in a < r < b (shell 1) and s2 in
 *    b < r < c (shell 2). Boundary value problem for the potential phi:
 *        div(s grad phi) = 0            in each shell,
 *        phi = P_l(cos theta)           on r = a,
 *        phi and s dphi/dr continuous   across r = b,
 *        dphi/dr = 0                    on r = c (no current leaves).
 *    Separation of variables: in each shell phi = R_k(r) P_l(cos theta) with
 *    R_k a combination of the two radial solutions r^l and r^-(l+1). To keep
 *    the numbers of order one whatever the radii and l (r^l and r^-(l+1)
 *    differ by many orders of magnitude in mm), each shell's pair is scaled
 *    at a radius of that shell:
 *        R_1(r) = A1 (r/b)^l + B1 (b/r)^(l+1)      a <= r <= b
 *        R_2(r) = A2 (r/c)^l + B2 (c/r)^(l+1)      b <= r <= c
 *    (the A_k r^l + B_k r^-(l+1) of the header with A_k, B_k rescaled), and
 *    r R'(r) = l A (r/x)^l - (l+1) B (x/r)^(l+1) for either. The four
 *    conditions (the last two multiplied by b and c) are the 4x4 system
 *
 *      [ (a/b)^l    (b/a)^(l+1)    0              0                ] [A1]   [1]
 *      [ 1          1             -(b/c)^l       -(c/b)^(l+1)      ] [B1] = [0]
 *      [ s1 l      -s1 (l+1)      -s2 l (b/c)^l   s2 (l+1)(c/b)^(l+1)] [A2]   [0]
 *      [ 0          0              l             -(l+1)            ] [B2]   [0]
 *
 *    solved here by elimination in closed form (no pivoting decisions, no
 *    cancellation beyond that of the formula itself):
 *
 *    row 4:        B2 = l/(l+1) A2, so R_2 = A2 g(r) with
 *                  g(r) = (r/c)^l + l/(l+1) (c/r)^(l+1),
 *                  r g'(r) = l [(r/c)^l - (c/r)^(l+1)]   (= 0 at r = c).
 *                  Let G = g(b) > 0 and D = b g'(b) <= 0, rho = s2/s1.
 *    rows 2, 3:    A1 + B1 = A2 G,   l A1 - (l+1) B1 = rho A2 D, hence
 *                  A1 = A2 alpha,  alpha = ((l+1) G + rho D) / (2l+1),
 *                  B1 = A2 beta,   beta  = (l G - rho D) / (2l+1).
 *    row 1:        A2 = 1 / (alpha (a/b)^l + beta (b/a)^(l+1)).
 *
 *    The denominator is positive: G > 0 and D <= 0 give beta >= 0 and
 *    alpha + beta = G > 0. If alpha >= 0 (and not both 0) it is positive at
 *    once; if alpha < 0 (s2 >> s1), then alpha (a/b)^l >= alpha because
 *    0 < (a/b)^l <= 1, and beta (b/a)^(l+1) >= beta, so it is >= G > 0.
 *
 *    Checks of the formula (also run by tests/test_verify.c):
 *    - l = 0: g = 1, G = 1, D = 0, alpha = 1, beta = 0, A2 = 1: phi = 1
 *      everywhere (the constant is the only solution with no current).
 *    - s1 = s2 (rho = 1), l >= 1: (l+1) G + D = (2l+1) (b/c)^l and
 *      l G - D = l (2l+1)/(l+1) (c/b)^(l+1), so A1 (r/b)^l = A2 (r/c)^l and
 *      B1 (b/r)^(l+1) = A2 l/(l+1) (c/r)^(l+1): R_1 = R_2 = A2 g(r), the
 *      single-shell form A r^l + B r^-(l+1) with B = l/(l+1) c^(2l+1) A
 *      (dphi/dr(c) = 0) and A fixed by phi(a) = 1:
 *          phi = g(r) / g(a) P_l(cos theta).
 *    Valid while (c/a)^(l+1) does not overflow (l up to a few hundred for
 *    c/a ~ 10).
 *
 * 2. The cubed-sphere shell mesh.
 *
 *    The surface of the cube [0, n]^3 carries the integer lattice points with
 *    at least one coordinate 0 or n: 6 n^2 + 2 of them (Euler: V - E + F = 2
 *    with F = 6 n^2 quadrilaterals, E = 12 n^2). cube_index numbers them
 *    once, so a point shared by two or three cube faces is one node. Point
 *    (i, j, k) maps to the direction of (t(i), t(j), t(k)) with
 *    t(m) = tan(pi/4 (2m - n)/n) (equiangular: the cells of a face subtend
 *    equal angles: their areas differ by a factor of at most about 1.4,
 *    against about 5 for the plain projection of the lattice); t(0) = -1
 *    and t(n) = 1 exactly, t odd in 2m - n. Layer L of nodes (0 .. nr1 + nr2)
 *    lies on the sphere of radius r_L, uniform in r within each shell,
 *    r_0 = a, r_nr1 = b, r_(nr1+nr2) = c exactly; node number
 *    L (6 n^2 + 2) + cube_index.
 *
 *    Cells: per cube face, per lattice square (p, q) and per layer L a
 *    hexahedron with local corners (i, j, k) in {0,1}^3 (index i + 2j + 4k):
 *    i along the face's u axis, j along its v axis, k outward, the face
 *    frames chosen so that e_u x e_v is the face's outward normal: the local
 *    frame is right-handed on every face. Each hexahedron is split into 6
 *    tetrahedra that all contain its smallest-numbered node v0: the three
 *    faces of the hexahedron not containing v0 are each cut by the diagonal
 *    through their own smallest-numbered node, and every resulting triangle
 *    is joined to v0. The three faces through v0 are then cut by the
 *    diagonal through v0, which is also their smallest node. So every
 *    quadrilateral face, seen from either of its cells, is cut by the
 *    diagonal through its smallest global node number: the two cells agree,
 *    across the cube's edges and corners too, since the numbering is
 *    global. The tetrahedra are oriented from the outward order of the
 *    hexahedron's faces (the triangle (t0, t1, t2) counterclockwise seen from
 *    outside the cell, the tetrahedron (t0, t2, t1, v0) is right-handed).
 *    None can fold, however thin the layers against the sag of a cell's
 *    spherical faces: the numbering is layer-major, so v0 is on the cell's
 *    inner sphere, directly below the smallest node v0' of its outer face,
 *    and both triangles of the outer face contain v0' (the diagonal through
 *    it), so those two tetrahedra contain the radial edge v0 v0' under their
 *    triangle; the other far faces are radial quadrilaterals, planar (in the
 *    plane of two radial lines) and not through v0. Every tetrahedron is
 *    still checked with the exact orient3d (a failure would be a bug:
 *    THX_EINTERNAL), never silently "fixed".
 *
 * 3. The anisotropic slab: see thx_slab_mesh below (same splitting rule;
 *    with lattice numbering it gives the six tetrahedra around the cell's
 *    main diagonal).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"
#include "thorax/geom/verify.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define GOLD 1.6180339887498948482 /* (1 + sqrt 5) / 2 */

/* ------------------------------------------------------------------ */
/* Legendre polynomials and the shells solution. */

/* Bonnet's recurrence (k+1) P_(k+1) = (2k+1) x P_k - k P_(k-1): forward
 * stable for |x| <= 1. NaN for l < 0. */
double thx_legendre(int l, double x)
{
    if (l < 0) return NAN;
    if (l == 0) return 1.0;
    double p0 = 1.0, p1 = x;
    for (int k = 1; k < l; k++) {
        double p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

/* NaN for l < 0, radii not 0 < a < b < c, conductivities not > 0, or r
 * outside [a, c] by more than rounding (1e-12 relative). */
double thx_shells_potential(int l, double a, double b, double c, double s1, double s2, double r, double ct)
{
    if (l < 0 || !(a > 0.0 && a < b && b < c && isfinite(c)) || !(s1 > 0.0 && s2 > 0.0) || !isfinite(s1) ||
        !isfinite(s2) || !(r >= a * (1.0 - 1e-12) && r <= c * (1.0 + 1e-12)))
        return NAN;
    double dl = l, rho = s2 / s1;
    double G = pow(b / c, dl) + dl / (dl + 1.0) * pow(c / b, dl + 1.0);
    double D = dl * (pow(b / c, dl) - pow(c / b, dl + 1.0));
    double alpha = ((dl + 1.0) * G + rho * D) / (2.0 * dl + 1.0);
    double beta = (dl * G - rho * D) / (2.0 * dl + 1.0);
    double A2 = 1.0 / (alpha * pow(a / b, dl) + beta * pow(b / a, dl + 1.0));
    double R;
    if (r < b) R = A2 * (alpha * pow(r / b, dl) + beta * pow(b / r, dl + 1.0));
    else R = A2 * (pow(r / c, dl) + dl / (dl + 1.0) * pow(c / r, dl + 1.0));
    return R * thx_legendre(l, ct);
}

/* ------------------------------------------------------------------ */
/* Hexahedron -> 6 tetrahedra by the smallest-node rule (see the top). */

/* The faces of the unit hexahedron (corner index i + 2j + 4k), each
 * counterclockwise seen from outside; face f fixes bit f/2 at value f%2. */
static const int hex_face[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

/* h: the 8 global node numbers (distinct) of a cell whose local frame is
 * right-handed; writes 6 right-handed tetrahedra (24 numbers) to t. */
static void split_hex(const int32_t h[8], int32_t *t)
{
    int m = 0;
    for (int i = 1; i < 8; i++)
        if (h[i] < h[m]) m = i;
    int nt = 0;
    for (int f = 0; f < 6; f++) {
        if (((m >> (f / 2)) & 1) == f % 2) continue; /* a face through v0 */
        const int *c = hex_face[f];
        int s = 0;
        for (int i = 1; i < 4; i++)
            if (h[c[i]] < h[c[s]]) s = i;
        int c0 = c[s], c1 = c[(s + 1) % 4], c2 = c[(s + 2) % 4], c3 = c[(s + 3) % 4];
        /* triangles (c0, c1, c2) and (c0, c2, c3), counterclockwise from outside; v0 is inside */
        int32_t *q = t + 4 * nt;
        q[0] = h[c0], q[1] = h[c2], q[2] = h[c1], q[3] = h[m];
        q[4] = h[c0], q[5] = h[c3], q[6] = h[c2], q[7] = h[m];
        nt += 2;
    }
}

/* The first tetrahedron that is not right-handed by the exact predicate, or
 * n_tets if all are (right-handed: orient3d(p0, p1, p2, p3) < 0). */
static size_t first_bad_tet(const thx_volume *v)
{
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        if (!(thx_orient3d(v->xyz + 3 * (size_t)q[0], v->xyz + 3 * (size_t)q[1], v->xyz + 3 * (size_t)q[2],
                           v->xyz + 3 * (size_t)q[3]) < 0.0))
            return t;
    }
    return v->n_tets;
}

/* Allocates the node tables of a volume without surfaces (every entry -1). */
static thx_status empty_node_tables(thx_ctx *ctx, thx_volume *v)
{
    v->n_surfaces = 0;
    v->node_surf = thx_malloc(ctx, v->n_nodes * sizeof *v->node_surf);
    v->node_snode = thx_malloc(ctx, v->n_nodes * sizeof *v->node_snode);
    if (!v->node_surf || !v->node_snode) return THX_ENOMEM;
    for (size_t i = 0; i < v->n_nodes; i++) v->node_surf[i] = v->node_snode[i] = -1;
    return THX_OK;
}

static void set_region(thx_region *r, const char *name, const double sigma[9], int anisotropic)
{
    memset(r, 0, sizeof *r);
    snprintf(r->name, sizeof r->name, "%s", name);
    memcpy(r->sigma, sigma, sizeof r->sigma);
    r->anisotropic = anisotropic;
    snprintf(r->source, sizeof r->source, "verification");
}

/* ------------------------------------------------------------------ */
/* Cubed-sphere shells. */

/* Number of the cube-surface lattice point (i, j, k), 0 .. 6n^2 + 1: the
 * (n+1)^2 points of k = 0, then for each 0 < k < n the 4n points of the ring
 * around the square (counterclockwise from (0, 0)), then k = n. */
static int32_t cube_index(int n, int i, int j, int k)
{
    int32_t sq = (int32_t)(n + 1) * (n + 1);
    if (k == 0) return i + (n + 1) * j;
    if (k == n) return sq + 4 * n * (n - 1) + i + (n + 1) * j;
    int32_t ring;
    if (j == 0) ring = i;                  /* (0..n-1, 0) */
    else if (i == n) ring = n + j;         /* (n, 0..n-1) */
    else if (j == n) ring = 2 * n + n - i; /* (n..1, n) */
    else ring = 3 * n + n - j;             /* (0, n..1) */
    return sq + 4 * n * (k - 1) + ring;
}

/* Equiangular coordinate of lattice value m on [-1, 1]. */
static double cube_t(int n, int m)
{
    if (m == 0) return -1.0;
    if (m == n) return 1.0;
    return tan((M_PI / 4.0) * (double)(2 * m - n) / (double)n);
}

/* Cube faces: normal axis, sign, and the axes u, v with e_u x e_v = outward normal. */
static const int cube_face[6][4] = {{0, +1, 1, 2}, {0, -1, 2, 1}, {1, +1, 2, 0},
                                    {1, -1, 0, 2}, {2, +1, 0, 1}, {2, -1, 1, 0}};

thx_status thx_shells_mesh(thx_ctx *ctx, double a, double b, double c, double s1, double s2, int n, int nr1, int nr2,
                           thx_volume **out, int32_t **inner, size_t *n_inner, int32_t **outer, size_t *n_outer)
{
    *out = NULL;
    *inner = *outer = NULL;
    *n_inner = *n_outer = 0;
    if (!(a > 0.0 && a < b && b < c && isfinite(c)))
        return thx_error(ctx, THX_EINPUT, "shells mesh: radii must satisfy 0 < a < b < c (a = %g, b = %g, c = %g)",
                         a, b, c);
    if (!(s1 > 0.0 && s2 > 0.0 && isfinite(s1) && isfinite(s2)))
        return thx_error(ctx, THX_EINPUT, "shells mesh: conductivities must be positive (s1 = %g, s2 = %g)", s1, s2);
    if (n < 1 || nr1 < 1 || nr2 < 1)
        return thx_error(ctx, THX_EINPUT, "shells mesh: need n, nr1, nr2 >= 1 (n = %d, nr1 = %d, nr2 = %d)", n, nr1,
                         nr2);
    int nl = nr1 + nr2 + 1; /* node layers */
    double ns_d = 6.0 * n * (double)n + 2.0;
    if (n > 10000 || nr1 > 1000000 || nr2 > 1000000 || ns_d * nl > 2147483647.0 ||
        36.0 * n * (double)n * (nl - 1) > (double)(SIZE_MAX / 32))
        return thx_error(ctx, THX_EINPUT, "shells mesh: n = %d, nr1 = %d, nr2 = %d is too large", n, nr1, nr2);
    size_t ns = (size_t)ns_d;

    thx_status st = THX_OK;
    thx_volume *v = NULL;
    double *dir = NULL;
    THX_TRY(thx_volume_create(ctx, &v));
    v->n_nodes = ns * (size_t)nl;
    v->n_tets = 36 * (size_t)n * (size_t)n * (size_t)(nl - 1);
    v->n_regions = 2;
    dir = thx_malloc(ctx, 3 * ns * sizeof *dir);
    v->xyz = thx_malloc(ctx, 3 * v->n_nodes * sizeof *v->xyz);
    v->tet = thx_malloc(ctx, 4 * v->n_tets * sizeof *v->tet);
    v->region = thx_malloc(ctx, v->n_tets * sizeof *v->region);
    v->regions = thx_calloc(ctx, 2, sizeof *v->regions);
    *inner = thx_malloc(ctx, ns * sizeof **inner);
    *outer = thx_malloc(ctx, ns * sizeof **outer);
    if (!dir || !v->xyz || !v->tet || !v->region || !v->regions || !*inner || !*outer) {
        st = THX_ENOMEM;
        goto done;
    }
    THX_TRY(empty_node_tables(ctx, v));
    double sig[9] = {0};
    sig[0] = sig[4] = sig[8] = s1;
    set_region(&v->regions[0], "inner_shell", sig, 0);
    sig[0] = sig[4] = sig[8] = s2;
    set_region(&v->regions[1], "outer_shell", sig, 0);

    /* unit directions of the cube-surface lattice points */
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                if (i > 0 && i < n && j > 0 && j < n && k > 0 && k < n) continue;
                double x = cube_t(n, i), y = cube_t(n, j), z = cube_t(n, k);
                double len = sqrt(x * x + y * y + z * z);
                size_t s = (size_t)cube_index(n, i, j, k);
                dir[3 * s] = x / len;
                dir[3 * s + 1] = y / len;
                dir[3 * s + 2] = z / len;
            }
    /* nodes, layer by layer */
    for (int L = 0; L < nl; L++) {
        double r;
        if (L == 0) r = a;
        else if (L < nr1) r = a + (b - a) * ((double)L / nr1);
        else if (L == nr1) r = b;
        else if (L < nl - 1) r = b + (c - b) * ((double)(L - nr1) / nr2);
        else r = c;
        double *p = v->xyz + 3 * ns * (size_t)L;
        for (size_t s = 0; s < 3 * ns; s++) p[s] = r * dir[s];
    }
    for (size_t s = 0; s < ns; s++) {
        (*inner)[s] = (int32_t)s;
        (*outer)[s] = (int32_t)(ns * (size_t)(nl - 1) + s);
    }
    /* cells */
    size_t t = 0;
    for (int L = 0; L < nl - 1; L++)
        for (int f = 0; f < 6; f++) {
            int ax = cube_face[f][0], u = cube_face[f][2], w = cube_face[f][3];
            for (int q = 0; q < n; q++)
                for (int p = 0; p < n; p++) {
                    int32_t h[8];
                    for (int corner = 0; corner < 8; corner++) {
                        int g[3];
                        g[ax] = cube_face[f][1] > 0 ? n : 0;
                        g[u] = p + (corner & 1);
                        g[w] = q + ((corner >> 1) & 1);
                        int layer = L + ((corner >> 2) & 1);
                        h[corner] = (int32_t)((size_t)layer * ns) + cube_index(n, g[0], g[1], g[2]);
                    }
                    split_hex(h, v->tet + 4 * t);
                    for (int e = 0; e < 6; e++) v->region[t + e] = L < nr1 ? 0 : 1;
                    t += 6;
                }
        }
    size_t bad = first_bad_tet(v);
    if (bad < v->n_tets)
        st = thx_error(ctx, THX_EINTERNAL, "shells mesh: tetrahedron %zu is not positive (n = %d, nr1 = %d, nr2 = %d)",
                       bad, n, nr1, nr2);

done:
    free(dir);
    if (st != THX_OK) {
        thx_volume_destroy(&v);
        free(*inner);
        free(*outer);
        *inner = *outer = NULL;
        return st;
    }
    *out = v;
    *n_inner = *n_outer = ns;
    return THX_OK;
}

/* ------------------------------------------------------------------ */
/* Anisotropic slab. */

/* sigma symmetric (to 1e-12 of its largest entry), finite, positive definite
 * (leading principal minors > 0)? */
static int spd(const double s[9])
{
    double mx = 0.0;
    for (int i = 0; i < 9; i++) {
        if (!isfinite(s[i])) return 0;
        mx = fmax(mx, fabs(s[i]));
    }
    if (fabs(s[1] - s[3]) > 1e-12 * mx || fabs(s[2] - s[6]) > 1e-12 * mx || fabs(s[5] - s[7]) > 1e-12 * mx) return 0;
    double m2 = s[0] * s[4] - s[1] * s[3];
    double m3 =
        s[0] * (s[4] * s[8] - s[5] * s[7]) - s[1] * (s[3] * s[8] - s[5] * s[6]) + s[2] * (s[3] * s[7] - s[4] * s[6]);
    return s[0] > 0.0 && m2 > 0.0 && m3 > 0.0;
}

/*
 * phi(p) = g . p with g = sigma^-1 e_x / (sigma^-1)_xx. The first column of
 * sigma^-1 is the first row of the cofactor matrix over det(sigma)
 * (sigma^-1 = adj(sigma)/det, adj = cofactor^T, sigma symmetric), so the
 * determinant cancels: g = (C_xx, C_xy, C_xz) / C_xx with
 *   C_xx = s_yy s_zz - s_yz s_zy,  C_xy = -(s_yx s_zz - s_yz s_zx),
 *   C_xz = s_yx s_zy - s_yy s_zx.
 * g_x = 1, and -sigma g = -e_x / (sigma^-1)_xx: the current flows along -x
 * only. phi = 0 at the origin and L at (L, 0, 0); on the ends x = 0 and
 * x = L it varies as g_y y + g_z z unless sigma couples x with neither y nor
 * z. NaN if C_xx <= 0 (sigma not positive definite).
 */
double thx_slab_potential(const double sigma[9], const double p[3])
{
    const double *s = sigma;
    double cxx = s[4] * s[8] - s[5] * s[7];
    double cxy = -(s[3] * s[8] - s[5] * s[6]);
    double cxz = s[3] * s[7] - s[4] * s[6];
    if (!(cxx > 0.0)) return NAN;
    return p[0] + (cxy / cxx) * p[1] + (cxz / cxx) * p[2];
}

/*
 * Nodes (i, j, k) -> i + (nx+1) (j + (ny+1) k) at (L i/nx, W j/ny, H k/nz)
 * (the last of each exactly L, W, H); cell tetrahedra by split_hex, which for
 * this numbering gives the six tetrahedra around the diagonal from the cell's
 * (0,0,0) corner to its (1,1,1) corner (every cell alike: conforming).
 * ends: the (ny+1)(nz+1) nodes on x = 0, then the (ny+1)(nz+1) on x = L,
 * each in node order. The region is "slab", anisotropic unless sigma is a
 * multiple of the identity.
 */
thx_status thx_slab_mesh(thx_ctx *ctx, double L, double W, double H, int nx, int ny, int nz, const double sigma[9],
                         thx_volume **out, int32_t **ends, size_t *n_ends)
{
    *out = NULL;
    *ends = NULL;
    *n_ends = 0;
    if (!(L > 0.0 && W > 0.0 && H > 0.0 && isfinite(L) && isfinite(W) && isfinite(H)))
        return thx_error(ctx, THX_EINPUT, "slab mesh: sizes must be positive (L = %g, W = %g, H = %g)", L, W, H);
    if (nx < 1 || ny < 1 || nz < 1)
        return thx_error(ctx, THX_EINPUT, "slab mesh: need nx, ny, nz >= 1 (%d, %d, %d)", nx, ny, nz);
    if ((nx + 1.0) * (ny + 1.0) * (nz + 1.0) > 2147483647.0)
        return thx_error(ctx, THX_EINPUT, "slab mesh: %d x %d x %d cells is too large", nx, ny, nz);
    if (!spd(sigma))
        return thx_error(ctx, THX_EINPUT, "slab mesh: sigma is not a symmetric positive definite tensor");

    thx_status st = THX_OK;
    thx_volume *v = NULL;
    size_t sx = (size_t)nx + 1, sy = (size_t)ny + 1, sz = (size_t)nz + 1;
    THX_TRY(thx_volume_create(ctx, &v));
    v->n_nodes = sx * sy * sz;
    v->n_tets = 6 * (size_t)nx * (size_t)ny * (size_t)nz;
    v->n_regions = 1;
    v->xyz = thx_malloc(ctx, 3 * v->n_nodes * sizeof *v->xyz);
    v->tet = thx_malloc(ctx, 4 * v->n_tets * sizeof *v->tet);
    v->region = thx_calloc(ctx, v->n_tets, sizeof *v->region);
    v->regions = thx_calloc(ctx, 1, sizeof *v->regions);
    *ends = thx_malloc(ctx, 2 * sy * sz * sizeof **ends);
    if (!v->xyz || !v->tet || !v->region || !v->regions || !*ends) {
        st = THX_ENOMEM;
        goto done;
    }
    THX_TRY(empty_node_tables(ctx, v));
    int iso = sigma[0] == sigma[4] && sigma[0] == sigma[8] && sigma[1] == 0.0 && sigma[2] == 0.0 && sigma[3] == 0.0 &&
              sigma[5] == 0.0 && sigma[6] == 0.0 && sigma[7] == 0.0;
    set_region(&v->regions[0], "slab", sigma, !iso);

    for (size_t k = 0; k < sz; k++)
        for (size_t j = 0; j < sy; j++)
            for (size_t i = 0; i < sx; i++) {
                double *p = v->xyz + 3 * (i + sx * (j + sy * k));
                p[0] = i == (size_t)nx ? L : L * ((double)i / nx);
                p[1] = j == (size_t)ny ? W : W * ((double)j / ny);
                p[2] = k == (size_t)nz ? H : H * ((double)k / nz);
            }
    size_t t = 0;
    for (size_t k = 0; k < (size_t)nz; k++)
        for (size_t j = 0; j < (size_t)ny; j++)
            for (size_t i = 0; i < (size_t)nx; i++) {
                int32_t h[8];
                for (int corner = 0; corner < 8; corner++)
                    h[corner] =
                        (int32_t)((i + (corner & 1)) + sx * ((j + ((corner >> 1) & 1)) + sy * (k + (corner >> 2))));
                split_hex(h, v->tet + 4 * t);
                t += 6;
            }
    size_t e = 0;
    for (int side = 0; side < 2; side++)
        for (size_t k = 0; k < sz; k++)
            for (size_t j = 0; j < sy; j++) (*ends)[e++] = (int32_t)((side ? (size_t)nx : 0) + sx * (j + sy * k));
    size_t bad = first_bad_tet(v);
    if (bad < v->n_tets)
        st = thx_error(ctx, THX_EINTERNAL, "slab mesh: tetrahedron %zu is not positive", bad);

done:
    if (st != THX_OK) {
        thx_volume_destroy(&v);
        free(*ends);
        *ends = NULL;
        return st;
    }
    *out = v;
    *n_ends = 2 * sy * sz;
    return THX_OK;
}

/* ------------------------------------------------------------------ */
/* Icospheres. */

/* The regular icosahedron's 12 vertices (on a sphere of radius sqrt(1 + phi^2)) and its 20 faces. */
static const double ico_v[12][3] = {{-1, GOLD, 0}, {1, GOLD, 0}, {-1, -GOLD, 0}, {1, -GOLD, 0}, {0, -1, GOLD}, {0, 1, GOLD},
                                    {0, -1, -GOLD}, {0, 1, -GOLD}, {GOLD, 0, -1}, {GOLD, 0, 1}, {-GOLD, 0, -1}, {-GOLD, 0, 1}};
static const int32_t ico_f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                     {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};

/* The midpoint node of edge (a, b) in the open-addressing table (key lo * n + hi, -1 = empty), added
 * (projected onto the unit sphere) on first use. */
static int32_t ico_mid(int64_t *key, int32_t *val, size_t cap, size_t n_all, double *x, size_t *nn, int32_t a, int32_t b)
{
    int64_t lo = a < b ? a : b, hi = a < b ? b : a, k = lo * (int64_t)n_all + hi;
    size_t h = (size_t)(((uint64_t)k * 0x9E3779B97F4A7C15ull) >> 20) % cap;
    while (key[h] != -1 && key[h] != k) h = (h + 1) % cap;
    if (key[h] == -1) {
        double m[3], r = 0;
        for (int d = 0; d < 3; d++) {
            m[d] = 0.5 * (x[3 * (size_t)a + (size_t)d] + x[3 * (size_t)b + (size_t)d]);
            r += m[d] * m[d];
        }
        r = sqrt(r);
        for (int d = 0; d < 3; d++) x[3 * *nn + (size_t)d] = m[d] / r;
        key[h] = k;
        val[h] = (int32_t)(*nn)++;
    }
    return val[h];
}

thx_status thx_icosphere(thx_ctx *ctx, int level, double r, const char *name, thx_role role, thx_surface **out)
{
    *out = NULL;
    if (level < 0 || level > 8 || !(r > 0.0) || !isfinite(r))
        return thx_error(ctx, THX_EINPUT, "icosphere: level %d (0 to 8) or radius %g (> 0) out of range", level, r);
    size_t n_all = 12, nt = 20;
    for (int l = 0; l < level; l++) {
        n_all += 3 * nt / 2; /* one new node per edge; E = 3F/2 */
        nt *= 4;
    }
    thx_surface *s = NULL;
    int64_t *key = NULL;
    int32_t *val = NULL, *t2 = NULL;
    thx_status st = THX_OK;
    THX_TRY(thx_surface_create(ctx, name, role, &s));
    s->xyz = thx_malloc(ctx, 3 * n_all * sizeof *s->xyz);
    s->tri = thx_malloc(ctx, 3 * nt * sizeof *s->tri);
    t2 = thx_malloc(ctx, 3 * nt * sizeof *t2);
    size_t cap = 2 * (3 * nt / 8 + 1) + 1; /* twice the edges of the last level's coarse mesh */
    key = thx_malloc(ctx, cap * sizeof *key);
    val = thx_malloc(ctx, cap * sizeof *val);
    if (!s->xyz || !s->tri || !t2 || !key || !val) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < 12; i++) {
        double n = sqrt(ico_v[i][0] * ico_v[i][0] + ico_v[i][1] * ico_v[i][1] + ico_v[i][2] * ico_v[i][2]);
        for (int d = 0; d < 3; d++) s->xyz[3 * i + (size_t)d] = ico_v[i][d] / n;
    }
    memcpy(s->tri, ico_f, sizeof ico_f);
    size_t nn = 12, n_tri = 20;
    for (int l = 0; l < level; l++) {
        for (size_t i = 0; i < cap; i++) key[i] = -1;
        for (size_t k = 0; k < n_tri; k++) {
            int32_t v[3] = {s->tri[3 * k], s->tri[3 * k + 1], s->tri[3 * k + 2]}, m[3];
            for (int e = 0; e < 3; e++) m[e] = ico_mid(key, val, cap, n_all, s->xyz, &nn, v[e], v[(e + 1) % 3]);
            /* m[e] is the midpoint of v[e] v[e+1]: three corner triangles and the middle one, same turn */
            const int32_t q[12] = {v[0], m[0], m[2], v[1], m[1], m[0], v[2], m[2], m[1], m[0], m[1], m[2]};
            memcpy(t2 + 12 * k, q, sizeof q);
        }
        n_tri *= 4;
        memcpy(s->tri, t2, 3 * n_tri * sizeof *t2);
    }
    s->n_nodes = nn;
    s->n_tris = n_tri;
    for (size_t i = 0; i < 3 * nn; i++) s->xyz[i] *= r;
    if (thx_surface_volume(s) < 0.0) /* counterclockwise seen from outside */
        for (size_t k = 0; k < n_tri; k++) {
            int32_t x = s->tri[3 * k + 1];
            s->tri[3 * k + 1] = s->tri[3 * k + 2];
            s->tri[3 * k + 2] = x;
        }
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    free(key);
    free(val);
    free(t2);
    return st;
}

/* ------------------------------------------------------------------ */
/* Error measures. */

/* Adds x^2 to the scaled sum of squares scale^2 ssq (LAPACK's dnrm2 way: no
 * overflow or underflow for any finite input). */
static void ssq_add(double x, double *scale, double *ssq)
{
    x = fabs(x);
    if (x == 0.0) return;
    if (*scale < x) {
        *ssq = 1.0 + *ssq * (*scale / x) * (*scale / x);
        *scale = x;
    } else {
        *ssq += (x / *scale) * (x / *scale);
    }
}

static double norm2(const double *u, size_t n)
{
    double scale = 0.0, ssq = 1.0;
    for (size_t i = 0; i < n; i++) ssq_add(u[i], &scale, &ssq);
    return scale * sqrt(ssq);
}

/* RDM = || u/|u| - v/|v| ||, computed from the differences (accurate when u
 * and v are nearly parallel, where sqrt(2 - 2 cos) loses everything). NaN if
 * n = 0 or either vector is zero or not finite. */
double thx_rdm(const double *u, const double *v, size_t n)
{
    double nu = norm2(u, n), nv = norm2(v, n);
    if (!(nu > 0.0 && nv > 0.0 && isfinite(nu) && isfinite(nv))) return NAN;
    double scale = 0.0, ssq = 1.0;
    for (size_t i = 0; i < n; i++) ssq_add(u[i] / nu - v[i] / nv, &scale, &ssq);
    return scale * sqrt(ssq);
}

/* MAG = |u| / |v|. NaN if n = 0 or v is zero or either is not finite. */
double thx_mag(const double *u, const double *v, size_t n)
{
    double nu = norm2(u, n), nv = norm2(v, n);
    if (!(nv > 0.0 && isfinite(nv) && isfinite(nu))) return NAN;
    return nu / nv;
}
