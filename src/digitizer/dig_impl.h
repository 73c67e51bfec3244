/* src/digitizer/dig_impl.h — helpers the digitizer's files share (private to src/digitizer/). */
#ifndef THORAX_DIGITIZER_DIG_IMPL_H
#define THORAX_DIGITIZER_DIG_IMPL_H

#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/core/vec.h"
#include "thorax/image/sample.h"

/* Lengths of the plane's steps (mm). */
double dig_len3(const double v[3]);
/* Pixel coordinates (a, b) -> RAS, and RAS -> the pixel coordinates of its projection on the plane. */
void dig_px_to_ras(const thx_image_slice *s, double a, double b, double ras[3]);
void dig_ras_to_px(const thx_image_slice *s, const double ras[3], double *a, double *b);

/* The plane's values with NaN replaced by the smallest finite value (*n_finite counts the finite
 * ones), smoothed by a Gaussian of sigma pixels (separable, truncated at 3 sigma, borders clamped);
 * malloc'd. */
float *dig_smooth(thx_ctx *ctx, const thx_image_slice *s, double sigma, size_t *n_finite);
/* Derivatives of f along u and v in value per mm (central differences, one-sided at the border):
 * gx, gy, and the magnitude g (each w h floats, the caller's). */
void dig_gradient(const float *f, size_t w, size_t h, double su, double sv, float *gx, float *gy, float *g);
/* Bilinear sample of f at pixel coordinates (clamped to the plane). */
double dig_bilinear(const float *f, size_t w, size_t h, double a, double b);
/* Moves (a, b) along the gradient direction at that point to the maximum of g on the line (a
 * parabola through g at -1, 0, +1 pixel; at most `reach` pixels in all, by repeated steps).
 * Unchanged where the gradient vanishes. */
void dig_edge_refine(const float *g, const float *gx, const float *gy, size_t w, size_t h, double su, double sv,
                     double reach, double *a, double *b);

/* Loops in pixel coordinates: pts[2 * i], pts[2 * i + 1]. */
typedef struct {
    double *xy;
    size_t n;
} dig_loop;
typedef struct {
    dig_loop *loop;
    size_t n, cap;
} dig_loops;
void dig_loops_free(dig_loops *L);
/* The zero level of f (w h values, > 0 inside) by marching squares, vertices linearly interpolated on
 * the cell edges; the outside of the grid counts as outside. Saddle cells join the inside corners
 * when conn8, the outside ones otherwise (the region's 8- or 4-connectivity). Every loop closed,
 * inside on its left (counterclockwise in (a, b) around an inside region, clockwise around a hole). */
thx_status dig_march(thx_ctx *ctx, const double *f, size_t w, size_t h, int conn8, dig_loops *out);
/* Signed area (a, b) of a loop (positive counterclockwise). */
double dig_area(const double *xy, size_t n);
/* The loop of largest positive area (the outer boundary of the region), or (size_t)-1 if none. */
size_t dig_largest_loop(const dig_loops *L);
/* Is the point inside the loop (even-odd)? */
int dig_inside(const double *xy, size_t n, double x, double y);

#endif
