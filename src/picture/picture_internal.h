/* What the picture module's files share (thorax/picture/picture.h). */
#ifndef THORAX_PICTURE_INTERNAL_H
#define THORAX_PICTURE_INTERNAL_H
#include "thorax/field/streamline.h"
#include "thorax/picture/picture.h"

/* The finite range of v[0..n) widened into *lo, *hi (picture.c). */
void picture_range_of(const double *v, size_t n, double *lo, double *hi);
/* A scale from the picture's settings: the fixed range (scope fixed), else lo..hi under the
 * scale model and mapping (true_range: the true range whatever the mapping, for maps of times);
 * swapped for --invert (picture.c). */
void picture_scale_settings(const thx_picture_opts *o, double lo, double hi, int true_range, thx_scale *sc);
/* Node labels and extrema marks over img (marks.c), for a single-panel picture drawn at img's size. */
thx_status picture_marks(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font, int frame,
                         thx_raster *img);
/* The views' frame (o->ax, o->sg) from --up/--front over the model's frame; refuses a model with
 * no frame where a named view or clip side needs one (picture_frame.c). */
thx_status picture_view_frame(thx_ctx *ctx, thx_picture_opts *o, const thx_picture_data *d);
/* The volume mesh's tetrahedra whose four nodes keep n.x + d >= 0 (cp NULL: all), their faces not
 * shared by two such tetrahedra, outward, as one new surface per tissue region that has any (named
 * after it; at most max): out[k] holds region region[k]; *n_out of them (tets.c). */
thx_status picture_tet_surfaces(thx_ctx *ctx, const thx_volume *v, const thx_clip_plane *cp, thx_surface **out,
                                int *region, int max, int *n_out);
/* Equipotential surfaces and slices (field_layers.c): picture_field_load checks the options against
 * the volume potentials read (the plane specifications, the value list) and finds their range;
 * picture_field_build makes the frame's meshes (kept until another frame is asked for);
 * picture_field_surfaces appends them to rs (at most max) as surfaces with values and scales;
 * picture_field_free frees what the two made. */
static inline int picture_has_field(const thx_picture_opts *o)
{
    return o->isosurface || o->n_slices || o->n_streamlines || o->volume_render;
}
thx_status picture_field_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d);
/* sort-last (picture_parts.c): whether this run reads its rank's part of the solution whose
 * solution.json is solution; the part read into d (the model read with its region table alone); the
 * frame's range over the ranks into d->part_lo, part_hi (collective; st this rank's status); the cuts
 * cut down to the own tetrahedra's triangles, with the normals of the whole */
struct cJSON;
int picture_part_wanted(const thx_picture_opts *o, const struct cJSON *solution);
thx_status picture_part_read(thx_ctx *ctx, const thx_picture_opts *o, const struct cJSON *solution, thx_picture_data *d);
thx_status picture_part_frame_range(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame, thx_status st);
thx_status picture_part_cuts(thx_ctx *ctx, thx_picture_data *d);
/* Sort-last's streamlines (collective, st this rank's status, carried): thx_streamlines_trace_parts on
 * the picture's part with render's options; the lines on rank 0 (*out; empty on the other ranks). */
thx_status picture_part_streamlines(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const double *phi,
                                    thx_status st, thx_streamlines **out);
void picture_part_box(const thx_picture_data *d, double box[2][3]); /* this rank's box (sides at +-inf) */
thx_status picture_field_build(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame);
size_t picture_field_surfaces(const thx_picture_opts *o, thx_picture_data *d, thx_render_surface *rs, size_t max);
void picture_field_free(thx_picture_data *d);
/* The scan under the model (scan_layer.c): picture_scan_load reads o->image and o->contours and
 * checks the planes; picture_scan_build (re)makes the planes' textures and the contour lines on
 * them when a plane, the window or the level changed; picture_scan_surfaces appends the contour
 * lines to rs (at most max) as wire surfaces; picture_scan_free frees what the three made. */
thx_status picture_scan_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d);
thx_status picture_scan_build(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d);
size_t picture_scan_surfaces(const thx_picture_data *d, thx_render_surface *rs, size_t max);
void picture_scan_free(thx_picture_data *d);
#endif
