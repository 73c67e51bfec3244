/* The model (thorax/model/model.h): its surfaces, interior points, frame and volume. */
#include "thorax/model/model.h"

#include <stdlib.h>
#include <string.h>

thx_status thx_model_create(thx_ctx *ctx, thx_model **out)
{
    *out = NULL;
    thx_model *m = thx_calloc(ctx, 1, sizeof *m);
    if (!m) return THX_ENOMEM;
    *out = m;
    return THX_OK;
}

void thx_model_destroy(thx_model **m)
{
    if (!m || !*m) return;
    thx_model *p = *m;
    for (size_t i = 0; i < p->n_surfaces; i++) thx_surface_destroy(&p->surf[i]);
    free(p->surf);
    free(p->has_interior);
    free(p->interior);
    free(p->provenance_json);
    free(p->edit_log);
    free(p->volume_check_json);
    thx_volume_destroy(&p->volume);
    free(p);
    *m = NULL;
}

thx_status thx_model_add_surface(thx_ctx *ctx, thx_model *m, thx_surface **s)
{
    thx_surface *sf = *s;
    *s = NULL; /* ownership passes to the model now, whatever happens below */
    if (!sf) return thx_error(ctx, THX_EINTERNAL, "thx_model_add_surface: NULL surface");
    for (size_t i = 0; i < m->n_surfaces; i++)
        if (strcmp(m->surf[i]->name, sf->name) == 0) {
            thx_status st = thx_error(ctx, THX_EINPUT, "surface \"%s\": a surface of that name is already in the model", sf->name);
            thx_surface_destroy(&sf);
            return st;
        }
    /* The three per-surface arrays are grown one at a time; each keeps its old
     * contents on failure, and n_surfaces only grows once all three fit. */
    size_t n = m->n_surfaces + 1;
    thx_surface **ns = thx_realloc(ctx, m->surf, n * sizeof *ns);
    if (ns) m->surf = ns;
    int *nh = ns ? thx_realloc(ctx, m->has_interior, n * sizeof *nh) : NULL;
    if (nh) m->has_interior = nh;
    thx_vec3 *ni = nh ? thx_realloc(ctx, m->interior, n * sizeof *ni) : NULL;
    if (!ni) {
        thx_surface_destroy(&sf);
        return THX_ENOMEM;
    }
    m->interior = ni;
    m->surf[n - 1] = sf;
    m->has_interior[n - 1] = 0;
    m->interior[n - 1] = thx_v3(0, 0, 0);
    m->n_surfaces = n;
    return THX_OK;
}

