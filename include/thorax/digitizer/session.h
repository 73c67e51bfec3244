/*
 * thorax/digitizer/session.h — a tracing session (issue 26 items 2, 3 and 6; paper 3.1: "each image
 * was digitized by hand, surface by surface, into closed loops"): the loops a user lays on the axial
 * planes of a scan, surface by surface, the tools that make and change them (points, the livewire,
 * threshold and seed, copy and snap, interpolation), undo and redo, and the log that replays them.
 *
 * The language. Everything a session does comes from one line of text, applied by thx_dig_apply;
 * the viewer turns each click and key into such a line before applying it, so that the log of
 * applied lines, replayed into a new session on the same image, gives the same loops byte for byte:
 *
 *   surface NAME[:ROLE]        the surface traced (made when new; ROLE outer, fat, muscle, lung, heart,
 *                              other; without one: outer for torso, fat, muscle, lung for lung*, heart
 *                              for heart, other otherwise)
 *   plane z=MM                 the axial plane traced: the image's plane of voxel centres nearest MM
 *   plane +N | plane -N        N of the image's planes on
 *   tool points | livewire     how the next point joins the last: a straight edge, or the livewire
 *                              (Mortensen & Barrett, thorax/digitizer/livewire.h) on the plane
 *   point X Y                  a point (RAS mm) at the end of the plane's open loop (a new loop when
 *                              none is open), joined to the last by the tool
 *   close                      closes the open loop (the tool joins its last point to its first)
 *   reopen L                   loop L (1-based, of the current surface on the current plane) opened
 *                              again: the next points go at its end
 *   move L I X Y               moves point I (1-based) of loop L
 *   insert L I X Y             a new point after point I of loop L
 *   delete L I                 removes point I of loop L (a closed loop keeps at least 3)
 *   delete-loop L              removes loop L
 *   region LO HI X Y           the region of values in [LO, HI] connected to (X, Y), 8-connected, its
 *                              boundary a new closed loop (thorax/digitizer/region.h)
 *   copy N [raw]               the surface's closed loops on this plane copied N planes on, snapped
 *                              there to the edges (thorax/digitizer/snap.h; raw: not snapped), and
 *                              that plane made the current one; refused when it has the surface's
 *                              loops already
 *   interpolate                every plane between two traced planes of the surface that has none of
 *                              its loops filled by shape-based interpolation (thorax/digitizer/interp.h);
 *                              loops paired by overlap when a plane has several
 *   undo | redo                the last change of loops taken back, or made again
 *
 * Loops are held per surface and per plane of the image (a layer of the contour model: z is the
 * plane's RAS z), as (x, y) RAS millimetres. Planes are the image's planes of voxel centres along RAS
 * z (thx_image_plane_range 'z'), numbered 0, 1, ... from the lowest. A bad line changes nothing and
 * says why, naming the line and the object.
 */
#ifndef THORAX_DIGITIZER_SESSION_H
#define THORAX_DIGITIZER_SESSION_H

#include "thorax/core/core.h"
#include "thorax/core/vec.h"
#include "thorax/image/image.h"
#include "thorax/image/sample.h"
#include "thorax/model/contours.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_dig_session thx_dig_session;

/* A loop as the session holds it (read-only to callers). */
typedef struct {
    thx_vec2 *p;
    size_t n, cap;
    int closed;
} thx_dig_loop;

typedef enum { THX_DIG_POINTS = 0, THX_DIG_LIVEWIRE = 1 } thx_dig_tool;

/* A session on img (borrowed: it must outlive the session), no surface yet, the middle plane
 * current, the points tool. THX_EINPUT when the image has fewer than 2 planes along RAS z. */
thx_status thx_dig_session_create(thx_ctx *ctx, const thx_image *img, thx_dig_session **out);
void thx_dig_session_destroy(thx_dig_session **s);

/* Applies one line of the language above. On success the line joins the log. On failure
 * (THX_EINPUT naming the line: "trace 'move 4 2 1 1': torso has 3 loops on plane z=12.0000")
 * nothing changes. */
