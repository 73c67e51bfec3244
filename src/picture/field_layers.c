/*
 * Equipotential surfaces and slices in a picture (thorax/picture/picture.h, `isosurface`,
 * `slices`; paper 4.3, "Volume potentials and vector flow"): the solution's volume potentials of
 * the frame cut by thorax/field, drawn beside the model's surfaces.
 *
 * The colour scale: the picture's own settings (scope, model, mapping, fixed range, inversion)
 * applied to the volume's potentials — this frame's range (frame scopes) or the series' (series
 * scopes) — so the equipotentials and slices have a bar of their own unless their range is the
 * body surface's. Slices by |J| (slice_current): the current density's magnitude per tetrahedron
 * (piecewise constant, as the finite elements make it), each slice triangle in its tetrahedron's
 * value, linear from 0 to the frame's largest |J| on the slices, viridis.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"
#include "thorax/field/field.h"
#include "thorax/field/streamline.h"
#include "thorax/io/solution_file.h"
#include "picture/picture_internal.h"

enum { ISO = 0, SLICE = 1, STREAM = 2 };

void picture_field_free(thx_picture_data *d)
{
    for (int k = 0; k < 2; k++) {
        thx_field_mesh_destroy(&d->field[k]);
        free(d->field_own[k]);
        d->field_own[k] = NULL;
    }
    for (int k = 0; k < 3; k++) {
        free(d->field_values[k]);
        d->field_values[k] = NULL;
    }
    for (int k = 0; k < 3; k++) {
        free(d->field_normals[k]);
        free(d->field_part_tri[k]);
        d->field_normals[k] = NULL;
        d->field_part_tri[k] = NULL;
    }
    thx_stream_tubes_destroy(&d->tubes);
    d->n_stream_lines = 0;
    free(d->field_own_tri);
    d->field_own_tri = NULL;
    d->field_frame = -1;
}

/* Cuts that cannot cut anything are refused (as thorax field refuses them, issue 24): a slice whose
 * plane leaves every node of the regions cut on one side, an isovalue written as a number that lies
 * outside the volume potentials of every frame. */
static thx_status empty_cuts(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d)
{
    const thx_volume *v = d->m->volume;
    for (int k = 0; k < o->n_slices; k++) {
        thx_field_plane p;
        THX_CHECK(thx_field_plane_parse(ctx, o->slices[k], &p));
        double dmin, dmax;
        if (d->part_size > 1) /* sort-last: the whole volume's span (thx_picture_parts_settle) */
            dmin = d->part_span[k][0], dmax = d->part_span[k][1];
        else
            thx_field_plane_span(v, d->field_use, &p, &dmin, &dmax);
        if (!(dmin <= 0 && dmax >= 0))
            return thx_error(ctx, THX_EINPUT, "--slice %s misses the volume of %s: its nodes lie %.6g to %.6g mm from the plane "
                             "(all on one side)", o->slices[k], o->solution, dmin, dmax);
    }
    if (o->isosurface) {
        double *x = NULL;
        size_t nx = 0;
        thx_status st = thx_field_values_explicit(ctx, o->isosurface, &x, &nx);
        for (size_t k = 0; st == THX_OK && k < nx; k++)
            if (!(d->vmin <= x[k] && x[k] <= d->vmax))
                st = thx_error(ctx, THX_EINPUT, "--isosurface %s: the value %g is outside the volume potentials of %s in "
                               "every frame (%g to %g): it cuts nothing", o->isosurface, x[k], o->solution, d->vmin, d->vmax);
        free(x);
        return st;
    }
    return THX_OK;
}

thx_status picture_field_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d)
{
    d->field_frame = -1;
    if (!d->volume) return THX_OK;
    const thx_volume *v = d->m->volume;
    d->field_use = malloc(v->n_regions ? v->n_regions : 1);
    if (!d->field_use) return thx_error(ctx, THX_ENOMEM, "out of memory (volume cuts)");
    THX_CHECK(thx_solution_domain(ctx, o->solution, v, d->field_use));
    d->vmin = INFINITY;
    d->vmax = -INFINITY;
    picture_range_of(d->volume->v, d->volume->n_rows * d->volume->n_frames, &d->vmin, &d->vmax);
    if (d->part_size > 1) return THX_OK; /* a part: the range and the cuts are the whole's (thx_picture_parts_settle) */
    if (!(d->vmin <= d->vmax)) return thx_error(ctx, THX_EINPUT, "the solution's volume potentials hold no finite value");
    return thx_picture_cuts_check(ctx, o, d);
}

