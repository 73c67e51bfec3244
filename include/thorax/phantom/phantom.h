/*
 * thorax/phantom/phantom.h — a synthetic, anatomically plausible human thorax, delivered
 * the way the paper's model started (section 3.1): as hand-digitized contours.
 *
 * Six surfaces, in this order (name, role, cap):
 *   torso   outer   grid     outer boundary of the torso
 *   fat     fat     grid     subcutaneous fat / skeletal muscle interface
 *   muscle  muscle  grid     inner border of the skeletal muscle
 *   lung_r  lung    polygon  right lung (subject's right, +x)
 *   lung_l  lung    polygon  left lung (smaller: cardiac notch)
 *   heart   heart   grid     epicardium
 * Nesting, on every layer: heart, lung_r and lung_l lie strictly inside muscle,
 * muscle inside fat inside torso, lungs and heart pairwise disjoint; the smooth
 * outlines keep at least THX_PHANTOM_MIN_GAP mm between any two surfaces, and
 * inner surfaces start and end at least one layer inside their container, so
 * no two caps share a plane. The lower lung layers are crescents whose concave
 * medial side wraps the heart and the diaphragm domes (the case of paper 3.2,
 * Figure 2B, that lacing must handle).
 *
 * Digitization imitates a person with a mouse (paper 3.1, "inevitably jagged
 * hand-digitized point set"; 3.2 "Manual editing": layer shifts from breathing):
 * uneven point spacing (closer where the outline bends), jitter normal to the
 * outline, a random start point, a random direction per loop, and a random
 * (x, y) shift of each whole layer. Jitter and shifts are bounded (2.5 sigma)
 * so that they can never close a gap.
 *
 * Anatomy (z in mm; layer k at z = 5 k): torso z = 0..270 (55 layers), fat
 * 10..260, muscle 20..250, right lung 30..240, left lung 30..230, heart
 * 60..160. Torso about 330 x 215 mm at mid-chest, flattened back with a spine
 * groove; fat 9-13 mm, muscle 12-22 mm thick (more at the back and toward the
 * shoulders); the heart an ellipsoid (long axis 124 mm) left and anterior,
 * apex anterior-left-inferior.
 *
 * Resolutions (paper 3.3, the two models of one set of scans):
 *   THX_PHANTOM_HIGH    every layer, 5 mm apart, "spacing 5": estimated
 *                       ~42,700 nodes, ~85,300 triangles (paper: 42,000 / 85,000);
 *   THX_PHANTOM_MEDIUM  every second layer (10 mm), "spacing 11": estimated
 *                       ~9,600 nodes, ~19,200 triangles (paper: 11,000 / 19,000).
 * The paper's medium pair is not consistent for closed surfaces (T = 2 V - 4:
 * 11,000 nodes would make 22,000 triangles); the same anatomy cannot give
 * 42,000 nodes at 5 mm and 11,000 at 11 mm either (the node count scales with
 * (5/11) * (1/2)), so the phantom meets both triangle counts and the high node
 * count, and stays ~13% under the medium node count.
 * The layers of the medium phantom are exactly the even layers of the high
 * phantom of the same seed: each loop is drawn from its own random stream,
 * keyed by (seed, layer, surface).
 *
 * Determinism: the same options give identical contours on every platform with
 * IEEE doubles (a private splitmix64 generator; never rand()).
 * Coordinates RAS, millimetres (see geom.h); layer k lies at z = 5 k.
 */
#ifndef THORAX_PHANTOM_PHANTOM_H
#define THORAX_PHANTOM_PHANTOM_H

#include "thorax/model/contours.h"
#include "thorax/model/electrodes.h"
#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { THX_PHANTOM_HIGH = 0, THX_PHANTOM_MEDIUM = 1 };

/* Number of surfaces of the phantom, and the smallest distance (mm) between the
 * smooth outlines of any two surfaces on any layer (before jitter). */
#define THX_PHANTOM_N_SURFACES 6
#define THX_PHANTOM_MIN_GAP 6.5

typedef struct {
    int resolution;      /* THX_PHANTOM_HIGH or THX_PHANTOM_MEDIUM (default MEDIUM) */
    unsigned long seed;  /* random seed (default 1) */
    double jitter_mm;    /* standard deviation of the point jitter normal to the outline
                            (default 0.6; bounded at 2.5 sigma, at most 1.5 mm) */
    double shift_mm;     /* standard deviation of each layer's (x, y) shift (default 1.0;
                            bounded at 2.5 sigma) */
} thx_phantom_opts;

