/*
 * Label maps -> contours (thorax/image/trace.h; docs/design/image.md, "Tracing label maps"):
 * per tissue a 3D mask cleaned by 6-connected flood fills, per plane the smoothed indicator traced
 * by marching squares at 0.5 (asymptotic decider), loops resampled at the node spacing.
 */
#include "thorax/image/trace.h"

#include "components.h"
#include "trace_plane.h"
#include "thorax/core/union_find.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void thx_trace_opts_default(thx_trace_opts *o)
{
    memset(o, 0, sizeof *o);
    o->min_size = 8;
    o->sigma = 0.5;
    o->holes = THX_TRACE_HOLES_FILL;
}

void thx_trace_report_free(thx_trace_report *rep)
{
    if (!rep) return;
    free(rep->tissue);
    rep->tissue = NULL;
    rep->n_tissues = 0;
}

/* ---- geometry of the cut ---------------------------------------------------------------------- */

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static void cut_init(const thx_image *img, cut *g, double *oblique_deg)
{
    int sa, ss, aa, as;
    double cosine;
    thx_image_axes(img, &sa, &ss, &aa, &as, &cosine);
    g->img = img;
    g->s = sa;
    g->a0 = sa == 0 ? 1 : 0;
    g->a1 = sa == 2 ? 1 : 2;
    g->ns = img->n[sa];
    g->n0 = img->n[g->a0];
    g->n1 = img->n[g->a1];
    g->st[0] = 1;
    g->st[1] = img->n[0];
    g->st[2] = img->n[0] * img->n[1];
    double u[3][3]; /* u[c] = RAS unit vector of index axis c */
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) u[c][r] = img->dir[r * 3 + c];
    double zx[3], yx[3], xx[3];
    for (int r = 0; r < 3; r++) {
        zx[r] = ss * u[sa][r];
        yx[r] = as * u[aa][r];
    }
    cross3(yx, zx, xx);
    if (thx_image_axis_aligned(img)) /* exactly RAS: no rounding residue in the coordinates */
        for (int r = 0; r < 3; r++) {
            xx[r] = round(xx[r]);
            yx[r] = round(yx[r]);
            zx[r] = round(zx[r]);
        }
    for (int r = 0; r < 3; r++) {
        g->Q[r * 3 + 0] = xx[r];
        g->Q[r * 3 + 1] = yx[r];
        g->Q[r * 3 + 2] = zx[r];
    }
    /* model p = Q^T ras; ras = origin + sum_c u_c spacing_c i_c */
    double po[3], pc[3][3];
    for (int m = 0; m < 3; m++) {
        const double *ax = m == 0 ? xx : m == 1 ? yx : zx;
        po[m] = ax[0] * img->origin[0] + ax[1] * img->origin[1] + ax[2] * img->origin[2];
        for (int c = 0; c < 3; c++) pc[c][m] = (ax[0] * u[c][0] + ax[1] * u[c][1] + ax[2] * u[c][2]) * img->spacing[c];
    }
    g->P0[0] = po[0];
    g->P0[1] = po[1];
    g->A0[0] = pc[g->a0][0];
    g->A0[1] = pc[g->a0][1];
    g->A1[0] = pc[g->a1][0];
    g->A1[1] = pc[g->a1][1];
    g->z0 = po[2];
    g->dz = pc[sa][2];
    if (oblique_deg) *oblique_deg = acos(fmin(1.0, fabs(zx[2]))) * 180.0 / M_PI;
}

/* ---- the tissue's mask and its cleaning ------------------------------------------------------ */

typedef struct {
    long lo, hi;              /* LUT range */
    unsigned char *lut;       /* hi - lo + 1 entries, or NULL: search `vals` */
    long *vals;
    size_t n;
    int all;
} labelset;

/* The paper's nesting (3.1): the torso's outer boundary holds the fat/muscle interface, which holds the
 * inner border of the muscle, which holds the organs. */
static int nest_depth(thx_role r)
{
    switch (r) {
    case THX_ROLE_OUTER: return 0;
    case THX_ROLE_FAT: return 1;
    case THX_ROLE_MUSCLE: return 2;
    default: return 3;
    }
}

static int in_set(const labelset *ls, long v)
{
    if (ls->all && v != 0) return 1;
    if (ls->lut) return v >= ls->lo && v <= ls->hi && ls->lut[v - ls->lo];
    size_t a = 0, b = ls->n;
    while (a < b) {
        size_t m = (a + b) / 2;
        if (ls->vals[m] < v) a = m + 1;
        else b = m;
    }
    return a < ls->n && ls->vals[a] == v;
}

static int cmp_long(const void *a, const void *b)
{
    long x = *(const long *)a, y = *(const long *)b;
    return (x > y) - (x < y);
}

/* Small components: those of fewer than `min` voxels (and, when !touching_ok, not touching the box's
 * faces) are set to `to`; counted, their voxels summed, the first THX_TRACE_SIZES_KEPT sizes kept. */
typedef struct {
    unsigned char val, to;
    size_t min;
    int touching_ok;
    size_t *count, *voxels, *sizes;
} clean_rule;

static unsigned char clean_decide(void *user, size_t size, int touches, size_t ordinal)
{
    clean_rule *r = user;
    (void)ordinal;
    if (!(size < r->min && (r->touching_ok || !touches))) return r->val;
    if (*r->count < THX_TRACE_SIZES_KEPT && r->sizes) r->sizes[*r->count] = size;
    (*r->count)++;
    *r->voxels += size;
    return r->to;
}

/* 6-connected components of mask voxels equal to `val` inside box [lo, hi) (inclusive lo, exclusive
 * hi per axis) that have fewer than min voxels (and, when !touching_ok, do not touch the box's
 * border) are set to `to` (thx_components6, shared with the segmentation). The number of components
 * changed goes to *count, their sizes to sizes (first THX_TRACE_SIZES_KEPT), the total to *voxels. */
static thx_status clean(thx_ctx *ctx, unsigned char *mask, const size_t n[3], const size_t lo[3], const size_t hi[3],
                        unsigned char val, unsigned char to, size_t min, int touching_ok, size_t *count, size_t *voxels,
                        size_t *sizes)
{
    clean_rule r = {val, to, min, touching_ok, count, voxels, sizes};
    return thx_components6(ctx, mask, n, lo, hi, val, clean_decide, &r, NULL);
}

