/*
 * Shared bodies of the import harnesses (tests/fuzz/fuzz_{tri,obj,stl,ply,vtk,vtp}.c
 * for surfaces, tests/fuzz/fuzz_volume_*.c for volume meshes); see fuzz.h.
 *
 * Surfaces: the input is one file, read by thx_surface_read_file with the
 * format fixed. Properties of an accepted file: at least one node, no more
 * nodes and no more triangles than the file has bytes (every node and every
 * triangle takes at least one byte of its own in each format: a text
 * number and a separator, or a binary scalar; a fan of k vertices gives
 * k - 2 triangles), finite coordinates, 0-based indices below the node
 * count; then thx_surface_import (force: the checks run, the surface comes
 * back) keeps the triangle count and stays within the nodes read.
 *
 * Volume meshes: thx_volume_import with --force and a default conductivity,
 * so that a readable mesh goes through the whole policy (regions, unused
 * nodes, orientation, surfaces, checks). Properties of an accepted mesh: no
 * more nodes or tetrahedra than the input has bytes, indices in range,
 * region numbers in the table, finite coordinates.
 */
#ifndef THORAX_TESTS_FUZZ_IMPORT_H
#define THORAX_TESTS_FUZZ_IMPORT_H

#include <math.h>

#include "fuzz.h"
#include "thorax/import/import.h"
#include "thorax/mesh/mesh.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static inline void fuzz_surface(const uint8_t *data, size_t size, const char *file, thx_import_format fmt)
{
    const char *path = fuzz_file(file, data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_surface *s = NULL;
    thx_surface_read_info info;
    if (thx_surface_read_file(ctx, path, NULL, fmt, "s", THX_ROLE_OUTER, &s, &info) == THX_OK) {
        FUZZ_ASSERT(s && s->n_nodes >= 1 && s->n_nodes <= size && s->n_tris <= size);
        FUZZ_ASSERT(info.n_nodes_read == s->n_nodes && info.n_tris_read == s->n_tris);
        for (size_t i = 0; i < 3 * s->n_nodes; i++) FUZZ_ASSERT(isfinite(s->xyz[i]));
        for (size_t i = 0; i < 3 * s->n_tris; i++) FUZZ_ASSERT(s->tri[i] >= 0 && (size_t)s->tri[i] < s->n_nodes);
        size_t nn = s->n_nodes, nt = s->n_tris;
        thx_surface_destroy(&s);
        if (nt <= 2000) {
            thx_import_opts o;
            thx_import_opts_default(&o);
            o.format = fmt;
            o.force = 1;
            thx_import_info in2;
            thx_status st = thx_surface_import(ctx, path, NULL, "s", THX_ROLE_OUTER, &o, &s, &in2);
            FUZZ_ASSERT(st == THX_OK);
            FUZZ_ASSERT(s->n_tris == nt && s->n_nodes <= nn);
            for (size_t i = 0; i < 3 * s->n_tris; i++) FUZZ_ASSERT(s->tri[i] >= 0 && (size_t)s->tri[i] < s->n_nodes);
            thx_import_info_free(&in2);
            thx_surface_destroy(&s);
        }
    }
    thx_surface_destroy(&s);
    thx_ctx_destroy(&ctx);
}

/* elem: the second file's name (a .tet or .elem beside m.pts), or NULL for a single file. */
static inline void fuzz_volume(const uint8_t *data, size_t size, const char *file, const char *elem, thx_volume_format fmt)
{
    char path[512], epath[512];
    const uint8_t *nul = elem ? memchr(data, 0, size) : NULL;
    size_t n1 = nul ? (size_t)(nul - data) : size;
    snprintf(path, sizeof path, "%s", fuzz_file(file, data, n1));
    if (elem) snprintf(epath, sizeof epath, "%s", fuzz_file(elem, nul ? nul + 1 : data, nul ? size - n1 - 1 : 0));
    thx_ctx *ctx = fuzz_ctx();
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.format = fmt;
    o.elem_path = elem ? epath : NULL;
    o.force = 1;
    thx_region_default("mean_thorax", &o.default_region);
    thx_model *m = NULL;
    thx_volume_import_info info;
    if (thx_volume_import(ctx, path, &o, &m, &info) == THX_OK) {
        const thx_volume *v = m->volume;
        FUZZ_ASSERT(v && v->n_nodes >= 4 && v->n_nodes <= size && v->n_tets >= 1 && v->n_tets <= size);
        FUZZ_ASSERT(info.n_tets_read == v->n_tets && info.n_nodes_read <= size);
        for (size_t i = 0; i < 3 * v->n_nodes; i++) FUZZ_ASSERT(isfinite(v->xyz[i]));
        for (size_t i = 0; i < 4 * v->n_tets; i++) FUZZ_ASSERT(v->tet[i] >= 0 && (size_t)v->tet[i] < v->n_nodes);
        for (size_t i = 0; i < v->n_tets; i++) FUZZ_ASSERT(v->region[i] >= 0 && (size_t)v->region[i] < v->n_regions);
        for (size_t k = 0; k < m->n_surfaces; k++) FUZZ_ASSERT(m->surf[k]->n_nodes <= v->n_nodes);
    }
    thx_volume_import_info_free(&info);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
}

#endif
