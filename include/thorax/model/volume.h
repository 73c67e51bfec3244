/*
 * thorax/model/volume.h — tetrahedral volume meshes with tissue regions (paper 3.3).
 *
 * A thx_volume is plain data:
 *   xyz      3 * n_nodes doubles (mm). Every surface node of the model is a
 *            volume node (node tables below); no two nodes coincide.
 *   tet      4 * n_tets node indices, 0-based, positively oriented in the
 *            usual right-handed sense used by VTK and Gmsh:
 *                ((p1 - p0) x (p2 - p0)) . (p3 - p0) > 0
 *            (that is thx_orient3d(p0, p1, p2, p3) < 0 in the convention of
 *            thorax/geom/predicates.h, the opposite of thorax/mesh/delaunay.h's output).
 *   region   per tetrahedron the index (0-based) of its tissue region in the
 *            region table.
 *   regions  the tissue regions: a name ("mean_thorax", "fat", "muscle",
 *            "lung_r", ...) and the conductivity of the tissue (siemens per
 *            metre): isotropic (sigma[0] = sigma[4] = sigma[8], off-diagonal
 *            0) or a full symmetric 3x3 tensor in the model's axes (row-major),
 *            with the literature source of the value.
 *   Node tables (paper 3.3: "we kept tables which described the location of
 *   each point, in terms of both the volume and surface point numbers"):
 *   surf_node[s][i]   the volume node of node i of surface s (0-based);
 *   node_surf[v], node_snode[v]   for a volume node v on a surface, that
 *                     surface's index and the node's number on it; -1 if v
 *                     is not on any surface (or is a Steiner node).
 *   steiner  the nodes added ON the surfaces by the mesher so that every
 *            surface triangle is a union of mesh faces: which triangle,
 *            barycentric coordinates (thx_steiner).
 */
#ifndef THORAX_VOLUME_H
#define THORAX_VOLUME_H

#include "thorax/model/surface.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char name[64];
    double sigma[9];     /* conductivity tensor, S/m, row-major, symmetric positive definite */
    int anisotropic;     /* 0: sigma is sigma[0] * identity */
    char source[256];    /* where the value comes from (literature reference) */
} thx_region;

/* A node added on a surface so that the surface's triangles are unions of
 * mesh faces (a Steiner point): on triangle tri of surface surf (0-based),
 * at bary[0] c0 + bary[1] c1 + bary[2] c2 of its corners (sum 1, each in
 * [0, 1]; a point on an edge has one coordinate 0). Surface data map to it
 * by these weights. */
typedef struct {
    int32_t node, surf, tri;
    double bary[3];
} thx_steiner;

typedef struct thx_volume {
    size_t n_nodes;
    double *xyz;
    size_t n_tets;
    int32_t *tet;
    int32_t *region;
    size_t n_regions;
    thx_region *regions;
    size_t n_surfaces;       /* the model's surfaces, in the model's order */
    size_t *surf_n_nodes;    /* nodes of each surface */
    int32_t **surf_node;     /* [s][i] -> volume node */
    int32_t *node_surf;      /* [v] -> surface index or -1 */
    int32_t *node_snode;     /* [v] -> node number on that surface or -1 */
    size_t n_steiner;        /* nodes added on the surfaces (node_surf -1 for them) */
    thx_steiner *steiner;
} thx_volume;

thx_status thx_volume_create(thx_ctx *ctx, thx_volume **out);
/* Frees the volume and all its arrays; accepts NULL; nulls *v. */
void thx_volume_destroy(thx_volume **v);

/* Signed volume of tetrahedron t, mm^3 (> 0 for every tetrahedron of a valid volume). */
double thx_volume_tet_volume(const thx_volume *v, size_t t);

/* A name that can name a file and a table row (a region's, a surface's): at least one character of
 * [A-Za-z0-9_.-], not starting with '.', shorter than cap (the bytes s may hold: 32 for a region,
 * 64 for a surface). */
int thx_name_ok(const char *s, size_t cap);
/* Whether a 3x3 row-major tensor is symmetric positive definite; if not, why[] says how. */
int thx_tensor_spd(const double *a, char *why, size_t size);
/* Whether a surface node and its volume node are the same point: the mesher snaps volume nodes to
 * a binary grid finer than the surfaces' 6 decimals; they agree within 1e-6 mm per coordinate. */
int thx_volume_same_node(const double *a, const double *b);

#ifdef __cplusplus
}
#endif
#endif
