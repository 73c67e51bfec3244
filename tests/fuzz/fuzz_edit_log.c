/*
 * Fuzz harness: edit logs (thx_edit_log_parse; thorax/edit/edit.h, docs/formats.md "Edit logs").
 * Properties of an accepted log:
 *  - it has its `end`: end_offset lies inside the text, at a line that reads "end" after blanks;
 *  - counts within what the bytes can hold: the shortest edit line is 13 bytes ("tri_flip a 1\n");
 *  - every edit is well formed: a valid surface name, indices below 2^31 - 1, finite numbers, a
 *    tri_add on three different nodes, a smoothing bandwidth > 0, lines increasing;
 *  - written again (thx_edit_log_text) and read back, the same header and the same edits, bit for
 *    bit (when the writer accepts the contour path: it refuses a CR inside it).
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/edit/edit.h"
#include "thorax/model/volume.h"

static int same_edit(const thx_edit *a, const thx_edit *b)
{
    return a->kind == b->kind && !strcmp(a->surface, b->surface) && a->node == b->node && a->tri == b->tri &&
           !memcmp(a->nodes, b->nodes, sizeof a->nodes) && !memcmp(a->v, b->v, sizeof a->v) &&
           a->layer.by_index == b->layer.by_index && a->layer.index == b->layer.index &&
           !memcmp(&a->layer.z, &b->layer.z, sizeof a->layer.z);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    thx_ctx *ctx = fuzz_ctx();
    thx_edit_log *log = NULL, *back = NULL;
    if (thx_edit_log_parse(ctx, "f.edits", (const char *)data, size, &log) == THX_OK) {
        size_t lead = strspn(log->text + log->end_offset, " \t\r\v\f");
        FUZZ_ASSERT(log->end_offset + lead + 3 <= log->len && !memcmp(log->text + log->end_offset + lead, "end", 3));
        FUZZ_ASSERT(13 * log->n_edits <= size);
        int line = 0;
        for (size_t i = 0; i < log->n_edits; i++) {
            const thx_edit *e = &log->edits[i];
            FUZZ_ASSERT(e->kind >= 0 && e->kind < THX_EDIT_KIND_COUNT && thx_name_ok(e->surface, sizeof e->surface));
            FUZZ_ASSERT(e->node < 2147483647u && e->tri < 2147483647u && e->layer.index < 2147483647u);
            for (int k = 0; k < 3; k++) FUZZ_ASSERT(isfinite(e->v[k]) && e->nodes[k] < 2147483647u);
            FUZZ_ASSERT(isfinite(e->layer.z));
            if (e->kind == THX_EDIT_TRI_ADD)
                FUZZ_ASSERT(e->nodes[0] != e->nodes[1] && e->nodes[1] != e->nodes[2] && e->nodes[0] != e->nodes[2]);
            if (e->kind == THX_EDIT_LAYER_SMOOTH) FUZZ_ASSERT(e->v[0] > 0);
            FUZZ_ASSERT(e->line > line);
            line = e->line;
        }
        char *text = NULL;
        if (thx_edit_log_text(ctx, log->has_contours ? log->contours_path : NULL,
                              log->has_contours ? log->contours_sha256 : NULL, log->has_recipe ? &log->recipe : NULL,
                              log->edits, log->n_edits, NULL, &text) == THX_OK) {
            FUZZ_ASSERT(thx_edit_log_parse(ctx, "w.edits", text, strlen(text), &back) == THX_OK);
            FUZZ_ASSERT(back->n_edits == log->n_edits && back->has_contours == log->has_contours &&
                        back->has_recipe == log->has_recipe);
            if (log->has_contours)
                FUZZ_ASSERT(!strcmp(back->contours_sha256, log->contours_sha256) &&
                            (!strcmp(back->contours_path, log->contours_path) || !log->contours_path[0]));
            if (log->has_recipe) FUZZ_ASSERT(thx_edit_recipe_same(&back->recipe, &log->recipe, NULL, 0));
            for (size_t i = 0; i < log->n_edits; i++) FUZZ_ASSERT(same_edit(&back->edits[i], &log->edits[i]));
        }
        free(text);
    }
    thx_edit_log_destroy(&back);
    thx_edit_log_destroy(&log);
    thx_ctx_destroy(&ctx);
    return 0;
}
