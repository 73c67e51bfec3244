/*
 * Default tissue conductivities (S/m, low frequency, the 0-100 Hz band of
 * electrocardiography). Every value names its source; users override them in
 * the model's region table.
 */
#include <stdio.h>
#include <string.h>

#include "thorax/mesh/mesh.h"
typedef struct {
    const char *tissue;
    double along, across; /* along the body axis (z) and across it; equal when isotropic */
    const char *source;
} tissue_default;

static const tissue_default defaults[] = {
    {"mean_thorax", 0.239, 0.239,
     "Klepfer, Johnson, MacLeod, IEEE TBME 44:706 (1997): mean of the thoracic tissues (Foster & Schwan 1989)"},
    {"fat", 0.04, 0.04, "Rush, Abildskov, McFee, Circ Res 12:40 (1963): subcutaneous fat"},
    {"muscle", 0.4, 0.04,
     "Rush, Abildskov, McFee (1963); anisotropy about 10:1 along/across the fibres, Epstein & Foster, Med Biol Eng "
     "Comput 21:51 (1983); fibres taken along the body axis"},
    {"lung", 0.05, 0.05, "Rush, Abildskov, McFee, Circ Res 12:40 (1963): inflated lung"},
    {"heart", 0.4, 0.4, "lumped myocardium and intracavitary blood (blood 0.67, Geddes & Baker, Med Biol Eng 5:271 (1967))"},
    {"blood", 0.67, 0.67, "Geddes & Baker, Med Biol Eng 5:271 (1967)"},
};

int thx_region_default(const char *tissue, thx_region *r)
{
    for (size_t k = 0; k < sizeof defaults / sizeof defaults[0]; k++) {
        if (strcmp(tissue, defaults[k].tissue) != 0) continue;
        memset(r, 0, sizeof *r);
        snprintf(r->name, sizeof r->name, "%s", tissue);
        r->sigma[0] = r->sigma[4] = defaults[k].across;
        r->sigma[8] = defaults[k].along;
        r->anisotropic = defaults[k].along != defaults[k].across;
        snprintf(r->source, sizeof r->source, "%s", defaults[k].source);
        return 0;
    }
    return -1;
}
