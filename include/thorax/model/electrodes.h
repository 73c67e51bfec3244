/*
 * thorax/model/electrodes.h — electrodes on the torso surface (model layer; the file is
 * thorax/io/electrodes_file.h, the ECG leads thorax/leads/leads.h).
 *
 * An electrode set lies on one surface of a model (normally the outer one).
 * An electrode is either a surface node (its signal is that node's row of a
 * surface series) or a point anywhere on the surface (node
 * THX_ELECTRODE_OFF_NODE): thx_electrodes_place projects its position to the
 * nearest point of the surface and records the triangle's corners and
 * barycentric weights there, so its signal is the weighted sum of three node
 * rows (the piecewise-linear field on the surface; docs/decisions.md, "Electrodes
 * anywhere on the surface"). File (docs/formats.md, "Electrodes"): a first line
 * `thorax-electrodes 1`, `surface NAME`, `count N`, then N lines
 * `NAME NODE X Y Z` (NODE 1-based on that surface, or `-` for a point off the
 * nodes; X Y Z, mm, its position, checked against the model when one is
 * given), then `end`.
 */
#ifndef THORAX_MODEL_ELECTRODES_H
#define THORAX_MODEL_ELECTRODES_H

#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* node[i] of an electrode anywhere on the surface (not on a node). */
#define THX_ELECTRODE_OFF_NODE (-1)
/* Default farthest an off-node electrode's position may lie from the surface, mm. */
#define THX_ELECTRODE_MAX_OFFSET_MM 10.0

typedef struct {
    char surface[64];   /* the surface the nodes belong to */
    size_t n;
    char (*name)[32];   /* electrode names: "RA", "LA", "LL", "V1".."V6", "A001".. */
    int32_t *node;      /* node on that surface, 0-based; THX_ELECTRODE_OFF_NODE: a point between nodes */
    double *xyz;        /* 3 n: the electrode's position, mm (its node's, for one on a node) */
    char path[512];     /* the file it was read from (thx_electrodes_read; "" otherwise): checks name it */
    /* Filled by thx_electrodes_place (placed = 1): electrode i's value is
     * sum_k weight[3i+k] * u[corner[3i+k]], k = 0..2, the weights >= 0 summing
     * to 1. An electrode on a node has corners (node, node, node), weights (1, 0, 0). */
    int32_t *corner;    /* 3 n, 0-based nodes of the surface; -1 before placing */
    double *weight;     /* 3 n */
    int placed;
} thx_electrodes;

thx_status thx_electrodes_create(thx_ctx *ctx, size_t n, thx_electrodes **out);
void thx_electrodes_destroy(thx_electrodes **e);
/* The invariants every set holds (checked before it is written, after it is read and before it
 * is checked against a model): at least one electrode, a surface name a model accepts, electrode
 * names of 1-31 characters from [A-Za-z0-9_.+-] that are not keywords of the electrode file,
 * unique; nodes >= 0 or THX_ELECTRODE_OFF_NODE; finite positions. `where` prefixes the messages. */
thx_status thx_electrodes_validate(thx_ctx *ctx, const thx_electrodes *e, const char *where);
/* NULL when s (at most cap bytes) is a valid electrode name / surface name of a set, else why not
 * ("is empty", "has a character outside [A-Za-z0-9_.+-]", ...). */
const char *thx_electrodes_name_why(const char *s, size_t cap);
const char *thx_electrodes_surface_name_why(const char *s, size_t cap);
/* Checks the set against the model: the surface exists, every node is on it, positions agree within
 * 1e-3 mm, an off-node electrode lies within THX_ELECTRODE_MAX_OFFSET_MM of the surface; errors name
 * the electrode. */
thx_status thx_electrodes_check(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m);

/* The surface of the model the set lies on; NULL (and an error naming the surfaces there) if none. */
const thx_surface *thx_electrodes_surface(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m);

/*
 * Places the set on its surface of m (src/model/electrodes_place.c): an electrode on a node is
 * checked as thx_electrodes_check does; an off-node one is projected to the nearest point of the
 * surface's triangles (ties: the lowest triangle number). A projection within 1e-3 mm of a
 * corner makes it that node's electrode (node set, xyz the node's); otherwise xyz becomes the
 * projected point and the triangle's corners and weights are recorded. An electrode farther than
 * max_offset mm from the surface is an error naming it and the distance. *max_moved (may be
 * NULL) gets the largest distance an electrode was moved. Sets placed = 1.
 */
thx_status thx_electrodes_place(thx_ctx *ctx, thx_electrodes *e, const thx_model *m, double max_offset,
                                double *max_moved);

/* A set of electrodes at the given nodes (0-based) of surface s, at their positions; names[i]
 * (NULL: "N<node 1-based>"). Placed. Caller destroys. */
thx_status thx_electrodes_from_nodes(thx_ctx *ctx, const thx_surface *s, const int32_t *nodes, const char (*names)[32],
                                     size_t n, thx_electrodes **out);

/* Electrode i's value from u, the values at the surface's nodes (the set placed, or every
 * electrode on a node). */
static inline double thx_electrode_value(const thx_electrodes *e, size_t i, const double *u)
{
    if (e->node[i] >= 0) return u[e->node[i]];
    const int32_t *c = e->corner + 3 * i;
    const double *w = e->weight + 3 * i;
    return w[0] * u[c[0]] + w[1] * u[c[1]] + w[2] * u[c[2]];
}

#ifdef __cplusplus
}
#endif
#endif
