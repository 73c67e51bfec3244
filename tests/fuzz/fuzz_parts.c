/*
 * Fuzz harness: a part of a solution's volume potentials (thx_fem_part_read, thorax/fem/parts.h).
 * The file ends with the SHA-256 of its bytes, which a mutated input would fail at once; so the
 * harness appends the right checksum to the input, and the reader's other checks meet the mutations.
 * Properties of an accepted part: the sizes fill the file exactly, every node number in range and
 * ascending, every tetrahedron's corners in the part, every cut a bisection's; written again and read
 * back, the same part.
 */
#include "fuzz.h"
#include "thorax/core/sha256.h"
#include "thorax/fem/parts.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > (1u << 20)) return 0;
    uint8_t *b = malloc(size + 32);
    if (!b) return 0;
    memcpy(b, data, size);
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, data, size);
    thx_sha256_final(&h, b + size);
    const char *path = fuzz_file("p.bin", b, size + 32);
    free(b);
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) abort();
    thx_fem_part p, q;
    if (thx_fem_part_read(ctx, path, &p) == THX_OK) {
        if (64 + 24 * ((size_t)p.ranks - 1) + 28 * p.n_nodes + 28 * p.n_tets + 8 * p.n_frames * p.n_nodes != size) abort();
        for (size_t k = 0; k < p.n_tets; k++)
            if (p.tet_id[k] < 0 || (size_t)p.tet_id[k] >= p.n_global_tets || (k && p.tet_id[k] <= p.tet_id[k - 1]) ||
                p.owner[k] < 0 || (uint32_t)p.owner[k] >= p.ranks)
                abort();
        for (size_t i = 0; i < p.n_nodes; i++)
            if (p.node[i] < 0 || (size_t)p.node[i] >= p.n_global || (i && p.node[i] <= p.node[i - 1])) abort();
        for (size_t k = 0; k < 4 * p.n_tets; k++)
            if (p.tet[k] < 0 || (size_t)p.tet[k] >= p.n_nodes) abort();
        for (uint32_t k = 0; k + 1 < p.ranks; k++)
            if (p.cuts[k].axis < 0 || p.cuts[k].axis > 2 || p.cuts[k].lo >= p.cuts[k].mid || p.cuts[k].mid >= p.cuts[k].hi) abort();
        const char *again = fuzz_file("q.bin", (const uint8_t *)"", 0);
        if (thx_fem_part_write(ctx, again, &p) != THX_OK || thx_fem_part_read(ctx, again, &q) != THX_OK) abort();
        if (q.n_nodes != p.n_nodes || q.n_tets != p.n_tets || q.n_frames != p.n_frames ||
            memcmp(q.node, p.node, 4 * p.n_nodes) || memcmp(q.tet, p.tet, 16 * p.n_tets) || q.n_own != p.n_own ||
            memcmp(q.tet_id, p.tet_id, 4 * p.n_tets) || memcmp(q.owner, p.owner, 4 * p.n_tets) ||
            memcmp(q.values, p.values, 8 * p.n_nodes * p.n_frames))
            abort();
        thx_fem_part_free(&q);
        thx_fem_part_free(&p);
    }
    thx_ctx_destroy(&ctx);
    return 0;
}
