/*
 * thorax/edit/edit.h — manual editing of a model's surfaces (paper 3.2, "Manual editing": "align
 * and adjust whole layers because of shifts in the subject's position between scans and movement
 * noise induced by breathing ... spatial smoothing ... move individual points within the layers
 * ... delete or rebuild any triangles"), with undo/redo and a replayable edit log (edit layer,
 * level 4; the viewer of issue 13 calls it, `thorax surfaces CONTOURS --edits LOG` replays it).
 *
 * Two kinds of edits:
 *  - mesh edits act on one surface's nodes and triangles by index:
 *      node_move    SURFACE NODE X Y Z   the node to (x, y, z), mm
 *      tri_delete   SURFACE TRI          the triangle removed; the triangles after it move down by one
 *      tri_add      SURFACE A B C        a triangle on three distinct nodes, appended (index n_tris),
 *                                        ordered to agree with the triangles it shares an edge with
 *      tri_flip     SURFACE TRI          the triangle's orientation reversed (its 2nd and 3rd nodes swapped)
 *  - layer edits act on the contours (paper 3.1: a layer is one surface's loops on one image plane)
 *    and lace that one surface again through the normal pipeline (thx_surface_build):
 *      layer_move   SURFACE LAYER DX DY  the layer's loops translated in their plane, mm
 *      layer_rotate SURFACE LAYER DEG    rotated in their plane about the layer's centroid (the area
 *                                        centroid of its loops), counterclockwise seen cranio-caudally
 *                                        (+x toward +y) for a positive angle, degrees
 *      layer_smooth SURFACE LAYER MM     each loop refitted by the smoothing spline of bandwidth MM
 *                                        (paper 3.1; thx_loop_resample) at its own point density
 *    LAYER is the layer's z (mm, matched within 1e-4 mm) or its number among the surface's layers
 *    (in increasing z). z never changes: a layer moves and turns only in its plane.
 *
 * Indices are 0-based in memory (thx_edit) and 1-based in the log, like the Utah formats.
 *
 * Node indices and re-lacing. A layer edit rebuilds its surface: node and triangle numbers of that
 * surface are those of the new lacing, and the mesh edits made on it since it was last laced are
 * gone from the surfaces (they stay in the log, which is replayed in order, so a replay discards
 * them at the same point and gives the same model). thx_edit_result.discarded says how many, and
 * thx_edit_session_mesh_edits counts them before the edit, so the viewer can warn first. Later
 * mesh edits refer to the new numbers. (In practice the other layers' nodes keep their numbers
 * when the edited layer keeps its node count, as a move or a rotation does; nothing relies on it.)
 *
 * Undo restores the model byte for byte: each edit keeps what it replaced (a node's coordinates,
 * a removed triangle and its place, the surface and the layer's loops before a re-lace, the
 * surface's interior point), and undo puts it back. Redo applies the edit again (deterministic:
 * the same state gives the same result). A new edit empties the redo stack.
 *
 * After each edit, undo and redo, the strict surface check (thorax/check/check.h) runs on the
 * edited surface and its findings come back in thx_edit_result (the report, and one line for a
 * status bar). An edit is applied whatever the check finds: a deleted triangle opens the surface,
 * and that is what the check says; the edit itself fails only when it cannot apply (a surface,
 * node, triangle or layer that does not exist, a duplicate triangle, coordinates not finite, no
 * contours for a layer edit, loops a layer edit made invalid). A failed edit changes nothing.
 *
 * The edit log (docs/formats.md, "Edit logs"): text, first line `thorax-edits 1`, a header naming
 * the contour file (its SHA-256 and path) and the surfaces build's options (`build ...`), one edit a
 * line in the words above, `#` comments, a last line `end`. Saving a session writes the model
 * directory with the log beside the surfaces (MODEL/edits.txt, named with its hash in model.json's
 * provenance; thorax/io/model_dir.h), so a model is reproducible from its contours plus its edits.
 */
#ifndef THORAX_EDIT_EDIT_H
#define THORAX_EDIT_EDIT_H

