/*
 * thorax/io/export_data.h — exports that carry data: potentials, currents, region names and
 * conductivities, written for ParaView (VTK XML .vtu/.vtp, legacy .vtk, a .pvd collection over
 * time) and Gmsh (MSH 4.1 with tagged boundary surfaces and $NodeData/$ElementData views)
 * (io layer; the geometry-only exports are thorax/io/model_dir.h; docs/formats.md, "Exports with
 * data").
 *
 * The io layer writes what it is given: the caller (thorax export) reads the series, picks the
 * frames and computes the currents (thorax/fem/fem.h, thx_fem_currents), and hands each frame's
 * arrays here. Every file is written atomically and claimed first (thx_export_claim's rule: an
 * existing file is replaced only when it is thorax's own export of that kind).
 *
 * Every VTK file carries, besides the caller's arrays:
 *   field data  "TimeValue" (Float64, 1 tuple; the frame's time in the series' time unit) when a
 *               time is given; "surface_name" (String, one per surface of the model, in model
 *               order); for a volume "region_name" (String) and "region_sigma" (Float64, 9
 *               components: the region's conductivity tensor, S/m, row-major), one tuple per
 *               region in region-table order (region id = tuple index + 1);
 *   volume (.vtu)  point data "surface", "surface_node" (the node tables, as the plain export);
 *               cell data "region" (Int32, 1-based id), "conductivity" (Float64, S/m: the
 *               isotropic value, or a third of the tensor's trace) and, in the geometry-only
 *               export (no frame) when a region is anisotropic, "conductivity_tensor" (Float64, 9
 *               components; per frame it would double each file: region_sigma holds it);
 *   surface (.vtp, .vtk)  cell data "surface" (Int32, the surface's 1-based index).
 */
#ifndef THORAX_IO_EXPORT_DATA_H
#define THORAX_IO_EXPORT_DATA_H

#include <stdint.h>

#include "thorax/io/model_dir.h"
#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One named array on the points (nodes) or the cells (tetrahedra, triangles) of an export:
 * n_comp values per point or cell (1 scalar, 3 vector, 9 tensor), tuple after tuple. Borrowed. */
typedef struct {
    const char *name; /* printable ASCII without '"', '<', '>', '&' (checked) */
    int n_comp;
    const double *v;
} thx_export_array;

/* The data of one export file: its time (has_time) and its arrays. Borrowed. */
typedef struct {
    int has_time;
    double time;
    const thx_export_array *point;
    size_t n_point;
    const thx_export_array *cell;
    size_t n_cell;
} thx_export_frame;

/*
 * The model's volume as a VTK XML UnstructuredGrid (.vtu) with the arrays above and fr's (NULL:
 * none); point arrays have m->volume->n_nodes tuples, cell arrays n_tets. Binary: every array is
 * raw little-endian appended data (Float64 points in mm, Int32 connectivity 0-based in
 * volume.tet's order, right-handed), field data inline ASCII. Byte-identical for the same input.
 */
thx_status thx_volume_export_vtu(thx_ctx *ctx, const thx_model *m, const thx_export_frame *fr, const char *path);

/*
 * Surface s of the model as VTK XML PolyData (fmt THX_EXPORT_VTP, binary as above) or legacy VTK
 * ASCII POLYDATA (THX_EXPORT_VTK: POINT_DATA / CELL_DATA arrays as SCALARS (1 component),
 * VECTORS (3) or FIELD arrays, values "%.17g"; FIELD FieldData with the same field arrays, the
 * strings one a line). Point arrays have the surface's n_nodes tuples, cell arrays n_tris.
 */
thx_status thx_surface_export_data(thx_ctx *ctx, const thx_model *m, size_t s, thx_export_format fmt,
                                   const thx_export_frame *fr, const char *path);

/*
 * A ParaView collection (.pvd): n datasets, files[i] (relative to the .pvd's directory) at
 * times[i] (strictly increasing). The file carries the comment "thorax collection" (its claim
 * signature). Claimed like the exports.
 */
thx_status thx_export_pvd(thx_ctx *ctx, const char *path, const char *const *files, const double *times, size_t n);
/* The claim alone for a .pvd (thx_export_claim's rule with the .pvd signature). */
thx_status thx_export_pvd_claim(thx_ctx *ctx, const char *path);

/*
 * A Gmsh view: values per frame on a subset of the volume's nodes ($NodeData) or of its
 * tetrahedra ($ElementData). ids[i] (0-based volume node or tetrahedron, NULL = 0..n-1 in order)
 * carries values(user, frame, out)[i * n_comp ...]; out holds n * n_comp doubles. time[f] is
 * frame f's time (the view's time steps 0..n_frames-1).
 */
typedef struct {
    const char *name; /* the view's name (printable ASCII without '"') */
    int on_cells;     /* 0: nodes, 1: tetrahedra */
    int n_comp;       /* 1 or 3 */
    size_t n;
    const int32_t *ids;
    size_t n_frames;
    const double *time;
    void (*values)(void *user, size_t frame, double *out);
    void *user;
} thx_msh_view;

/*
 * The model's volume as Gmsh MSH 4.1 ASCII with its surfaces tagged: physical groups of
 * dimension 3 (tag = region id, the region's name) and 2 (tag = surface index + 1, the surface's
 * name); one volume entity per region and one surface entity per surface; the tetrahedra (type
 * 4, element tags = volume.tet line numbers) and, per surface, the faces of the tetrahedra that
 * lie on it (type 2, counterclockwise seen from outside the surface, element tags after the
 * tetrahedra): the surface's triangles themselves, or their pieces where the mesher put Steiner
 * nodes on them (found from the node tables and v->steiner, exactly). Then each view as
 * $NodeData / $ElementData sections, one per frame (string tag: name; real tag: time; integer
 * tags: step, components, count). Node tags = volume node numbers. Byte-identical for the same
 * input. A surface whose triangles are not all covered by faces of the tetrahedra (a mesh that
 * does not conform to it) is written as its own triangles on their volume nodes, with a warning.
 */
thx_status thx_volume_export_msh(thx_ctx *ctx, const thx_model *m, const thx_msh_view *views, size_t n_views,
                                 const char *path);

#ifdef __cplusplus
}
#endif
#endif
