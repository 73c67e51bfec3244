/*
 * thorax/field/streamline.h — current streamlines through a tetrahedral volume (paper 4.3, "Volume
 * potentials and vector flow": "streamlines of current ... computed with a second-order Runge-Kutta
 * integration, the containing element found by walking from the last one").
 *
 * The field. The current density J = -sigma grad(phi) is constant per tetrahedron for linear
 * elements. The integrator sees the continuous field made from it: J averaged to the nodes
 * (volume-weighted over the tetrahedra of the domain around each node: thx_fem_currents' j_node) and
 * interpolated linearly (barycentric) inside each tetrahedron. docs/decisions.md, "Current
 * streamlines (issue 16)", says why: the piecewise-constant field's normal component jumps between
 * elements, and its exact lines get stuck on faces where the next element's J points back; on the
 * dipole tests the averaged field's lines stay closer to the exact field lines and all of them reach
 * the boundary.
 *
 * The domain: the tetrahedra of the regions the caller marks (use_region; thorax forward's epicardial
 * problem leaves the heart's interior out). A line stops where it leaves the domain: on the mesh's
 * boundary or on a face to a region outside it (the epicardium), its last point on that face.
 *
 * Integration in arc length: dx/ds = +-J/|J| (forward +, backward -), s in mm. The step is a
 * fraction of the local tetrahedron's mean edge length (thx_stream_opts.step); RK2 (midpoint, the
 * paper's), RK4 (classical) with that step fixed, RK45 (Dormand-Prince 5(4), error per step held
 * below tolerance x the local edge length, the step between min_step and max_step of it). Each point
 * is located by thx_tet_locate from the tetrahedron of the point before (the locator's seed grid only
 * for a seed). Stops (the reason recorded per line, thx_stream_stop): leaving the domain (the last
 * point clipped to the face it leaves by: the straight step along the field from the last point,
 * walked face to face), |J| below min_current x the largest |J| at the domain's nodes, the length or
 * the number of steps reaching their maxima, and a closed loop (after going farther than twice
 * loop_tol from its seed the line passes within loop_tol of it; its last point is then the seed).
 *
 * Units: coordinates mm; J in whatever unit the caller's j_node has (thx_fem_currents: A/m^2 for phi
 * in V, mA/m^2 for phi in mV); phi as given. Indices 0-based.
 *
 * Determinism: the same field, seeds and options give the same lines in the same order, whatever
 * the number of OpenMP threads (seeds are traced in parallel, each into its own buffer).
 */
#ifndef THORAX_FIELD_STREAMLINE_H
#define THORAX_FIELD_STREAMLINE_H
#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"
#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef enum { THX_STREAM_RK2 = 0, THX_STREAM_RK4 = 1, THX_STREAM_RK45 = 2 } thx_stream_integrator;
enum { THX_STREAM_FORWARD = 1, THX_STREAM_BACKWARD = 2, THX_STREAM_BOTH = 3 };

/* Why a line ended (cell data "stop_reason" of the VTP, docs/formats.md). */
typedef enum {
    THX_STOP_BOUNDARY = 0,    /* left the domain: last point on the face it left by */
    THX_STOP_LOW_CURRENT = 1, /* |J| < min_current x max |J| */
    THX_STOP_MAX_LENGTH = 2,  /* reached max_length (mm) */
    THX_STOP_MAX_STEPS = 3,   /* took max_steps steps */
    THX_STOP_LOOP = 4         /* came back to its seed: a closed current loop */
} thx_stream_stop;
#define THX_STOP_COUNT 5
/* "boundary", "low_current", "max_length", "max_steps", "loop" (static). */
const char *thx_stream_stop_name(int reason);

typedef struct {
    int integrator;     /* thx_stream_integrator (default RK2) */
    int direction;      /* THX_STREAM_FORWARD, _BACKWARD or _BOTH (default both) */
    double step;        /* RK2/RK4 step, RK45 first step: fraction of the local mean edge length (0.2) */
    double step_mm;     /* > 0: the RK2/RK4 step, RK45 first step in mm instead (0) */
    double tolerance;   /* RK45: largest error per step, fraction of the local mean edge length (1e-4) */
    double min_step;    /* RK45: smallest step, fraction of the local mean edge length (0.01) */
    double max_step;    /* RK45: largest step, fraction of the local mean edge length (0.5) */
    double min_current; /* stop below this fraction of the largest nodal |J| (1e-3) */
    double max_length;  /* mm per line and direction; 0: 4 x the mesh's bounding-box diagonal (0) */
    size_t max_steps;   /* per line and direction (100000) */
    int loops;          /* detect closed loops (1) */
    double loop_tol;    /* fraction of the seed's tetrahedron's mean edge length (0.5) */
} thx_stream_opts;
void thx_stream_opts_default(thx_stream_opts *o);