/* ---- components (one surface each) and siblings (pulled apart) ----------------------------------- */

static unsigned char keep_all_decide(void *user, size_t size, int touches, size_t ordinal)
{
    (void)user;
    (void)size;
    (void)touches;
    (void)ordinal;
    return 1;
}

#define MAX_SPLIT 16 /* more components than this: a fragmented region, traced as one surface */

/* keeps the components of group `want` */
typedef struct {
    const size_t *grp;
    size_t want;
} pick_rule;
static unsigned char pick_decide(void *user, size_t size, int touches, size_t ordinal)
{
    const pick_rule *r = user;
    (void)size;
    (void)touches;
    return r->grp[ordinal] == r->want;
}

/* The voxels equal to 1 in box [lo, hi): their count, the sums of their indices and their index box
 * b = {min i, max i, min j, max j, min k, max k}. */
static void box_scan(const thx_image *img, const unsigned char *m, const size_t lo[3], const size_t hi[3], size_t *count,
                     double sum[3], long b[6])
{
    double s0 = 0, s1 = 0, s2 = 0;
    size_t cnt = 0;
    long mn0 = LONG_MAX, mn1 = LONG_MAX, mn2 = LONG_MAX, mx0 = -1, mx1 = -1, mx2 = -1;
    const size_t n0 = img->n[0], n01 = img->n[0] * img->n[1];
#pragma omp parallel for reduction(+ : s0, s1, s2, cnt) reduction(min : mn0, mn1, mn2) reduction(max : mx0, mx1, mx2) \
    schedule(static)
    for (long k = (long)lo[2]; k < (long)hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++) {
            const unsigned char *r = m + (size_t)k * n01 + j * n0;
            for (size_t i = lo[0]; i < hi[0]; i++)
                if (r[i] == 1) {
                    s0 += (double)i;
                    s1 += (double)j;
                    s2 += (double)k;
                    cnt++;
                    if ((long)i < mn0) mn0 = (long)i;
                    if ((long)i > mx0) mx0 = (long)i;
                    if ((long)j < mn1) mn1 = (long)j;
                    if ((long)j > mx1) mx1 = (long)j;
                    if (k < mn2) mn2 = k;
                    if (k > mx2) mx2 = k;
                }
        }
    *count = cnt;
    sum[0] = s0, sum[1] = s1, sum[2] = s2;
    b[0] = mn0, b[1] = mx0, b[2] = mn1, b[3] = mx1, b[4] = mn2, b[5] = mx2;
}

static int lab_in(const labelset *ls, long x)
{
    if (ls->all && x != 0) return 1;
    if (ls->lut) return (unsigned long)(x - ls->lo) <= (unsigned long)(ls->hi - ls->lo) ? ls->lut[x - ls->lo] : 0;
    return in_set(ls, x);
}

/* The voxels equal to 1 in box [lo, hi): their count, the RAS centroid of their centres and the
 * RAS x range of their index box's corners. */
static void box_centroid(const thx_image *img, const unsigned char *m, const size_t lo[3], const size_t hi[3],
                         size_t *count, double ras[3], double xr[2])
{
    double sum[3];
    size_t cnt;
    long bx[6];
    box_scan(img, m, lo, hi, &cnt, sum, bx);
    long mn0 = bx[0], mx0 = bx[1], mn1 = bx[2], mx1 = bx[3], mn2 = bx[4], mx2 = bx[5];
    double s0 = sum[0], s1 = sum[1], s2 = sum[2];
    xr[0] = INFINITY;
    xr[1] = -INFINITY;
    for (int corner = 0; cnt && corner < 8; corner++) {
        double id[3] = {(double)(corner & 1 ? mx0 : mn0), (double)(corner & 2 ? mx1 : mn1), (double)(corner & 4 ? mx2 : mn2)};
        double x = img->origin[0];
        for (int c = 0; c < 3; c++) x += img->dir[c] * img->spacing[c] * id[c];
        xr[0] = fmin(xr[0], x);
        xr[1] = fmax(xr[1], x);
    }
    *count = cnt;
    double idx[3] = {cnt ? s0 / (double)cnt : 0, cnt ? s1 / (double)cnt : 0, cnt ? s2 / (double)cnt : 0};
    for (int r = 0; r < 3; r++) {
        ras[r] = img->origin[r];
        for (int c = 0; c < 3; c++) ras[r] += img->dir[r * 3 + c] * img->spacing[c] * idx[c];
    }
}

/* Sets the voxels equal to 0 in box [wlo, whi) whose label is a sibling's (sl) to 2; returns the
 * voxels equal to 1 in [lo, hi) with a face on such a voxel. */
static size_t mark_siblings(const thx_image *img, unsigned char *m, const labelset *sl, const size_t wlo[3],
                            const size_t whi[3], const size_t lo[3], const size_t hi[3])
{
    const size_t n0 = img->n[0], n1 = img->n[1], n2 = img->n[2], n01 = n0 * n1;
#pragma omp parallel for schedule(static)
    for (long k = (long)wlo[2]; k < (long)whi[2]; k++)
        for (size_t j = wlo[1]; j < whi[1]; j++) {
            size_t q = (size_t)k * n01 + j * n0;
            for (size_t i = wlo[0]; i < whi[0]; i++)
                if (!m[q + i] && lab_in(sl, (long)img->v[q + i])) m[q + i] = 2;
        }
    size_t cnt = 0;
#pragma omp parallel for reduction(+ : cnt) schedule(static)
    for (long k = (long)lo[2]; k < (long)hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++)
            for (size_t i = lo[0]; i < hi[0]; i++) {
                size_t q = (size_t)k * n01 + j * n0 + i;
                if (m[q] != 1) continue;
                cnt += (i > 0 && m[q - 1] == 2) || (i + 1 < n0 && m[q + 1] == 2) || (j > 0 && m[q - n0] == 2) ||
                       (j + 1 < n1 && m[q + n0] == 2) || (k > 0 && m[q - n01] == 2) ||
                       ((size_t)k + 1 < n2 && m[q + n01] == 2);
            }
    return cnt;
}