thx_status thx_picture_cuts_check(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d)
{
    if (!d->volume) {
        if (!picture_has_field(o)) return THX_OK;
        return thx_error(ctx, THX_EINPUT, "%s: the volume potentials were not read (give a cut with the --solution at the start)",
                         o->isosurface ? "--isosurface" : o->n_slices ? "--slice" : o->n_streamlines ? "--streamlines" : "--volume");
    }
    /* the specifications checked (the values against the series' range), the option named */
    thx_status st = THX_OK;
    const char *opt = "--slice";
    for (int k = 0; k < o->n_slices && st == THX_OK; k++) {
        thx_field_plane p;
        st = thx_field_plane_parse(ctx, o->slices[k], &p);
    }
    for (int k = 0; k < o->n_streamlines && st == THX_OK; k++) {
        thx_seed_spec spec;
        opt = "--streamlines";
        st = thx_seed_spec_parse(ctx, o->streamlines[k], &spec);
    }
    if (st == THX_OK && o->isosurface) {
        double *values = NULL;
        size_t n = 0;
        opt = "--isosurface";
        st = thx_field_values_parse(ctx, o->isosurface, d->vmin, d->vmax, &values, &n);
        free(values);
    }
    if (st != THX_OK) {
        char msg[512];
        snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
        return thx_error(ctx, st, "%s: %s", opt, msg);
    }
    return empty_cuts(ctx, o, d);
}

/* The range the potentials' scale covers at a frame: the picture's scope over the volume. */
static void volume_range(const thx_picture_opts *o, const thx_picture_data *d, int frame, double *lo, double *hi)
{
    if (o->scope == THX_SCOPE_FIXED) {
        *lo = o->lo;
        *hi = o->hi;
        return;
    }
    if ((o->scope == THX_SCOPE_FRAME || o->scope == THX_SCOPE_SURFACES) && d->part_size > 1) {
        *lo = d->part_lo; /* sort-last: the whole's, over the ranks (picture_part_frame_range) */
        *hi = d->part_hi;
        if (*lo <= *hi) return;
    } else if (o->scope == THX_SCOPE_FRAME || o->scope == THX_SCOPE_SURFACES) {
        const thx_series *x = d->volume;
        size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
        *lo = INFINITY;
        *hi = -INFINITY;
        picture_range_of(x->v + f * x->n_rows, x->n_rows, lo, hi);
        if (*lo <= *hi) return;
    }
    *lo = d->vmin;
    *hi = d->vmax;
}

/* The slices' triangles each with its own three vertices, valued by its tetrahedron's |J|. */
static thx_status slices_by_current(thx_ctx *ctx, thx_picture_data *d, const double *phi)
{
    const thx_field_mesh *m = d->field[SLICE];
    const thx_volume *v = d->m->volume;
    double *jt = malloc(3 * (v->n_tets ? v->n_tets : 1) * sizeof *jt);
    d->field_own[SLICE] = malloc(9 * (m->n_tris ? m->n_tris : 1) * sizeof(double));
    d->field_own_tri = malloc(3 * (m->n_tris ? m->n_tris : 1) * sizeof(int32_t));
    d->field_values[SLICE] = malloc(3 * (m->n_tris ? m->n_tris : 1) * sizeof(double));
    if (!jt || !d->field_own[SLICE] || !d->field_own_tri || !d->field_values[SLICE]) {
        free(jt);
        return thx_error(ctx, THX_ENOMEM, "out of memory (slices by |J|)");
    }
    thx_fem_currents(v, d->field_use, phi, jt, NULL);
    double jmax = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        const double *j = jt + 3 * (size_t)m->cell[t];
        double a = sqrt(j[0] * j[0] + j[1] * j[1] + j[2] * j[2]);
        if (isfinite(a) && a > jmax && (!d->part_own || d->part_own[m->cell[t]])) jmax = a;
        for (int c = 0; c < 3; c++) {
            memcpy(d->field_own[SLICE] + 9 * t + 3 * c, m->xyz + 3 * (size_t)m->tri[3 * t + c], 3 * sizeof(double));
            d->field_own_tri[3 * t + c] = (int32_t)(3 * t + (size_t)c);
            d->field_values[SLICE][3 * t + c] = a;
        }
    }
    free(jt);
    d->field_lo[SLICE] = 0;
    d->field_hi[SLICE] = jmax > 0 ? jmax : 1;
    thx_surface *s = &d->field_surf[SLICE];
    s->n_nodes = 3 * m->n_tris;
    s->xyz = d->field_own[SLICE];
    s->n_tris = m->n_tris;
    s->tri = d->field_own_tri;
    return THX_OK;
}

