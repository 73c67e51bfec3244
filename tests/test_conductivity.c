/*
 * The default conductivities (thx_region_default) against the literature they cite, as
 * docs/decisions.md and the region table of model.json give them: a changed value changes every
 * forward solution and defibrillation current without breaking any structural test.
 */
#include <string.h>

#include "testlib.h"
#include "thorax/mesh/mesh.h"
int main(void)
{
    /* tissue, across, along (S/m), a word of its source */
    static const struct {
        const char *tissue;
        double across, along;
        const char *cites;
    } lit[] = {
        {"mean_thorax", 0.239, 0.239, "Klepfer"}, /* Klepfer, Johnson, MacLeod 1997 */
        {"fat", 0.04, 0.04, "Rush"},              /* Rush, Abildskov, McFee 1963 */
        {"muscle", 0.04, 0.4, "Epstein"},          /* 0.4 along the fibres, 10:1 (Epstein & Foster 1983) */
        {"lung", 0.05, 0.05, "Rush"},
        {"heart", 0.4, 0.4, "Geddes"},
        {"blood", 0.67, 0.67, "Geddes"},           /* Geddes & Baker 1967 */
    };
    for (size_t k = 0; k < sizeof lit / sizeof lit[0]; k++) {
        thx_region r;
        CHECK(thx_region_default(lit[k].tissue, &r) == 0);
        CHECK(!strcmp(r.name, lit[k].tissue));
        CHECK_NEAR(r.sigma[0], lit[k].across, 1e-12);
        CHECK_NEAR(r.sigma[4], lit[k].across, 1e-12);
        CHECK_NEAR(r.sigma[8], lit[k].along, 1e-12);
        CHECK(r.sigma[1] == 0 && r.sigma[2] == 0 && r.sigma[3] == 0 && r.sigma[5] == 0 && r.sigma[6] == 0 && r.sigma[7] == 0);
        CHECK(r.anisotropic == (lit[k].along != lit[k].across));
        CHECK(strstr(r.source, lit[k].cites) != NULL);
    }
    thx_region r;
    CHECK(thx_region_default("liver", &r) == -1);

    /* conductivities as thorax mesh --sigma and thorax sigma read them */
    thx_ctx *ctx = NULL;
    CHECK(thx_ctx_create(&ctx) == THX_OK);
    double s[9];
    int an = -1;
    CHECK(thx_sigma_parse(ctx, "0.2", s, &an) == THX_OK && an == 0);
    CHECK(s[0] == 0.2 && s[4] == 0.2 && s[8] == 0.2 && s[1] == 0 && s[5] == 0);
    CHECK(thx_sigma_parse(ctx, "0.3,0.3,0.3", s, &an) == THX_OK && an == 0); /* a multiple of I: isotropic */
    CHECK(thx_sigma_parse(ctx, "0.04,0.04,0.4", s, &an) == THX_OK && an == 1);
    CHECK(s[0] == 0.04 && s[4] == 0.04 && s[8] == 0.4 && s[2] == 0 && s[6] == 0);
    CHECK(thx_sigma_parse(ctx, "1,2,3,0.5,0.25,-0.5", s, &an) == THX_OK && an == 1);
    /* row-major and symmetric: sxy at [0][1] and [1][0], sxz at [0][2] and [2][0], syz at [1][2] and [2][1] */
    CHECK(s[1] == 0.5 && s[3] == 0.5 && s[2] == 0.25 && s[6] == 0.25 && s[5] == -0.5 && s[7] == -0.5);
    static const char *bad[] = {"", "0", "-1", "nan", "inf", "1,2", "1,2,3,4", "1,1,1,2,0,0", "1,0,1", "0.2 ", "0.2,", "x"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        CHECK(thx_sigma_parse(ctx, bad[k], s, &an) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "conductivity") != NULL);
    }
    /* a table: assignments by name, the unknown refused with the nearest name, nothing changed */
    thx_region table[3];
    CHECK(thx_region_default("mean_thorax", &table[0]) == 0);
    CHECK(thx_region_default("lung", &table[1]) == 0);
    CHECK(thx_region_default("muscle", &table[2]) == 0);
    snprintf(table[1].name, sizeof table[1].name, "lung_l");
    thx_region before[3];
    memcpy(before, table, sizeof table);
    CHECK(thx_regions_assign(ctx, table, 3, "lung_k=0.1", NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "did you mean lung_l") != NULL);
    CHECK(thx_regions_assign(ctx, table, 3, "brain=0.1", NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "did you mean") == NULL && strstr(thx_ctx_message(ctx), "mean_thorax, lung_l, muscle"));
    CHECK(thx_regions_assign(ctx, table, 3, "lung_l=-2", NULL) == THX_EINPUT);
    CHECK(thx_regions_assign(ctx, table, 3, "lung_l", NULL) == THX_EINPUT);
    CHECK(memcmp(before, table, sizeof table) == 0);
    CHECK(thx_regions_assign(ctx, table, 3, "lung_l=0.08", "Faes et al. 1999") == THX_OK);
    CHECK(table[1].sigma[0] == 0.08 && table[1].sigma[8] == 0.08 && !table[1].anisotropic);
    CHECK(!strcmp(table[1].source, "Faes et al. 1999"));
    CHECK(thx_regions_assign(ctx, table, 3, "muscle=0.1", NULL) == THX_OK);
    CHECK(!table[2].anisotropic && table[2].sigma[8] == 0.1 && !strcmp(table[2].source, "set by the user"));
    CHECK(memcmp(&before[0], &table[0], sizeof table[0]) == 0);
    /* the defaults' "along" on the model's superior axis: the muscle of a model whose up is -y */
    thx_region t2[2];
    CHECK(thx_region_default("muscle", &t2[0]) == 0 && thx_region_default("fat", &t2[1]) == 0);
    thx_frame f;
    CHECK(thx_frame_from_names(ctx, "-y", "-z", "test", &f) == THX_OK);
    thx_regions_orient(t2, 2, &f);
    CHECK(t2[0].sigma[0] == 0.04 && t2[0].sigma[4] == 0.4 && t2[0].sigma[8] == 0.04 && t2[0].anisotropic);
    CHECK(t2[1].sigma[0] == 0.04 && t2[1].sigma[4] == 0.04 && t2[1].sigma[8] == 0.04);
    CHECK(thx_region_default("muscle", &t2[0]) == 0);
    thx_frame ras = thx_frame_ras(), none;
    memset(&none, 0, sizeof none);
    thx_regions_orient(t2, 1, &ras);
    thx_regions_orient(t2, 1, &none);
    CHECK(t2[0].sigma[8] == 0.4 && t2[0].sigma[0] == 0.04); /* RAS or no frame: along z */
    CHECK(thx_frame_from_names(ctx, "+x", "+y", "test", &f) == THX_OK);
    thx_regions_orient(t2, 1, &f);
    CHECK(t2[0].sigma[0] == 0.4 && t2[0].sigma[4] == 0.04 && t2[0].sigma[8] == 0.04);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