static thx_status sr_push(thx_ctx *ctx, thx_trace_tissue_report **sr, size_t **sr_t, size_t *n, size_t *cap,
                          const thx_trace_tissue_report *r, size_t t)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 8;
        thx_trace_tissue_report *a = thx_realloc(ctx, *sr, nc * sizeof *a);
        if (!a) return THX_ENOMEM;
        *sr = a;
        size_t *b = thx_realloc(ctx, *sr_t, nc * sizeof *b);
        if (!b) return THX_ENOMEM;
        *sr_t = b;
        *cap = nc;
    }
    (*sr)[*n] = *r;
    (*sr_t)[*n] = t;
    (*n)++;
    return THX_OK;
}

/* The surfaces traced (c->surf[i] <-> sr[i], in tracing order) put in the order of the tissues given,
 * a tissue's components right to left (decreasing centroid RAS x), and named: the tissue's name
 * for one component, NAME_right and NAME_left for two, NAME_1, NAME_2, ... for more. */
static thx_status order_surfaces(thx_ctx *ctx, thx_contours *c, const thx_trace_opts *o, thx_trace_tissue_report *sr,
                                 const size_t *sr_t, size_t n, const char *what)
{
    if (c->n_surfaces != n) return thx_error(ctx, THX_EINPUT, "trace: internal error: %zu surfaces, %zu reports", c->n_surfaces, n);
    size_t *perm = thx_malloc(ctx, (n ? n : 1) * sizeof *perm);
    thx_contour_surface *ns = thx_malloc(ctx, (n ? n : 1) * sizeof *ns);
    thx_trace_tissue_report *nr = thx_malloc(ctx, (n ? n : 1) * sizeof *nr);
    if (!perm || !ns || !nr) {
        free(perm);
        free(ns);
        free(nr);
        return THX_ENOMEM;
    }
    size_t m = 0;
    for (size_t t = 0; t < o->n_tissues; t++) {
        size_t a = m;
        for (size_t i = 0; i < n; i++)
            if (sr_t[i] == t) perm[m++] = i;
        for (size_t i = a + 1; i < m; i++) /* insertion sort: decreasing RAS x, ties by component */
            for (size_t j = i; j > a && sr[perm[j]].centroid_ras[0] > sr[perm[j - 1]].centroid_ras[0]; j--) {
                size_t tmp = perm[j];
                perm[j] = perm[j - 1];
                perm[j - 1] = tmp;
            }
        for (size_t i = a; i < m; i++) {
            size_t k = i - a, nk = m - a;
            char nm[160];
            if (nk == 1) snprintf(nm, sizeof nm, "%s", o->tissues[t].name);
            else if (nk == 2 && (sr[perm[a]].ras_x_range[0] > sr[perm[a + 1]].ras_x_range[1]))
                snprintf(nm, sizeof nm, "%s_%s", o->tissues[t].name, k == 0 ? "right" : "left");
            else snprintf(nm, sizeof nm, "%s_%zu", o->tissues[t].name, k + 1);
            if (strlen(nm) >= sizeof c->surf[0].name) {
                thx_status e = thx_error(ctx, THX_EINPUT,
                                         "%s: tissue \"%s\" has %zu components, one surface each: the name \"%s\" is "
                                         "longer than 63 characters (give the tissue a shorter name)",
                                         what, o->tissues[t].name, nk, nm);
                free(perm);
                free(ns);
                free(nr);
                return e;
            }
            snprintf(c->surf[perm[i]].name, sizeof c->surf[0].name, "%s", nm);
            snprintf(sr[perm[i]].name, sizeof sr[0].name, "%s", nm);
            sr[perm[i]].component = k;
        }
    }
    for (size_t i = 0; i < n; i++) {
        ns[i] = c->surf[perm[i]];
        nr[i] = sr[perm[i]];
    }
    memcpy(c->surf, ns, n * sizeof *ns);
    memcpy(sr, nr, n * sizeof *nr);
    free(perm);
    free(ns);
    free(nr);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            if (strcmp(c->surf[i].name, c->surf[j].name) == 0)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: surface \"%s\" named twice: a tissue's components are named NAME_right/_left "
                                 "(or NAME_1..), which another --label's name takes (rename one)",
                                 what, c->surf[i].name);
    return THX_OK;
}

/* ---- the driver --------------------------------------------------------------------------------- */

typedef struct {
    size_t plane;   /* output plane number */
    size_t loop0, n; /* its loops in the tissue's loop list */
} layer_rec;

typedef struct {
    polyset loops;        /* all loops of the tissue (model coordinates), plane by plane */
    double *area;         /* signed area per loop */
    layer_rec *layers;
    size_t n_layers, cap_layers, cap_area;
} tissue_trace;

/* Whether organ tissues a and b are siblings: both of depth 3 (organs), neither `all`, their label
 * sets disjoint (blood {5} inside heart {4,5} is nested, not a sibling). */
static int siblings(const thx_trace_opts *o, size_t a, size_t b)
{
    const thx_trace_tissue *A = &o->tissues[a], *B = &o->tissues[b];
    if (a == b || nest_depth(A->role) != 3 || nest_depth(B->role) != 3 || A->all || B->all) return 0;
    for (size_t i = 0; i < A->n_values; i++)
        for (size_t j = 0; j < B->n_values; j++)
            if (A->values[i] == B->values[j]) return 0;
    return 1;
}

/* The label set of tissue t (sib = 0: its own values, and every tissue's for the outer role) or of
 * its siblings (sib = 1). */
/* Whether loops l and k of the tissue (outer loops, on neighbouring planes) overlap: a point just inside
 * an edge of one (to its left: outer loops run counterclockwise) in the other; loops that coincide (a
 * straight stack) overlap too. */
static int loops_overlap(const tissue_trace *tt, size_t l, size_t k)
{
    const double *ab = tt->area + 5 * l + 1, *bb = tt->area + 5 * k + 1;
    if (ab[0] > bb[1] || bb[0] > ab[1] || ab[2] > bb[3] || bb[2] > ab[3]) return 0;
    const poly *A = &tt->loops.l[l], *B = &tt->loops.l[k];
    for (size_t i = 0; i < A->n; i++)
        if (tp_point_in(B->p, B->n, tp_inward(A, i))) return 1;
    for (size_t i = 0; i < B->n; i++)
        if (tp_point_in(A->p, A->n, tp_inward(B, i))) return 1;
    return 0;
}

