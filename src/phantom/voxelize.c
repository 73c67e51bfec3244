/*
 * Closed surfaces and the phantom as images (thorax/phantom/voxelize.h): label maps by exact inside
 * tests, partial volume, and the simulated scans' noise and bias.
 *
 * thx_voxelize, for closed triangle surfaces. All nodes go once into the grid's continuous index
 * coordinates (u, v, w); rays run along w through the points of an n x n sub-grid of each voxel's
 * (u, v) square, at integer "column coordinates" U = (u + 1/2) n - 1/2 (likewise V), so that a
 * ray's position is an exact double. A triangle is crossed by the ray (U, V) when (U, V) lies in
 * its projection, decided by exact orient2d with the ray moved symbolically by eps (1, eta)
 * (0 < eta << eps << 1): a point exactly on an edge counts when the counterclockwise edge runs
 * downward (dy < 0) or along +x (dy == 0, dx > 0), which is that perturbation's sign and holds at
 * vertices too, so a ray through a shared edge or vertex meets each sheet of a closed surface
 * exactly once. Edge-on triangles (zero projected area) are never crossed. Per ray the crossings,
 * sorted by w, give every surface's winding number along the ray (+1/-1 by the projection's
 * orientation); the region between two crossings is 1 + the innermost surface (smallest enclosed
 * volume) of nonzero winding, and its length inside each voxel is added to that voxel's region
 * fraction: exact along the ray, n x n sub-samples across it. Triangles are bucketed by the voxel
 * rows (j) their projection spans, so memory is a row of voxels and the triangles; time is the
 * rays times their crossings plus the voxels.
 *
 * thx_phantom_voxelize, for the phantom's analytic anatomy: the region at every voxel corner; a
 * voxel whose eight corners agree is that region whole, any other is sampled at n^3 points. The
 * phantom's surfaces are smooth (radii of curvature >= 6 mm, LUNG_BLEND) and at least 6.5 mm apart
 * (THX_PHANTOM_MIN_GAP), so a boundary that passes through a voxel of <= 5 mm without separating
 * two of its corners only grazes it (docs/design/image.md gives the measured effect).
 */
#include "thorax/phantom/voxelize.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"
#include "thorax/phantom/phantom.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MAX_REGIONS 255

static const char *const TISSUE_NAME[THX_TISSUE_COUNT] = {"air", "fat", "muscle", "soft_tissue", "lung", "heart"};
/* CT: Hounsfield units (air -1000, subcutaneous fat about -100, skeletal muscle 40, soft tissue of the
 * mediastinum 30, aerated lung about -800, heart (myocardium ~50 with blood ~40) 45). MR: a T1-weighted
 * spin-echo-like scale 0..1000 (fat brightest, muscle and myocardium grey, lung and air dark; slow blood
 * a little brighter than muscle). */
static const double TISSUE_CT[THX_TISSUE_COUNT] = {-1000, -100, 40, 30, -800, 45};
static const double TISSUE_MR[THX_TISSUE_COUNT] = {0, 900, 400, 300, 40, 450};

const char *thx_tissue_name(thx_tissue t) { return t < THX_TISSUE_COUNT ? TISSUE_NAME[t] : "?"; }

double thx_tissue_value(thx_modality m, thx_tissue t)
{
    if (t >= THX_TISSUE_COUNT) return -1;
    if (m == THX_MODALITY_CT) return TISSUE_CT[t];
    if (m == THX_MODALITY_MR) return TISSUE_MR[t];
    return -1;
}

thx_tissue thx_tissue_of_role(thx_role role, int model_has_fat)
{
    switch (role) {
    case THX_ROLE_OUTER: return model_has_fat ? THX_TISSUE_FAT : THX_TISSUE_SOFT;
    case THX_ROLE_FAT: return THX_TISSUE_MUSCLE;
    case THX_ROLE_LUNG: return THX_TISSUE_LUNG;
    case THX_ROLE_HEART: return THX_TISSUE_HEART;
    default: return THX_TISSUE_SOFT;
    }
}

