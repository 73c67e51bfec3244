/* Internal to src/field: the one marching-tetrahedra cutter behind isosurfaces and slices. */
#ifndef THORAX_FIELD_IMPL_H
#define THORAX_FIELD_IMPL_H

#include "thorax/field/field.h"

/*
 * Cuts the tetrahedra of v (those of use_region's regions; NULL = all) where the node scalar s
 * crosses each of cuts[0..n_cuts-1] (distinct), appending to out with tag = tag0 + cut index.
 * Vertex values: iso != 0: the cut value itself; else phi interpolated along the edge (phi NULL:
 * 0). The rules of thorax/field/field.h (node at the value = above, degenerate and film triangles
 * dropped, orientation to increasing s, deterministic order) hold here. what ("potential",
 * "plane coordinate") names s in messages.
 */
thx_status field_cut(thx_ctx *ctx, const thx_volume *v, const double *s, const double *cuts, size_t n_cuts,
                     int32_t tag0, const double *phi, int iso, const unsigned char *use_region, const char *what,
                     thx_field_mesh *out);

/* Grows the mesh's arrays to hold n_points points and n_tris triangles. */
thx_status field_mesh_reserve(thx_ctx *ctx, thx_field_mesh *m, size_t n_points, size_t n_tris);
/* ... and n_cpoints contour points and n_segs segments. */
thx_status field_mesh_reserve_contours(thx_ctx *ctx, thx_field_mesh *m, size_t n_cpoints, size_t n_segs);

/* An open-addressing table from (a, b, k) keys to indices: one cut point per mesh edge (a < b)
 * or node (a == b) and value k. */
typedef struct {
    int32_t a, b, k, idx;
} field_key;
typedef struct {
    field_key *slot; /* idx < 0: empty */
    size_t mask;
} field_hash;
thx_status field_hash_init(thx_ctx *ctx, field_hash *h, size_t expected);
void field_hash_free(field_hash *h);
/* The slot for the key: slot->idx < 0 when the key is new (the caller fills it). */
field_key *field_hash_slot(field_hash *h, int32_t a, int32_t b, int32_t k);

/* Removes, among triangles [t0, n_tris) whose three vertices satisfy is_node[vertex - p0] (p0 the
 * first vertex of this cut), pairs with the same vertex set (a face reached from both sides), then
 * the vertices [p0, n_points) no triangle uses, renumbering the rest in order of first use. */
thx_status field_prune(thx_ctx *ctx, thx_field_mesh *m, size_t p0, size_t t0, const unsigned char *is_node);

#endif
