/*
 * Internals of the edit module (src/edit): what an applied edit replaced, shared between the
 * operations (ops.c), the session (session.c), the log (log.c) and the replay (replay.c).
 */
#ifndef THORAX_EDIT_IMPL_H
#define THORAX_EDIT_IMPL_H

#include "thorax/edit/edit.h"

/* What one applied edit replaced: enough to put the model and the contours back byte for byte. */
typedef struct {
    thx_edit e;                /* the edit as applied */
    size_t surf;               /* the model's surface */
    double old_xyz[3];         /* node_move: the node's coordinates before */
    int32_t old_tri[3];        /* tri_delete: the removed triangle (at index e.tri) */
    thx_surface *old_surface;  /* layer edits: the surface before the re-lace (owned) */
    int old_has_interior;      /* layer edits: its interior point */
    thx_vec3 old_interior;
    size_t cs, layer;          /* layer edits: the contour surface and layer */
    thx_loop *old_loops;       /* layer edits: the layer's loops before (owned) */
    size_t old_n_loops;
    size_t old_mesh_edits;     /* the session's count of mesh edits on surf before */
} edit_undo;

/* The session (thorax/edit/edit.h). Invariants: the model is the base model with the undo stack's
 * edits applied in order; the contours are the contours the base model was built from with every
 * layer edit of the base and of the undo stack applied; mesh_edits[k] counts the mesh edits on
 * surface k since its last lacing. */
struct thx_edit_session {
    thx_model *m;
    thx_contours *c;          /* NULL: no layer edits */
    int has_recipe;
    thx_edit_recipe recipe;
    char contours_name[1024]; /* "" when unknown */
    char contours_sha256[65]; /* "" when unknown */
    char note[768];
    thx_edit_session_opts opts;
    char *base_text;          /* the loaded log up to its `end` line, or NULL (a new header) */
    size_t n_base;            /* edits in the base */
    edit_undo *undo;
    size_t n_undo, cap_undo;
    thx_edit *redo;
    size_t n_redo, cap_redo;
    size_t *mesh_edits;       /* per model surface */
    /* the volume mesh the model was read with (held apart from m: an edit may leave it stale), the
       surfaces it was built on (copies, to tell whether the edits changed them), the directory the
       model was read from ("" when made in memory), and what the last save did with the mesh */
    thx_volume *kept_volume;
    thx_surface **mesh_surf;
    size_t n_mesh_surf;
    char source_dir[4096];
    char save_note[1024];
};

/* The volume mesh and the surfaces it was built on set apart (at session create). */
thx_status edit_keep_volume(thx_ctx *ctx, thx_edit_session *s);
void edit_kept_free(thx_edit_session *s);
/* The session's log text into s->m->edit_log (for a save). */
thx_status edit_session_set_log(thx_ctx *ctx, thx_edit_session *s);
/* The model's record of its contours ("input_from_model") made relative to dir, where the model is
 * about to be saved, from the contour file the session read: a saved model finds its contours from
 * wherever it is opened (the record relative to the old folder pointed elsewhere). Nothing changes
 * when the session has no contours or the record already says so. */
thx_status edit_rebase_contours(thx_ctx *ctx, thx_edit_session *s, const char *dir);


/* Applies e in the session, pushing its undo record and counting it, then checks the surface into
 * res (when not NULL); the redo stack is left alone (the callers decide). A failure names the edit,
 * as "LOG:LINE: EDIT: reason" when log_path is given and the edit has a line. */
thx_status edit_session_apply(thx_ctx *ctx, thx_edit_session *s, const thx_edit *e, const char *log_path,
                              thx_edit_result *res);

/* The model's surface of that name, or -1. */
long edit_find_surface(const thx_model *m, const char *name);

/* The contour surface and layer a layer edit means; THX_EINPUT saying what is missing. */
thx_status edit_layer_locate(thx_ctx *ctx, const thx_contours *c, const thx_edit *e, size_t *cs, size_t *layer);

/* Applies a layer edit's change to the contours alone (the layer's loops moved, turned or
 * smoothed); the loops before go to *old / *n_old (owned by the caller: edit_loops_free), so the
 * caller can put them back with edit_loops_swap. */
thx_status edit_layer_transform(thx_ctx *ctx, thx_contours *c, size_t cs, size_t layer, const thx_edit *e,
                                thx_loop **old, size_t *n_old);
/* Exchanges the layer's loops with (*loops, *n). */
void edit_loops_swap(thx_contours *c, size_t cs, size_t layer, thx_loop **loops, size_t *n);
void edit_loops_free(thx_loop *loops, size_t n);

/* Applies e to the model (and, for a layer edit, the contours, then re-laces with recipe), filling
 * *u with what it replaced and the edit-specific fields of *res (tri, tri_nodes, neighbours, note,
 * relaced). On failure nothing changed and the message is the reason alone (the caller names the
 * edit). */
thx_status edit_op_apply(thx_ctx *ctx, thx_model *m, thx_contours *c, const thx_edit_recipe *recipe,
                         const thx_edit *e, edit_undo *u, thx_edit_result *res);
/* Puts back what u replaced (cannot fail: it only moves what u holds), then clears u. */
void edit_op_undo(thx_model *m, thx_contours *c, edit_undo *u);
/* Frees what u holds. */
void edit_undo_clear(edit_undo *u);

/* The recipe's options one by one (recipe.c), as the log's `build` line writes them:
 * spacing smoothing start cap cap_grid concave_tol max_edge phase_weight fan_limit projected_aspect
 * merge_tol untangle_tol strict. */
#define EDIT_RECIPE_NFIELDS 13
/* The defaults of `thorax surfaces` (spacing 5). */
void edit_recipe_default(thx_edit_recipe *r);
const char *edit_recipe_field_name(int f);
/* What a value of field f looks like (for messages). */
const char *edit_recipe_field_help(int f);
/* The field of that name, or -1. */
int edit_recipe_field(const char *name);
/* Field f's value as the log writes it (numbers in their shortest exact form). */
void edit_recipe_format(const thx_edit_recipe *r, int f, char *buf, size_t cap);
/* Sets field f from its text; 0, or -1 if the text is not a valid value. */
int edit_recipe_parse(thx_edit_recipe *r, int f, const char *text);

/* A number written plainly in decimal: [+-] digits [. digits] [e [+-] digits] (or [+-] . digits
 * ...), finite; no hex, inf, nan or trailing characters. 0, or -1. */
int edit_parse_real(const char *s, double *out);

/* The shortest "%.Ng" form of v that reads back to v. */
void edit_fmt_double(char *buf, size_t cap, double v);

#endif
