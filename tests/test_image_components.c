/* thx_components6 (src/image/components.c), the scanline flood fill that the tracer's cleaning and
 * the segmentation's largest component share, against a union-find over the same voxels written
 * here: random masks (dense enough for U shapes that join only through a higher plane), the whole
 * volume and a box inside it, the components' sizes, rim contact and order, and the mask after a
 * decision per component. */
#include <stdlib.h>
#include <string.h>

#include "image/components.h"
#include "testlib.h"

static size_t find(size_t *par, size_t a)
{
    while (par[a] != a) a = par[a] = par[par[a]];
    return a;
}

typedef struct {
    size_t n, size[4096], ordinal[4096];
    int touch[4096];
} seen;

/* records each component; keeps those of odd ordinal or of size 1 touching the box */
static unsigned char decide(void *user, size_t size, int touches, size_t ordinal)
{
    seen *s = user;
    if (s->n < 4096) {
        s->size[s->n] = size;
        s->touch[s->n] = touches;
        s->ordinal[s->n] = ordinal;
    }
    s->n++;
    return (unsigned char)((ordinal & 1) || (size == 1 && touches));
}

/* one case: mask of n voxels with density p (seeded), box lo..hi, val 1 or 0 */
static void one(thx_ctx *ctx, const size_t n[3], const size_t lo[3], const size_t hi[3], double p, unsigned seed,
                unsigned char val)
{
    size_t nv = n[0] * n[1] * n[2], st[3] = {1, n[0], n[0] * n[1]};
    unsigned char *m = malloc(nv), *m0 = malloc(nv), *want = malloc(nv);
    size_t *par = malloc(nv * sizeof *par), *root_ord = malloc(nv * sizeof *root_ord);
    size_t *size = calloc(nv, sizeof *size);
    int *touch = calloc(nv, sizeof *touch);
    srand(seed);
    for (size_t q = 0; q < nv; q++) m[q] = (double)rand() / RAND_MAX < p;
    memcpy(m0, m, nv);
    /* the union-find: voxels equal to val inside the box, joined to their +i, +j, +k neighbours */
#define IN(i, j, k) ((i) >= lo[0] && (i) < hi[0] && (j) >= lo[1] && (j) < hi[1] && (k) >= lo[2] && (k) < hi[2])
    for (size_t q = 0; q < nv; q++) par[q] = q;
    for (size_t k = 0; k < n[2]; k++)
        for (size_t j = 0; j < n[1]; j++)
            for (size_t i = 0; i < n[0]; i++) {
                size_t q = i + st[1] * j + st[2] * k, idx[3] = {i, j, k};
                if (!IN(i, j, k) || m0[q] != val) continue;
                for (int c = 0; c < 3; c++) {
                    if (idx[c] + 1 >= hi[c]) continue;
                    size_t r = q + st[c];
                    if (m0[r] == val) par[find(par, q)] = find(par, r);
                }
            }
    size_t ncomp = 0;
    for (size_t q = 0; q < nv; q++) root_ord[q] = (size_t)-1;
    for (size_t k = 0; k < n[2]; k++)
        for (size_t j = 0; j < n[1]; j++)
            for (size_t i = 0; i < n[0]; i++) {
                size_t q = i + st[1] * j + st[2] * k, idx[3] = {i, j, k};
                if (!IN(i, j, k) || m0[q] != val) continue;
                size_t r = find(par, q);
                if (root_ord[r] == (size_t)-1) root_ord[r] = ncomp++; /* ordinal: order of the first voxel */
                size[r]++;
                for (int c = 0; c < 3; c++)
                    if (idx[c] == lo[c] || idx[c] + 1 == hi[c]) touch[r] = 1;
            }
    /* the expected mask: each component's voxels get the decision, everything else unchanged */
    memcpy(want, m0, nv);
    for (size_t k = 0; k < n[2]; k++)
        for (size_t j = 0; j < n[1]; j++)
            for (size_t i = 0; i < n[0]; i++) {
                size_t q = i + st[1] * j + st[2] * k;
                if (!IN(i, j, k) || m0[q] != val) continue;
                size_t r = find(par, q);
                want[q] = (unsigned char)((root_ord[r] & 1) || (size[r] == 1 && touch[r]));
            }
    seen s;
    memset(&s, 0, sizeof s);
    size_t got_n = 0;
    CHECK_OK(ctx, thx_components6(ctx, m, n, lo, hi, val, decide, &s, &got_n));
    CHECK(got_n == ncomp);
    CHECK(s.n == ncomp);
    CHECK(ncomp > 3 && ncomp < 4096);
    /* the components as the union-find orders them: sizes, rim contact, ordinals */
    size_t bad = 0;
    for (size_t q = 0; q < nv; q++) {
        if (root_ord[q] == (size_t)-1) continue; /* q is a root with an ordinal */
        size_t o = root_ord[q];
        if (o >= s.n || s.size[o] != size[q] || s.touch[o] != touch[q] || s.ordinal[o] != o) bad++;
    }
    CHECK(bad == 0);
    CHECK(memcmp(m, want, nv) == 0);
    free(m), free(m0), free(want), free(par), free(root_ord), free(size), free(touch);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    const size_t n[3] = {23, 17, 13}, all_lo[3] = {0, 0, 0};
    const size_t lo[3] = {3, 2, 1}, hi[3] = {20, 15, 11};
    for (unsigned seed = 1; seed <= 6; seed++) {
        /* near the percolation threshold (0.31 for 6-connectivity): many components, long and bent */
        one(ctx, n, all_lo, n, 0.28 + 0.02 * seed, seed, 1);
        one(ctx, n, lo, hi, 0.30, 100 + seed, 1);
        one(ctx, n, lo, hi, 0.70, 200 + seed, 0); /* the background's components (the cavity pass) */
    }
    /* a U: two columns joined only at the top plane; the fill starts at the bottom of the left one */
    {
        size_t u[3] = {5, 3, 6};
        unsigned char m[90];
        memset(m, 0, sizeof m);
        for (size_t k = 0; k < 6; k++) {
            m[1 + 5 * 1 + 15 * k] = 1;
            m[3 + 5 * 1 + 15 * k] = 1;
        }
        m[2 + 5 * 1 + 15 * 5] = 1;
        seen s;
        memset(&s, 0, sizeof s);
        size_t nc = 0;
        const size_t z[3] = {0, 0, 0};
        CHECK_OK(ctx, thx_components6(ctx, m, u, z, u, 1, decide, &s, &nc));
        CHECK(nc == 1 && s.size[0] == 13 && s.touch[0] == 1);
    }
    /* a solid block: one component of long runs, every voxel in it */
    {
        size_t b[3] = {40, 5, 4};
        unsigned char m[800];
        memset(m, 1, sizeof m);
        m[17 + 40 * 2 + 200 * 1] = 0; /* a one-voxel cavity: the background's one component */
        seen s;
        memset(&s, 0, sizeof s);
        size_t nc = 0;
        const size_t z[3] = {0, 0, 0};
        CHECK_OK(ctx, thx_components6(ctx, m, b, z, b, 1, decide, &s, &nc));
        CHECK(nc == 1 && s.size[0] == 799 && s.touch[0] == 1);
        memset(&s, 0, sizeof s);
        memset(m, 1, sizeof m);
        m[17 + 40 * 2 + 200 * 1] = 0;
        CHECK_OK(ctx, thx_components6(ctx, m, b, z, b, 0, decide, &s, &nc));
        CHECK(nc == 1 && s.size[0] == 1 && s.touch[0] == 0 && m[17 + 40 * 2 + 200 * 1] == 0);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