static thx_status build_labelset(thx_ctx *ctx, const thx_trace_opts *o, size_t t, int sib, float lo, float hi,
                                 labelset *ls)
{
    memset(ls, 0, sizeof *ls);
    const thx_trace_tissue *ti = &o->tissues[t];
    int outer = ti->role == THX_ROLE_OUTER;
#define TAKE(k) (sib ? siblings(o, t, (k)) : ((k) == t || outer))
    size_t n = 0;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (TAKE(k)) n += o->tissues[k].n_values;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (o->tissues[k].all && TAKE(k)) ls->all = 1;
    ls->vals = thx_malloc(ctx, (n ? n : 1) * sizeof *ls->vals);
    if (!ls->vals) return THX_ENOMEM;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (TAKE(k))
            for (size_t j = 0; j < o->tissues[k].n_values; j++) ls->vals[ls->n++] = o->tissues[k].values[j];
    qsort(ls->vals, ls->n, sizeof *ls->vals, cmp_long);
    if (hi - lo < 16777216.0f) {
        ls->lo = (long)lo;
        ls->hi = (long)hi;
        ls->lut = thx_calloc(ctx, (size_t)(ls->hi - ls->lo + 1), 1);
        if (!ls->lut) return THX_ENOMEM;
        for (size_t j = 0; j < ls->n; j++)
            if (ls->vals[j] >= ls->lo && ls->vals[j] <= ls->hi) ls->lut[ls->vals[j] - ls->lo] = 1;
    }
    return THX_OK;
#undef TAKE
}

static void labelset_free(labelset *ls)
{
    free(ls->lut);
    free(ls->vals);
}