/* ---- the field ---- */

typedef struct thx_stream_field thx_stream_field;

/*
 * The field to integrate on the volume v (borrowed: it must outlive the field and not change).
 * j_node: 3 n_nodes values, J at each node (copied). phi: n_nodes potentials (copied; NULL: lines
 * carry no potential, 0). use_region: per region of v, whether its tetrahedra are in the domain
 * (NULL: all). Builds the point locator (thx_tet_locator). THX_EINPUT when the domain is empty or
 * j_node holds a value that is not finite (naming the node, 1-based).
 */
thx_status thx_stream_field_create(thx_ctx *ctx, const thx_volume *v, const double *j_node, const double *phi,
                                   const unsigned char *use_region, thx_stream_field **out);
void thx_stream_field_destroy(thx_stream_field **f);

/* The largest |J| at the domain's nodes. */
double thx_stream_field_max(const thx_stream_field *f);

/*
 * The domain's tetrahedron holding p (walking from hint, a tetrahedron, or < 0: the locator's grid,
 * then a scan of every tetrahedron if the walk fails — a mesh with holes), or -1 when p is outside
 * the domain (on a part, -2: beyond the part's edge, thx_stream_field_set_part). A point clearly inside hint (every barycentric coordinate above 1e-9, in floating
 * point) is taken there without the walk; every other goes to the walk's exact tests. If j (3) or phi
 * are not NULL: the interpolated field there. Thread-safe.
 */
long thx_stream_field_eval(const thx_stream_field *f, const double p[3], long hint, double *j, double *phi);

/* ---- seeds ---- */

typedef enum { THX_SEED_POINT, THX_SEED_LINE, THX_SEED_SPHERE, THX_SEED_REGION, THX_SEED_DENSITY } thx_seed_kind;

typedef struct {
    thx_seed_kind kind;
    double a[3];       /* point; line start; sphere centre */
    double b[3];       /* line end */
    double radius;     /* sphere, mm */
    size_t n;          /* seeds (line, sphere, region, density); 1 for a point */
    char region[64];   /* region name */
    uint64_t rng_seed; /* region and density: the random stream's seed (1 unless set) */
    char text[256];    /* the spec as given (for messages) */
} thx_seed_spec;

/*
 * Reads a seed spec: point:X,Y,Z | line:X,Y,Z:X,Y,Z:N | sphere:X,Y,Z:R:N | region:NAME:N |
 * density:N (mm; N >= 1; R > 0). THX_EINPUT naming the spec and what is wrong.
 */
thx_status thx_seed_spec_parse(thx_ctx *ctx, const char *text, thx_seed_spec *s);

/*
 * The seed points of a spec, appended to *xyz (3 per seed) and *tet (the domain tetrahedron holding
 * each), *n counting them (start with NULL, NULL, 0; the caller frees both arrays).
 *  point   the point; outside the domain: THX_EINPUT naming the spec.
 *  line    n points evenly from a to b (ends included; n = 1: the middle); sphere: n points spread
 *          evenly on the sphere (a Fibonacci lattice). Points outside the domain are dropped (logged);
 *          none inside: THX_EINPUT.
 *  region  n points uniformly distributed in the region's volume (random, from rng_seed). A region
 *          outside the domain (the heart of an epicardial solution) gets its seeds on its faces to
 *          the domain (uniform by area), just inside the domain's tetrahedron there. Unknown name:
 *          THX_EINPUT listing the regions.
 *  density n points drawn with probability proportional to |J| x volume per tetrahedron (|J| at the
 *          centroid), uniform inside it (random, from rng_seed).
 * Deterministic: the same spec gives the same points.
 */
thx_status thx_stream_seeds(thx_ctx *ctx, const thx_stream_field *f, const thx_seed_spec *s, double **xyz, long **tet,
                            size_t *n);

/* ---- the lines ---- */

