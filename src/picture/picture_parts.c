/*
 * Sort-last's data (thorax/picture/picture.h, thx_picture_parts_settle; docs/design/parallel.md):
 * under mpirun, a picture of a solution whose volume potentials are in parts for as many ranks
 * (thorax forward --volume under mpirun, thorax/fem/parts.h) has each rank read the model's
 * surfaces and region table, and its own part of the volume: its tetrahedra, their ghosts and their
 * nodes' values. The volume's cuts are then made on the part (picture/field_layers.c), the ghosts
 * giving the cut's vertices on the part's edge the whole's normals, and only the own tetrahedra's
 * triangles are drawn. Streamlines are traced across the parts, handed from rank to rank, and drawn
 * by rank 0 (picture_part_streamlines).
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"
#include "thorax/fem/parts.h"
#include "thorax/field/field.h"
#include "thorax/field/streamline.h"
#include "thorax/parallel/parallel.h"
#include "picture/picture_internal.h"

int picture_part_wanted(const thx_picture_opts *o, const cJSON *solution)
{
    int size = thx_par_size();
    if (size < 2 || !picture_has_field(o)) return 0;
    const cJSON *vp = cJSON_GetObjectItem(solution, "volume_parts"), *r = vp ? cJSON_GetObjectItem(vp, "ranks") : NULL;
    return cJSON_IsNumber(r) && r->valuedouble == size;
}

/* What sort-last cannot draw exactly, refused before anything is read further. */
static thx_status part_refusals(thx_ctx *ctx, const thx_picture_opts *o)
{
    const char *what = o->clip[0] ? "--clip" : o->panels ? "--panels" : o->arrows ? "--arrows" : o->image ? "--image" : o->tetrahedra ? "--tetrahedra"
                     : o->n_landmarks ? "--landmarks" : o->n_electrodes ? "--electrodes"
                     : NULL;
    if (what)
        return thx_error(ctx, THX_EINPUT, "%s: not drawn by sort-last rendering (each rank its part of %s's volume): run it "
                         "with one process, or on a number of ranks other than the parts'", what, o->solution);
    for (int k = 0; k < o->n_streamlines; k++) { /* random seeds are drawn over the whole volume at once */
        thx_seed_spec sp;
        if (thx_seed_spec_parse(ctx, o->streamlines[k], &sp) == THX_OK && (sp.kind == THX_SEED_REGION || sp.kind == THX_SEED_DENSITY))
            return thx_error(ctx, THX_EINPUT, "--streamlines %s: %s seeds are drawn at random over the whole volume, not by "
                             "sort-last rendering (each rank its part of %s's volume): give point:, line: or sphere: seeds, "
                             "or run it with one process", o->streamlines[k], sp.kind == THX_SEED_REGION ? "region" : "density",
                             o->solution);
    }
    if (o->renderer == 1 && !o->volume_render)
        return thx_error(ctx, THX_EINPUT, "sort-last rendering of %s's parts traces only the volume (--volume); draw the cuts "
                         "with OpenGL (thorax render, --renderer gl)", o->solution);
    if (o->volume_render && (o->isosurface || o->n_slices))
        return thx_error(ctx, THX_EINPUT, "--volume: sort-last volume rendering of %s's parts draws the volume alone (the "
                         "ranks' layers are blended, not depth-tested): leave out --slice and --isosurface", o->solution);
    if (o->volume_render && (o->environment || o->rt.shutter > 0))
        return thx_error(ctx, THX_EINPUT, "%s: not drawn by sort-last volume rendering of %s's parts",
                         o->environment ? "--environment" : "--motion-blur", o->solution);
    return THX_OK;
}

thx_status picture_part_read(thx_ctx *ctx, const thx_picture_opts *o, const cJSON *solution, thx_picture_data *d)
{
    THX_CHECK(part_refusals(ctx, o));
    int rank = thx_par_rank(), size = thx_par_size();
    thx_volume *v = d->m->volume;
    if (!v) return thx_error(ctx, THX_EINPUT, "%s: the model %s has no volume mesh", o->solution, d->model_dir);
    const cJSON *vp = cJSON_GetObjectItem(solution, "volume_parts"), *dir = cJSON_GetObjectItem(vp, "manifest");
    thx_fem_part p;
    THX_CHECK(thx_fem_part_open(ctx, o->solution, cJSON_IsString(dir) ? dir->valuestring : NULL, rank, size, v->n_regions,
                                &p, d->part_unit, sizeof d->part_unit));
    thx_status st = thx_series_create(ctx, p.n_nodes, p.n_frames, &d->volume);
    if (st == THX_OK && !(d->part_own = malloc(p.n_tets ? p.n_tets : 1))) st = thx_error(ctx, THX_ENOMEM, "out of memory (part)");
    if (st != THX_OK) {
        thx_fem_part_free(&p);
        return st;
    }
    free(d->volume->v); /* the part's values taken as they are (frame after frame, as a series holds them) */
    d->volume->v = p.values;
    p.values = NULL;
    snprintf(d->volume->unit, sizeof d->volume->unit, "%s", d->part_unit);
    for (size_t t = 0; t < p.n_tets; t++) d->part_own[t] = (uint32_t)p.owner[t] == p.rank;
    /* the part becomes the model's volume: its nodes and tetrahedra, the model's regions */
    v->n_nodes = p.n_nodes;
    v->xyz = p.xyz;
    v->n_tets = p.n_tets;
    v->tet = p.tet;
    v->region = p.region;
    d->part_cuts = p.cuts;
    d->part_node = p.node; /* the streamlines' exchanges name nodes and tetrahedra by their numbers in the whole */
    d->part_tet_id = p.tet_id;
    d->part_owner = p.owner;
    p.node = p.tet_id = p.owner = NULL;
    p.xyz = NULL;
    p.tet = NULL;
    p.region = NULL;
    p.cuts = NULL;
    thx_fem_part_free(&p);
    d->part_jmax = NAN;
    d->part_rank = rank;
    d->part_size = size;
    return THX_OK;
}