thx_status thx_image_trace(thx_ctx *ctx, const thx_image *img, const thx_trace_opts *o, thx_contours **out,
                           thx_trace_report *rep)
{
    *out = NULL;
    if (rep) memset(rep, 0, sizeof *rep);
    const char *what = img->path[0] ? img->path : "<image>";
    if (!img->integral)
        return thx_error(ctx, THX_EINPUT,
                         "%s: not a label map: its voxels are stored as %s, not integers (threshold or segment the "
                         "image first)", what, img->stored_type[0] ? img->stored_type : "non-integral values");
    if (!o->n_tissues) return thx_error(ctx, THX_EINPUT, "%s: no tissue to trace (give at least one label)", what);
    if (!(o->spacing >= 0) || !(o->node_spacing >= 0) || !(o->sigma >= 0) || !isfinite(o->spacing) ||
        !isfinite(o->node_spacing) || o->sigma > 2)
        return thx_error(ctx, THX_EINPUT, "trace: bad options (spacing %g, node spacing %g, sigma %g)", o->spacing,
                         o->node_spacing, o->sigma);
    for (size_t t = 0; t < o->n_tissues; t++) {
        if (!o->tissues[t].all && !o->tissues[t].n_values)
            return thx_error(ctx, THX_EINPUT, "tissue \"%s\": no label value", o->tissues[t].name);
        for (size_t k = 0; k < t; k++)
            if (strcmp(o->tissues[k].name, o->tissues[t].name) == 0)
                return thx_error(ctx, THX_EINPUT, "tissue \"%s\" given twice", o->tissues[t].name);
    }
    cut g;
    double oblique;
    cut_init(img, &g, &oblique);
    float vlo, vhi;
    thx_image_range(img, &vlo, &vhi);
    size_t nv = thx_image_count(img);

    /* planes: every image plane (in increasing z), or `spacing` apart from the lowest */
    double hs = img->spacing[g.s];
    int resampled = o->spacing > 0;
    double zlo = g.dz > 0 ? g.z0 : g.z0 + g.dz * (double)(g.ns - 1);
    double span = hs * (double)(g.ns - 1);
    double pspace = resampled ? o->spacing : hs;
    size_t np = resampled ? (size_t)floor(span / pspace + 1e-9) + 1 : g.ns;
    double inplane = fmax(img->spacing[g.a0], img->spacing[g.a1]);
    double h = o->node_spacing > 0 ? o->node_spacing : fmax(inplane, pspace);
    /* loops enclosing less than one voxel's in-plane area are dropped when cleaning (min_size > 1): at a
       gently sloping boundary (a lung's dome) the staircase's single-voxel steps give beads of the
       smoothed field just over 0.5, loops of a tenth of a voxel that the lacing would have to branch to */
    double amin = o->min_size > 1 ? img->spacing[g.a0] * img->spacing[g.a1] : 0;

    thx_status st = THX_OK;
    thx_contours *c = NULL;
    size_t *order = NULL;
    thx_trace_tissue_report *sr = NULL; /* per surface traced (in tracing order): its report */
    size_t *sr_t = NULL, n_sr = 0, cap_sr = 0; /* and its tissue */
    unsigned char *scratch = NULL;      /* one component's mask */
    long *t_first = NULL, *t_last = NULL;
    unsigned char *mask = NULL;
    long *pb = NULL;
    polyset *pout = NULL;    /* per output plane: its loops */
    thx_status *pst = NULL;  /* per output plane: the status of its tracing */
    size_t *pcount = NULL;   /* per output plane: holes seen, islands filled, tiny loops dropped */
    thx_vec2 *pprobe = NULL; /* per output plane: a point inside its largest filled hole, or NaN */
    size_t *kcount = NULL;   /* per image plane along the superior axis: the tissue's voxels */
    tissue_trace tt = {0};
    labelset ls = {0};
    double w[2 * KR + 1];
    tp_gauss_weights(o->sigma, w);
    if (rep) {
        rep->tissue = thx_calloc(ctx, o->n_tissues, sizeof *rep->tissue);
        if (!rep->tissue) return THX_ENOMEM;
        rep->n_tissues = o->n_tissues;
        rep->n_planes = np;
        rep->plane_spacing = pspace;
        rep->node_spacing = h;
        rep->z_first = zlo;
        rep->sup_axis = g.s;
        rep->oblique_deg = oblique;
        memcpy(rep->to_ras, g.Q, sizeof g.Q);
    }
    /* listed values absent from the image */
    {
        size_t nval = 0;
        for (size_t t = 0; t < o->n_tissues; t++) nval += o->tissues[t].n_values;
        long *vals = thx_malloc(ctx, (nval ? nval : 1) * sizeof *vals);
        unsigned char *seen = thx_calloc(ctx, nval ? nval : 1, 1);
        if (!vals || !seen) {
            free(vals);
            free(seen);
            st = THX_ENOMEM;
            goto done;
        }
        nval = 0;
        for (size_t t = 0; t < o->n_tissues; t++)
            for (size_t j = 0; j < o->tissues[t].n_values; j++) vals[nval++] = o->tissues[t].values[j];
        qsort(vals, nval, sizeof *vals, cmp_long);
        size_t left = nval;
        for (size_t i = 0; i < nv && left; i++) {
            long v = (long)img->v[i];
            size_t a = 0, b = nval;
            while (a < b) {
                size_t m = (a + b) / 2;
                if (vals[m] < v) a = m + 1;
                else b = m;
            }
            for (; a < nval && vals[a] == v; a++)
                if (!seen[a]) {
                    seen[a] = 1;
                    left--;
                }
        }
        for (size_t j = 0; j < nval; j++)
            if (!seen[j] && (j == 0 || vals[j] != vals[j - 1]) && rep) {
                if (rep->n_absent < THX_TRACE_SIZES_KEPT) rep->absent[rep->n_absent] = vals[j];
                rep->n_absent++;
            }
        free(vals);
        free(seen);
    }

    THX_TRY(thx_contours_create(ctx, &c));
    c->spacing = h;
    c->frame = thx_frame_ras();
    snprintf(c->image, sizeof c->image, "%s", img->path);
    snprintf(c->image_sha256, sizeof c->image_sha256, "%s", img->sha256);
    mask = thx_malloc(ctx, nv);
    pb = thx_malloc(ctx, 4 * g.ns * sizeof *pb);
    pout = thx_calloc(ctx, np, sizeof *pout);
    pst = thx_calloc(ctx, np, sizeof *pst);
    pcount = thx_calloc(ctx, 3 * np, sizeof *pcount);
    pprobe = thx_calloc(ctx, np ? np : 1, sizeof *pprobe);
    kcount = thx_malloc(ctx, g.ns * sizeof *kcount);
    if (!mask || !pb || !pout || !pst || !pcount || !pprobe || !kcount) {
        st = THX_ENOMEM;
        goto done;
    }
    /* the surfaces in the order given; traced in the paper's nesting order (outer, fat, muscle, then the
       organs) so that each tissue's container is traced before it: an inner surface must close inside its
       container's end planes, or the two caps would lie in one plane (a scan that cuts a torso or a neck
       cuts every layer at its end planes) */
    order = thx_malloc(ctx, o->n_tissues * sizeof *order);
    t_first = thx_malloc(ctx, o->n_tissues * sizeof *t_first);
    t_last = thx_malloc(ctx, o->n_tissues * sizeof *t_last);
    if (!order || !t_first || !t_last) {
        st = THX_ENOMEM;
        goto done;
    }
    {
        size_t k = 0;
        for (int d = 0; d <= 3; d++)
            for (size_t t = 0; t < o->n_tissues; t++)
                if (nest_depth(o->tissues[t].role) == d) order[k++] = t;
    }
    for (size_t oi = 0; oi < o->n_tissues; oi++) {
        size_t t = order[oi];
        const thx_trace_tissue *ti = &o->tissues[t];
        thx_trace_tissue_report trr;
        memset(&trr, 0, sizeof trr);
        snprintf(trr.name, sizeof trr.name, "%s", ti->name);
        size_t sidx = 0;
        t_first[t] = t_last[t] = -1;
        /* the container: the deepest tissue traced before of a lesser depth */
        long container = -1;
        for (size_t oj = 0; oj < oi; oj++) {
            size_t u = order[oj];
            if (nest_depth(o->tissues[u].role) >= nest_depth(ti->role)) continue;
            if (container < 0 || nest_depth(o->tissues[u].role) > nest_depth(o->tissues[container].role))
                container = (long)u;
        }
        /* the mask, its box and the in-plane box of each plane (before cleaning: a removed component
           only widens its planes' boxes) */
        THX_TRY(build_labelset(ctx, o, t, 0, vlo, vhi, &ls));
        for (size_t k = 0; k < g.ns; k++) {
            pb[4 * k] = pb[4 * k + 2] = LONG_MAX;
            pb[4 * k + 1] = pb[4 * k + 3] = LONG_MIN;
        }
        /* plane by plane along the superior axis, in parallel (each plane writes its own voxels, box
           and count) */
#pragma omp parallel for schedule(dynamic, 4)
        for (long k = 0; k < (long)g.ns; k++) {
            long *b = pb + 4 * k;
            size_t cnt = 0;
            for (size_t v = 0; v < g.n1; v++) {
                size_t row = 0, first = 0, last = 0;
                for (size_t u = 0; u < g.n0; u++) {
                    size_t q = vox(&g, (size_t)k, u, v);
                    long x = (long)img->v[q];
                    /* in_set, its look-up table inlined */
                    unsigned char m = (ls.all && x != 0) ? 1
                                      : ls.lut ? ((unsigned long)(x - ls.lo) <= (unsigned long)(ls.hi - ls.lo) ? ls.lut[x - ls.lo] : 0)
                                               : (unsigned char)in_set(&ls, x);
                    mask[q] = m;
                    if (m) {
                        if (!row) first = u;
                        last = u;
                        row++;
                    }
                }
                if (!row) continue;
                cnt += row;
                if ((long)first < b[0]) b[0] = (long)first;
                if ((long)last > b[1]) b[1] = (long)last;
                if ((long)v < b[2]) b[2] = (long)v;
                if ((long)v > b[3]) b[3] = (long)v;
            }
            kcount[k] = cnt;
        }
        size_t lo[3] = {SIZE_MAX, SIZE_MAX, SIZE_MAX}, hi[3] = {0, 0, 0}, count = 0;
        for (size_t k = 0; k < g.ns; k++) {
            if (!kcount[k]) continue;
            count += kcount[k];
            if (k < lo[g.s]) lo[g.s] = k;
            hi[g.s] = k + 1;
            if ((size_t)pb[4 * k] < lo[g.a0]) lo[g.a0] = (size_t)pb[4 * k];
            if ((size_t)pb[4 * k + 1] + 1 > hi[g.a0]) hi[g.a0] = (size_t)pb[4 * k + 1] + 1;
            if ((size_t)pb[4 * k + 2] < lo[g.a1]) lo[g.a1] = (size_t)pb[4 * k + 2];
            if ((size_t)pb[4 * k + 3] + 1 > hi[g.a1]) hi[g.a1] = (size_t)pb[4 * k + 3] + 1;
        }
        labelset_free(&ls);
        memset(&ls, 0, sizeof ls);
        if (!count) {
            st = thx_error(ctx, THX_EINPUT, "%s: tissue \"%s\": none of its label values is in the image", what, ti->name);
            goto done;
        }
        /* 3D cleaning in the box widened by one voxel (the outside of a cavity reaches the rim). With
           holes filled, a cavity is a hole in each of its planes and is filled with them: only kept
           holes need the cavity pass. */
        for (int q = 0; q < 3; q++) {
            if (lo[q] > 0) lo[q]--;
            if (hi[q] < img->n[q]) hi[q]++;
        }
        if (o->min_size > 1) {
            THX_TRY(clean(ctx, mask, img->n, lo, hi, 1, 0, o->min_size, 1, &trr.n_removed, &trr.removed_voxels,
                          trr.removed_size));
            if (o->holes == THX_TRACE_HOLES_KEEP)
                THX_TRY(clean(ctx, mask, img->n, lo, hi, 0, 1, o->min_size, 0, &trr.n_cavities, &trr.cavity_voxels, NULL));
        }
        trr.voxels = count - trr.removed_voxels + trr.cavity_voxels;
        if (!trr.voxels) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: tissue \"%s\": all of its %zu voxels are in components of fewer than %zu voxels "
                           "(--min-size): nothing left to trace",
                           what, ti->name, trr.removed_voxels, o->min_size);
            goto done;
        }
        /* components: an organ's region of several 6-connected 3D components (two lungs under one label)
           gives a surface per component; siblings: organs of disjoint labels, marked 2 in the mask traced
           (the field S(tissue) - S(siblings)) */
        size_t ncomp = 1;
        int is_organ = nest_depth(ti->role) == 3, has_sib = 0;
        for (size_t k = 0; k < o->n_tissues; k++) has_sib |= siblings(o, t, k);
        size_t grp[MAX_SPLIT];
        if (is_organ) THX_TRY(thx_components6(ctx, mask, img->n, lo, hi, 1, keep_all_decide, NULL, &ncomp));
        if (ncomp > MAX_SPLIT) ncomp = 1;
        if (ncomp > 1 && !scratch) {
            scratch = thx_calloc(ctx, nv, 1);
            if (!scratch) {
                st = THX_ENOMEM;
                goto done;
            }
        }
        if (ncomp > 1) {
            /* components whose index boxes, widened by the smoothing's reach in the plane (KR + 1 voxels)
               and a plane across, overlap are one group, one surface: only organs well apart are split
               (two lungs; not parts that touch along an edge, whose loops would merge in the field) */
            long bx[MAX_SPLIT][6];
            size_t par[MAX_SPLIT];
            for (size_t cc = 0; cc < ncomp; cc++) {
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++) {
                        size_t q = k * img->n[0] * img->n[1] + j * img->n[0];
                        memcpy(scratch + q + lo[0], mask + q + lo[0], hi[0] - lo[0]);
                    }
                for (size_t q = 0; q < ncomp; q++) grp[q] = q;
                pick_rule pr = {grp, cc};
                THX_TRY(thx_components6(ctx, scratch, img->n, lo, hi, 1, pick_decide, &pr, NULL));
                size_t cnt;
                double sum[3];
                box_scan(img, scratch, lo, hi, &cnt, sum, bx[cc]);
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++)
                        memset(scratch + k * img->n[0] * img->n[1] + j * img->n[0] + lo[0], 0, hi[0] - lo[0]);
                par[cc] = cc;
            }
            for (size_t a = 0; a < ncomp; a++)
                for (size_t b = a + 1; b < ncomp; b++) {
                    int apart = 0;
                    for (int q = 0; q < 3; q++) {
                        long r = q == g.s ? 1 : KR + 1;
                        apart |= bx[a][2 * q] > bx[b][2 * q + 1] + r || bx[b][2 * q] > bx[a][2 * q + 1] + r;
                    }
                    if (!apart) uf_union(par, a, b);
                }
            size_t ng = 0, gid[MAX_SPLIT];
            for (size_t a = 0; a < ncomp; a++) gid[a] = SIZE_MAX;
            for (size_t a = 0; a < ncomp; a++) {
                size_t r = uf_find(par, a);
                if (gid[r] == SIZE_MAX) gid[r] = ng++;
                grp[a] = gid[r];
            }
            trr.n_components = ncomp; /* before grouping, for the report */
            ncomp = ng;
        }
        /* the box the field reads: the tissue's box widened by the buffer's rim (and the smoothing across
           planes) */
        size_t wlo[3], whi[3];
        for (int q = 0; q < 3; q++) {
            size_t r = q == g.s ? (size_t)KR + 1 : (size_t)PAD;
            wlo[q] = lo[q] > r ? lo[q] - r : 0;
            whi[q] = hi[q] + r < img->n[q] ? hi[q] + r : img->n[q];
        }
        if (has_sib) THX_TRY(build_labelset(ctx, o, t, 1, vlo, vhi, &ls));
        thx_trace_tissue_report trr0 = trr;
        for (size_t comp = 0; comp < ncomp; comp++) {
            unsigned char *work = mask;
            trr = trr0;
            snprintf(trr.tissue, sizeof trr.tissue, "%s", ti->name);
            trr.component = comp;
            if (ncomp > 1) {
                work = scratch; /* the group's components only */
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++) {
                        size_t q = k * img->n[0] * img->n[1] + j * img->n[0];
                        memcpy(work + q + lo[0], mask + q + lo[0], hi[0] - lo[0]);
                    }
                pick_rule pr = {grp, comp};
                THX_TRY(thx_components6(ctx, work, img->n, lo, hi, 1, pick_decide, &pr, NULL));
            }
            box_centroid(img, work, lo, hi, &trr.voxels, trr.centroid_ras, trr.ras_x_range);
            if (has_sib) trr.contact_voxels = mark_siblings(img, work, &ls, wlo, whi, lo, hi);
            /* trace plane by plane (increasing z): the planes are independent, traced in parallel each into
               its own slot (each thread with its own scratch and context), then joined in plane order, so
               the contours are the same bytes whatever the thread count */
            tp_polyset_clear(&tt.loops);
            tt.n_layers = 0;
            for (size_t p = 0; p < np; p++) {
                tp_polyset_clear(&pout[p]);
                pst[p] = THX_OK;
                pcount[3 * p] = pcount[3 * p + 1] = pcount[3 * p + 2] = 0;
            }
            {
                long bad = -1;
                char bad_msg[1024] = "";
    #pragma omp parallel
                {
                    plane_scratch sc;
                    memset(&sc, 0, sizeof sc);
                    thx_ctx *lc = NULL;
                    int ok = thx_ctx_create(&lc) == THX_OK;
    #pragma omp for schedule(dynamic, 1)
                    for (long p = 0; p < (long)np; p++) {
                        double z = zlo + pspace * (double)p;
                        /* continuous image plane index of z */
                        double tk = (z - g.z0) / g.dz;
                        if (tk < 0) tk = 0;
                        if (tk > (double)(g.ns - 1)) tk = (double)(g.ns - 1);
                        if (!resampled) tk = g.dz > 0 ? (double)p : (double)(g.ns - 1 - (size_t)p);
                        thx_status r = ok ? tp_trace_plane(lc, &g, work, pb, tk, resampled, w, o->holes, h, amin, &sc, &pout[p],
                                                        &pcount[3 * p], &pcount[3 * p + 1], &pcount[3 * p + 2], &pprobe[p])
                                          : THX_ENOMEM;
                        pst[p] = r;
                        if (r != THX_OK) {
    #pragma omp critical(thx_trace_err)
                            if (bad < 0 || p < bad) {
                                bad = p;
                                snprintf(bad_msg, sizeof bad_msg, "%s", ok ? thx_ctx_message(lc) : "out of memory");
                            }
                        }
                    }
                    tp_scratch_free(&sc);
                    thx_ctx_destroy(&lc);
                }
                if (bad >= 0) {
                    st = thx_error(ctx, pst[bad], "%s", bad_msg);
                    goto done;
                }
            }
            /* a filled hole that opens: its probe outside every loop of a neighbouring plane */
            for (size_t p = 0; p < np; p++) {
                if (isnan(pprobe[p].x)) continue;
                int open = 0;
                for (int side = -1; side <= 1 && !open; side += 2) {
                    if ((side < 0 && p == 0) || (side > 0 && p + 1 == np)) continue;
                    const polyset *N = &pout[p + (size_t)side];
                    int in = 0;
                    for (size_t l = 0; l < N->n && !in; l++) in = tp_point_in(N->l[l].p, N->l[l].n, pprobe[p]);
                    open = !in;
                }
                if (open && !trr.n_holes_open++) trr.z_hole_open = zlo + pspace * (double)p;
            }
            for (size_t p = 0; p < np; p++) {
                trr.n_holes += pcount[3 * p];
                trr.n_islands_filled += pcount[3 * p + 1];
                trr.n_tiny += pcount[3 * p + 2];
                if (!pout[p].n) continue;
                /* the layer */
                if (tt.n_layers == tt.cap_layers) {
                    size_t ncap = tt.cap_layers ? 2 * tt.cap_layers : 64;
                    layer_rec *nl = thx_realloc(ctx, tt.layers, ncap * sizeof *nl);
                    if (!nl) {
                        st = THX_ENOMEM;
                        goto done;
                    }
                    tt.layers = nl;
                    tt.cap_layers = ncap;
                }
                tt.layers[tt.n_layers].plane = p;
                tt.layers[tt.n_layers].loop0 = tt.loops.n;
                tt.layers[tt.n_layers].n = pout[p].n;
                tt.n_layers++;
                for (size_t l = 0; l < pout[p].n; l++) {
                    poly *d;
                    THX_TRY(tp_polyset_new(ctx, &tt.loops, &d));
                    *d = pout[p].l[l];
                    pout[p].l[l].p = NULL;
                    pout[p].l[l].n = 0;
                }
                pout[p].n = 0;
            }
            /* loops with no partner on either neighbouring plane: dropped (the lacing cannot close them) */
            size_t nl = tt.loops.n;
            if (nl > tt.cap_area) {
                free(tt.area);
                tt.area = thx_malloc(ctx, nl * 5 * sizeof *tt.area);
                if (!tt.area) {
                    st = THX_ENOMEM;
                    goto done;
                }
                tt.cap_area = nl;
            }
            for (size_t l = 0; l < nl; l++) {
                tt.area[5 * l] = tp_poly_area(tt.loops.l[l].p, tt.loops.l[l].n);
                tp_bbox(tt.loops.l[l].p, tt.loops.l[l].n, tt.area + 5 * l + 1);
            }
            unsigned char *keep = thx_malloc(ctx, nl ? nl : 1);
            if (!keep) {
                st = THX_ENOMEM;
                goto done;
            }
            /* to a fixed point: a loop whose only partners are dropped has none */
            for (size_t l = 0; l < nl; l++) keep[l] = 1;
            for (int changed = 1; changed;) {
                changed = 0;
                for (size_t L = 0; L < tt.n_layers; L++) {
                    const layer_rec *lr = &tt.layers[L];
                    for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                        if (!keep[l] || tt.area[5 * l] < 0) continue; /* a kept hole goes with its outer loop */
                        int partner = 0;
                        for (int side = -1; side <= 1 && !partner; side += 2) {
                            if ((side < 0 && L == 0) || (side > 0 && L + 1 == tt.n_layers)) continue;
                            const layer_rec *nb = &tt.layers[L + (size_t)side];
                            if (nb->plane != lr->plane + (size_t)side) continue;
                            for (size_t k = nb->loop0; k < nb->loop0 + nb->n && !partner; k++)
                                partner = keep[k] && tt.area[5 * k] >= 0 && loops_overlap(&tt, l, k);
                        }
                        if (!partner) {
                            keep[l] = 0;
                            changed = 1;
                        }
                    }
                }
            }
            /* a layer of holes only (its outer loops dropped) goes too */
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                int outer_kept = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) outer_kept |= keep[l] && tt.area[5 * l] > 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                    if (!outer_kept) keep[l] = 0;
                    if (!keep[l] && tt.area[5 * l] > 0) trr.n_flat_dropped++;
                }
            }
            /* inside the container's end planes */
            if (container >= 0 && t_first[container] >= 0) {
                for (size_t L = 0; L < tt.n_layers; L++) {
                    const layer_rec *lr = &tt.layers[L];
                    if ((long)lr->plane > t_first[container] && (long)lr->plane < t_last[container]) continue;
                    int had = 0;
                    for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                        had |= keep[l];
                        keep[l] = 0;
                    }
                    trr.n_trimmed_layers += (size_t)had;
                }
            }
            /* one stack of consecutive planes */
            long first = -1, last = -1, gap_at = -1;
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                int any = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) any |= keep[l];
                if (!any) continue;
                if (first < 0) first = (long)lr->plane;
                else if ((long)lr->plane != last + 1 && gap_at < 0) gap_at = last;
                last = (long)lr->plane;
            }
            if ((first < 0 || first == last) && ncomp > 1) {
                /* a component one plane thick (or with no loop partnered): dropped, counted */
                free(keep);
                continue;
            }
            if (first < 0) {
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\": no plane holds a loop with a partner above or below (its %zu voxels lie "
                               "within single planes)", what, ti->name, trr.voxels);
                goto done;
            }
            if (gap_at >= 0) {
                /* the next plane with loops after the gap */
                long resume = -1;
                for (size_t L = 0; L < tt.n_layers && resume < 0; L++)
                    if ((long)tt.layers[L].plane > gap_at + 1) {
                        for (size_t l = tt.layers[L].loop0; l < tt.layers[L].loop0 + tt.layers[L].n; l++)
                            if (keep[l]) resume = (long)tt.layers[L].plane;
                    }
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\" vanishes and reappears along the superior axis: it is in the planes "
                               "z=%g..%g and again from z=%g to z=%g, none between (a surface is one stack of consecutive "
                               "layers: trace the parts as tissues of their own, or remove the stray part with a larger "
                               "--min-size)",
                               what, ti->name, zlo + pspace * (double)first, zlo + pspace * (double)gap_at,
                               zlo + pspace * (double)resume, zlo + pspace * (double)last);
                goto done;
            }
            if (first == last) {
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\" lies in one plane only (z=%g): a surface needs at least two layers (a finer "
                               "--spacing may give it more)", what, ti->name, zlo + pspace * (double)first);
                goto done;
            }
            {
                char tmp[64];
                snprintf(tmp, sizeof tmp, "%s", ti->name);
                if (ncomp > 1) snprintf(tmp, sizeof tmp, "\x01%zu.%zu", t, comp); /* named when sorted */
                st = thx_contours_add_surface(ctx, c, tmp, ti->role, THX_CAP_GRID, 0, &sidx);
                if (st != THX_OK) {
                    free(keep);
                    goto done;
                }
            }
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                double z = zlo + pspace * (double)lr->plane;
                int any = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                    if (!keep[l]) continue;
                    any = 1;
                    st = thx_contours_add_loop(ctx, c, sidx, z, tt.loops.l[l].p, tt.loops.l[l].n);
                    if (st != THX_OK) break;
                    trr.n_loops++;
                    trr.area_sum += tt.area[5 * l];
                }
                if (st != THX_OK) break;
                if (any) {
                    if (!trr.n_layers) trr.z_first = z;
                    trr.z_last = z;
                    trr.n_layers++;
                }
            }
            free(keep);
            if (st != THX_OK) goto done;
            if (t_first[t] < 0 || first < t_first[t]) t_first[t] = first;
            if (last > t_last[t]) t_last[t] = last;
            THX_TRY(sr_push(ctx, &sr, &sr_t, &n_sr, &cap_sr, &trr, t));
            if (work == scratch)
                for (size_t k = wlo[2]; k < whi[2]; k++)
                    for (size_t j = wlo[1]; j < whi[1]; j++)
                        memset(work + k * img->n[0] * img->n[1] + j * img->n[0] + wlo[0], 0, whi[0] - wlo[0]);
        }
        labelset_free(&ls);
        memset(&ls, 0, sizeof ls);
        {
            /* the tissue's surfaces traced: named, and ordered right to left (decreasing centroid RAS x) */
            size_t first_sr = n_sr, kept = 0;
            while (first_sr > 0 && sr_t[first_sr - 1] == t) first_sr--;
            kept = n_sr - first_sr;
            if (!kept) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\": none of its %zu components holds a loop with a partner above or "
                               "below (each lies within single planes)", what, ti->name, ncomp);
                goto done;
            }
            for (size_t i = first_sr; i < n_sr; i++) {
                sr[i].n_components = kept;
                sr[i].components_dropped = ncomp - kept;
            }
        }
    }
    THX_TRY(order_surfaces(ctx, c, o, sr, sr_t, n_sr, what));
    if (rep) {
        free(rep->tissue);
        rep->tissue = sr;
        rep->n_tissues = n_sr;
        sr = NULL;
    }
    *out = c;
    c = NULL;
done:
    labelset_free(&ls);
    for (size_t p = 0; pout && p < np; p++) tp_polyset_free(&pout[p]);
    free(pout);
    free(pst);
    free(pcount);
    free(pprobe);
    free(kcount);
    tp_polyset_free(&tt.loops);
    free(tt.layers);
    free(tt.area);
    free(mask);
    free(pb);
    thx_contours_destroy(&c);
    free(sr);
    free(sr_t);
    free(scratch);
    free(order);
    free(t_first);
    free(t_last);
    if (st != THX_OK && rep) thx_trace_report_free(rep);
    return st;
}
