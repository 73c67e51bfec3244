/* 6-connected components of a byte mask by scanline fill (src/image/components.h). */
#include "components.h"

#include <stdlib.h>

typedef struct {
    size_t row;    /* j + n1 k */
    size_t i0, i1; /* the run, inclusive */
} run;

#define SEEN 2 /* a voxel of the component being filled */
#define DONE 4 /* a voxel of a component already decided */

thx_status thx_components6(thx_ctx *ctx, unsigned char *mask, const size_t n[3], const size_t lo[3], const size_t hi[3],
                           unsigned char val, thx_cc_decide decide, void *user, size_t *n_components)
{
    if (n_components) *n_components = 0;
    for (int c = 0; c < 3; c++)
        if (lo[c] >= hi[c]) return THX_OK;
    const size_t n0 = n[0], n1 = n[1];
    size_t seed_cap = 1024, run_cap = 1024, ns, nr, ordinal = 0;
    size_t *seed = thx_malloc(ctx, seed_cap * sizeof *seed); /* (row, i) pairs */
    run *runs = thx_malloc(ctx, run_cap * sizeof *runs);
    thx_status st = THX_OK;
    if (!seed || !runs) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t k = lo[2]; k < hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++) {
            const size_t row0 = j + n1 * k;
            unsigned char *line = mask + row0 * n0;
            for (size_t i = lo[0]; i < hi[0]; i++) {
                if (line[i] != val) continue;
                /* a new component: fill it from (row0, i) */
                ns = nr = 0;
                seed[ns++] = row0;
                seed[ns++] = i;
                size_t size = 0;
                int touches = 0;
                while (ns) {
                    size_t si = seed[--ns], row = seed[--ns];
                    unsigned char *m = mask + row * n0;
                    if (m[si] != val) continue; /* filled since it was seeded */
                    size_t a = si, b = si;
                    while (a > lo[0] && m[a - 1] == val) a--;
                    while (b + 1 < hi[0] && m[b + 1] == val) b++;
                    for (size_t q = a; q <= b; q++) m[q] |= SEEN;
                    size += b - a + 1;
                    size_t rj = row % n1, rk = row / n1;
                    if (a == lo[0] || b + 1 == hi[0] || rj == lo[1] || rj + 1 == hi[1] || rk == lo[2] || rk + 1 == hi[2])
                        touches = 1;
                    if (nr == run_cap) {
                        run *nw = thx_realloc(ctx, runs, 2 * run_cap * sizeof *runs);
                        if (!nw) {
                            st = THX_ENOMEM;
                            goto done;
                        }
                        runs = nw;
                        run_cap *= 2;
                    }
                    runs[nr].row = row;
                    runs[nr].i0 = a;
                    runs[nr].i1 = b;
                    nr++;
                    /* one seed per run of `val` in each neighbouring row of the box, over [a, b] */
                    size_t nb[4];
                    int nn = 0;
                    if (rj > lo[1]) nb[nn++] = row - 1;
                    if (rj + 1 < hi[1]) nb[nn++] = row + 1;
                    if (rk > lo[2]) nb[nn++] = row - n1;
                    if (rk + 1 < hi[2]) nb[nn++] = row + n1;
                    for (int t = 0; t < nn; t++) {
                        const unsigned char *o = mask + nb[t] * n0;
                        for (size_t q = a; q <= b; q++) {
                            if (o[q] != val || (q > a && o[q - 1] == val)) continue;
                            if (ns + 2 > seed_cap) {
                                size_t *nw = thx_realloc(ctx, seed, 2 * seed_cap * sizeof *seed);
                                if (!nw) {
                                    st = THX_ENOMEM;
                                    goto done;
                                }
                                seed = nw;
                                seed_cap *= 2;
                            }
                            seed[ns++] = nb[t];
                            seed[ns++] = q;
                        }
                    }
                }
                unsigned char to = (unsigned char)(decide(user, size, touches, ordinal++) | DONE);
                for (size_t r = 0; r < nr; r++) {
                    unsigned char *m = mask + runs[r].row * n0;
                    for (size_t q = runs[r].i0; q <= runs[r].i1; q++) m[q] = to;
                }
            }
        }
    if (n_components) *n_components = ordinal;
done:
    /* the marks cleared (also after a failure: the mask holds 0 and 1 again, a component half-filled
       keeping its value) */
    for (size_t k = lo[2]; k < hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++) {
            unsigned char *line = mask + (j + n1 * k) * n0;
            for (size_t i = lo[0]; i < hi[0]; i++) line[i] &= 1;
        }
    free(seed);
    free(runs);
    return st;
}