/* The frame's streamlines: J at the nodes (the finite elements' J per tetrahedron, volume-weighted),
 * the seeds of every specification, lines both ways by RK2, tubes round them. */
static thx_status build_streamlines(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const double *phi,
                                    double lo, double hi, int frame, thx_status st)
{
    thx_streamlines *lines = NULL;
    if (d->part_size > 1) /* sort-last: traced across the parts, the lines on rank 0 (collective: st carried) */
        st = picture_part_streamlines(ctx, o, d, phi, st, &lines);
    if (st != THX_OK) return st;
    if (d->part_size <= 1) {
        const thx_volume *v = d->m->volume;
        double *jn = malloc(3 * (v->n_nodes ? v->n_nodes : 1) * sizeof *jn);
        if (!jn) return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
        thx_fem_currents(v, d->field_use, phi, NULL, jn);
        thx_stream_field *f = NULL;
        st = thx_stream_field_create(ctx, v, jn, phi, d->field_use, &f);
        free(jn);
        double *xyz = NULL;
        long *tet = NULL;
        size_t n = 0;
        for (int k = 0; k < o->n_streamlines && st == THX_OK; k++) {
            thx_seed_spec spec;
            st = thx_seed_spec_parse(ctx, o->streamlines[k], &spec);
            if (st == THX_OK) st = thx_stream_seeds(ctx, f, &spec, &xyz, &tet, &n);
        }
        thx_stream_opts so;
        thx_stream_opts_default(&so);
        if (st == THX_OK) st = thx_streamlines_trace(ctx, f, xyz, tet, n, &so, &lines);
        free(xyz);
        free(tet);
        thx_stream_field_destroy(&f);
    }
    double radius = o->stream_radius;
    if (st == THX_OK && !(radius > 0)) {
        double blo[3], bhi[3];
        thx_picture_bounds(d, blo, bhi);
        radius = 0.004 * sqrt((bhi[0] - blo[0]) * (bhi[0] - blo[0]) + (bhi[1] - blo[1]) * (bhi[1] - blo[1]) +
                              (bhi[2] - blo[2]) * (bhi[2] - blo[2]));
    }
    if (st == THX_OK) st = thx_stream_tubes_make(ctx, lines, radius, 8, 1, &d->tubes);
    if (st == THX_OK) d->n_stream_lines = lines->n_lines;
    if (st == THX_OK && lines->n_lines && d->tubes->n_tris == 0 && !d->field_warned) {
        /* every line ended at its seed: said (once, not at every frame of a movie), not drawn in silence */
        size_t why[THX_STOP_COUNT] = {0};
        for (size_t k = 0; k < lines->n_lines; k++)
            if (lines->stop[k] >= 0 && lines->stop[k] < THX_STOP_COUNT) why[lines->stop[k]]++;
        int most = 0;
        for (int r = 1; r < THX_STOP_COUNT; r++)
            if (why[r] > why[most]) most = r;
        d->field_warned = 1;
        thx_log(ctx, THX_LOG_WARN, "--streamlines: none of the %zu lines from the seeds goes anywhere in frame %d (%zu stop at "
                "once: %s): the picture is drawn without them", lines->n_lines, frame + 1, why[most],
                thx_stream_stop_name(most));
    }
    thx_streamlines_destroy(&lines);
    if (st != THX_OK) return st;
    const thx_stream_tubes *t = d->tubes;
    d->field_values[STREAM] = malloc((t->n_vertices ? t->n_vertices : 1) * sizeof(double));
    if (!d->field_values[STREAM]) return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (t->n_vertices)
        memcpy(d->field_values[STREAM], o->stream_potential ? t->potential : t->current, t->n_vertices * sizeof(double));
    double jmax = 0;
    for (size_t i = 0; i < t->n_vertices; i++)
        if (isfinite(t->current[i]) && t->current[i] > jmax) jmax = t->current[i];
    d->field_lo[STREAM] = o->stream_potential ? lo : 0;
    d->field_hi[STREAM] = o->stream_potential ? hi : jmax > 0 ? jmax : 1;
    thx_surface *sf = &d->field_surf[STREAM];
    sf->n_nodes = t->n_vertices;
    sf->xyz = t->xyz;
    sf->n_tris = t->n_tris;
    sf->tri = t->tri;
    return THX_OK;
}

