/*
 * thorax/digitizer/livewire.h — the livewire ("intelligent scissors", Mortensen & Barrett 1995;
 * Falcão et al.'s live-wire on the fly, 2000) on one plane of an image (issue 26 item 2: the path
 * between two clicks follows the strongest edge). docs/design/digitizer.md gives the costs, their
 * defaults, why, and the measured accuracy and speed.
 *
 * Planes. The digitizer works on a thx_image_slice (thorax/image/sample.h: thx_image_sample_plane
 * cuts one; axial, coronal, sagittal or an index plane). A pixel (a, b) is sample v[a + w b], its
 * centre at RAS origin + a du + b dv; "pixel coordinates" below are such (a, b) as doubles. NaN
 * samples (outside the image) are walls: a path never enters them.
 *
 * Graph. Pixels are nodes, 8-connected; the link p -> q costs
 *     l(p, q) = wZ fZ(q) + wG fG(q) |q - p| / |diagonal| + wD fD(p, q)
 * (lengths in mm), scaled to an integer 0..THX_LIVEWIRE_MAX_LINK (rounded; a link costs at least 1):
 *   fZ(q) = 0 on a zero crossing of the Laplacian of the Gaussian-smoothed plane (the pixel of a sign
 *           change nearer zero), 1 elsewhere;
 *   fG(q) = 1 - G(q) / max G, G the gradient magnitude of the smoothed plane (central differences in
 *           mm); scaled by the link's length over the diagonal's (1/sqrt 2 for a square pixel's side
 *           links, 1 for diagonals: the paper's Euclidean scaling);
 *   fD(p, q) = 2 / (3 pi) (acos(D(p) . L) + acos(L . D(q))), D(x) the unit vector (Iy, -Ix) / G
 *           across the gradient, L the unit link p -> q, or q -> p when D(p) . (q - p) < 0 (the
 *           paper's formula: a link across the gradient, or against a smooth boundary's direction,
 *           costs more). Where G is 0, D is 0 and the term is 2/3.
 * Dijkstra from the seed with Dial's bucket queue (integer costs below MAX_LINK + 1: a circular array
 * of buckets), expanded on the fly: a path query expands only until its target leaves the queue, and
 * later queries continue from where the last stopped. The per-pixel features (smoothing, gradient,
 * zero crossings) are computed once per plane by create; a link's cost when the search expands its
 * pixel, so a short path touches only the pixels around it.
 */
#ifndef THORAX_DIGITIZER_LIVEWIRE_H
#define THORAX_DIGITIZER_LIVEWIRE_H

#include "thorax/image/sample.h"

#ifdef __cplusplus
extern "C" {
#endif

#define THX_LIVEWIRE_MAX_LINK 255

typedef struct {
    double wz, wg, wd; /* weights of the Laplacian zero crossing, gradient magnitude and direction terms
                          (Mortensen & Barrett's 0.43, 0.43, 0.14) */
    double sigma;      /* Gaussian smoothing of the plane before the derivatives, in pixels (1.0) */
    int subvoxel;      /* 1: each path point moved along the gradient to the gradient magnitude's maximum
                          (a parabola through three samples, at most one pixel); 0: pixel centres (1) */
} thx_livewire_opts;

void thx_livewire_opts_default(thx_livewire_opts *o);

typedef struct thx_livewire thx_livewire;

/*
 * Computes the plane's cost features (copied: the slice may be freed afterwards) into a new livewire
 * with no seed. THX_EINPUT for an empty plane, a plane with no finite sample, negative weights or all
 * zero, or sigma < 0. The caller destroys *out.
 */
thx_status thx_livewire_create(thx_ctx *ctx, const thx_image_slice *plane, const thx_livewire_opts *o,
                               thx_livewire **out);
void thx_livewire_destroy(thx_livewire **lw);

/* Sets the seed at the pixel nearest the RAS point (projected onto the plane along its normal); the
 * previous tree is dropped. THX_EINPUT when the point's pixel lies outside the plane or is NaN. */
thx_status thx_livewire_seed(thx_ctx *ctx, thx_livewire *lw, const double ras[3]);
/* The same by pixel index (a, b). */
thx_status thx_livewire_seed_pixel(thx_ctx *ctx, thx_livewire *lw, size_t a, size_t b);

/*
 * The optimal path from the seed to the pixel nearest the RAS point `to`: *xyz (malloc'd, the
 * caller frees) holds *n RAS points (3 doubles each), seed first, target last; with o->subvoxel the
 * points are moved onto the edge (the seed's and the target's too). THX_EINPUT with no seed, a
 * target outside the plane, or one the seed cannot reach (walled off by NaN).
 */
thx_status thx_livewire_path(thx_ctx *ctx, thx_livewire *lw, const double to[3], double **xyz, size_t *n);

/* The same by pixel index (a, b), as pixel indices (a + w b, seed first; *idx malloc'd) and the path's
 * total integer cost (cost may be NULL). No sub-voxel step. */
thx_status thx_livewire_path_pixels(thx_ctx *ctx, thx_livewire *lw, size_t a, size_t b, size_t **idx, size_t *n,
                                    long *cost);

/* The integer cost of the link from pixel p to its neighbour q (both indices a + w b, 8-neighbours;
 * -1 when q is not a neighbour or either is NaN): the graph the search runs on, for checks. */
long thx_livewire_link_cost(const thx_livewire *lw, size_t p, size_t q);

/* Plane size and the number of pixels whose cost is final (the on-the-fly expansion so far). */
void thx_livewire_size(const thx_livewire *lw, size_t *w, size_t *h, size_t *n_done);

/*
 * Path cooling (Mortensen & Barrett 1995, 3.4): while the free point moves, the part of the path next
 * to the seed stops changing; it is frozen and its far end becomes the new seed, so the user clicks
 * less on a long boundary. Each path query (thx_livewire_path, _path_pixels) records the prefix it
 * shares with the query before it (since the seed). When each of the last k queries shared at least
 * min_pixels (and 2) pixels with the one before, the prefix the last k + 1 paths have in common is returned (*xyz malloc'd, *n RAS points, the
 * seed first, as thx_livewire_path gives them) and the seed moves to its last pixel (the next
 * path's first); otherwise *n = 0 and nothing changes. THX_EINPUT for k outside 1..COOL_MAX.
 */
#define THX_LIVEWIRE_COOL_MAX 32
thx_status thx_livewire_cool(thx_ctx *ctx, thx_livewire *lw, int k, size_t min_pixels, double **xyz, size_t *n);

/*
 * A closed loop through the points clicked[0..m-1] (RAS, m >= 2): the livewire from each to the
 * next and from the last back to the first, joined (each shared point once). *xyz malloc'd, *n
 * points, no repeated closing point. The seed is left at the last point's.
 */
thx_status thx_livewire_loop(thx_ctx *ctx, thx_livewire *lw, const double *clicked, size_t m, double **xyz,
                             size_t *n);

#ifdef __cplusplus
}
#endif
#endif
