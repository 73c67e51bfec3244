/*
 * thorax/model/landmarks.h — map3d landmarks: coronary arteries, pacing and recording sites,
 * occlusions, cutting planes, needles and fibres drawn with the surfaces (model layer; the file
 * is thorax/io/landmarks_file.h, the meshes thorax/geom/landmark_mesh.h).
 *
 * A landmark set is a list of segments. Each segment has a type and one or more points, each
 * point a position (mm, the frame of the surfaces it belongs to) and a radius (mm, >= 0) and an
 * optional short label. What the points mean depends on the type (map3d manual, "Landmark
 * files", and its drawing code):
 *
 *   artery, cath, cannula   a polyline drawn as a tube; the radius at each point, linearly
 *                           interpolated between points (a radius 0 at an end closes the tube
 *                           to a point). At least 2 points, not all at one place.
 *   occlusion, closure,     a site drawn as a sphere of the point's radius at every point
 *   stimulus, lead,         (map3d's files give one point; a segment of several is a set of
 *   paceneedle, recneedle   sites). At least 1 point.
 *   plane                   exactly 3 points spanning a plane (not collinear): a disc through
 *                           their centroid, of radius = point 1's radius and thickness = point
 *                           2's radius; point 3's radius is unused.
 *   rod                     a needle track: a thin tube along the points, of point 1's radius
 *                           (the others unused). At least 2 points, not all at one place.
 *   fiber                   a fibre direction: an arrow along the points, from the first to the
 *                           last, shaft radius = point 1's radius. At least 2 points, not all at
 *                           one place.
 *
 * Invariants (thx_landmarks_validate): every type known, point counts as above, coordinates and
 * radii finite with |x| <= THX_LANDMARK_MAX_COORD and 0 <= radius <= THX_LANDMARK_MAX_COORD,
 * labels of 1..39 characters from printable ASCII without blanks and '#' (one word on its line,
 * as map3d reads it) or empty, a segment index >= 0 when present, colour components 0..255.
 * Segments are numbered from 1 in messages and in the file, points from 1 in messages.
 */
#ifndef THORAX_MODEL_LANDMARKS_H
#define THORAX_MODEL_LANDMARKS_H

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The landmark types, in map3d's order (its LM_COR = 1 ... LM_CANNULA = 12, minus one). */
typedef enum {
    THX_LANDMARK_ARTERY = 0, /* "artery" (also read: "coronary"): a coronary artery or vein */
    THX_LANDMARK_OCCLUSION,  /* "occlusion": an occlusion that can be opened and closed */
    THX_LANDMARK_CLOSURE,    /* "closure" (also read: "stitch"): a permanent occlusion */
    THX_LANDMARK_STIMULUS,   /* "stimulus": a stimulation (pacing) site */
    THX_LANDMARK_LEAD,       /* "lead": an electrode or lead location */
    THX_LANDMARK_PLANE,      /* "plane": a (drawn, not functional) cutting plane */
    THX_LANDMARK_ROD,        /* "rod": a rod in a needle track */
    THX_LANDMARK_PACENEEDLE, /* "paceneedle": a pacing needle's entry point */
    THX_LANDMARK_CATH,       /* "cath" (also read: "catheter"): a catheter in a vessel */
    THX_LANDMARK_FIBER,      /* "fiber": a local fibre direction */
    THX_LANDMARK_RECNEEDLE,  /* "recneedle": a recording needle's entry point */
    THX_LANDMARK_CANNULA,    /* "cannula": a coronary cannula */
    THX_LANDMARK_TYPE_COUNT
} thx_landmark_type;

/* How a type is drawn (the header comment above). */
typedef enum {
    THX_LANDMARK_SHAPE_TUBE,    /* artery, cath, cannula */
    THX_LANDMARK_SHAPE_SPHERES, /* occlusion, closure, stimulus, lead, paceneedle, recneedle */
    THX_LANDMARK_SHAPE_DISC,    /* plane */
    THX_LANDMARK_SHAPE_ROD,     /* rod */
    THX_LANDMARK_SHAPE_ARROW    /* fiber */
} thx_landmark_shape;