typedef struct {
    size_t n_lines;
    size_t *first;        /* n_lines + 1: line i's points are first[i] .. first[i+1]-1 */
    size_t n_points;
    double *xyz;          /* 3 n_points, mm */
    double *current;      /* n_points: |J| */
    double *potential;    /* n_points: phi (0 without potentials) */
    double *arc;          /* n_points: arc length from the seed, mm */
    int32_t *tet;         /* n_points: the tetrahedron holding the point (0-based) */
    int32_t *seed;        /* n_lines: the seed it started from (0-based, in the seeds' order) */
    int8_t *direction;    /* n_lines: +1 forward, -1 backward */
    int8_t *stop;         /* n_lines: thx_stream_stop */
    double *length;       /* n_lines: mm */
    size_t n_steps;       /* integration steps taken, every line */
    size_t n_evals;       /* field evaluations, every line */
} thx_streamlines;

/*
 * Traces a line from each seed (xyz: 3 n_seeds; tet: the tetrahedron of each, or NULL to locate
 * them): with THX_STREAM_BOTH the forward line, then the backward line (none when the forward one
 * closed a loop), seed after seed. A seed outside the domain gives THX_EINPUT naming it (0-based
 * index and coordinates). *out is the caller's (thx_streamlines_destroy).
 */
thx_status thx_streamlines_trace(thx_ctx *ctx, const thx_stream_field *f, const double *xyz, const long *tet,
                                 size_t n_seeds, const thx_stream_opts *o, thx_streamlines **out);
void thx_streamlines_destroy(thx_streamlines **s);

/* ---- on a part of the volume (sort-last, docs/design/parallel.md "Streamlines on the parts") ----
 *
 * The field is made on a part (the tetrahedra a rank owns and their ghosts, thorax/fem/parts.h) with
 * j_node the whole's J at every node of the part (the caller completes the nodes of the ghosts'
 * far side from the parts that own them). thx_stream_field_set_part marks the own tetrahedra (own,
 * borrowed: n_tets bytes) and the whole's largest nodal
 * |J| and bounding-box diagonal (agreed by the caller); id (n_tets, borrowed) the tetrahedra's numbers
 * in the whole (the locator's walk takes the whole's path) and edge (4 n_tets, borrowed) the faces
 * with no neighbour in the part that have one in the whole (thx_tet_locator_set_part). Then thx_stream_seeds keeps a point outside
 * the part with tetrahedron -1 (the caller agrees which part holds it, and drops or refuses as one
 * process does), and a line is traced piece by piece: thx_stream_start from its seed, then
 * thx_stream_run until it stops (its thx_stream_stop), or its point enters a tetrahedron the part
 * does not own (THX_STREAM_HANDOVER: the state is the owner's to run on), or a step reaches beyond
 * what the part can tell (THX_STREAM_UNSURE: a stage or the straight path out of the part by a face
 * of its edge, one the whole has a tetrahedron behind). The state
 * holds everything the next step needs, so a line run in pieces has the one process's points to
 * the bit. On the whole (no part set), thx_streamlines_trace is start and run. */
#define THX_STREAM_GOING (-1)
#define THX_STREAM_HANDOVER (-2)
#define THX_STREAM_UNSURE (-3)

typedef struct {
    double x0[3], k_start[3], j0, phi0, loop_tol; /* the seed: point, direction, |J|, phi, loop tolerance */
    double x[3], k1[3], h, len;                   /* the current point, direction, step and length so far */
    int64_t t, t0, step;                          /* tetrahedra of the point and of the seed (part's numbers), steps */
    int32_t sign, away;
} thx_stream_state;

/* One piece of a line as it grows (the caller frees it with thx_stream_piece_free). */
typedef struct {
    size_t n, cap;
    double *xyz, *cur, *phi, *arc;
    int32_t *tet;
    int stop, dir;
    double length;
} thx_stream_piece;
void thx_stream_piece_free(thx_stream_piece *b);

void thx_stream_field_set_part(thx_stream_field *f, const unsigned char *own, const int32_t *id, const unsigned char *edge,
                               double jmax, double diag);
/* The field's point locator (its faces' neighbours: thx_tet_neighbour). */
const struct thx_tet_locator *thx_stream_field_locator(const thx_stream_field *f);
/* The seed x0 in tetrahedron t0, direction sign (+1, -1): the state and the first point into b;
 * THX_STREAM_GOING, or why the line ends there. *nomem set when a point could not be kept. */
