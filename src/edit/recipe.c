/*
 * The recipe (thorax/edit/edit.h): the options of `thorax surfaces` that decide the surfaces, one
 * table of fields for the three places they are written and read: the provenance's "options"
 * (model.json), the edit log's `build` line, and the comparison a replay makes before it edits.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "edit/edit_impl.h"

enum { F_REAL, F_INT, F_POINT, F_CAP, F_BOOL };

static const struct {
    const char *name; /* in the log's build line */
    const char *json; /* in the provenance's options */
    int type;
    const char *help;
} FIELDS[EDIT_RECIPE_NFIELDS] = {
    {"spacing", "spacing_mm", F_REAL, "mm, > 0"},
    {"smoothing", "smoothing_mm", F_REAL, "mm, >= 0"},
    {"start", "start_point_mm", F_POINT, "X,Y in mm"},
    {"cap", "cap", F_CAP, "per-surface, polygon or grid"},
    {"cap_grid", "cap_grid_mm", F_REAL, "mm, >= 0"},
    {"concave_tol", "concave_tol", F_REAL, "a number"},
    {"max_edge", "max_edge", F_REAL, "a number"},
    {"phase_weight", "phase_weight", F_REAL, "a number >= 0"},
    {"fan_limit", "fan_limit", F_INT, "a whole number 0..1000000"},
    {"projected_aspect", "projected_aspect", F_REAL, "a number >= 1"},
    {"merge_tol", "merge_tol_mm", F_REAL, "mm, >= 0"},
    {"untangle_tol", "untangle_tol_mm", F_REAL, "mm, >= 0"},
    {"strict", "strict", F_BOOL, "0 or 1"},
};

/* The address of a real field's value (NULL for the others). */
static double *real_of(thx_edit_recipe *r, int f)
{
    switch (f) {
    case 0: return &r->surfaces.spacing;
    case 1: return &r->surfaces.smoothing;
    case 4: return &r->surfaces.cap_grid;
    case 5: return &r->surfaces.lace.concave_tol;
    case 6: return &r->surfaces.lace.max_edge;
    case 7: return &r->surfaces.lace.phase_weight;
    case 9: return &r->surfaces.lace.projected_aspect;
    case 10: return &r->repair.merge_tol;
    case 11: return &r->repair.untangle_tol;
    default: return NULL;
    }
}

void edit_recipe_default(thx_edit_recipe *r)
{
    memset(r, 0, sizeof *r);
    thx_surfaces_opts_default(&r->surfaces);
    r->surfaces.spacing = 5.0;
    thx_repair_opts_default(&r->repair, 5.0);
}

const char *edit_recipe_field_name(int f) { return f >= 0 && f < EDIT_RECIPE_NFIELDS ? FIELDS[f].name : "?"; }
const char *edit_recipe_field_help(int f) { return f >= 0 && f < EDIT_RECIPE_NFIELDS ? FIELDS[f].help : "?"; }

int edit_recipe_field(const char *name)
{
    for (int f = 0; f < EDIT_RECIPE_NFIELDS; f++)
        if (strcmp(FIELDS[f].name, name) == 0) return f;
    return -1;
}

void edit_recipe_format(const thx_edit_recipe *r, int f, char *buf, size_t cap)
{
    char a[40], b[40];
    thx_edit_recipe *w = (thx_edit_recipe *)r; /* real_of only reads through it here */
    switch (FIELDS[f].type) {
    case F_REAL: edit_fmt_double(buf, cap, *real_of(w, f)); break;
    case F_INT: snprintf(buf, cap, "%d", r->surfaces.lace.fan_limit); break;
    case F_POINT:
        edit_fmt_double(a, sizeof a, r->surfaces.start.x);
        edit_fmt_double(b, sizeof b, r->surfaces.start.y);
        snprintf(buf, cap, "%s,%s", a, b);
        break;
    case F_CAP:
        snprintf(buf, cap, "%s", r->surfaces.cap_method < 0 ? "per-surface"
                                 : r->surfaces.cap_method == THX_CAP_GRID ? "grid" : "polygon");
        break;
    default: snprintf(buf, cap, "%d", r->repair.strict ? 1 : 0); break;
    }
}

int edit_recipe_parse(thx_edit_recipe *r, int f, const char *text)
{
    double v, w;
    switch (FIELDS[f].type) {
    case F_REAL:
        if (edit_parse_real(text, &v)) return -1;
        if ((f == 0 && !(v > 0)) || ((f == 1 || f == 4 || f == 7 || f == 10 || f == 11) && v < 0) || (f == 9 && v < 1))
            return -1;
        *real_of(r, f) = v;
        if (f == 0) r->repair.spacing = v;
        return 0;
    case F_INT:
        if (edit_parse_real(text, &v) || v != floor(v) || v < 0 || v > 1000000 || strpbrk(text, ".eE")) return -1;
        r->surfaces.lace.fan_limit = (int)v;
        return 0;
    case F_POINT: {
        const char *comma = strchr(text, ',');
        char x[64];
        if (!comma || (size_t)(comma - text) >= sizeof x) return -1;
        memcpy(x, text, (size_t)(comma - text));
        x[comma - text] = '\0';
        if (edit_parse_real(x, &v) || edit_parse_real(comma + 1, &w)) return -1;
        r->surfaces.start.x = v;
        r->surfaces.start.y = w;
        return 0;
    }
    case F_CAP:
        if (strcmp(text, "per-surface") == 0) r->surfaces.cap_method = -1;
        else if (strcmp(text, "polygon") == 0) r->surfaces.cap_method = THX_CAP_POLYGON;
        else if (strcmp(text, "grid") == 0) r->surfaces.cap_method = THX_CAP_GRID;
        else return -1;
        return 0;
    default:
        if (strcmp(text, "0") && strcmp(text, "1")) return -1;
        r->repair.strict = text[0] == '1';
        return 0;
    }
}