/* Coordinates and radii beyond this many millimetres (1e7 mm = 10 km) are refused: nothing
 * anatomical is that large, and the meshes' products of coordinates stay far from overflow. */
#define THX_LANDMARK_MAX_COORD 1e7
/* Longest label (map3d reads a label with "%39s"). */
#define THX_LANDMARK_LABEL_MAX 39

/* The name the writer uses ("artery", "paceneedle", ...: map3d's names, lower case); "?" for a
 * value out of range. Static storage. */
const char *thx_landmark_type_name(thx_landmark_type t);
/* Parses a type name as the reader accepts it: a name above or one of the aliases "coronary",
 * "stitch", "catheter", in any case. Returns 0 and *out, or -1 if unknown. */
int thx_landmark_type_parse(const char *s, thx_landmark_type *out);
/* The names and aliases the parser knows, comma separated, for messages. Static storage. */
const char *thx_landmark_type_names(void);
/* How a type is drawn, and the fewest points it needs (tube/rod/arrow 2, spheres 1, disc 3;
 * a disc needs exactly 3). */
thx_landmark_shape thx_landmark_type_shape(thx_landmark_type t);
size_t thx_landmark_type_min_points(thx_landmark_type t);

/* One point of a segment. */
typedef struct {
    double xyz[3];  /* mm */
    double radius;  /* mm, >= 0; its meaning depends on the type (header comment) */
    char label[THX_LANDMARK_LABEL_MAX + 1]; /* "" for none */
} thx_landmark_point;

typedef struct {
    thx_landmark_type type;
    size_t n;                /* points */
    thx_landmark_point *pt;  /* n points, owned by the set */
    int has_index;           /* the file gave an index (map3d's "segnumval": e.g. a needle number) */
    long index;              /* >= 0 when has_index */
    int has_color;           /* the file gave a colour; else the type's default is drawn */
    unsigned char rgb[3];    /* 0..255 */
    int line;                /* line of the segment's header in the file it was read from; 0 otherwise */
} thx_landmark_segment;

/* A landmark set. Plain data: fields may be read directly; change it through the functions
 * below (or keep their invariants and run thx_landmarks_validate). */
typedef struct {
    size_t n;                   /* segments (0 allowed: an empty set) */
    thx_landmark_segment *seg;  /* n segments */
    char path[512];             /* the file it was read from ("" otherwise): messages name it */
} thx_landmarks;

/* A new empty set. Caller destroys. */
thx_status thx_landmarks_create(thx_ctx *ctx, thx_landmarks **out);
/* Frees the set, its segments and points; accepts NULL; nulls *lm. */
void thx_landmarks_destroy(thx_landmarks **lm);
/* Appends a segment of type t with n points copied from pts (pts NULL: n zeroed points); no
 * colour, no index. *out (may be NULL) points at the new segment, valid until the next append.
 * The segment is not validated here (thx_landmarks_validate does it). */
thx_status thx_landmarks_add_segment(thx_ctx *ctx, thx_landmarks *lm, thx_landmark_type t,
                                     const thx_landmark_point *pts, size_t n, thx_landmark_segment **out);

/* Whether two landmark points are at one place for drawing: closer than 1e-9 of their
 * magnitude (plus 1e-9 mm). The tube and plane checks and the meshes use this one rule. */
int thx_landmark_points_coincide(const double a[3], const double b[3]);

/* The invariants above. Errors name the segment and point (1-based) and, when the set was read
 * from a file, its path and the segment's line; `where` (may be "" or NULL) prefixes them:
 * "a.lmarks:7: segment 2 (artery) point 3: radius -1 is negative". */
thx_status thx_landmarks_validate(thx_ctx *ctx, const thx_landmarks *lm, const char *where);
/* The same for one segment, k its 0-based number (for messages). */
thx_status thx_landmark_segment_validate(thx_ctx *ctx, const thx_landmark_segment *s, size_t k, const char *where);
/* NULL when s is a valid label (possibly empty), else why not. */
const char *thx_landmark_label_why(const char *s);

#ifdef __cplusplus
}
#endif
#endif
