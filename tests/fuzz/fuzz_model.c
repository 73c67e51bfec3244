/*
 * Fuzz harness: a model directory's manifest (thx_model_read). The input is
 * model.json; beside it lie fixed small valid files: a box (8 nodes, 12
 * triangles) and a tetrahedral heart (4, 4) with a volume mesh of them (18
 * nodes, 50 tetrahedra, 2 regions, node tables, 6 Steiner records), as
 * `thorax mesh` wrote them. Properties of an accepted manifest: every surface
 * is one of those files (counts at most 8 nodes / 12 triangles), a volume at
 * most 18 nodes and 50 tetrahedra, a frame valid when set; and the model
 * written back and read again has the same surfaces, counts, frame and volume.
 */
#include "fuzz.h"
#include "thorax/model.h"
#include "thorax/volume.h"

static const struct {
    const char *name, *text;
} FILES[] = {
    {"box.pts",
        "0.000000 0.000000 0.000000\n"
        "20.000000 0.000000 0.000000\n"
        "0.000000 20.000000 0.000000\n"
        "20.000000 20.000000 0.000000\n"
        "0.000000 0.000000 20.000000\n"
        "20.000000 0.000000 20.000000\n"
        "0.000000 20.000000 20.000000\n"
        "20.000000 20.000000 20.000000\n"},
    {"box.fac",
        "1 3 4\n"
        "1 4 2\n"
        "5 6 8\n"
        "5 8 7\n"
        "1 2 6\n"
        "1 6 5\n"
        "3 7 8\n"
        "3 8 4\n"
        "1 5 7\n"
        "1 7 3\n"
        "2 4 8\n"
        "2 8 6\n"},
    {"box.vmap",
        "1\n"
        "2\n"
        "3\n"
        "4\n"
        "5\n"
        "6\n"
        "7\n"
        "8\n"},
    {"heart.pts",
        "5.000000 5.000000 5.000000\n"
        "15.000000 5.000000 5.000000\n"
        "5.000000 15.000000 5.000000\n"
        "5.000000 5.000000 15.000000\n"},
    {"heart.fac",
        "1 3 2\n"
        "1 2 4\n"
        "2 3 4\n"
        "1 4 3\n"},
    {"heart.vmap",
        "9\n"
        "10\n"
        "11\n"
        "12\n"},
    {"volume.pts",
        "0 0 0\n"
        "20 0 0\n"
        "0 20 0\n"
        "20 20 0\n"
        "0 0 20\n"
        "20 0 20\n"
        "0 20 20\n"
        "20 20 20\n"
        "5 5 5\n"
        "15 5 5\n"
        "5 15 5\n"
        "5 5 15\n"
        "10 10 0\n"
        "10 10 20\n"
        "10 0 10\n"
        "10 20 10\n"
        "0 10 10\n"
        "20 10 10\n"},
    {"volume.tet",
        "12 5 14 7 1\n"
        "10 13 18 4 1\n"
        "9 11 13 3 1\n"
        "3 4 16 11 1\n"
        "9 1 13 2 1\n"
        "9 1 15 5 1\n"
        "7 12 17 14 1\n"
        "7 5 17 12 1\n"
        "9 12 17 5 1\n"
        "11 14 17 12 1\n"
        "10 16 18 13 1\n"
        "12 9 17 11 1\n"
        "11 16 17 14 1\n"
        "7 14 17 16 1\n"
        "12 6 15 14 1\n"
        "13 16 18 4 1\n"
        "10 2 13 4 1\n"
        "11 9 13 10 1\n"
        "7 14 16 8 1\n"
        "9 5 15 12 1\n"
        "5 6 15 12 1\n"
        "11 4 13 3 1\n"
        "8 4 18 16 1\n"
        "7 3 16 11 1\n"
        "12 11 14 10 1\n"
        "8 16 18 14 1\n"
        "12 6 14 5 1\n"
        "10 15 18 14 1\n"
        "14 15 18 6 1\n"
        "1 9 17 5 1\n"
        "9 2 13 10 1\n"
        "6 8 18 14 1\n"
        "12 11 10 9 2\n"
        "12 14 15 10 1\n"
        "7 16 17 11 1\n"
        "12 10 15 9 1\n"
        "10 2 18 6 1\n"
        "4 2 18 10 1\n"
        "9 3 13 1 1\n"
        "1 3 17 9 1\n"
        "7 11 17 3 1\n"
        "3 11 17 9 1\n"
        "11 13 16 10 1\n"
        "9 2 15 1 1\n"
        "11 4 16 13 1\n"
        "14 16 18 10 1\n"
        "10 6 18 15 1\n"
        "10 14 16 11 1\n"
        "9 10 15 2 1\n"
        "6 2 15 10 1\n"},
    {"volume.steiner",
        "13 1 1 0.5 0 0.5\n"
        "14 1 3 0.5 0 0.5\n"
        "15 1 5 0.5 0 0.5\n"
        "16 1 7 0.5 0 0.5\n"
        "17 1 9 0.5 0 0.5\n"
        "18 1 11 0.5 0 0.5\n"},
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int ready;
    if (!ready) {
        for (size_t k = 0; k < sizeof FILES / sizeof *FILES; k++)
            fuzz_file(FILES[k].name, (const uint8_t *)FILES[k].text, strlen(FILES[k].text));
        ready = 1;
    }
    fuzz_file("model.json", data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_model *m = NULL;
    if (thx_model_read(ctx, fuzz_dir(), &m) == THX_OK) {
        FUZZ_ASSERT(m->n_surfaces <= size / 8);
        for (size_t s = 0; s < m->n_surfaces; s++)
            FUZZ_ASSERT(m->surf[s]->n_nodes >= 1 && m->surf[s]->n_nodes <= 18 && m->surf[s]->n_tris <= 50);
        if (m->frame.set) FUZZ_ASSERT(thx_frame_valid(&m->frame));
        if (m->volume) FUZZ_ASSERT(m->volume->n_nodes <= 18 && m->volume->n_tets <= 50);
        char out[512];
        snprintf(out, sizeof out, "%s/out", fuzz_dir());
        FUZZ_ASSERT(thx_model_write(ctx, m, out) == THX_OK);
        thx_model *r = NULL;
        FUZZ_ASSERT(thx_model_read(ctx, out, &r) == THX_OK);
        FUZZ_ASSERT(r->n_surfaces == m->n_surfaces && !r->volume == !m->volume);
        for (size_t s = 0; s < m->n_surfaces; s++)
            FUZZ_ASSERT(!strcmp(r->surf[s]->name, m->surf[s]->name) && r->surf[s]->n_nodes == m->surf[s]->n_nodes &&
                        r->surf[s]->n_tris == m->surf[s]->n_tris && r->surf[s]->role == m->surf[s]->role);
        FUZZ_ASSERT(r->frame.set == m->frame.set);
        if (m->frame.set)
            FUZZ_ASSERT(r->frame.up.axis == m->frame.up.axis && r->frame.up.sign == m->frame.up.sign &&
                        r->frame.front.axis == m->frame.front.axis && r->frame.front.sign == m->frame.front.sign);
        if (m->volume) FUZZ_ASSERT(r->volume->n_nodes == m->volume->n_nodes && r->volume->n_tets == m->volume->n_tets);
        thx_model_destroy(&r);
    }
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return 0;
}