int thx_stream_start(const thx_stream_field *f, const thx_stream_opts *o, const double x0[3], long t0, double sign,
                     thx_stream_state *s, thx_stream_piece *b, int *nomem);
/* Steps from s, the points into b: a thx_stream_stop (b->stop, b->length set), THX_STREAM_HANDOVER
 * (s->t is then the part's tetrahedron the point is in, owned elsewhere) or THX_STREAM_UNSURE. */
int thx_stream_run(const thx_stream_field *f, const thx_stream_opts *o, thx_stream_state *s, thx_stream_piece *b,
                   size_t *n_steps, size_t *n_evals, int *nomem);

/* A rank's part of a volume in parts (thorax/fem/parts.h), as thx_streamlines_trace_parts reads it
 * (every array borrowed). */
typedef struct {
    const unsigned char *own; /* n_tets: owned by this rank */
    const int32_t *node_id;   /* n_nodes: the nodes' numbers in the whole, ascending */
    const int32_t *tet_id;    /* n_tets: the tetrahedra's numbers in the whole, ascending */
    const int32_t *owner;     /* n_tets: the rank owning each */
    int rank;
} thx_stream_part;

/*
 * Collective (thorax/parallel/parallel.h; every rank, st its status so far, carried and agreed):
 * thx_streamlines_trace's lines on a volume in parts, v the rank's part (its nodes and tetrahedra,
 * the model's regions), phi its nodes' potentials, j_node (3 per node) J at its nodes from the
 * part's own tetrahedra and ghosts (thx_fem_currents on the part: the caller's, as field stays
 * below fem), use the domain's regions, the seeds from specs
 * (point, line and sphere: every rank makes them all; region and density are the caller's to
 * refuse). J at the nodes is completed from the parts that own a tetrahedron round each, the seeds
 * are traced by the part owning their tetrahedron (the lowest-numbered holding them), the lines
 * handed from part to part in rounds until none is on its way, and joined on rank 0: *out there is
 * the one process's lines (the points' tetrahedra numbered in the whole, n_steps and n_evals every
 * rank's), an empty set elsewhere. what names the solution in messages.
 */
thx_status thx_streamlines_trace_parts(thx_ctx *ctx, const thx_volume *v, const thx_stream_part *part, const unsigned char *use,
                                      const double *phi, const double *j_node, const thx_seed_spec *specs, int n_specs,
                                      const thx_stream_opts *o, const char *what, thx_status st, thx_streamlines **out);

/* ---- tubes and files ---- */

/* A triangle mesh around the lines: per line with two distinct points or more, a ring of `sides`
 * vertices (radius mm) at each point, framed by parallel transport so the tube does not twist,
 * neighbouring rings joined by two triangles per side; caps: a fan closing each end. Triangles are
 * counterclockwise seen from outside. Per vertex the line point's |J| and phi; per triangle its line. */
typedef struct {
    size_t n_vertices;
    double *xyz;          /* 3 n_vertices */
    double *normal;       /* 3 n_vertices, unit, outward */
    double *current;      /* n_vertices */
    double *potential;    /* n_vertices */
    size_t n_tris;
    int32_t *tri;         /* 3 n_tris, 0-based */
    int32_t *line;        /* n_tris: the line (index into thx_streamlines) */
} thx_stream_tubes;

thx_status thx_stream_tubes_make(thx_ctx *ctx, const thx_streamlines *s, double radius, int sides, int caps,
                                 thx_stream_tubes **out);
void thx_stream_tubes_destroy(thx_stream_tubes **t);

/*
 * Writes the lines (tubes NULL) or the tubes to path, by its extension: .vtp (VTK XML PolyData,
 * binary appended: Lines or Polys, point data current_magnitude, potential, arc_length (lines) and tet (lines),
 * cell data stop_reason, direction, seed, length) or .obj (Wavefront: v, then l per line or f per
 * triangle, the cell data in comments). docs/formats.md, "Streamlines". Atomic; an existing file is
 * replaced only if thorax wrote it (thx_atomic_open_output).
 */
thx_status thx_streamlines_write(thx_ctx *ctx, const thx_streamlines *s, const thx_stream_tubes *tubes,
                                 const char *path);

#ifdef __cplusplus
}
#endif
#endif