thx_status thx_edit_recipe_json(thx_ctx *ctx, const thx_edit_recipe *r, struct cJSON *op)
{
    int ok = 1;
    thx_edit_recipe *w = (thx_edit_recipe *)r;
    for (int f = 0; f < EDIT_RECIPE_NFIELDS && ok; f++) {
        const char *k = FIELDS[f].json;
        switch (FIELDS[f].type) {
        case F_REAL: ok = cJSON_AddNumberToObject(op, k, *real_of(w, f)) != NULL; break;
        case F_INT: ok = cJSON_AddNumberToObject(op, k, r->surfaces.lace.fan_limit) != NULL; break;
        case F_POINT: {
            cJSON *sp = cJSON_AddArrayToObject(op, k);
            ok = sp != NULL;
            if (ok) {
                cJSON_AddItemToArray(sp, cJSON_CreateNumber(r->surfaces.start.x));
                cJSON_AddItemToArray(sp, cJSON_CreateNumber(r->surfaces.start.y));
                ok = cJSON_GetArraySize(sp) == 2;
            }
            break;
        }
        case F_CAP: {
            char v[32];
            edit_recipe_format(r, f, v, sizeof v);
            ok = cJSON_AddStringToObject(op, k, v) != NULL;
            break;
        }
        default: ok = cJSON_AddBoolToObject(op, k, r->repair.strict) != NULL; break;
        }
    }
    return ok ? THX_OK : thx_error(ctx, THX_ENOMEM, "out of memory recording the build options");
}

thx_status thx_edit_recipe_from_provenance(thx_ctx *ctx, const char *provenance_json, const char *where,
                                           thx_edit_recipe *r)
{
    edit_recipe_default(r);
    if (!provenance_json) return thx_error(ctx, THX_EINPUT, "%s: no provenance: the build options are unknown", where);
    cJSON *p = cJSON_Parse(provenance_json);
    const cJSON *op = p ? cJSON_GetObjectItemCaseSensitive(p, "options") : NULL;
    thx_status st = THX_OK;
    if (!cJSON_IsObject(op)) {
        st = thx_error(ctx, THX_EINPUT, "%s: the provenance has no \"options\" object: not a model thorax surfaces built",
                       where);
        goto done;
    }
    for (int f = 0; f < EDIT_RECIPE_NFIELDS; f++) {
        const char *k = FIELDS[f].json;
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(op, k);
        char text[96] = "";
        if (FIELDS[f].type == F_BOOL) {
            if (cJSON_IsBool(v)) snprintf(text, sizeof text, "%d", cJSON_IsTrue(v) ? 1 : 0);
        } else if (FIELDS[f].type == F_CAP) {
            if (cJSON_IsString(v)) snprintf(text, sizeof text, "%s", v->valuestring);
        } else if (FIELDS[f].type == F_POINT) {
            const cJSON *x = cJSON_GetArrayItem(v, 0), *y = cJSON_GetArrayItem(v, 1);
            if (cJSON_IsArray(v) && cJSON_GetArraySize(v) == 2 && cJSON_IsNumber(x) && cJSON_IsNumber(y)) {
                char a[40], b[40];
                edit_fmt_double(a, sizeof a, x->valuedouble);
                edit_fmt_double(b, sizeof b, y->valuedouble);
                snprintf(text, sizeof text, "%s,%s", a, b);
            }
        } else if (cJSON_IsNumber(v)) {
            edit_fmt_double(text, sizeof text, v->valuedouble);
        }
        if (!text[0] || edit_recipe_parse(r, f, text)) {
            st = thx_error(ctx, THX_EINPUT, "%s: provenance \"options\".\"%s\" is missing or not %s", where, k,
                           FIELDS[f].help);
            goto done;
        }
    }
done:
    cJSON_Delete(p);
    return st;
}

int thx_edit_recipe_same(const thx_edit_recipe *here, const thx_edit_recipe *log, char *what, size_t cap)
{
    for (int f = 0; f < EDIT_RECIPE_NFIELDS; f++) {
        char a[96], b[96];
        edit_recipe_format(here, f, a, sizeof a);
        edit_recipe_format(log, f, b, sizeof b);
        if (strcmp(a, b) != 0) {
            if (what) snprintf(what, cap, "%s: %s here, %s in the log", FIELDS[f].name, a, b);
            return 0;
        }
    }
    return 1;
}