/* Fills the defaults listed above. */
void thx_phantom_opts_default(thx_phantom_opts *o);

/* Node spacing (mm) written as the file's "spacing": 5 (high) or 11 (medium). */
double thx_phantom_spacing(int resolution);

/* Builds the digitized contours. spacing is set to thx_phantom_spacing();
 * cap grids use the resampling spacing (cap_grid = 0). The result passes
 * thx_contours_validate. Caller destroys *out. Errors: THX_EINPUT for bad
 * options, THX_EINTERNAL if the phantom breaks its own invariants (a bug). */
thx_status thx_phantom_contours(thx_ctx *ctx, const thx_phantom_opts *o, thx_contours **out);

/* Expected size of the surface model built from the phantom, from its smooth
 * (un-jittered) outlines, following the surface builder's rules:
 *   each loop is resampled into max(3, round(L / S)) nodes (L its perimeter,
 *   S the spacing); a grid cap adds about area / S^2 nodes, a polygon cap none;
 *   a closed surface of V nodes has 2 V - 4 triangles. */
typedef struct {
    char name[16];
    int first_layer, last_layer; /* layer indices k (z = 5 k) of the end loops */
    size_t layers;               /* layers used at this resolution */
    size_t loop_nodes, cap_nodes, nodes, triangles;
} thx_phantom_surface_count;

typedef struct {
    size_t layers;               /* distinct layers at this resolution */
    size_t loops;                /* loops digitized */
    size_t loop_nodes, cap_nodes;
    size_t nodes, triangles;     /* totals over the surfaces */
    double min_gap;              /* smallest distance between smooth outlines on a layer, mm */
    thx_phantom_surface_count surf[THX_PHANTOM_N_SURFACES];
} thx_phantom_counts;

/* Computes the estimate above for o->resolution (the seed does not matter). */
thx_status thx_phantom_estimate(thx_ctx *ctx, const thx_phantom_opts *o, thx_phantom_counts *out);

/*
 * The phantom's electrodes on its outer surface (the model built from
 * `thorax phantom` contours): the standard 12-lead positions (RA, LA, LL at
 * the shoulders and the left hip end of the torso as limb-lead proxies, the
 * Mason-Likar convention; V1-V6 at the precordial landmarks: 4th intercostal
 * space either side of the sternum, V4 5th space mid-clavicular, V5 anterior
 * axillary, V6 mid-axillary, all at the height of V4 for V5/V6), each the
 * surface node nearest its landmark; and a body-surface-mapping array of
 * n_array electrodes (default 192: 16 columns evenly around the torso at 12
 * heights over the thorax), named A001...
 */
thx_status thx_phantom_electrodes(thx_ctx *ctx, const thx_model *m, thx_electrodes **leads12, size_t n_array,
                                  thx_electrodes **array);

/*
 * The phantom's epicardial potentials: a current dipole at the centre of
 * the heart, in an unbounded homogeneous medium of conductivity sigma,
 * tracing a vectorcardiographic loop (P, QRS and T loops with physiological
 * timing and amplitudes) sampled every dt ms; potentials in mV at the nodes
 * of the heart surface (rows: the heart surface's nodes in order).
 */
typedef struct {
    size_t n_frames;  /* default 500 (500 ms at 1 ms) */
    double dt_ms;     /* default 1 */
    double sigma;     /* S/m, default 0.2 */
    double peak_mv;   /* largest |potential| on the heart surface over the beat, mV: when > 0 it sets the
                         dipole's scale; 0 (the default): dipole_mam does */
    double dipole_mam; /* the dipole moment at the QRS peak, mA m (default 0.016: lead II peaks at about
                          1.5 mV on the phantom; docs/decisions.md, "The phantom's ECG amplitudes") */
} thx_beat_opts;

void thx_beat_opts_default(thx_beat_opts *o);
/* The dipole moment at frame f (time f * o->dt_ms; 3 values, RAS) for the default loop shape, in units
 * where |p| = 1 at the QRS peak (o may be NULL: dt 1 ms). thx_phantom_epicardial places it at the centroid
 * of the heart's enclosed volume and multiplies it by dipole_mam (or by the factor that gives peak_mv);
 * the series' label reports the moment and the place. */
