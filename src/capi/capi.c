/* Flat accessors for bindings (thorax/capi/capi.h): copies in and out of caller arrays, no struct
 * layouts crossing the boundary. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "thorax/capi/capi.h"
#include "thorax/check/check_volume.h"
#include "thorax/fem/fem.h"
#include "thorax/mesh/mesh.h"

#ifndef THORAX_VERSION_STRING
#define THORAX_VERSION_STRING "unknown"
#endif

const char *thx_capi_version(void)
{
    return THORAX_VERSION_STRING;
}

size_t thx_capi_model_n_surfaces(const thx_model *m)
{
    return m ? m->n_surfaces : 0;
}

static thx_status surface_at(thx_ctx *ctx, const thx_model *m, size_t s, const thx_surface **out)
{
    if (!m) return thx_error(ctx, THX_EINPUT, "no model (NULL)");
    if (s >= m->n_surfaces)
        return thx_error(ctx, THX_EINPUT, "surface %zu: the model has %zu surface%s (0-based)", s, m->n_surfaces,
                         m->n_surfaces == 1 ? "" : "s");
    *out = m->surf[s];
    return THX_OK;
}

thx_status thx_capi_surface_info(thx_ctx *ctx, const thx_model *m, size_t s, const char **name, const char **role,
                                 size_t *n_nodes, size_t *n_tris)
{
    const thx_surface *su = NULL;
    THX_CHECK(surface_at(ctx, m, s, &su));
    if (name) *name = su->name;
    if (role) *role = thx_role_name(su->role);
    if (n_nodes) *n_nodes = su->n_nodes;
    if (n_tris) *n_tris = su->n_tris;
    return THX_OK;
}

thx_status thx_capi_surface_copy(thx_ctx *ctx, const thx_model *m, size_t s, double *xyz, int32_t *tri)
{
    const thx_surface *su = NULL;
    THX_CHECK(surface_at(ctx, m, s, &su));
    if (xyz && su->n_nodes) memcpy(xyz, su->xyz, 3 * su->n_nodes * sizeof *xyz);
    if (tri && su->n_tris) memcpy(tri, su->tri, 3 * su->n_tris * sizeof *tri);
    return THX_OK;
}

thx_status thx_capi_surface_find(thx_ctx *ctx, const thx_model *m, const char *name, const char *role_name,
                                 size_t *index)
{
    if (!m) return thx_error(ctx, THX_EINPUT, "no model (NULL)");
    thx_role role = THX_ROLE_OTHER;
    if (!name) {
        if (!role_name || thx_role_parse(role_name, &role) != 0)
            return thx_error(ctx, THX_EINPUT, "'%s' is not a surface role (outer, fat, muscle, lung, heart, other)",
                             role_name ? role_name : "(null)");
    }
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (name ? !strcmp(m->surf[s]->name, name) : m->surf[s]->role == role) {
            *index = s;
            return THX_OK;
        }
    if (name) return thx_error(ctx, THX_EINPUT, "the model has no surface named \"%s\"", name);
    return thx_error(ctx, THX_EINPUT, "the model has no surface of role %s", role_name);
}

void thx_capi_volume_info(const thx_model *m, size_t *n_nodes, size_t *n_tets, size_t *n_regions)
{
    const thx_volume *v = m ? m->volume : NULL;
    if (n_nodes) *n_nodes = v ? v->n_nodes : 0;
    if (n_tets) *n_tets = v ? v->n_tets : 0;
    if (n_regions) *n_regions = v ? v->n_regions : 0;
}

thx_status thx_capi_volume_copy(thx_ctx *ctx, const thx_model *m, double *xyz, int32_t *tet, int32_t *region)
{
    const thx_volume *v = m ? m->volume : NULL;
    if (!v) return thx_error(ctx, THX_EINPUT, "the model has no volume mesh (thorax mesh makes one)");
    if (xyz && v->n_nodes) memcpy(xyz, v->xyz, 3 * v->n_nodes * sizeof *xyz);
    if (tet && v->n_tets) memcpy(tet, v->tet, 4 * v->n_tets * sizeof *tet);
    if (region && v->n_tets) memcpy(region, v->region, v->n_tets * sizeof *region);
    return THX_OK;
}

thx_status thx_capi_region_info(thx_ctx *ctx, const thx_model *m, size_t r, const char **name, double sigma[9])
{
    const thx_volume *v = m ? m->volume : NULL;
    if (!v) return thx_error(ctx, THX_EINPUT, "the model has no volume mesh (thorax mesh makes one)");
    if (r >= v->n_regions)
        return thx_error(ctx, THX_EINPUT, "region %zu: the volume has %zu region%s (0-based)", r, v->n_regions,
                         v->n_regions == 1 ? "" : "s");
    if (name) *name = v->regions[r].name;
    if (sigma) memcpy(sigma, v->regions[r].sigma, 9 * sizeof *sigma);
    return THX_OK;
}

void thx_capi_series_shape(const thx_series *s, size_t *n_rows, size_t *n_frames)
{
    if (n_rows) *n_rows = s ? s->n_rows : 0;
    if (n_frames) *n_frames = s ? s->n_frames : 0;
}

const char *thx_capi_series_unit(const thx_series *s)
{
    return s ? s->unit : "";
}

const char *thx_capi_series_time_unit(const thx_series *s)
{
    return s ? s->time_unit : "";
}

void thx_capi_series_copy(const thx_series *s, double *values, double *time)
{
    if (!s) return;
    if (values)
        for (size_t f = 0; f < s->n_frames; f++)
            for (size_t r = 0; r < s->n_rows; r++) values[r * s->n_frames + f] = s->v[f * s->n_rows + r];
    if (time && s->n_frames) memcpy(time, s->time, s->n_frames * sizeof *time);
}

thx_status thx_capi_series_from(thx_ctx *ctx, size_t n_rows, size_t n_frames, const double *values,
                                const double *time, const char *unit, const char *time_unit, thx_series **out)
{
    *out = NULL;
    if (!values && n_rows && n_frames) return thx_error(ctx, THX_EINPUT, "series: no values (NULL)");
    for (size_t r = 0; r < n_rows; r++)
        for (size_t f = 0; f < n_frames; f++)
            if (!isfinite(values[r * n_frames + f]))
                return thx_error(ctx, THX_EINPUT, "series: row %zu frame %zu (0-based) is %g, not a finite number", r, f,
                                 values[r * n_frames + f]);
    if (unit && strlen(unit) >= sizeof((thx_series *)0)->unit)
        return thx_error(ctx, THX_EINPUT, "series: unit \"%s\" is longer than %zu characters", unit,
                         sizeof((thx_series *)0)->unit - 1);
    if (time_unit && strlen(time_unit) >= sizeof((thx_series *)0)->time_unit)
        return thx_error(ctx, THX_EINPUT, "series: time unit \"%s\" is longer than %zu characters", time_unit,
                         sizeof((thx_series *)0)->time_unit - 1);
    thx_series *s = NULL;
    THX_CHECK(thx_series_create(ctx, n_rows, n_frames, &s));
    for (size_t f = 0; f < n_frames; f++)
        for (size_t r = 0; r < n_rows; r++) s->v[f * n_rows + r] = values[r * n_frames + f];
    if (time) memcpy(s->time, time, n_frames * sizeof *time);
    if (unit) snprintf(s->unit, sizeof s->unit, "%s", unit);
    if (time_unit) snprintf(s->time_unit, sizeof s->time_unit, "%s", time_unit);
    thx_status st = thx_series_validate(ctx, s, "series");
    if (st != THX_OK) {
        thx_series_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}

/* The volume check `thorax check`, `thorax mesh` and `thorax forward` run: THX_ECHECK with every
 * reason in the message when the volume fails. */