#include "thorax/check/check.h"
#include "thorax/core/fileio.h"
#include "thorax/geom/repair.h"
#include "thorax/geom/surfaces.h"
#include "thorax/model/contours.h"
#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

struct cJSON;

/* ---- edits ------------------------------------------------------------------------------------ */

typedef enum {
    THX_EDIT_NODE_MOVE = 0,
    THX_EDIT_TRI_DELETE,
    THX_EDIT_TRI_ADD,
    THX_EDIT_TRI_FLIP,
    THX_EDIT_LAYER_MOVE,
    THX_EDIT_LAYER_ROTATE,
    THX_EDIT_LAYER_SMOOTH,
    THX_EDIT_KIND_COUNT
} thx_edit_kind;

/* The log's word for a kind ("node_move", ...; static storage), and the kind of a word (0, or -1
 * if it is none). */
const char *thx_edit_kind_name(thx_edit_kind k);
int thx_edit_kind_parse(const char *word, thx_edit_kind *out);
/* Whether a kind is a layer edit (acts on the contours and re-laces). */
int thx_edit_kind_is_layer(thx_edit_kind k);

/* Which layer of a surface a layer edit means. */
typedef struct {
    int by_index;  /* 1: index; 0: z */
    size_t index;  /* 0-based among the surface's layers, in increasing z */
    double z;      /* mm; matched within THX_EDIT_Z_TOL */
} thx_edit_layer;
#define THX_EDIT_Z_TOL 1e-4

/* One edit. Plain data; build one with the constructors below. */
typedef struct {
    thx_edit_kind kind;
    char surface[64];   /* the surface's name */
    size_t node;        /* node_move: 0-based node */
    size_t tri;         /* tri_delete, tri_flip: 0-based triangle */
    size_t nodes[3];    /* tri_add: 0-based nodes, in the order given (tri_add orders them itself) */
    double v[3];        /* node_move: x y z (mm); layer_move: dx dy (mm); layer_rotate: degrees;
                           layer_smooth: bandwidth (mm, > 0) */
    thx_edit_layer layer; /* layer edits */
    int line;           /* the log line it came from (0: not from a log) */
} thx_edit;

thx_edit thx_edit_node_move(const char *surface, size_t node, thx_vec3 to);
thx_edit thx_edit_tri_delete(const char *surface, size_t tri);
thx_edit thx_edit_tri_add(const char *surface, size_t a, size_t b, size_t c);
thx_edit thx_edit_tri_flip(const char *surface, size_t tri);
thx_edit thx_edit_layer_move(const char *surface, thx_edit_layer layer, double dx, double dy);
thx_edit thx_edit_layer_rotate(const char *surface, thx_edit_layer layer, double degrees);
thx_edit thx_edit_layer_smooth(const char *surface, thx_edit_layer layer, double bandwidth_mm);
thx_edit_layer thx_edit_layer_z(double z);
thx_edit_layer thx_edit_layer_index(size_t index);

/* The edit as a log line (no newline, 1-based indices, numbers in the shortest form that reads
 * back to the same double): "tri_add torso 12 13 40". Returns the length snprintf would give. */
int thx_edit_format(const thx_edit *e, char *buf, size_t cap);

/* ---- the recipe: how the surfaces were built from the contours ------------------------------- */

/* The options of `thorax surfaces` that decide the surfaces (the repair of the contours and the
 * build), with spacing and start point as used (not "from the file"). A layer edit laces with it;
 * the log's `build` line records it, and a replay refuses a run whose recipe differs. lace.window
 * is not an option of the command and keeps its default. */
typedef struct {
    thx_surfaces_opts surfaces; /* spacing > 0 */
    thx_repair_opts repair;     /* repair.spacing == surfaces.spacing */
} thx_edit_recipe;

