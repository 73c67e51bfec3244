/* The flat accessors for bindings (thorax/capi/capi.h), in C, so that the sanitized builds check them
 * too (the Python binding's tests, python/tests, do not run there): copies equal the structs they
 * come from, series cross between row-major arrays and the frame-by-frame store both ways, and
 * every refusal names what is wrong. Meshing and forward solutions through capi are compared with
 * the CLI by python/tests. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/capi/capi.h"
#include "thorax/model/model.h"

static void test_model(thx_ctx *ctx)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    CHECK(m != NULL);
    if (!m) return;
    CHECK(thx_capi_model_n_surfaces(m) == m->n_surfaces);
    CHECK(thx_capi_model_n_surfaces(NULL) == 0);
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const char *name = NULL, *role = NULL;
        size_t nn = 0, nt = 0;
        CHECK_OK(ctx, thx_capi_surface_info(ctx, m, s, &name, &role, &nn, &nt));
        const thx_surface *su = m->surf[s];
        CHECK(name == su->name && !strcmp(role, thx_role_name(su->role)));
        CHECK(nn == su->n_nodes && nt == su->n_tris);
        double *xyz = malloc(3 * nn * sizeof *xyz);
        int32_t *tri = malloc(3 * nt * sizeof *tri);
        CHECK_OK(ctx, thx_capi_surface_copy(ctx, m, s, xyz, tri));
        CHECK(!memcmp(xyz, su->xyz, 3 * nn * sizeof *xyz));
        CHECK(!memcmp(tri, su->tri, 3 * nt * sizeof *tri));
        CHECK_OK(ctx, thx_capi_surface_copy(ctx, m, s, NULL, NULL)); /* either output may be NULL */
        free(xyz);
        free(tri);
        size_t k = 99;
        CHECK_OK(ctx, thx_capi_surface_find(ctx, m, su->name, NULL, &k));
        CHECK(k == s);
    }
    size_t k = 99;
    CHECK_OK(ctx, thx_capi_surface_find(ctx, m, NULL, "heart", &k));
    CHECK(k < m->n_surfaces && m->surf[k]->role == THX_ROLE_HEART);
    CHECK(thx_capi_surface_find(ctx, m, "spleen", NULL, &k) == THX_EINPUT && tl_msg_has(ctx, "no surface named \"spleen\""));
    CHECK(thx_capi_surface_find(ctx, m, NULL, "liver", &k) == THX_EINPUT && tl_msg_has(ctx, "'liver' is not a surface role"));
    size_t n = m->n_surfaces;
    CHECK(thx_capi_surface_info(ctx, m, n, NULL, NULL, NULL, NULL) == THX_EINPUT && tl_msg_has(ctx, "the model has 6 surfaces"));
    CHECK(thx_capi_surface_copy(ctx, NULL, 0, NULL, NULL) == THX_EINPUT && tl_msg_has(ctx, "no model"));
    /* not meshed: counts 0, copies refused */
    size_t vn = 1, vt = 1, vr = 1;
    thx_capi_volume_info(m, &vn, &vt, &vr);
    CHECK(vn == 0 && vt == 0 && vr == 0);
    CHECK(thx_capi_volume_copy(ctx, m, NULL, NULL, NULL) == THX_EINPUT && tl_msg_has(ctx, "no volume mesh"));
    CHECK(thx_capi_region_info(ctx, m, 0, NULL, NULL) == THX_EINPUT && tl_msg_has(ctx, "no volume mesh"));
    thx_series *torso = NULL, *epi = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, m->surf[k]->n_nodes, 1, &epi));
    CHECK(thx_capi_forward(ctx, m, epi, &torso) == THX_EINPUT && torso == NULL && tl_msg_has(ctx, "no volume mesh"));
    CHECK(thx_capi_mesh(ctx, m, -1, NULL, NULL) == THX_EINPUT && tl_msg_has(ctx, "grid spacing -1 mm"));
    thx_series_destroy(&epi);
    thx_model_destroy(&m);
}

static void test_series(thx_ctx *ctx)
{
    enum { R = 5, F = 7 };
    double v[R * F], t[F], back[R * F], tb[F];
    for (int r = 0; r < R; r++)
        for (int f = 0; f < F; f++) v[r * F + f] = 100.0 * r + f + 0.25;
    for (int f = 0; f < F; f++) t[f] = 2.5 * f;
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_capi_series_from(ctx, R, F, v, t, "mV", "ms", &s));
    if (!s) return;
    size_t nr = 0, nf = 0;
    thx_capi_series_shape(s, &nr, &nf);
    CHECK(nr == R && nf == F);
    /* stored frame by frame: v[f * rows + r] */
    CHECK(s->v[3 * R + 2] == 203.25 && s->v[0 * R + 4] == 400.25);
    CHECK(!strcmp(thx_capi_series_unit(s), "mV") && !strcmp(thx_capi_series_time_unit(s), "ms"));
    thx_capi_series_copy(s, back, tb);
    CHECK(!memcmp(back, v, sizeof v) && !memcmp(tb, t, sizeof t));
    thx_series_destroy(&s);
    /* no times: 0, 1, 2 ... ms */
    CHECK_OK(ctx, thx_capi_series_from(ctx, R, F, v, NULL, NULL, NULL, &s));
    if (s) CHECK(s->time[6] == 6.0 && !strcmp(s->unit, "") && !strcmp(s->time_unit, "ms"));
    thx_series_destroy(&s);
    /* refusals */
    v[1 * F + 2] = NAN;
    CHECK(thx_capi_series_from(ctx, R, F, v, t, "mV", "ms", &s) == THX_EINPUT && !s && tl_msg_has(ctx, "row 1 frame 2"));
    v[1 * F + 2] = 0;
    t[3] = t[2];
    CHECK(thx_capi_series_from(ctx, R, F, v, t, "mV", "ms", &s) != THX_OK && !s);
    t[3] = 7.5;
    CHECK(thx_capi_series_from(ctx, R, F, v, t, "a unit name far longer than thirty-one bytes", "ms", &s) == THX_EINPUT &&
          !s && tl_msg_has(ctx, "longer than 31"));
    CHECK(thx_capi_series_from(ctx, R, F, NULL, t, "mV", "ms", &s) == THX_EINPUT && !s);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    CHECK(strcmp(thx_capi_version(), "unknown") != 0 && strchr(thx_capi_version(), '.') != NULL);
    test_model(ctx);
    test_series(ctx);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
