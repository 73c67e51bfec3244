/*
 * The conductivity table of a volume's tissue regions: the default conductivities (S/m, low
 * frequency, the 0-100 Hz band of electrocardiography), each naming its source (docs/decisions.md,
 * "Default conductivities", says how far each was checked), and the assignments that change a
 * table (thorax mesh --sigma, thorax sigma).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
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
    {"blood", 0.67, 0.67, "Geddes & Baker, Med Biol Eng 5:271 (1967): 150 ohm cm"},
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

void thx_regions_orient(thx_region *table, size_t n, const thx_frame *frame)
{
    if (!frame || !frame->set || frame->up.axis < 0 || frame->up.axis > 2 || frame->up.axis == 2) return;
    for (size_t r = 0; r < n; r++) {
        double *s = table[r].sigma;
        int diagonal = s[1] == 0 && s[2] == 0 && s[3] == 0 && s[5] == 0 && s[6] == 0 && s[7] == 0;
        if (!table[r].anisotropic || !diagonal || s[0] != s[4]) continue; /* not a default's shape */
        double along = s[8], across = s[0];
        s[0] = s[4] = s[8] = across;
        s[4 * frame->up.axis] = along;
    }
}

int thx_sigma_in_range(const double sigma[9], char *why, size_t size)
{
    for (int k = 0; k < 9; k++) {
        double x = sigma[k];
        if (k % 4 == 0 && !(x >= THX_SIGMA_MIN)) {
            snprintf(why, size, "the diagonal entry %g is below %g S/m", x, THX_SIGMA_MIN);
            return 0;
        }
        if (!(fabs(x) <= THX_SIGMA_MAX)) {
            snprintf(why, size, "the %s %g is beyond %g S/m", k % 4 ? "entry" : "diagonal entry", x, THX_SIGMA_MAX);
            return 0;
        }
    }
    return 1;
}

thx_status thx_sigma_parse(thx_ctx *ctx, const char *text, double sigma[9], int *anisotropic)
{
    double c[7];
    int n = 0;
    const char *p = text;
    while (n < 7) {
        char *end = NULL;
        c[n] = strtod(p, &end);
        if (end == p || (*end && *end != ',')) {
            n = -1;
            break;
        }
        n++;
        if (!*end) break;
        p = end + 1;
    }
    if (n != 1 && n != 3 && n != 6)
        return thx_error(ctx, THX_EINPUT,
                         "conductivity '%s': expected a number (isotropic), three (sxx,syy,szz) or six "
                         "(sxx,syy,szz,sxy,sxz,syz), in S/m in the model's axes",
                         text);
    for (int k = 0; k < n; k++)
        if (!isfinite(c[k]) || (k < 3 && !(c[k] > 0)))
            return thx_error(ctx, THX_EINPUT, "conductivity '%s': %s %g is not a positive number (S/m)", text,
                             n == 1 ? "the value" : k < 3 ? "the diagonal entry" : "the entry", c[k]);
    memset(sigma, 0, 9 * sizeof *sigma);
    if (n == 1) {
        sigma[0] = sigma[4] = sigma[8] = c[0];
    } else {
        sigma[0] = c[0];
        sigma[4] = c[1];
        sigma[8] = c[2];
        if (n == 6) {
            sigma[1] = sigma[3] = c[3];
            sigma[2] = sigma[6] = c[4];
            sigma[5] = sigma[7] = c[5];
        }
    }
    char why[160];
    if (!thx_sigma_in_range(sigma, why, sizeof why))
        return thx_error(ctx, THX_EINPUT, "conductivity '%s': %s (thorax takes %g to %g S/m)", text, why, THX_SIGMA_MIN,
                         THX_SIGMA_MAX);
    if (!thx_tensor_spd(sigma, why, sizeof why))
        return thx_error(ctx, THX_EINPUT, "conductivity '%s': the tensor is %s", text, why);
    /* a tensor that is a multiple of the identity is stored as the number it is */
    int iso = sigma[0] == sigma[4] && sigma[4] == sigma[8];
    for (int k = 0; k < 9; k++)
        if (k % 4 && sigma[k] != 0) iso = 0;
    *anisotropic = !iso;
    return THX_OK;
}

thx_status thx_regions_assign(thx_ctx *ctx, thx_region *table, size_t n, const char *assignment, const char *source)
{
    const char *eq = strchr(assignment, '=');
    size_t len = eq ? (size_t)(eq - assignment) : 0;
    if (!eq || len == 0 || !eq[1])
        return thx_error(ctx, THX_EINPUT, "'%s': expected NAME=SIGMA (a region's name, then its conductivity in S/m)",
                         assignment);
    long found = -1;
    for (size_t r = 0; r < n && found < 0; r++)
        if (strlen(table[r].name) == len && !strncmp(table[r].name, assignment, len)) found = (long)r;
    if (found < 0) {
        char name[64], names[16 * 68] = "", near[64] = "";
        snprintf(name, sizeof name, "%.*s", (int)(len < 63 ? len : 63), assignment);
        size_t best = 64;
        for (size_t r = 0; r < n; r++) {
            size_t at = strlen(names);
            if (at + 70 < sizeof names) snprintf(names + at, sizeof names - at, "%s%s", r ? ", " : "", table[r].name);
            size_t d = thx_name_distance(name, table[r].name), limit = strlen(table[r].name) / 3 + 1;
            if (d <= limit && d < best) {
                best = d;
                snprintf(near, sizeof near, "%s", table[r].name);
            }
        }
        if (near[0])
            return thx_error(ctx, THX_EINPUT, "no region \"%s\" (did you mean %s? the regions are %s)", name, near, names);
        return thx_error(ctx, THX_EINPUT, "no region \"%s\" (the regions are %s)", name, names);
    }
    double s[9];
    int aniso = 0;
    thx_status st = thx_sigma_parse(ctx, eq + 1, s, &aniso);
    if (st != THX_OK) {
        char why[512];
        snprintf(why, sizeof why, "%s", thx_ctx_message(ctx));
        return thx_error(ctx, st, "region \"%s\": %s", table[found].name, why);
    }
    memcpy(table[found].sigma, s, sizeof s);
    table[found].anisotropic = aniso;
    snprintf(table[found].source, sizeof table[found].source, "%s", source ? source : "set by the user");
    return THX_OK;
}