thx_status picture_field_build(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame)
{
    if (!d->volume) return THX_OK;
    /* built again for another frame, or other options (a viewer's script line may change them) */
    char key[sizeof d->field_key];
    size_t kl = (size_t)snprintf(key, sizeof key, "%s|%d|%d|%.17g|%d|%d|%.17g|%.17g|%d", o->isosurface ? o->isosurface : "",
                                 o->slice_current, o->stream_potential, o->stream_radius, o->scope, o->mapping, o->lo, o->hi,
                                 o->style);
    for (int k = 0; k < o->n_slices && kl < sizeof key; k++) kl += (size_t)snprintf(key + kl, sizeof key - kl, "|s%s", o->slices[k]);
    for (int k = 0; k < o->n_streamlines && kl < sizeof key; k++)
        kl += (size_t)snprintf(key + kl, sizeof key - kl, "|l%s", o->streamlines[k]);
    if (d->field_frame == frame && !strcmp(key, d->field_key)) return THX_OK;
    picture_field_free(d);
    if (strcmp(key, d->field_key)) d->field_warned = 0;
    memcpy(d->field_key, key, sizeof key);
    const thx_volume *v = d->m->volume;
    const thx_series *x = d->volume;
    size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
    const double *phi = x->v + f * x->n_rows;
    double lo, hi;
    volume_range(o, d, frame, &lo, &hi);
    memset(d->field_surf, 0, sizeof d->field_surf);
    snprintf(d->field_surf[ISO].name, sizeof d->field_surf[ISO].name, "equipotentials");
    snprintf(d->field_surf[SLICE].name, sizeof d->field_surf[SLICE].name, "slices");
    snprintf(d->field_surf[STREAM].name, sizeof d->field_surf[STREAM].name, "streamlines");
    d->field_surf[ISO].role = d->field_surf[SLICE].role = d->field_surf[STREAM].role = THX_ROLE_OTHER;
    thx_status st = THX_OK;
    if (o->isosurface) {
        double *values = NULL;
        size_t n = 0;
        /* percentages and counts are of the scale's range (true ends, not the symmetric ones); a
           frame of one value has none: the series' */
        double rlo = lo, rhi = hi;
        if (o->scope != THX_SCOPE_FIXED && !(rlo < rhi)) {
            rlo = d->vmin;
            rhi = d->vmax;
        }
        st = thx_field_values_parse(ctx, o->isosurface, rlo, rhi, &values, &n);
        if (st == THX_OK) st = thx_field_mesh_create(ctx, &d->field[ISO]);
        if (st == THX_OK) st = thx_field_isosurface(ctx, v, phi, values, n, d->field_use, d->field[ISO]);
        free(values);
        if (st == THX_OK) {
            const thx_field_mesh *m = d->field[ISO];
            d->field_values[ISO] = malloc((m->n_points ? m->n_points : 1) * sizeof(double));
            if (!d->field_values[ISO]) st = thx_error(ctx, THX_ENOMEM, "out of memory (equipotentials)");
            else if (m->n_points) memcpy(d->field_values[ISO], m->value, m->n_points * sizeof(double));
            d->field_surf[ISO].n_nodes = m->n_points;
            d->field_surf[ISO].xyz = m->xyz;
            d->field_surf[ISO].n_tris = m->n_tris;
            d->field_surf[ISO].tri = m->tri;
            d->field_lo[ISO] = lo;
            d->field_hi[ISO] = hi;
            if (n && m->n_tris == 0 && !d->field_warned) { /* said once, not at every frame of a movie */
                d->field_warned = 1;
                thx_log(ctx, THX_LOG_WARN, "--isosurface %s: no equipotential surface in frame %d (its values lie outside "
                        "the potentials of that frame); the picture is drawn without it", o->isosurface, frame + 1);
            }
        }
    }
    if (st == THX_OK && o->n_slices) {
        thx_field_plane planes[8];
        for (int k = 0; k < o->n_slices && st == THX_OK; k++) st = thx_field_plane_parse(ctx, o->slices[k], &planes[k]);
        if (st == THX_OK) st = thx_field_mesh_create(ctx, &d->field[SLICE]);
        if (st == THX_OK && d->part_size > 1) /* sort-last: oblique planes snap nodes at the whole's scale */
            st = thx_field_slice_scaled(ctx, v, phi, planes, (size_t)o->n_slices, d->field_use, d->part_slice_scale,
                                        d->field[SLICE]);
        else if (st == THX_OK)
            st = thx_field_slice(ctx, v, phi, planes, (size_t)o->n_slices, d->field_use, d->field[SLICE]);
        if (st == THX_OK && o->slice_current) st = slices_by_current(ctx, d, phi);
        else if (st == THX_OK) {
            const thx_field_mesh *m = d->field[SLICE];
            d->field_values[SLICE] = malloc((m->n_points ? m->n_points : 1) * sizeof(double));
            if (!d->field_values[SLICE]) st = thx_error(ctx, THX_ENOMEM, "out of memory (slices)");
            else if (m->n_points) memcpy(d->field_values[SLICE], m->value, m->n_points * sizeof(double));
            d->field_surf[SLICE].n_nodes = m->n_points;
            d->field_surf[SLICE].xyz = m->xyz;
            d->field_surf[SLICE].n_tris = m->n_tris;
            d->field_surf[SLICE].tri = m->tri;
            d->field_lo[SLICE] = lo;
            d->field_hi[SLICE] = hi;
        }
    }
    /* sort-last's streamlines are traced across the ranks: reached by every rank, whatever failed before */
    if (o->n_streamlines && (st == THX_OK || d->part_size > 1)) st = build_streamlines(ctx, o, d, phi, lo, hi, frame, st);
    if (st == THX_OK && d->part_size > 1) st = picture_part_cuts(ctx, d); /* sort-last: the own triangles drawn */
    if (st != THX_OK) {
        picture_field_free(d);
        return st;
    }
    d->field_frame = frame;
    return THX_OK;
}

