/*
 * Fuzz harness: a stand-alone map3d .pts/.fac pair (thx_surface_read_ptsfac).
 * The input up to its first NUL byte is the .pts file, the rest the .fac file.
 * Property of an accepted pair: at least one node, no more nodes than the .pts
 * bytes can hold (5 bytes for "0 0 0"), no more triangles than the .fac bytes
 * can hold, finite coordinates, 0-based indices within the node count, and a
 * write/read round trip that keeps the counts.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nul = memchr(data, 0, size);
    size_t np = nul ? (size_t)(nul - data) : size;
    size_t nf = nul ? size - np - 1 : 0;
    char pts[512];
    snprintf(pts, sizeof pts, "%s", fuzz_file("s.pts", data, np));
    const char *fac = fuzz_file("s.fac", nul ? nul + 1 : data, nf);
    thx_ctx *ctx = fuzz_ctx();
    thx_surface *s = NULL;
    int base = -1;
    if (thx_surface_read_ptsfac(ctx, pts, fac, "s", THX_ROLE_OUTER, &s, &base) == THX_OK) {
        FUZZ_ASSERT(s->n_nodes >= 1 && 5 * s->n_nodes <= np + 1);
        FUZZ_ASSERT(5 * s->n_tris <= nf + 1);
        FUZZ_ASSERT(base == 0 || base == 1);
        for (size_t i = 0; i < 3 * s->n_nodes; i++) FUZZ_ASSERT(isfinite(s->xyz[i]));
        for (size_t i = 0; i < 3 * s->n_tris; i++) FUZZ_ASSERT(s->tri[i] >= 0 && (size_t)s->tri[i] < s->n_nodes);
        char p2[512], f2[512];
        snprintf(p2, sizeof p2, "%s/r.pts", fuzz_dir());
        snprintf(f2, sizeof f2, "%s/r.fac", fuzz_dir());
        FUZZ_ASSERT(thx_surface_write_ptsfac(ctx, s, p2, f2) == THX_OK);
        thx_surface *r = NULL;
        int b2 = -1;
        /* Written 1-based: a pair whose triangles never use the last node reads back as ambiguous
         * (refused, by design); any pair read back has the same counts. */
        if (thx_surface_read_ptsfac(ctx, p2, f2, "s", THX_ROLE_OUTER, &r, &b2) == THX_OK) {
            FUZZ_ASSERT(r->n_nodes == s->n_nodes && r->n_tris == s->n_tris);
        }
        thx_surface_destroy(&r);
    }
    thx_surface_destroy(&s);
    thx_ctx_destroy(&ctx);
    return 0;
}
