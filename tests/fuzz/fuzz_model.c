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
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/volume.h"
#include "model_fixture.h"

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