/* Adds the recipe to a provenance "options" object, as `thorax surfaces` records it: spacing_mm,
 * smoothing_mm, start_point_mm, cap, cap_grid_mm, concave_tol, max_edge, phase_weight, fan_limit,
 * projected_aspect, merge_tol_mm, untangle_tol_mm, strict. THX_ENOMEM on failure. */
thx_status thx_edit_recipe_json(thx_ctx *ctx, const thx_edit_recipe *r, struct cJSON *options);
/* Reads those keys back from a model's provenance (JSON text of the object; `where` names it in
 * messages). THX_EINPUT naming the key when one is missing or of the wrong type. */
thx_status thx_edit_recipe_from_provenance(thx_ctx *ctx, const char *provenance_json, const char *where,
                                           thx_edit_recipe *r);
/* 1 if the two recipes are the same bit for bit; else 0 with the first differing option and both
 * values in what ("spacing: 11 here, 5 in the log"; what may be NULL). */
int thx_edit_recipe_same(const thx_edit_recipe *here, const thx_edit_recipe *log, char *what, size_t cap);

/* ---- what an edit did ------------------------------------------------------------------------ */

typedef struct {
    thx_edit_kind kind;
    size_t surface;          /* index of the edited surface in the model */
    int relaced;             /* 1: a layer edit laced the surface again */
    size_t discarded;        /* mesh edits on this surface since its last lacing that the re-lace
                                discarded (0 for a mesh edit) */
    size_t tri;              /* tri_add: index of the new triangle; tri_delete, tri_flip: the triangle */
    int32_t tri_nodes[3];    /* tri_add: the new triangle's nodes (0-based) as stored */
    int neighbours_agree;    /* tri_add: edges shared with existing triangles that decided the order
                                (0: none shared, the order as given) */
    int neighbours_disagree; /* tri_add: shared edges that voted for the other order (outvoted) */
    char note[256];          /* what the edit did beyond the obvious ("" if nothing) */
    thx_surface_report check;/* the strict check of the edited surface after the edit */
    int check_ok;            /* check.ok */
    char summary[512];       /* the check in one line, nodes and triangles 1-based:
                                "torso: passes: closed, orientation ok, solid angle 4pi within 3.1e-07,
                                no self-intersections (3023 nodes, 6042 triangles)" */
} thx_edit_result;

/* The one-line summary of a surface report (as thx_edit_result.summary). */
void thx_edit_check_summary(const thx_surface_report *r, char *buf, size_t cap);

/* ---- the session ------------------------------------------------------------------------------ */

typedef struct thx_edit_session thx_edit_session; /* opaque: the model, its contours, the stacks */

typedef struct {
    thx_check_opts check; /* the check after each edit (thx_check_opts_default) */
    int drop_volume;      /* a model with a volume mesh: 0 refuses it (an edit would invalidate the mesh
                             built on the surfaces), 1 holds it apart from the edited model: saved
                             again only while the surfaces are unchanged (thx_edit_session_save) */
} thx_edit_session_opts;

void thx_edit_session_opts_default(thx_edit_session_opts *o);

/*
 * A session on a model in memory. Takes ownership of *model (nulls it, even on failure) and of
 * *contours (may be NULL: no layer edits; else the contours as the build saw them, i.e. repaired
 * with recipe->repair). recipe: required with contours. contours_name and contours_sha256 (the
 * contour file's path as the log should name it, and the SHA-256 of its bytes) go into the log's
 * header; either may be NULL. If the model holds an edit log (model->edit_log), the session starts
 * after it: its edits are the session's base (kept in the log, not undoable), and its layer edits
 * are applied to the contours so that later layer edits start from them. o: NULL for defaults.
 */
thx_status thx_edit_session_create(thx_ctx *ctx, thx_model **model, thx_contours **contours,
                                   const thx_edit_recipe *recipe, const char *contours_name,
                                   const char *contours_sha256, const thx_edit_session_opts *o,
                                   thx_edit_session **out);
