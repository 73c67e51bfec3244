/*
 * A slice whose lacing has triangles under 1 degree, laced again (src/geom/build.c, quality_retry;
 * issue 25, item 6). The chains are one slice of the bench map's left lung (tests/data/lace: two
 * crescents at the lung's base, with the loops of the layers beyond), as the surface build laces
 * them. The default lacing (metric on the chains mapped to a common centroid and RMS radius, with
 * the arc-length phase) fans a node over a straight run of the other crescent: 0.13 degree. On the
 * chains' own positions: 0.69 degree. The whole slice by one dynamic programme over every pair of
 * nodes on the own positions (thx_lace_opts.whole_dp): every angle above 1 degree (13.6), as thorax
 * check and thorax mesh need. Each lacing must be a closed band: na + nb triangles, every edge of either
 * chain in exactly one triangle, every diagonal in two.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/geom/surfaces.h"

#define MAXN 400

static thx_ctx *ctx;
static thx_vec2 pts[6][MAXN];
static int32_t ids[6][MAXN];
static size_t cnt[6];
static double zs[6];
static int kind[6]; /* 0 chain, 1 below, 2 above */
static int nrec;
static double xyz[3 * 2 * MAXN];

static int load(void)
{
    FILE *f = fopen(tl_src_path(__FILE__, "data/lace/crescents.txt"), "r");
    if (!f) return -1;
    char line[256], word[16];
    size_t n;
    double z, x, y;
    nrec = -1;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#') continue;
        if (line[0] >= 'a' && line[0] <= 'z' && sscanf(line, "%15s %zu %lf", word, &n, &z) == 3 && nrec + 1 < 6) {
            nrec++;
            kind[nrec] = strcmp(word, "chain") == 0 ? 0 : strcmp(word, "below") == 0 ? 1 : 2;
            zs[nrec] = z;
            continue;
        }
        if (nrec >= 0 && sscanf(line, "%lf %lf", &x, &y) == 2 && cnt[nrec] < MAXN) pts[nrec][cnt[nrec]++] = (thx_vec2){x, y};
    }
    fclose(f);
    nrec++;
    return nrec == 6 && kind[0] == 0 && kind[1] == 0 ? 0 : -1;
}

static double min_angle(const int32_t *t, size_t nt)
{
    double m = 180;
    for (size_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            const double *o = xyz + 3 * t[3 * i + k], *u = xyz + 3 * t[3 * i + (k + 1) % 3], *v = xyz + 3 * t[3 * i + (k + 2) % 3];
            double a[3] = {u[0] - o[0], u[1] - o[1], u[2] - o[2]}, b[3] = {v[0] - o[0], v[1] - o[1], v[2] - o[2]};
            double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            m = fmin(m, atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * 180 / M_PI);
        }
    return m;
}

/* a closed band: every chain edge in one triangle, every other edge in two */
static int band(const int32_t *t, size_t nt, size_t na, size_t nb)
{
    size_t nn = na + nb;
    int *use = calloc(nn * nn, sizeof *use);
    if (!use) return 0;
    for (size_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            size_t a = (size_t)t[3 * i + k], b = (size_t)t[3 * i + (k + 1) % 3];
            use[(a < b ? a : b) * nn + (a < b ? b : a)]++;
        }
    int ok = nt == na + nb;
    for (size_t a = 0; a < nn && ok; a++)
        for (size_t b = a + 1; b < nn && ok; b++) {
            int chain_edge = (b < na && (b == a + 1 || (a == 0 && b == na - 1))) ||
                             (a >= na && (b == a + 1 || (a == na && b == nn - 1)));
            if (use[a * nn + b]) ok = use[a * nn + b] == (chain_edge ? 1 : 2);
            else ok = !chain_edge;
        }
    free(use);
    return ok;
}

int main(void)
{
    thx_ctx_create(&ctx);
    CHECK(load() == 0);
    if (tl_fail) return tl_finish();
    size_t na = cnt[0], nb = cnt[1];
    for (int c = 0; c < 2; c++)
        for (size_t i = 0; i < cnt[c]; i++) {
            size_t g = c ? na + i : i;
            ids[c][i] = (int32_t)g;
            xyz[3 * g] = pts[c][i].x, xyz[3 * g + 1] = pts[c][i].y, xyz[3 * g + 2] = zs[c];
        }
    thx_chain A = {0}, B = {0}, below[2] = {{0}}, above[2] = {{0}};
    size_t nbel = 0, nabv = 0;
    for (int r = 2; r < nrec; r++) {
        thx_chain *q = kind[r] == 1 ? &below[nbel++] : &above[nabv++];
        q->n = cnt[r], q->p = pts[r], q->id = ids[r], q->z = zs[r];
    }
    A.n = na, A.p = pts[0], A.id = ids[0], A.z = zs[0], A.beyond = below, A.n_beyond = nbel;
    B.n = nb, B.p = pts[1], B.id = ids[1], B.z = zs[1], B.beyond = above, B.n_beyond = nabv;
    const char *name[3] = {"default", "own positions", "whole-slice DP"};
    double ang[3];
    for (int v = 0; v < 3; v++) {
        thx_lace_opts o;
        thx_lace_opts_default(&o);
        o.spacing = 1.0;
        if (v >= 1) o.raw_positions = 1, o.phase_weight = 0;
        if (v == 2) o.whole_dp = 1;
        int32_t *t = NULL;
        size_t nt = 0, cap = 0;
        thx_lace_stats st;
        memset(&st, 0, sizeof st);
        CHECK(thx_lace(ctx, &A, &B, &o, &t, &nt, &cap, &st) == THX_OK);
        ang[v] = min_angle(t, nt);
        printf("%-15s %zu triangles, smallest angle %.3f deg, closed band: %s\n", name[v], nt, ang[v],
               band(t, nt, na, nb) ? "yes" : "no");
        CHECK(band(t, nt, na, nb));
        free(t);
    }
    CHECK(ang[0] < 1.0);  /* the case: a fan the check fails */
    CHECK(ang[1] < 1.0);  /* the own positions alone do not mend it */
    CHECK(ang[2] >= 1.0); /* the whole-slice DP does */
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