void thx_beat_dipole(const thx_beat_opts *o, size_t f, double p[3]);
thx_status thx_phantom_epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_beat_opts *o, thx_series **out);

/*
 * Electrodes and the beat on any torso, in its anatomical frame (thorax/model/frame.h).
 *
 * thx_torso_electrodes: the 12-lead positions and the body-surface array of
 * thx_phantom_electrodes (thorax/model/electrodes.h) on the outer surface of any
 * model, the landmarks taken along frame's superior, anterior and left axes
 * (frame NULL: m->frame). THX_EINPUT naming the missing frame when neither
 * is set. thx_phantom_electrodes itself uses m->frame, or RAS when the model
 * has none (the phantom's own convention; the CLI refuses such a model).
 * Positions are the nodes' model coordinates.
 *
 * thx_torso_epicardial: thx_phantom_epicardial with the dipole's anatomical
 * directions (RAS in thx_beat_dipole) carried into the model's axes by
 * frame (required, set): left-inferior in the body whatever the axes.
 */
thx_status thx_torso_electrodes(thx_ctx *ctx, const thx_model *m, const thx_frame *frame, thx_electrodes **leads12,
                                size_t n_array, thx_electrodes **array);
thx_status thx_torso_epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_frame *frame, const thx_beat_opts *o,
                                thx_series **out);

/*
 * The phantom's smooth anatomy as a point test (the phantom as a scan, thorax/phantom/voxelize.h).
 * Each surface is the solid of its smooth outlines between its first and last layer, with flat
 * caps on those planes (as the surfaces built from the contours have): torso, fat and muscle the
 * polar curves r < R(theta, z), the heart its ellipsoid, a lung the region of the implicit
 * function whose zero set the lung outlines trace. The region of a point is 0 outside the torso,
 * else 1 + the index (order above) of the innermost surface that holds it: 1 subcutaneous fat
 * (inside torso, outside fat), 2 skeletal muscle (inside fat, outside muscle), 3 the rest of the
 * thorax inside the muscle, 4 right lung, 5 left lung, 6 heart. The field is independent of the
 * seed, jitter and shifts (those are the digitization's, not the anatomy's).
 */
typedef struct thx_phantom_field thx_phantom_field;
typedef struct thx_phantom_plane thx_phantom_plane; /* the field on one plane z = const */

thx_status thx_phantom_field_create(thx_ctx *ctx, thx_phantom_field **out);
void thx_phantom_field_destroy(thx_phantom_field **f);
/* Heights (mm) of surface s's first and last layers (its caps). */
void thx_phantom_slab(const thx_phantom_field *f, int surface, double *z0, double *z1);
/* A box holding the torso (RAS mm). */
void thx_phantom_bounds(const thx_phantom_field *f, double lo[3], double hi[3]);
/* The field on the plane z: create allocates, set refills one (for another z). */
thx_status thx_phantom_plane_create(thx_ctx *ctx, const thx_phantom_field *f, double z, thx_phantom_plane **out);
void thx_phantom_plane_set(const thx_phantom_field *f, double z, thx_phantom_plane *p);
void thx_phantom_plane_destroy(thx_phantom_plane **p);
/* Region (0..6, above) of the point (x, y) of the plane; a point on a surface belongs to the outer side. */
int thx_phantom_region(const thx_phantom_plane *p, double x, double y);
/* The smooth outline of `surface` on the plane z, counterclockwise: the curve the contours are digitized
 * from (the shells 720 points in theta, the heart 360 on its ellipse, a lung its marching-squares trace
 * at 1.25 mm, the largest loop), for measuring distances to the analytic surfaces. *pts is the caller's
 * to free; *n = 0 when z lies outside the surface's slab. */
thx_status thx_phantom_section(thx_ctx *ctx, const thx_phantom_field *f, int surface, double z, thx_vec2 **pts,
                               size_t *n);
/* Volume (mm^3) enclosed by each surface: Simpson's rule in z (steps of about dz mm) over the areas
 * of the sections (the shells by the trapezoid rule in theta, the heart's ellipses exactly, the
 * lungs the areas of the outlines the contours are drawn from). Independent of the point test. */
thx_status thx_phantom_volumes(thx_ctx *ctx, const thx_phantom_field *f, double dz, double vol[THX_PHANTOM_N_SURFACES]);

#ifdef __cplusplus
}
#endif
#endif