size_t picture_field_surfaces(const thx_picture_opts *o, thx_picture_data *d, thx_render_surface *rs, size_t max)
{
    size_t n = 0;
    if (d->field_frame < 0) return 0;
    for (int k = 0; k < 3 && n < max; k++) {
        const thx_surface *s = &d->field_surf[k];
        if ((k < 2 ? !d->field[k] : !d->tubes) || s->n_tris == 0) continue;
        int shown = o->n_only == 0;
        for (int q = 0; q < o->n_only; q++) shown |= !strcmp(o->only[q], s->name);
        if (!shown) continue;
        thx_render_surface *r = &rs[n];
        memset(r, 0, sizeof *r);
        r->surf = s;
        r->mode = THX_DRAW_PHONG;
        r->values = d->field_values[k];
        r->normals = d->field_normals[k]; /* sort-last: the whole's (NULL: the surface's own) */
        r->n_levels = o->levels;
        r->contour_color[3] = 1;
        r->line_width = 1.5f;
        r->color[0] = r->color[1] = r->color[2] = 0.8f;
        r->color[3] = k == ISO ? 0.55f : 1.0f; /* nested equipotentials seen through each other */
        int current = (k == SLICE && o->slice_current) || (k == STREAM && !o->stream_potential);
        d->field_current[k] = (unsigned char)current;
        if (current) {
            r->cmap = THX_CMAP_VIRIDIS;
            r->style = THX_DATA_CONTINUOUS;
            thx_scale_from_range_mapped(&r->scale, THX_SCALE_LINEAR, THX_MAPPING_TRUE, d->field_lo[k], d->field_hi[k]);
        } else {
            r->cmap = (thx_colormap)o->cmap;
            r->style = k == ISO ? THX_DATA_CONTINUOUS : (thx_data_style)o->style;
            picture_scale_settings(o, d->field_lo[k], d->field_hi[k], 0, &r->scale);
        }
        for (int w = 0; w < o->n_whole; w++) r->no_clip |= !strcmp(o->whole[w], s->name);
        for (int l = 0; l < o->n_look; l++)
            if (!strcmp(o->look[l].name, s->name)) {
                r->mode = o->look[l].mode;
                if (o->look[l].opacity >= 0) r->color[3] = o->look[l].opacity;
                if (!current && o->look[l].style >= 0) r->style = o->look[l].style;
            }
        n++;
    }
    return n;
}