thx_status thx_dig_apply(thx_ctx *ctx, thx_dig_session *s, const char *line);

/* The lines applied, in order (the log; pointers owned by the session). */
size_t thx_dig_log(const thx_dig_session *s, const char *const **lines);

/* ---- what is traced ---- */

size_t thx_dig_n_surfaces(const thx_dig_session *s);
const char *thx_dig_surface_name(const thx_dig_session *s, size_t i);
thx_role thx_dig_surface_role(const thx_dig_session *s, size_t i);
/* A number that changes whenever surface i's loops change (undo and redo included). */
unsigned long thx_dig_surface_gen(const thx_dig_session *s, size_t i);
/* The current surface (-1: none yet), plane and tool. */
int thx_dig_current_surface(const thx_dig_session *s);
long thx_dig_current_plane(const thx_dig_session *s);
thx_dig_tool thx_dig_current_tool(const thx_dig_session *s);
/* Planes: how many, and the RAS z of plane k (bitwise the same for every surface and call). */
long thx_dig_n_planes(const thx_dig_session *s);
double thx_dig_plane_z(const thx_dig_session *s, long k);
/* Surface i's loops on plane k: *loops (owned by the session, valid until the next apply), count. */
size_t thx_dig_loops(const thx_dig_session *s, size_t i, long k, const thx_dig_loop **loops);
/* The planes holding surface i's loops, ascending: at most max into k (may be NULL); the count. */
size_t thx_dig_planes_traced(const thx_dig_session *s, size_t i, long *k, size_t max);
/* The steps undo and redo would take. */
size_t thx_dig_n_undo(const thx_dig_session *s);
size_t thx_dig_n_redo(const thx_dig_session *s);

/* The current plane sampled (the session's own, valid until the plane changes); NULL after a
 * failure (ctx says why). */
const thx_image_slice *thx_dig_slice(thx_ctx *ctx, thx_dig_session *s);

/* The livewire's path from the open loop's last point to (x, y) on the current plane, what `point X
 * Y` with the livewire tool would append (*xyz malloc'd, RAS, *n points, the last point first):
 * drawn while the mouse moves. The search continues from one call to the next. *n = 0 when no loop
 * is open. */
thx_status thx_dig_preview(thx_ctx *ctx, thx_dig_session *s, double x, double y, double **xyz, size_t *n);

/* ---- checks ---- */

/* A crossing on a plane: loop la of surface sa touches loop lb of surface sb (sa == sb and la == lb:
 * itself) near (x, y). Loops 0-based. */
typedef struct {
    size_t sa, la, sb, lb;
    double x, y;
} thx_dig_crossing;
/* The crossings among every surface's closed loops on plane k (thorax/digitizer/valid.h): *out
 * malloc'd (NULL when none). */
thx_status thx_dig_crossings(thx_ctx *ctx, const thx_dig_session *s, long k, thx_dig_crossing **out, size_t *n);

/* ---- outputs ---- */

/* The contours traced: every surface with a closed loop (only: that surface alone; -1 all), its
 * layers ascending, each closed loop without repeated consecutive points (a loop left with fewer
 * than 3 is skipped); the image's path and SHA-256 and the RAS frame recorded. *n_skipped (may be
 * NULL) counts open loops and loops skipped. THX_EINPUT when nothing is traced. */
thx_status thx_dig_contours(thx_ctx *ctx, const thx_dig_session *s, int only, thx_contours **out, size_t *n_skipped);

/* Loads contours (a contour file traced on this image, to go on with): each surface's loops onto the
 * image plane nearest its layer's z, as closed loops. The session starts from them: they are not
 * logged and undo does not take them back (a saved session names the file it started from). Only
 * before the first line is applied. THX_EINPUT when a layer lies more than half a plane from every
 * image plane, or two layers of a surface fall on one plane. */
thx_status thx_dig_load(thx_ctx *ctx, thx_dig_session *s, const thx_contours *c);

#ifdef __cplusplus
}
#endif
#endif