/*
 * A session on a model directory (thx_model_read). The contours: contours_path if not NULL (then a
 * file whose SHA-256 differs from the model's record is an error), else the file the model's
 * provenance names ("input_from_model", relative to the model directory, then "input"), used only
 * if its SHA-256 is the recorded "input_sha256". They are read and repaired with the recipe the
 * provenance records. Without contours the session allows mesh edits only, and
 * thx_edit_session_note says why.
 */
thx_status thx_edit_session_open(thx_ctx *ctx, const char *model_dir, const char *contours_path,
                                 const thx_edit_session_opts *o, thx_edit_session **out);
/* Frees the session, its model and contours; accepts NULL; nulls *s. */
void thx_edit_session_destroy(thx_edit_session **s);

/* Applies an edit (see the header comment) and checks the edited surface into *res (may be NULL).
 * On failure nothing changed; the message names the edit ("tri_delete torso 9000: triangle 9000 out
 * of range 1..6042"), prefixed "LOG:LINE: " when the edit came from a log. */
thx_status thx_edit_apply(thx_ctx *ctx, thx_edit_session *s, const thx_edit *e, thx_edit_result *res);
/* Undoes the last edit of the session (not the base from a loaded log) / applies the last undone one
 * again; *res (may be NULL) holds the check of the surface afterwards. THX_EINPUT when there is
 * nothing to undo / redo. */
thx_status thx_edit_undo(thx_ctx *ctx, thx_edit_session *s, thx_edit_result *res);
thx_status thx_edit_redo(thx_ctx *ctx, thx_edit_session *s, thx_edit_result *res);
size_t thx_edit_undo_count(const thx_edit_session *s);
size_t thx_edit_redo_count(const thx_edit_session *s);

/* The model being edited (owned by the session; valid until the next call on it). */
const thx_model *thx_edit_session_model(const thx_edit_session *s);
/* The contours layer edits act on (edited as the session went), or NULL. */
const thx_contours *thx_edit_session_contours(const thx_edit_session *s);
/* Why the session has no contours (or "" when it has). */
const char *thx_edit_session_note(const thx_edit_session *s);
/* Mesh edits made on surface k since it was last laced (base edits from a loaded log included):
 * what a layer edit on it would discard. */
size_t thx_edit_session_mesh_edits(const thx_edit_session *s, size_t k);

/* The edit log of the session as it would be saved: the loaded log (up to its `end`) or a new
 * header, the session's edits, `end`. *text malloc'd (caller frees). */
thx_status thx_edit_session_log_text(thx_ctx *ctx, const thx_edit_session *s, char **text);
/* Writes the log alone to path, atomically; an existing file is replaced only when it is an edit log
 * thorax wrote (thx_atomic_open_output with marker "thorax-edits"). */
thx_status thx_edit_session_write_log(thx_ctx *ctx, const thx_edit_session *s, const char *path);
/* Saves the edited model: the model directory with the log as edits.txt (thx_model_write: dir is
 * replaced only when it is thorax's own model). The session's model keeps the log
 * (model->edit_log). save_claimed writes into a directory claimed earlier (thx_outdir_claim).
 * The volume mesh the model was opened with (drop_volume) is saved with it while the surfaces are
 * still those it was built on (no edit, or all undone). Saved into the directory the session was
 * opened on (thx_edit_session_open), the model keeps the folders other commands wrote into it (its
 * electrodes), and a mesh the edits made stale is moved aside into DIR.mesh-before-edit, never
 * deleted (src/edit/save.c); thx_edit_session_save_note then says where and how to mesh again. */
thx_status thx_edit_session_save(thx_ctx *ctx, thx_edit_session *s, const char *dir);
thx_status thx_edit_session_save_claimed(thx_ctx *ctx, thx_edit_session *s, thx_outdir *od);
/* What the last save did with a volume mesh it could not keep ("" nothing to say). */
const char *thx_edit_session_save_note(const thx_edit_session *s);
/* Whether the session holds a volume mesh apart (the model was opened with one, drop_volume). */
int thx_edit_session_has_mesh(const thx_edit_session *s);
/* Ends the session and hands its model over (with its log in model->edit_log) and its contours
 * (may be NULL to free them). *s is destroyed and nulled, also on failure. */
