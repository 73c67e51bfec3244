/*
 * thorax/model/contours.h — digitized contours (paper 3.1): the input of model construction
 * (model layer; the contour file is thorax/io/contours_file.h).
 *
 * In memory the contours are held surface by surface: each surface has the
 * layers (z planes) on which it was digitized, sorted by increasing z, and on
 * each layer one or more closed loops of (x, y) points in millimetres, in the
 * order they were digitized (any start point, either direction). The text
 * format is documented in docs/formats.md.
 *
 * Invariants after a successful thx_contours_read (thorax/check/contours.h) or
 * thx_contours_validate (thorax/geom/contours_valid.h):
 *  - every loop has >= 3 points, finite coordinates, no two consecutive equal
 *    points (including last/first), and does not intersect itself;
 *  - a surface's layers have strictly increasing z and are consecutive in the
 *    file's list of layers (a surface does not vanish and reappear).
 * The _raw readers and thx_contours_validate_structure check everything but
 * the loops' geometry (repeated points, self-intersection): what
 * thx_contours_repair (thorax/geom/repair.h) mends, as `thorax surfaces` does.
 */
#ifndef THORAX_MODEL_CONTOURS_H
#define THORAX_MODEL_CONTOURS_H

#include "thorax/model/frame.h"
#include "thorax/model/surface.h"

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
    char image[1024];  /* the image the contours were traced from ("image sha256:HEX PATH" line; "" if none) */
    char image_sha256[65]; /* its SHA-256, 64 lowercase hex digits ("" if none) */
    size_t n_surfaces;
    thx_contour_surface *surf;
} thx_contours;

/* Checks the structure: surfaces, layers in increasing and consecutive z, loops of at least 3
 * finite points (not the loops' geometry: thx_contours_validate, thorax/geom/contours_valid.h).
 * Errors name file:line (when the contours came from a file), surface, layer, loop and point. */
thx_status thx_contours_validate_structure(thx_ctx *ctx, const thx_contours *c);

/* Where the structural walk stands, for a check of the loops' geometry (thx_contours_validate_with):
 * after point `point` of loop `loop` passed (point < loop's n), or after the whole loop
 * (point == SIZE_MAX). path is the file's name for messages ("<contours>" when built in memory),
 * layer_no the 1-based layer number messages use. */
typedef struct {
    const char *path;
    const thx_contour_surface *surf;
    const thx_contour_layer *layer;
    size_t loop;
    int layer_no;
    size_t point;
} thx_contours_at;
typedef thx_status (*thx_contours_check_fn)(thx_ctx *ctx, const thx_contours_at *at, void *user);
/* The structural walk of thx_contours_validate_structure, calling fn (when not NULL) at each point
 * and after each loop that passed; the first error stops the walk. */
thx_status thx_contours_validate_with(thx_ctx *ctx, const thx_contours *c, thx_contours_check_fn fn, void *user);

/* The sorted distinct z of all layers of all surfaces (the file's layers): *zs malloc'd (caller
 * frees), *nz its length. */
thx_status thx_contours_layer_z(thx_ctx *ctx, const thx_contours *c, double **zs, size_t *nz);
/* The index of the surface called name, or -1. */
int thx_contours_find_surface(const thx_contours *c, const char *name);

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
/* Builders for readers: the layer of surface cs at height z, appended when z is not its last
 * layer's (index: the file's layer number, 0-based, or -1; line: the layer's line, or 0), and a new
 * empty loop appended to layer L (line: the loop's line, or 0). */
thx_status thx_contours_layer(thx_ctx *ctx, thx_contour_surface *cs, double z, int index, int line,
                              thx_contour_layer **out);
thx_status thx_contours_layer_add_loop(thx_ctx *ctx, thx_contour_layer *L, int line, thx_loop **out);

#ifdef __cplusplus
}
#endif
#endif
