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
    return tl_finish();
}
