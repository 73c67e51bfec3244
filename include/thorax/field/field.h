/*
 * thorax/field/field.h — inside the volume (paper 4.3, "Volume potentials and vector flow"):
 * equipotential surfaces and slices of a tetrahedral volume's potentials, as triangle meshes
 * with data, and contour lines on them (field layer, level 4; docs/decisions.md, "Slices and
 * equipotential surfaces (issue 16)").
 *
 * Both cuts are the same operation: a scalar s per volume node (the potential for an
 * equipotential surface, n.x - d for a plane) cut at a value c through every tetrahedron, the
 * cut exact because s is linear on a tetrahedron (P1 data). Invariants of the output mesh:
 *   - one vertex per cut mesh edge and value (or per mesh node when the cut passes through a
 *     node), so neighbouring tetrahedra share their vertices: the surface is conforming, and
 *     closed where it does not reach the volume's boundary (or the boundary of the regions cut);
 *   - a node whose s equals c exactly counts as above c (symbolic perturbation s + eps), so
 *     every tetrahedron is cut or not without a tolerance; triangles made degenerate by it (two
 *     corners on one node) are dropped, and a face of the mesh lying in the cut, reached from
 *     both sides, is dropped twice over (it bounds a film of no thickness): no hole, no
 *     duplicate face, no zero-area triangle from that rule;
 *   - every triangle's normal (right-hand rule on its corner order) points to increasing s:
 *     along +grad phi for an equipotential surface, along +n for a plane;
 *   - triangles come in the order of the values (planes), then of the tetrahedra; vertices in
 *     the order they are first used. The output is the same for any thread count.
 * Indices are 0-based; coordinates in mm, potentials in the series' unit.
 */