void thx_voxelize_opts_default(thx_voxelize_opts *o)
{
    memset(o, 0, sizeof *o);
    o->sub = 4;
}

thx_status thx_voxel_grid(thx_ctx *ctx, const double lo[3], const double hi[3], double h, int margin, thx_image *img)
{
    memset(img, 0, sizeof *img);
    if (!(h > 0) || !isfinite(h) || margin < 0)
        return thx_error(ctx, THX_EINPUT, "voxel grid: voxel size %g mm must be > 0", h);
    size_t n[3];
    double a[3];
    for (int c = 0; c < 3; c++) {
        if (!isfinite(lo[c]) || !isfinite(hi[c]) || hi[c] < lo[c])
            return thx_error(ctx, THX_EINPUT, "voxel grid: empty or non-finite box along axis %d", c);
        double f0 = floor(lo[c] / h) - margin, f1 = ceil(hi[c] / h) + margin;
        if (f1 <= f0) f1 = f0 + 1;
        if (f1 - f0 > 1e5)
            return thx_error(ctx, THX_EINPUT, "voxel grid: %.0f voxels along axis %d (voxel %g mm): too many", f1 - f0, c, h);
        n[c] = (size_t)(f1 - f0);
        a[c] = (f0 + 0.5) * h;
    }
    THX_CHECK(thx_image_alloc(ctx, n, img));
    for (int c = 0; c < 3; c++) {
        img->spacing[c] = h;
        img->origin[c] = a[c];
    }
    return THX_OK;
}

static int check_opts(thx_ctx *ctx, const thx_voxelize_opts *o, const thx_image *labels, const thx_image *mix)
{
    if (o->sub < 1 || o->sub > 16) return thx_error(ctx, THX_EINPUT, "voxelize: %d sub-samples per side (1..16)", o->sub);
    if (!labels || !labels->v) return thx_error(ctx, THX_EINPUT, "voxelize: no grid");
    if (mix && (!mix->v || memcmp(mix->n, labels->n, sizeof mix->n)))
        return thx_error(ctx, THX_EINPUT, "voxelize: the mixed image's grid differs from the labels'");
    return THX_OK;
}

/* Label (plurality, ties to the higher region) and mix of one voxel from its fractions f[0..nr-1]. */
static void finish_voxel(const double *f, int nr, const double *values, float *label, float *mixv)
{
    int best = 0;
    double m = 0;
    for (int r = 0; r < nr; r++) {
        if (f[r] >= f[best]) best = r;
        if (values) m += f[r] * values[r];
    }
    *label = (float)best;
    if (mixv) *mixv = (float)m;
}

/* ---- closed triangle surfaces ------------------------------------------- */

typedef struct {
    uint32_t col;   /* ray within the voxel row: sub-row * columns + column */
    uint16_t surf;
    int16_t sign;
    double w;
} crossing;

static int crossing_cmp(const void *pa, const void *pb)
{
    const crossing *a = pa, *b = pb;
    if (a->col != b->col) return a->col < b->col ? -1 : 1;
    if (a->w != b->w) return a->w < b->w ? -1 : 1;
    return (a->surf > b->surf) - (a->surf < b->surf);
}

/* Is p inside the counterclockwise triangle's edge a->b, with the symbolic perturbation? */
static int edge_in(const double *a, const double *b, const double *p)
{
    double d = thx_orient2d(a, b, p);
    if (d != 0) return d > 0;
    double dy = b[1] - a[1], dx = b[0] - a[0];
    return dy < 0 || (dy == 0 && dx > 0);
}