thx_status thx_picture_parts_settle(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_status st)
{
    if (thx_par_size() < 2) return st;
    /* the same collectives on every rank, whatever it read: its extremes, or none */
    double v[2 + 2 * 8 + 1];
    for (int k = 0; k < 19; k++) v[k] = -INFINITY;
    int parts = st == THX_OK && d->part_size > 1;
    if (parts) {
        v[0] = -d->vmin;
        v[1] = d->vmax;
        v[18] = thx_field_slice_scale(d->m->volume); /* the slices' snapping scale: the whole's, the largest */
        for (int k = 0; k < o->n_slices && k < 8; k++) {
            thx_field_plane p;
            if (thx_field_plane_parse(ctx, o->slices[k], &p) != THX_OK) continue; /* (refused by the check below) */
            double lo, hi;
            thx_field_plane_span(d->m->volume, d->field_use, &p, &lo, &hi);
            v[2 + 2 * k] = -lo;
            v[3 + 2 * k] = hi;
        }
    }
    st = thx_par_max(ctx, st, v, 19);
    if (st != THX_OK || !parts) return st;
    d->vmin = -v[0];
    d->vmax = v[1];
    for (int k = 0; k < 8; k++) d->part_span[k][0] = -v[2 + 2 * k], d->part_span[k][1] = v[3 + 2 * k];
    d->part_slice_scale = v[18];
    if (!(d->vmin <= d->vmax)) st = thx_error(ctx, THX_EINPUT, "the solution's volume potentials hold no finite value");
    if (st == THX_OK) st = thx_picture_cuts_check(ctx, o, d);
    return thx_par_agree(ctx, st, NULL);
}

thx_status picture_part_frame_range(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame, thx_status st)
{
    double r[2] = {-INFINITY, -INFINITY};
    if (st == THX_OK) {
        const thx_series *x = d->volume;
        size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
        double lo = INFINITY, hi = -INFINITY;
        picture_range_of(x->v + f * x->n_rows, x->n_rows, &lo, &hi);
        r[0] = -lo;
        r[1] = hi;
    }
    st = thx_par_max(ctx, st, r, 2);
    d->part_lo = -r[0];
    d->part_hi = r[1];
    d->part_frame = frame;
    return st;
}

thx_status picture_part_cuts(thx_ctx *ctx, thx_picture_data *d)
{
    for (int k = 0; k < 2; k++) {
        free(d->field_normals[k]);
        free(d->field_part_tri[k]);
        d->field_normals[k] = NULL;
        d->field_part_tri[k] = NULL;
        thx_surface *s = &d->field_surf[k];
        if (!d->field[k] || !s->n_tris) continue;
        const int32_t *cell = d->field[k]->cell; /* per triangle of field[k]: slices by |J| keep their order */
        /* the normals summed over every triangle, ghosts' included, as the renderer sums them */
        double *acc = calloc(3 * s->n_nodes + 1, sizeof *acc);
        int32_t *own = malloc(3 * s->n_tris * sizeof *own);
        if (!acc || !own) {
            free(acc);
            free(own);
            return thx_error(ctx, THX_ENOMEM, "out of memory (the part's cuts)");
        }
        thx_surface_normal_sums(s, acc);
        size_t n = 0;
        for (size_t t = 0; t < s->n_tris; t++)
            if (d->part_own[cell[t]]) memcpy(own + 3 * n++, s->tri + 3 * t, 3 * sizeof *own);
        d->field_normals[k] = acc;
        d->field_part_tri[k] = own;
        s->tri = own;
        s->n_tris = n;
    }
    return THX_OK;
}

void picture_part_box(const thx_picture_data *d, double box[2][3])
{
    thx_fem_cut_box((const thx_fem_cut *)d->part_cuts, d->part_size, d->part_rank, box);
}

/* ---- streamlines on the parts (docs/design/parallel.md, "Streamlines on the parts") ---- */

thx_status picture_part_streamlines(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const double *phi,
                                    thx_status st, thx_streamlines **out)
{
    thx_seed_spec spec[64];
    int n_spec = o->n_streamlines < 64 ? o->n_streamlines : 64;
    for (int k = 0; k < n_spec && st == THX_OK; k++) st = thx_seed_spec_parse(ctx, o->streamlines[k], &spec[k]);
    thx_stream_part part = {d->part_own, d->part_node, d->part_tet_id, d->part_owner, d->part_rank};
    thx_stream_opts so;
    thx_stream_opts_default(&so);
    const thx_volume *v = d->m->volume; /* J at the part's nodes from its own tetrahedra and ghosts */
    double *jn = malloc((3 * v->n_nodes + 1) * sizeof *jn);
    if (st == THX_OK && !jn) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK) thx_fem_currents(v, d->field_use, phi, NULL, jn);
    st = thx_streamlines_trace_parts(ctx, v, &part, d->field_use, phi, jn, spec, n_spec, &so, o->solution, st, out);
    free(jn);
    return st;
}