thx_status thx_edit_session_finish(thx_ctx *ctx, thx_edit_session **s, thx_model **model, thx_contours **contours);

/* ---- the log ----------------------------------------------------------------------------------- */

/* A log as read: its header, its edits and its text. */
typedef struct {
    char path[1024];         /* the file's name for messages ("<edits>" for text in memory) */
    int has_contours;        /* a `contours` line: */
    char contours_sha256[65];/*   the SHA-256 of the contour file's bytes */
    char contours_path[1024];/*   the path it names (informative: the replay is given its contours) */
    int contours_line;
    int has_recipe;          /* a `build` line: the recipe the surfaces were built with */
    thx_edit_recipe recipe;
    int recipe_line;
    size_t n_edits;
    thx_edit *edits;         /* n_edits, each with its line */
    char *text;              /* the whole text, NUL-terminated (owned) */
    size_t len;
    size_t end_offset;       /* where the `end` line starts in text */
} thx_edit_log;

/* Reads an edit log strictly: errors name file and line ("edits.txt:7: tri_add torso: 3 node
 * numbers needed, 2 given"), nothing is returned half-read. Refused: a NUL byte, a line over 4096
 * bytes, a file over 64 MiB, a first line other than `thorax-edits 1` (another version is named),
 * an unknown word, a wrong number of values, a number that is not plain decimal (hex, inf, nan,
 * trailing characters) or not finite, an index < 1 or > 2^31 - 1, a name with characters a
 * surface name cannot have, a header line after the first edit or given twice, a `build` line
 * with a missing, unknown or repeated option, a smoothing bandwidth <= 0, a tri_add with a
 * repeated node, a file without its `end` line, anything but comments after it. Caller destroys. */
thx_status thx_edit_log_read(thx_ctx *ctx, const char *path, thx_edit_log **out);
thx_status thx_edit_log_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_edit_log **out);
void thx_edit_log_destroy(thx_edit_log **log);

/* The text of a log: header (`contours` when sha256 is not NULL, `build` when recipe is not NULL),
 * then the edits, then `end`. comment (may be NULL) becomes a `#` line under the first. */
thx_status thx_edit_log_text(thx_ctx *ctx, const char *contours_name, const char *contours_sha256,
                             const thx_edit_recipe *recipe, const thx_edit *edits, size_t n, const char *comment,
                             char **text);

/* ---- replay ------------------------------------------------------------------------------------ */

/* Called after each replayed edit with its result (for a progress line). */
typedef void (*thx_edit_replay_fn)(void *user, const thx_edit_log *log, const thx_edit *e, const thx_edit_result *r);

/*
 * Applies a log's edits in order to a session just created on the model built from the contours
 * (no edits of its own yet). Before any edit: the log's `contours` hash must be the session's
 * contours' hash, and its `build` recipe the session's (else "LOG:LINE: ..." saying what differs).
 * An edit that does not apply stops the replay with "LOG:LINE: " and the reason; the session's
 * model is then partly edited and must be discarded (the CLI writes nothing). On success the log
 * becomes the session's base (its edits are not undoable): the model's edit log is the log's text
 * as given up to its `end` line (comments kept), then `end`.
 */
thx_status thx_edit_replay(thx_ctx *ctx, thx_edit_session *s, const thx_edit_log *log, thx_edit_replay_fn fn,
                           void *user);

/*
 * Records in a provenance object (`thorax surfaces`) where the contours are, for a session opened on
 * the model later: "input_sha256" (the SHA-256 of the contour file) and "input_from_model" (its path
 * relative to the model directory model_dir, which need not exist yet; left out when no relative
 * path exists). THX_EIO naming the file when it cannot be read.
 */
thx_status thx_edit_record_contours(thx_ctx *ctx, struct cJSON *provenance, const char *contours_path,
                                    const char *model_dir, char sha256_out[65]);

#ifdef __cplusplus
}
#endif
#endif