thx_status thx_voxelize(thx_ctx *ctx, const thx_surface *const *s, size_t ns, const thx_voxelize_opts *o,
                        thx_image *labels, thx_image *mix)
{
    thx_voxelize_opts def;
    if (!o) {
        thx_voxelize_opts_default(&def);
        o = &def;
    }
    THX_CHECK(check_opts(ctx, o, labels, mix));
    if (ns + 1 > MAX_REGIONS) return thx_error(ctx, THX_EINPUT, "voxelize: %zu surfaces (at most %d)", ns, MAX_REGIONS - 1);
    const int n = o->sub, nr = (int)ns + 1;
    const size_t ni = labels->n[0], nj = labels->n[1], nk = labels->n[2];
    const size_t ncol = ni * (size_t)n, nrow = nj * (size_t)n;
    const double *values = mix ? o->values : NULL;
    thx_status st = THX_OK;
    double **uvw = thx_calloc(ctx, ns ? ns : 1, sizeof *uvw);
    size_t *rank = thx_calloc(ctx, ns ? ns : 1, sizeof *rank), *tri0 = thx_calloc(ctx, ns + 1, sizeof *tri0);
    size_t *bstart = thx_calloc(ctx, nj + 1, sizeof *bstart), *bfill = NULL, *bucket = NULL;
    double *vol = thx_calloc(ctx, ns ? ns : 1, sizeof *vol), *acc = NULL, *f = NULL;
    int *wind = thx_calloc(ctx, ns ? ns : 1, sizeof *wind);
    crossing *cr = NULL;
    size_t ncr = 0, cap = 0;
    if (!uvw || !rank || !tri0 || !bstart || !vol || !wind) { st = THX_ENOMEM; goto done; }

    /* innermost = smallest enclosed volume; rank[s] = how many surfaces are larger (ties: index) */
    for (size_t a = 0; a < ns; a++) vol[a] = fabs(thx_surface_volume(s[a]));
    for (size_t a = 0; a < ns; a++)
        for (size_t b = 0; b < ns; b++)
            if (vol[b] > vol[a] || (vol[b] == vol[a] && b < a)) rank[a]++;

    /* nodes in column coordinates (U, V, w) */
    for (size_t a = 0; a < ns; a++) {
        tri0[a + 1] = tri0[a] + s[a]->n_tris;
        uvw[a] = thx_malloc(ctx, (s[a]->n_nodes ? s[a]->n_nodes : 1) * 3 * sizeof(double));
        if (!uvw[a]) { st = THX_ENOMEM; goto done; }
        for (size_t q = 0; q < s[a]->n_nodes; q++) {
            double ijk[3];
            thx_image_ras_to_index(labels, s[a]->xyz + 3 * q, ijk);
            uvw[a][3 * q] = (ijk[0] + 0.5) * n - 0.5;
            uvw[a][3 * q + 1] = (ijk[1] + 0.5) * n - 0.5;
            uvw[a][3 * q + 2] = ijk[2];
        }
    }
    /* bucket the triangles by the voxel rows their projections span (two passes: count, fill) */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t a = 0; a < ns; a++)
            for (size_t t = 0; t < s[a]->n_tris; t++) {
                const int32_t *T = s[a]->tri + 3 * t;
                double v0 = uvw[a][3 * T[0] + 1], v1 = uvw[a][3 * T[1] + 1], v2 = uvw[a][3 * T[2] + 1];
                double lo = ceil(fmin(v0, fmin(v1, v2))), hi = floor(fmax(v0, fmax(v1, v2)));
                if (lo < 0) lo = 0;
                if (hi > (double)nrow - 1) hi = (double)nrow - 1;
                if (hi < lo) continue;
                size_t j0 = (size_t)lo / (size_t)n, j1 = (size_t)hi / (size_t)n;
                for (size_t j = j0; j <= j1; j++) {
                    if (pass == 0) bstart[j + 1]++;
                    else bucket[bfill[j]++] = tri0[a] + t;
                }
            }
        if (pass == 0) {
            for (size_t j = 0; j < nj; j++) bstart[j + 1] += bstart[j];
            bucket = thx_malloc(ctx, (bstart[nj] ? bstart[nj] : 1) * sizeof *bucket);
            bfill = thx_malloc(ctx, (nj ? nj : 1) * sizeof *bfill);
            if (!bucket || !bfill) { st = THX_ENOMEM; goto done; }
            memcpy(bfill, bstart, nj * sizeof *bfill);
        }
    }
    acc = thx_malloc(ctx, ni * nk * (size_t)nr * sizeof *acc);
    f = thx_malloc(ctx, (size_t)nr * sizeof *f);
    if (!acc || !f) { st = THX_ENOMEM; goto done; }

    for (size_t j = 0; j < nj; j++) {
        ncr = 0;
        for (size_t e = bstart[j]; e < bstart[j + 1]; e++) {
            size_t g = bucket[e], a = 0;
            while (tri0[a + 1] <= g) a++; /* few surfaces: a linear search */
            const int32_t *T = s[a]->tri + 3 * (g - tri0[a]);
            const double *A = uvw[a] + 3 * T[0], *B = uvw[a] + 3 * T[1], *C = uvw[a] + 3 * T[2];
            double area2 = thx_orient2d(A, B, C);
            if (area2 == 0) continue;
            int sign = area2 > 0 ? 1 : -1;
            if (area2 < 0) {
                const double *t = B;
                B = C;
                C = t;
                area2 = -area2;
            }
            double vlo = ceil(fmin(A[1], fmin(B[1], C[1]))), vhi = floor(fmax(A[1], fmax(B[1], C[1])));
            double ulo = ceil(fmin(A[0], fmin(B[0], C[0]))), uhi = floor(fmax(A[0], fmax(B[0], C[0])));
            vlo = fmax(vlo, (double)(j * (size_t)n));
            vhi = fmin(vhi, (double)(j * (size_t)n + (size_t)n - 1));
            ulo = fmax(ulo, 0);
            uhi = fmin(uhi, (double)ncol - 1);
            for (double V = vlo; V <= vhi; V++)
                for (double U = ulo; U <= uhi; U++) {
                    double p[2] = {U, V};
                    if (!edge_in(A, B, p) || !edge_in(B, C, p) || !edge_in(C, A, p)) continue;
                    double la = thx_orient2d(B, C, p) / area2, lb = thx_orient2d(C, A, p) / area2;
                    int flat = A[2] == B[2] && B[2] == C[2]; /* a plane of constant w: crossed exactly there */
                    if (ncr == cap) {
                        size_t nc = cap ? 2 * cap : 4096;
                        crossing *x = thx_realloc(ctx, cr, nc * sizeof *x);
                        if (!x) { st = THX_ENOMEM; goto done; }
                        cr = x;
                        cap = nc;
                    }
                    crossing *c = &cr[ncr++];
                    c->col = (uint32_t)((size_t)(V - (double)(j * (size_t)n)) * ncol + (size_t)U);
                    c->surf = (uint16_t)a;
                    c->sign = (int16_t)sign;
                    c->w = flat ? A[2] : la * A[2] + lb * B[2] + (1.0 - la - lb) * C[2];
                }
        }
        if (ncr) qsort(cr, ncr, sizeof *cr, crossing_cmp); /* cr is NULL while no row has crossed yet */
        memset(acc, 0, ni * nk * (size_t)nr * sizeof *acc);
        for (size_t e = 0; e < ncr;) {
            uint32_t col = cr[e].col;
            size_t i = (col % ncol) / (size_t)n;
            double *ac = acc + i * nk * (size_t)nr;
            memset(wind, 0, ns * sizeof *wind);
            int region = 0;
            double w0 = 0;
            for (; e < ncr && cr[e].col == col; e++) {
                double w1 = cr[e].w;
                if (region > 0) {
                    double a0 = fmax(w0, -0.5), a1 = fmin(w1, (double)nk - 0.5);
                    if (a1 > a0) {
                        size_t k0 = (size_t)floor(a0 + 0.5), k1 = (size_t)floor(a1 + 0.5);
                        if (k1 >= nk) k1 = nk - 1;
                        for (size_t k = k0; k <= k1; k++) {
                            double len = fmin(a1, (double)k + 0.5) - fmax(a0, (double)k - 0.5);
                            if (len > 0) ac[k * (size_t)nr + (size_t)region] += len;
                        }
                    }
                }
                wind[cr[e].surf] += cr[e].sign;
                region = 0;
                size_t best = 0;
                for (size_t a = 0; a < ns; a++)
                    if (wind[a] && (region == 0 || rank[a] > best)) {
                        region = (int)a + 1;
                        best = rank[a];
                    }
                w0 = w1;
            }
            if (region != 0) {
                size_t V = col / ncol, U = col % ncol;
                st = thx_error(ctx, THX_EINPUT,
                               "voxelize: surface \"%s\" is not closed: the ray through voxel column (%zu, %zu) "
                               "(sub-ray %zu, %zu) ends inside it",
                               s[region - 1]->name, U / (size_t)n, j, U % (size_t)n, V);
                goto done;
            }
        }
        for (size_t i = 0; i < ni; i++)
            for (size_t k = 0; k < nk; k++) {
                const double *ac = acc + (i * nk + k) * (size_t)nr;
                double in = 0;
                for (int r = 1; r < nr; r++) {
                    f[r] = ac[r] / ((double)n * n);
                    in += f[r];
                }
                f[0] = fmax(0.0, 1.0 - in);
                size_t at = thx_image_at(labels, i, j, k);
                finish_voxel(f, nr, values, &labels->v[at], values ? &mix->v[at] : NULL);
                /* An exact tie (to rounding) is a boundary through the voxel's centre (a flat face on the
                   plane of voxel centres: a cap at an odd millimetre in a 2 mm grid). No side is right;
                   the voxels of such a layer alternate (by the parity of i + j + k) between the higher
                   and the lower of the tied regions, so that the layer keeps its volume (always the
                   higher had added half a layer of voxels per such cap). */
                int best = (int)labels->v[at];
                if ((i + j + k) % 2)
                    for (int r = 0; r < best; r++)
                        if (f[best] - f[r] <= 1e-9) {
                            labels->v[at] = (float)r;
                            break;
                        }
            }
    }
    labels->integral = 1;
    if (mix) mix->integral = 0;
