/*
 * thorax/image/trace.h — a label map cut into planes and each tissue's boundary traced into the
 * contour model (paper 3.1: "one closed loop per tissue boundary per image, a layer"; issue 25
 * item 2). docs/design/image.md, "Tracing label maps", gives the algorithm and its measured accuracy.
 *
 * Tissues. A tissue is a set of label values with a surface name and role. Its region is the union
 * of its labels. The paper's nesting: a tissue of role THX_ROLE_OUTER (the torso's outer boundary)
 * also takes every other tissue's labels (whatever lies inside the body is inside its outer
 * boundary), and `all` takes every non-zero value of the map. The surfaces are boundaries of solids:
 * with THX_TRACE_HOLES_FILL (the default) a hole of a tissue in a plane (a loop of background
 * inside it, and any island inside that) is filled, so a ring of muscle gives its outer boundary,
 * and the inner boundary is the surface of the tissues inside it (the lacing builds surfaces of
 * solid loops only: thorax/geom/repair.h refuses holes wider than the node spacing). With
 * THX_TRACE_HOLES_KEEP the holes are kept as loops of the other orientation (clockwise seen
 * cranio-caudally), for readers that take them.
 *
 * Planes. Along the image's index axis nearest to superior (thx_image_axes): every image plane, or
 * planes `spacing` mm apart. Per tissue: its indicator (1 inside, 0 outside) cleaned in 3D
 * (6-connected components of fewer than min_size voxels removed; with holes kept, cavities of
 * fewer than min_size voxels filled too — with holes filled a cavity goes with the holes), smoothed by a Gaussian of sigma voxels in the plane (and across planes
 * when resampling, then interpolated linearly between the two image planes around the resampled
 * one: the trilinear interpolation of the smoothed indicator), traced by marching squares at 0.5
 * (saddle cells by the asymptotic decider: the bilinear interpolant's value at its saddle point),
 * the vertices by linear interpolation on the cell edges. The loops are resampled at node_spacing
 * by arc length (finer where that would make loops cross). A loop with no loop of its tissue
 * overlapping it on either neighbouring plane (a component one plane thick, which the lacing
 * cannot close) is dropped and counted.
 *
 * Components (organs). A tissue of an organ role (not outer, fat or muscle) whose cleaned region
 * has several 6-connected 3D components (two lungs under one label) gives one surface per
 * component: two side by side (their RAS x ranges apart) are NAME_right and NAME_left (+x is the
 * subject's right), others NAME_1, NAME_2, ... from right to left (decreasing centroid RAS x; ties in
 * the order of their first voxel in memory), in place of the tissue's surface. A component whose loops all lack a partner (one plane thick) is dropped when
 * another remains. A region that branches between planes is one component: one surface.
 *
 * Siblings. Organ tissues whose label sets are disjoint (heart and lungs; not blood in the heart,
 * whose labels are a subset) are siblings: where one's voxels face another's (a map with no voxel
 * between them), each boundary is pulled into its own tissue. The field traced at 0.5 is then
 * S(tissue) - S(siblings) (S the smoothed indicator): unchanged beyond the smoothing's reach of a
 * sibling, at 0.75 of S(tissue) at a face contact, so the two loops keep a gap (docs/design/image.md,
 * "Siblings that touch").
 *
 * Coordinates. Model axes are the image's: z along the superior index axis (pointing superior),
 * y along the index axis nearest anterior (pointing anterior), x = y cross z; the model point of
 * RAS point q is Q^T q with Q = [x y z] (a rotation). For an axis-aligned image Q = I: model
 * coordinates are RAS millimetres. The frame is +z superior, +y anterior (for an oblique image the
 * nearest axes: rep->oblique_deg says by how much). A layer's z is its plane's superior coordinate.
 */
#ifndef THORAX_IMAGE_TRACE_H
#define THORAX_IMAGE_TRACE_H

#include "thorax/image/image.h"
#include "thorax/model/contours.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const long *values;  /* the label values of the tissue (n_values of them) */
    size_t n_values;
    int all;             /* 1: every non-zero value (values may then be empty) */
    const char *name;    /* surface name ([A-Za-z0-9_.-], 1-63 characters) */
    thx_role role;
} thx_trace_tissue;

typedef enum { THX_TRACE_HOLES_FILL = 0, THX_TRACE_HOLES_KEEP = 1 } thx_trace_holes;

