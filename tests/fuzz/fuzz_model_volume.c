/*
 * Fuzz harness: a model's volume mesh files (thx_model_read -> src/io/model/volume_io.c). The manifest
 * and the surfaces are the fixed model of model_fixture.h; the input, cut at its NUL bytes, gives
 * volume.pts, volume.tet, volume.steiner and box.vmap in that order (a part not given keeps the
 * fixture's file). Properties of an accepted model: no more nodes, tetrahedra and Steiner records
 * than their files' bytes can hold ("0 0 0" is 5 bytes, "1 2 3 4 1" 9, a Steiner line 11), every
 * tetrahedron's nodes in range, and a write/read round trip with the same counts.
 */
#include "fuzz.h"
#include "model_fixture.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/volume.h"
static const char *const PARTS[] = {"volume.pts", "volume.tet", "volume.steiner", "box.vmap"};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (size_t k = 0; k < sizeof FILES / sizeof *FILES; k++)
        fuzz_file(FILES[k].name, (const uint8_t *)FILES[k].text, strlen(FILES[k].text));
    fuzz_file("model.json", (const uint8_t *)MODEL_JSON, strlen(MODEL_JSON));
    size_t len[4] = {0}, off = 0;
    int given = 0;
    for (; given < 4 && off <= size; given++) {
        const uint8_t *nul = memchr(data + off, 0, size - off);
        size_t n = nul ? (size_t)(nul - (data + off)) : size - off;
        fuzz_file(PARTS[given], data + off, n);
        len[given] = n;
        off += n + 1;
        if (!nul) { given++; break; }
    }
    thx_ctx *ctx = fuzz_ctx();
    thx_model *m = NULL;
    if (thx_model_read(ctx, fuzz_dir(), &m) == THX_OK) {
        const thx_volume *v = m->volume;
        FUZZ_ASSERT(v != NULL);
        if (given > 0) FUZZ_ASSERT(5 * v->n_nodes <= len[0] + 1);
        if (given > 1) FUZZ_ASSERT(9 * v->n_tets <= len[1] + 1);
        if (given > 2) FUZZ_ASSERT(11 * v->n_steiner <= len[2] + 1);
        /* (an inverted or flat tetrahedron is read: reporting it is thorax check's job) */
        for (size_t t = 0; t < v->n_tets; t++)
            for (int c = 0; c < 4; c++) FUZZ_ASSERT(v->tet[4 * t + c] >= 0 && (size_t)v->tet[4 * t + c] < v->n_nodes);
        char out[512];
        snprintf(out, sizeof out, "%s/out", fuzz_dir());
        FUZZ_ASSERT(thx_model_write(ctx, m, out) == THX_OK);
        thx_model *r = NULL;
        FUZZ_ASSERT(thx_model_read(ctx, out, &r) == THX_OK);
        FUZZ_ASSERT(r->volume && r->volume->n_nodes == v->n_nodes && r->volume->n_tets == v->n_tets &&
                    r->volume->n_steiner == v->n_steiner);
        thx_model_destroy(&r);
    }
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return 0;
}