#ifndef THORAX_FIELD_FIELD_H
#define THORAX_FIELD_FIELD_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"
#include "thorax/model/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * A cut of the volume: triangles with a value per vertex, and optional contour segments.
 *   xyz, value   n_points vertices (3 doubles, mm) and the potential there (interpolated along
 *                the cut tetrahedron edge: exact for P1 data; for an equipotential surface the
 *                requested value itself);
 *   tri          3 * n_tris vertex indices, counterclockwise seen from the side s increases to;
 *   tag          per triangle the index of its value (isosurface) or plane (slice) in the list
 *                the caller gave;
 *   cell         per triangle the tetrahedron it lies in (0-based), for cell data such as |J|;
 *   cxyz, cvalue n_cpoints contour points (their own vertices, not the triangles');
 *   seg          2 * n_segs contour point indices, with the side of greater potential on the
 *                left seen from the triangle's normal side;
 *   seg_tag      per segment the index of its contour value; seg_tri the triangle it crosses.
 * Owned by the mesh; thx_field_mesh_destroy frees it all.
 */
typedef struct thx_field_mesh {
    size_t n_points;
    double *xyz;
    double *value;
    size_t n_tris;
    int32_t *tri;
    int32_t *tag;
    int32_t *cell;
    size_t n_cpoints;
    double *cxyz;
    double *cvalue;
    size_t n_segs;
    int32_t *seg;
    int32_t *seg_tag;
    int32_t *seg_tri;
} thx_field_mesh;

/* An empty mesh. Caller destroys it. */
thx_status thx_field_mesh_create(thx_ctx *ctx, thx_field_mesh **out);
/* Frees the mesh; accepts NULL; nulls *m. */
void thx_field_mesh_destroy(thx_field_mesh **m);
/* Empties the mesh (triangles and contours), keeping nothing. */
void thx_field_mesh_clear(thx_field_mesh *m);
/* Appends src's triangles and contours to dst, src's tags increased by tag_offset. */
thx_status thx_field_mesh_append(thx_ctx *ctx, thx_field_mesh *dst, const thx_field_mesh *src, int32_t tag_offset);
/* Grows the mesh's point and triangle arrays to hold n_points and n_tris (the counts unchanged):
 * for a caller that fills a mesh itself (the cut of a volume in parts put together on one rank). */
thx_status thx_field_mesh_reserve(thx_ctx *ctx, thx_field_mesh *m, size_t n_points, size_t n_tris);
/* Total area of the triangles with tag == tag (tag < 0: all), mm^2. */
double thx_field_mesh_area(const thx_field_mesh *m, int tag);

/* A plane n.x = d (n a unit vector) and a point on it (origin = d n unless given). */
typedef struct {
    double n[3];
    double d;
    double origin[3];
} thx_field_plane;

/*
 * Parses a plane: "x=MM", "y=MM", "z=MM" (normal along the axis), or "PX,PY,PZ:NX,NY,NZ" (a
 * point and a normal, any length but not zero). THX_EINPUT with a message naming what.
 */
thx_status thx_field_plane_parse(thx_ctx *ctx, const char *spec, thx_field_plane *p);

/*
 * Parses a list of values to cut at, relative to a range [lo, hi] (a frame's potentials):
 *   "-5,0,5"     the values themselves ("0": the zero equipotential; a number is always a value);
 *   "count:10"   a count: 10 values evenly inside the range, ends excluded (lo + k (hi-lo)/11);
 *   "25%,50%"    percentages of the range (lo + p/100 (hi - lo)), each in [0, 100].
 * Mixing percentages and plain values is allowed item by item. *values (n of them) is the
 * caller's (free). Values must be finite and distinct; a count between 1 and 1000. (Before issue
 * 24 a lone integer was a count, so "--isosurface 0" was refused as a count of none.)
 */
thx_status thx_field_values_parse(thx_ctx *ctx, const char *spec, double lo, double hi, double **values, size_t *n);

/*
 * The values of a list that are numbers, not counts or percentages (those the range does not
 * move): *n of them into *values (caller frees; NULL when none). Used to tell, before cutting,
 * that a value lies outside every frame's potentials (issue 24).
 */
thx_status thx_field_values_explicit(thx_ctx *ctx, const char *spec, double **values, size_t *n);

/*
 * The signed distances of the plane to the nodes of the tetrahedra of the regions with use[r]
 * set (NULL = all), their least in *dmin and largest in *dmax (mm; +inf, -inf when no tetrahedron
 * is used). The plane cuts those regions iff dmin <= 0 <= dmax.
 */
void thx_field_plane_span(const thx_volume *v, const unsigned char *use, const thx_field_plane *p, double *dmin,
                          double *dmax);

/*
 * Equipotential surfaces of phi (v->n_nodes values, one frame) at values[0..n_values-1] by
 * marching tetrahedra, appended to out (tag = value index, cell = tetrahedron). use_region
 * (v->n_regions flags, NULL = all) restricts the cut to those regions' tetrahedra: the surface
 * then ends at their boundary. THX_EINPUT for a non-finite phi at a node of a cut region or a
 * non-finite value.
 */
thx_status thx_field_isosurface(thx_ctx *ctx, const thx_volume *v, const double *phi, const double *values,
                                size_t n_values, const unsigned char *use_region, thx_field_mesh *out);

/*
 * Slices: the volume cut by planes[0..n_planes-1] exactly through each tetrahedron (a triangle
 * or a quadrilateral, made two triangles), phi interpolated to the vertices (tag = plane index).
 * phi may be NULL (geometry only: value 0). use_region as for thx_field_isosurface.
 */
thx_status thx_field_slice(thx_ctx *ctx, const thx_volume *v, const double *phi, const thx_field_plane *planes,
                           size_t n_planes, const unsigned char *use_region, thx_field_mesh *out);

/*
 * The same, with the scale of the snapping tolerance given. Planes oblique to the axes snap onto
 * themselves the nodes whose n.x lies within 16 eps max(scale, |d|) of d (n.x rounds; a node laid
 * on the plane must stay on it); thx_field_slice takes as scale the largest |coordinate| of v's
 * nodes (thx_field_slice_scale). A part of a volume (thorax/fem/parts.h) passes the whole's, so that
 * its cut is the whole's around each of its tetrahedra.
 */
thx_status thx_field_slice_scaled(thx_ctx *ctx, const thx_volume *v, const double *phi, const thx_field_plane *planes,
                                  size_t n_planes, const unsigned char *use_region, double scale, thx_field_mesh *out);
/* The largest |coordinate| of v's nodes (0 for none): thx_field_slice's scale. */
double thx_field_slice_scale(const thx_volume *v);

/*
 * Contour lines of the mesh's vertex values at values[0..n_values-1] by marching triangles over
 * its triangles (exact for values linear on each triangle), appended as segments (seg_tag =
 * value index, seg_tri = triangle). One contour point per cut triangle edge and value; a vertex
 * exactly at a value counts as above it, as in the volume cut.
 */
thx_status thx_field_contours(thx_ctx *ctx, thx_field_mesh *m, const double *values, size_t n_values);

/*
 * Writers (docs/formats.md, "Slices and equipotential surfaces"). Every file is written
 * atomically and claimed first: an existing file is replaced only when it is thorax's own field
 * output (its second line carries "thorax field").
 *
 * VTK XML PolyData (.vtp), binary appended, Float64: points (the triangles' vertices, then the
 * contour points), polys, lines (the contour segments); point data "potential"; cell data (polys
 * then lines) per the caller's cell arrays below plus "tetrahedron" (Int32, 0-based source
 * tetrahedron; -1 on a line); field data "TimeValue" when has_time.
 */
typedef struct {
    const char *tag_name[2];    /* cell data names of tag_value[i][tag] ("iso_value", "plane"), NULL: none */
    const double *tag_value[2]; /* per tag: the value written for its triangles (and the lines on them) */
    const double *cell_scalar;  /* per tetrahedron of the volume: written per triangle (e.g. |J|), or NULL */
    const char *cell_scalar_name; /* its name ("current_magnitude") */
    const double *seg_value;    /* per contour value index: written per line as "contour_value", or NULL */
    int has_time;
    double time;
} thx_field_write_opts;

/* The claim alone (nothing written): path may be written by thx_field_mesh_write_vtp/obj. */
thx_status thx_field_claim(thx_ctx *ctx, const char *path);
thx_status thx_field_mesh_write_vtp(thx_ctx *ctx, const thx_field_mesh *m, const thx_field_write_opts *o,
                                    const char *path);
/* Wavefront OBJ: v lines (mm), one group per tag (tag_names[tag]: one word each, n_tags of them;
 * NULL: "cut_TAG", 1-based), f lines (1-based), then "g contours" and l lines; the potential is not
 * carried (OBJ has no vertex data): a comment says so. */
thx_status thx_field_mesh_write_obj(thx_ctx *ctx, const thx_field_mesh *m, const char *const *tag_names, size_t n_tags,
                                    const char *path);

#ifdef __cplusplus
}
#endif
#endif
