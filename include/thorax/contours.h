/*
 * thorax/contours.h — digitized contours (paper 3.1): the input of model construction.
 *
 * In memory the contours are held surface by surface: each surface has the
 * layers (z planes) on which it was digitized, sorted by increasing z, and on
 * each layer one or more closed loops of (x, y) points in millimetres, in the
 * order they were digitized (any start point, either direction). The text
 * format is documented in docs/formats.md.
 *
 * Invariants after a successful thx_contours_read / thx_contours_validate:
 *  - every loop has >= 3 points, finite coordinates, no two consecutive equal
 *    points (including last/first), and does not intersect itself;
 *  - a surface's layers have strictly increasing z and are consecutive in the
 *    file's list of layers (a surface does not vanish and reappear).
 * The _raw readers and thx_contours_validate_structure check everything but
 * the loops' geometry (repeated points, self-intersection): what
 * thx_contours_repair (thorax/repair.h) mends, as `thorax surfaces` does.
 *
 * The reader is bounded and reads nothing in part: a NUL byte, a number with
 * trailing characters, hex/inf/nan or a value out of range, a layer without
 * loops, a loop cut short and a file without its 'end' line are refused, with
 * file:line and the surface, layer and loop concerned. Memory is a small
 * multiple of the file's size (no count is read from the file).
 */
#ifndef THORAX_CONTOURS_H
#define THORAX_CONTOURS_H

#include "thorax/frame.h"
#include "thorax/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_CAP_POLYGON = 0, /* triangulate the end loop itself */
    THX_CAP_GRID = 1     /* fill the end loop with a grid of points, triangulate in 2D */
} thx_cap_method;

typedef struct {
    size_t n;     /* number of points */
    thx_vec2 *p;  /* n points; the closing edge p[n-1] -> p[0] is implicit */
    int line;     /* source line of the loop's header (0 if not from a file) */
    int *lines;   /* source line of each point, or NULL if not from a file */
} thx_loop;

typedef struct {
    double z;        /* plane of the layer, mm */
    int index;       /* index of the layer in the file's list of layers (0-based) */
    int line;        /* source line of the layer's header */
    size_t n_loops;
    thx_loop *loops;
} thx_contour_layer;

typedef struct {
    char name[64];
    thx_role role;
    thx_cap_method cap;
    double cap_grid;   /* grid spacing for THX_CAP_GRID, mm (0 = the resampling spacing) */
    int line;          /* source line of the surface declaration */
    size_t n_layers;
    thx_contour_layer *layers;
} thx_contour_surface;

typedef struct {
    char path[512];    /* file the contours came from ("" if built in memory) */
    size_t n_layers;   /* number of layers in the file (all surfaces together) */
    double spacing;    /* suggested node spacing for resampling, mm (0 = not given) */
    thx_frame frame;   /* the anatomical frame ("frame UP FRONT" line; .set = 0 when absent) */
    size_t n_surfaces;
    thx_contour_surface *surf;
} thx_contours;

/* Reads and validates a contour file. On error the message names file and line
 * and, where known, surface and layer. Caller destroys *out. */
thx_status thx_contours_read(thx_ctx *ctx, const char *path, thx_contours **out);
/* Parses contour text held in memory; `name` is used in messages. */
thx_status thx_contours_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out);
/* As read / parse, checking the structure only (not repeated points nor self-intersections). */
thx_status thx_contours_read_raw(thx_ctx *ctx, const char *path, thx_contours **out);
thx_status thx_contours_parse_raw(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out);
/* Checks the invariants listed above (used by read; call it on contours built in memory). */
thx_status thx_contours_validate(thx_ctx *ctx, const thx_contours *c);
/* Checks all but the loops' geometry (what the _raw readers check). */
thx_status thx_contours_validate_structure(thx_ctx *ctx, const thx_contours *c);
/* Writes contours in the text format, atomically (temporary file + rename); the frame line
 * ("frame UP FRONT") when c->frame.set. */
thx_status thx_contours_write(thx_ctx *ctx, const thx_contours *c, const char *path, const char *comment);

/* Builders for contours made in memory (the phantom, tests). */
thx_status thx_contours_create(thx_ctx *ctx, thx_contours **out);
/* Adds a surface; returns its index in *idx. */
thx_status thx_contours_add_surface(thx_ctx *ctx, thx_contours *c, const char *name, thx_role role,
                                    thx_cap_method cap, double cap_grid, size_t *idx);
/* Appends a loop (copied) to surface `s` on the layer at height z (created if new;
 * layers must be added in increasing z per surface). */
thx_status thx_contours_add_loop(thx_ctx *ctx, thx_contours *c, size_t s, double z,
                                 const thx_vec2 *pts, size_t n);
void thx_contours_destroy(thx_contours **c);

#ifdef __cplusplus
}
#endif
#endif