typedef struct {
    const thx_trace_tissue *tissues;
    size_t n_tissues;
    double spacing;       /* mm between planes; 0: every image plane */
    size_t min_size;      /* components (and cavities) of fewer voxels removed (filled); 0: none */
    double node_spacing;  /* mm between the loops' nodes; 0: the larger of the in-plane voxel size and
                             the plane spacing (the lacing's triangles then near equilateral) */
    double sigma;         /* Gaussian smoothing, voxels (the partial-volume scale); 0: none */
    int holes;            /* thx_trace_holes */
} thx_trace_opts;

/* Defaults: every image plane, min_size 8, node spacing 0 (see above), sigma 0.5, holes filled. */
void thx_trace_opts_default(thx_trace_opts *o);

#define THX_TRACE_SIZES_KEPT 16
typedef struct {
    char name[64];                  /* the surface's name (the tissue's, or NAME_right/_left/_1.. below) */
    char tissue[64];                /* the tissue (the --label) it comes from */
    size_t component, n_components; /* which of the tissue's surfaces (0-based) and how many it gave */
    size_t components_dropped;      /* its components dropped (one plane thick) */
    double centroid_ras[3];         /* the centroid of its voxels, RAS mm */
    double ras_x_range[2];          /* the RAS x range of its voxels' index box, mm */
    size_t contact_voxels;          /* its voxels with a face on a sibling tissue's voxel (pulled apart) */
    size_t n_layers, n_loops;       /* of the surface traced */
    size_t n_holes;                 /* holes met (filled, or kept as loops) */
    size_t n_holes_open;            /* filled holes whose region lies outside the tissue on a neighbouring
                                       plane (it opens there: a lung around the diaphragm's dome), where
                                       filling closes the surface over what is not the tissue */
    double z_hole_open;             /* the first such hole's plane */
    size_t n_islands_filled;        /* loops inside a filled hole */
    size_t n_tiny;                  /* loops of less than a voxel's in-plane area, dropped (min_size > 1) */
    size_t n_flat_dropped;          /* loops with no partner on either neighbouring plane, dropped */
    size_t n_trimmed_layers;        /* layers on or beyond its container's end planes, dropped (the paper's
                                       nesting: outer > fat > muscle > the organs; caps never share a plane) */
    size_t n_removed, removed_voxels; /* 3D components below min_size removed */
    size_t removed_size[THX_TRACE_SIZES_KEPT]; /* the voxel counts of the first of them */
    size_t n_cavities, cavity_voxels; /* cavities below min_size filled (holes kept only) */
    size_t voxels;                  /* voxels of the tissue after cleaning */
    double z_first, z_last;         /* its first and last layer */
    double area_sum;                /* sum of its loops' signed areas (holes negative), mm^2 */
} thx_trace_tissue_report;

typedef struct {
    size_t n_planes;                /* planes cut */
    double plane_spacing;           /* mm */
    double node_spacing;            /* mm, as used */
    double z_first;                 /* the first plane's z */
    int sup_axis;                   /* the image's index axis cut across */
    double oblique_deg;             /* angle between the model's z and RAS superior (0: axis aligned) */
    double to_ras[9];               /* Q, row-major: RAS = Q * model */
    long absent[THX_TRACE_SIZES_KEPT]; /* listed values with no voxel in the image */
    size_t n_absent;
    size_t n_tissues;               /* surfaces traced (one per tissue, or more: components) */
    thx_trace_tissue_report *tissue; /* one per surface of the contours, in their order (owned:
                                       thx_trace_report_free) */
} thx_trace_report;

/*
 * Traces the tissues of `labels` (an integral image: THX_EINPUT otherwise) into *out (created;
 * the caller destroys it): one surface per tissue in the order given, layers in increasing z,
 * spacing = the node spacing, frame RAS-like (+z +y), image_path/image_sha256 from labels. rep may
 * be NULL. THX_EINPUT, naming the tissue, when a tissue has no voxel, lies in one plane only, or
 * vanishes and reappears along the superior axis (a gap: the contour model's surfaces are one
 * stack of consecutive layers; the message gives both parts' extent and voxels, so that a larger
 * min_size can remove the stray part).
 */
thx_status thx_image_trace(thx_ctx *ctx, const thx_image *labels, const thx_trace_opts *opts, thx_contours **out,
                           thx_trace_report *rep);
void thx_trace_report_free(thx_trace_report *rep);

#ifdef __cplusplus
}
#endif
#endif
