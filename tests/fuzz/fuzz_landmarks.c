/*
 * Fuzz harness: map3d landmark files (thx_landmarks_parse, thx_landmarks_write, thx_landmarks_read,
 * thx_landmarks_mesh). Properties of an accepted input:
 *  - counts within what the bytes can hold: a segment takes at least 16 bytes, a point 8 (less
 *    one for the last line's newline);
 *  - the set passes thx_landmarks_validate;
 *  - written and read back, the set is equal field by field (numbers exactly);
 *  - its meshes are built, every one closed and edge-manifold with consistent orientation (each
 *    directed edge once, its reverse once), finite, no triangle of zero area.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/geom/landmark_mesh.h"
#include "thorax/io/landmarks_file.h"
#include "thorax/model/landmarks.h"

static int cmp_edge(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;
    return *x < *y ? -1 : *x > *y;
}

static void check_mesh(const thx_surface *s)
{
    FUZZ_ASSERT(s && s->n_tris >= 4 && s->n_nodes >= 4);
    for (size_t i = 0; i < 3 * s->n_nodes; i++) FUZZ_ASSERT(isfinite(s->xyz[i]));
    int64_t *e = malloc(3 * s->n_tris * sizeof *e);
    FUZZ_ASSERT(e != NULL);
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        for (int k = 0; k < 3; k++) {
            FUZZ_ASSERT(v[k] >= 0 && (size_t)v[k] < s->n_nodes);
            e[3 * t + (size_t)k] = (int64_t)v[k] << 32 | v[(k + 1) % 3];
        }
        thx_vec3 a = thx_surface_node(s, (size_t)v[0]), b = thx_surface_node(s, (size_t)v[1]),
                 c = thx_surface_node(s, (size_t)v[2]);
        FUZZ_ASSERT(thx_v3_norm(thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a))) > 0);
    }
    qsort(e, 3 * s->n_tris, sizeof *e, cmp_edge);
    for (size_t i = 0; i < 3 * s->n_tris; i++) {
        FUZZ_ASSERT(i + 1 == 3 * s->n_tris || e[i] != e[i + 1]);
        int64_t rev = (e[i] & 0xffffffff) << 32 | (e[i] >> 32);
        FUZZ_ASSERT(bsearch(&rev, e, 3 * s->n_tris, sizeof *e, cmp_edge) != NULL);
    }
    free(e);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    thx_ctx *ctx = fuzz_ctx();
    thx_landmarks *lm = NULL;
    if (thx_landmarks_parse(ctx, "f.lmarks", (const char *)data, size, &lm) == THX_OK) {
        FUZZ_ASSERT(lm != NULL);
        FUZZ_ASSERT(lm->n * 16 <= size + 1);
        size_t pts = 0;
        for (size_t k = 0; k < lm->n; k++) pts += lm->seg[k].n;
        FUZZ_ASSERT(pts * 8 <= size + 1);
        FUZZ_ASSERT(thx_landmarks_validate(ctx, lm, NULL) == THX_OK);

        char p[512];
        snprintf(p, sizeof p, "%s/r.lmarks", fuzz_dir());
        FUZZ_ASSERT(thx_landmarks_write(ctx, lm, p) == THX_OK);
        thx_landmarks *r = NULL;
        FUZZ_ASSERT(thx_landmarks_read(ctx, p, &r) == THX_OK);
        FUZZ_ASSERT(r->n == lm->n);
        for (size_t k = 0; k < lm->n; k++) {
            const thx_landmark_segment *a = &lm->seg[k], *b = &r->seg[k];
            FUZZ_ASSERT(a->type == b->type && a->n == b->n && a->has_index == b->has_index && a->has_color == b->has_color);
            FUZZ_ASSERT(!a->has_index || a->index == b->index);
            FUZZ_ASSERT(!a->has_color || !memcmp(a->rgb, b->rgb, 3));
            for (size_t i = 0; i < a->n; i++) {
                for (int c = 0; c < 3; c++) FUZZ_ASSERT(a->pt[i].xyz[c] == b->pt[i].xyz[c]);
                FUZZ_ASSERT(a->pt[i].radius == b->pt[i].radius && !strcmp(a->pt[i].label, b->pt[i].label));
            }
        }
        thx_landmarks_destroy(&r);

        thx_landmark_mesh_opts o;
        thx_landmark_mesh_opts_default(&o);
        o.sides = 5; /* small meshes: the fuzzer's time goes to inputs */
        o.disc_sides = 7;
        o.sphere_level = 0;
        thx_landmark_meshes *m = NULL;
        thx_status st = thx_landmarks_mesh(ctx, lm, &o, &m);
        if (st != THX_OK) fprintf(stderr, "mesh refused: %s\n", thx_ctx_message(ctx));
        FUZZ_ASSERT(st == THX_OK && m && m->n == lm->n);
        for (size_t k = 0; k < m->n; k++) check_mesh(m->surf[k]);
        thx_landmark_meshes_destroy(&m);
    } else {
        FUZZ_ASSERT(lm == NULL);
    }
    thx_landmarks_destroy(&lm);
    thx_ctx_destroy(&ctx);
    return 0;
}