done:
    if (uvw)
        for (size_t a = 0; a < ns; a++) free(uvw[a]);
    free(uvw);
    free(rank);
    free(tri0);
    free(bstart);
    free(bfill);
    free(bucket);
    free(vol);
    free(acc);
    free(f);
    free(wind);
    free(cr);
    return st;
}

/* ---- the phantom's analytic anatomy ------------------------------------- */

#define PH_REGIONS (THX_PHANTOM_N_SURFACES + 1)

/* RAS of the continuous index (i, j) on the plane (any k: the grid's third axis is along z). */
static void plane_xy(const thx_image *g, double i, double j, double *x, double *y)
{
    double a = i * g->spacing[0], b = j * g->spacing[1];
    *x = g->origin[0] + g->dir[0] * a + g->dir[1] * b;
    *y = g->origin[1] + g->dir[3] * a + g->dir[4] * b;
}

thx_status thx_phantom_voxelize(thx_ctx *ctx, const thx_voxelize_opts *o, thx_image *labels, thx_image *mix,
                                size_t *mixed)
{
    thx_voxelize_opts def;
    if (!o) {
        thx_voxelize_opts_default(&def);
        o = &def;
    }
    THX_CHECK(check_opts(ctx, o, labels, mix));
    const double *d = labels->dir;
    if (fabs(d[2]) > 1e-12 || fabs(d[5]) > 1e-12 || fabs(fabs(d[8]) - 1) > 1e-12)
        return thx_error(ctx, THX_EINPUT, "phantom voxelize: the grid's third axis must run along z (an axial grid)");
    const int n = o->sub;
    const size_t ni = labels->n[0], nj = labels->n[1], nk = labels->n[2], nc = (ni + 1) * (nj + 1);
    const double *values = mix ? o->values : NULL;
    thx_status st = THX_OK;
    thx_phantom_field *fld = NULL;
    thx_phantom_plane *P = NULL;
    unsigned char *c0 = thx_malloc(ctx, nc), *c1 = thx_malloc(ctx, nc), *mx = thx_malloc(ctx, ni * nj);
    uint16_t *cnt = thx_malloc(ctx, ni * nj * PH_REGIONS * sizeof *cnt);
    size_t n_mixed = 0;
    if (!c0 || !c1 || !mx || !cnt) { st = THX_ENOMEM; goto done; }
    THX_TRY(thx_phantom_field_create(ctx, &fld));
    THX_TRY(thx_phantom_plane_create(ctx, fld, 0, &P));
    for (size_t kc = 0; kc <= nk; kc++) {
        /* corners of the plane k = kc - 1/2 */
        double z = labels->origin[2] + d[8] * labels->spacing[2] * ((double)kc - 0.5);
        thx_phantom_plane_set(fld, z, P);
        for (size_t jc = 0; jc <= nj; jc++)
            for (size_t ic = 0; ic <= ni; ic++) {
                double x, y;
                plane_xy(labels, (double)ic - 0.5, (double)jc - 0.5, &x, &y);
                c1[jc * (ni + 1) + ic] = (unsigned char)thx_phantom_region(P, x, y);
            }
        if (kc > 0) {
            size_t k = kc - 1, layer_mixed = 0;
            for (size_t j = 0; j < nj; j++)
                for (size_t i = 0; i < ni; i++) {
                    size_t q = j * (ni + 1) + i;
                    unsigned char r = c0[q];
                    int same = c0[q + 1] == r && c0[q + ni + 1] == r && c0[q + ni + 2] == r && c1[q] == r &&
                               c1[q + 1] == r && c1[q + ni + 1] == r && c1[q + ni + 2] == r;
                    mx[j * ni + i] = (unsigned char)!same;
                    layer_mixed += !same;
                    uint16_t *cn = cnt + (j * ni + i) * PH_REGIONS;
                    memset(cn, 0, PH_REGIONS * sizeof *cn);
                    if (same) cn[r] = (uint16_t)(n * n * n);
                }
            n_mixed += layer_mixed;
            for (int m = 0; m < n && layer_mixed; m++) {
                double zs = labels->origin[2] + d[8] * labels->spacing[2] * ((double)k - 0.5 + (m + 0.5) / n);
                thx_phantom_plane_set(fld, zs, P);
                for (size_t j = 0; j < nj; j++)
                    for (size_t i = 0; i < ni; i++) {
                        if (!mx[j * ni + i]) continue;
                        uint16_t *cn = cnt + (j * ni + i) * PH_REGIONS;
                        for (int b = 0; b < n; b++)
                            for (int a = 0; a < n; a++) {
                                double x, y;
                                plane_xy(labels, (double)i - 0.5 + (a + 0.5) / n, (double)j - 0.5 + (b + 0.5) / n, &x, &y);
                                cn[thx_phantom_region(P, x, y)]++;
                            }
                    }
            }
            double f[PH_REGIONS];
            int centre_set = 0;
            for (size_t j = 0; j < nj; j++)
                for (size_t i = 0; i < ni; i++) {
                    const uint16_t *cn = cnt + (j * ni + i) * PH_REGIONS;
                    for (int r = 0; r < PH_REGIONS; r++) f[r] = cn[r] / (double)(n * n * n);
                    size_t at = thx_image_at(labels, i, j, k);
                    finish_voxel(f, PH_REGIONS, values, &labels->v[at], values ? &mix->v[at] : NULL);
                    /* a tie for the largest count (an even n: 32 of 64, 4 of 8): the region at the voxel's
                     * centre decides when it is one of the tied, rather than always the higher number */
                    int best = (int)labels->v[at], tied = 0;
                    for (int r = 0; r < best; r++) tied |= cn[r] == cn[best];
                    if (!tied || !mx[j * ni + i]) continue;
                    if (!centre_set) {
                        thx_phantom_plane_set(fld, labels->origin[2] + d[8] * labels->spacing[2] * (double)k, P);
                        centre_set = 1;
                    }
                    double x, y;
                    plane_xy(labels, (double)i, (double)j, &x, &y);
                    int rc = thx_phantom_region(P, x, y);
                    if (cn[rc] == cn[best]) labels->v[at] = (float)rc;
                }
        }
        unsigned char *t = c0;
        c0 = c1;
        c1 = t;
    }
    labels->integral = 1;
    if (mix) mix->integral = 0;
done:
    if (mixed) *mixed = n_mixed;
    thx_phantom_plane_destroy(&P);
    thx_phantom_field_destroy(&fld);
    free(c0);
    free(c1);
    free(mx);
    free(cnt);
    return st;
}

