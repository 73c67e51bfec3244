/* Private parts of the current streamlines (thorax/field/streamline.h): the field's data, shared by
 * streamline_field.c (the field, point location), streamline_seeds.c and streamline_trace.c. */
#ifndef THORAX_FIELD_STREAMLINE_IMPL_H
#define THORAX_FIELD_STREAMLINE_IMPL_H
#include "thorax/field/streamline.h"
#include "thorax/mesh/tet_locate.h"

struct thx_stream_field {
    const thx_volume *v;       /* borrowed */
    thx_tet_locator *loc;
    double *j;                 /* 3 n_nodes */
    double *phi;               /* n_nodes, or NULL */
    unsigned char *active;     /* n_tets: in the domain */
    double jmax;               /* largest |J| at the domain's nodes */
    double lo[3], hi[3];       /* the mesh's bounding box, mm */
    double diag;               /* its diagonal, mm (the whole's on a part) */
    const unsigned char *own;  /* on a part: n_tets, its own tetrahedra (borrowed); NULL: the whole */
    const unsigned char *edge; /* on a part: 4 n_tets, the faces on its edge (thx_tet_locator_set_part) */
};

/* The mean edge length of tetrahedron t, mm: the cell size steps are fractions of. */
double thx_stream_cell_size(const thx_volume *v, size_t t);
/* Barycentric coordinates of p in tetrahedron t (sum 1; all >= 0 inside, to rounding). */
void thx_stream_bary(const thx_volume *v, size_t t, const double p[3], double lam[4]);
/* J (3) and phi (may be NULL) at p in tetrahedron t, linear interpolation (p may be slightly out). */
void thx_stream_interp(const thx_stream_field *f, size_t t, const double p[3], double *j, double *phi);
/*
 * The straight path from p (in the domain's tetrahedron t) along the unit vector d, walked face to
 * face through the domain: the distance to where it leaves the domain (the face it leaves by is on
 * the mesh's boundary or borders a tetrahedron outside the domain), or +infinity if that is farther
 * than smax. *exit_tet: the last domain tetrahedron. On a part, *unknown is set when the path
 * leaves the part within smax by a face of its edge (the whole going on behind it).
 */
double thx_stream_exit(const thx_stream_field *f, size_t t, const double p[3], const double d[3], double smax,
                       long *exit_tet, int *unknown);
/* The domain's tetrahedron of lowest number holding p, t one that holds it. p on a face, an edge or a
 * node of t is held by the tetrahedra round it too, and which one a walk finds depends on where it
 * starts (the whole's locator grid or a part's); the lowest is every walk's (on a part in the whole's
 * numbering too: a part's tetrahedra ascend as the whole's, and the part owning one round p holds
 * them all). The seeds' rule: their tetrahedron sets their line's first step. */
long thx_stream_field_lowest(const thx_stream_field *f, const double p[3], long t);
/* A uniform double in [0, 1) from the state (splitmix64). */
double thx_stream_rand(uint64_t *state);
#endif