static thx_status volume_gate(thx_ctx *ctx, const thx_model *m, const char *what)
{
    thx_volume_report r;
    memset(&r, 0, sizeof r);
    thx_status st = thx_volume_check(ctx, m->volume, m, NULL, &r);
    if (st == THX_ECHECK) {
        char text[1024];
        size_t n = 0;
        text[0] = '\0';
        for (size_t k = 0; k < r.n_reasons && n + 4 < sizeof text; k++) {
            snprintf(text + n, sizeof text - n, "%s%s", k ? "; " : "", r.reasons[k]);
            n = strlen(text);
        }
        st = thx_error(ctx, THX_ECHECK, "%s: the volume fails its check: %s", what, text);
    }
    thx_volume_report_free(&r);
    return st;
}

thx_status thx_capi_mesh(thx_ctx *ctx, thx_model *m, double grid_mm, size_t *n_nodes, size_t *n_tets)
{
    if (!m) return thx_error(ctx, THX_EINPUT, "mesh: no model (NULL)");
    if (!(grid_mm >= 0) || !isfinite(grid_mm))
        return thx_error(ctx, THX_EINPUT, "mesh: grid spacing %g mm: must be 0 (the default) or positive", grid_mm);
    thx_mesh_opts o;
    thx_mesh_opts_default(&o);
    o.grid = grid_mm;
    thx_mesh_stats S;
    THX_CHECK(thx_mesh_build(ctx, m, &o, &S));
    thx_status st = volume_gate(ctx, m, "mesh");
    if (st != THX_OK) {
        thx_volume_destroy(&m->volume);
        return st;
    }
    if (n_nodes) *n_nodes = m->volume->n_nodes;
    if (n_tets) *n_tets = m->volume->n_tets;
    return THX_OK;
}

thx_status thx_capi_forward(thx_ctx *ctx, const thx_model *m, const thx_series *epi, thx_series **torso)
{
    *torso = NULL;
    if (!m || !epi) return thx_error(ctx, THX_EINPUT, "forward: no model or no epicardial series (NULL)");
    if (!m->volume || !m->volume->n_tets)
        return thx_error(ctx, THX_EINPUT, "forward: the model has no volume mesh (thorax mesh makes one)");
    /* PETSc keeps the argv it was started with: static storage. No signal handlers: the host
       program (Python) keeps its own SIGINT/SIGSEGV handling. */
    static char name[] = "libthorax", nosig[] = "-no_signal_handler";
    static char *argv[] = {name, nosig, NULL};
    if (thx_fem_init(2, argv, NULL, NULL) != THX_OK)
        return thx_error(ctx, THX_ESOLVER, "forward: PETSc could not be initialized (PetscInitialize failed)");
    THX_CHECK(volume_gate(ctx, m, "forward"));
    thx_forward_opts fo;
    thx_forward_opts_default(&fo);
    thx_forward_result R;
    memset(&R, 0, sizeof R);
    thx_status st = thx_forward_epicardial(ctx, m, epi, &fo, &R);
    if (st == THX_OK) {
        *torso = R.torso;
        R.torso = NULL;
    }
    thx_forward_result_free(&R);
    return st;
}

void thx_capi_finalize(void)
{
    thx_fem_finalize();
}