/* ---- noise and bias ------------------------------------------------------ */

static uint64_t mix64(uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Two standard normal numbers for voxel `at` (Box-Muller on two uniforms of its own stream). */
static void normal2(unsigned long seed, size_t at, double *n1, double *n2)
{
    uint64_t s = mix64((uint64_t)seed * 0xD1B54A32D192ED03ull ^ mix64((uint64_t)at));
    uint64_t a = mix64(s), b = mix64(s ^ 0x6A09E667F3BCC909ull);
    double u1 = ((double)(a >> 11) + 1.0) * 0x1.0p-53; /* (0, 1] */
    double u2 = (double)(b >> 11) * 0x1.0p-53;
    double r = sqrt(-2.0 * log(u1));
    *n1 = r * cos(2.0 * M_PI * u2);
    *n2 = r * sin(2.0 * M_PI * u2);
}

thx_status thx_scan_degrade(thx_ctx *ctx, thx_image *img, thx_modality m, double bias, double sigma,
                            thx_noise_kind kind, unsigned long seed)
{
    if (m == THX_MODALITY_LABELS && (bias != 0 || sigma != 0))
        return thx_error(ctx, THX_EINPUT, "a label map takes no noise or bias");
    if (!(sigma >= 0) || !isfinite(sigma)) return thx_error(ctx, THX_EINPUT, "noise: sigma %g must be >= 0", sigma);
    if (!(fabs(bias) < 1)) return thx_error(ctx, THX_EINPUT, "bias: amplitude %g must lie in (-1, 1)", bias);
    if (kind == THX_NOISE_RICIAN && m != THX_MODALITY_MR)
        return thx_error(ctx, THX_EINPUT, "Rician noise is the magnitude of an MR signal: use it with --modality mr");
    double off = m == THX_MODALITY_CT ? 1000.0 : 0.0;
    for (size_t k = 0; k < img->n[2]; k++)
        for (size_t j = 0; j < img->n[1]; j++)
            for (size_t i = 0; i < img->n[0]; i++) {
                size_t at = thx_image_at(img, i, j, k);
                double v = img->v[at];
                if (bias != 0) {
                    double u = img->n[0] > 1 ? 2.0 * (double)i / (double)(img->n[0] - 1) - 1 : 0;
                    double w = img->n[1] > 1 ? 2.0 * (double)j / (double)(img->n[1] - 1) - 1 : 0;
                    double t = img->n[2] > 1 ? 2.0 * (double)k / (double)(img->n[2] - 1) - 1 : 0;
                    double q = 0.5 * u + 0.3 * w + 0.2 * (2 * t * t - 1);
                    v = (v + off) * (1 + bias * q) - off;
                }
                if (sigma > 0) {
                    double n1, n2;
                    normal2(seed, at, &n1, &n2);
                    if (kind == THX_NOISE_RICIAN) v = hypot(v + sigma * n1, sigma * n2);
                    else v += sigma * n1;
                }
                img->v[at] = (float)v;
            }
    img->integral = 0;
    return THX_OK;
}
