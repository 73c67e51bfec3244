/*
 * Manual editing in the viewer (paper 3.2, "Manual editing"), on the edit library
 * (thorax/edit/edit.h): an edit session opens on the model directory at the first edit; each edit
 * (a node moved by Alt+drag, the picked triangle deleted or flipped, a triangle built on the last
 * three picked nodes, the picked node's layer moved, turned or smoothed, or any edit-log line by
 * script) goes through the session, which runs the strict check on the edited surface — its
 * one-line verdict goes to the status line and stdout — and keeps undo and redo. The picture draws
 * the session's surfaces. Saving writes the model directory with its edit log (edits.txt), which
 * `thorax surfaces CONTOURS --edits LOG` replays.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/edit/edit.h"
#include "view/view_internal.h"

/* A deep copy of a surface. */
static thx_status copy_surface(thx_ctx *ctx, const thx_surface *s, thx_surface **out)
{
    thx_surface *c = NULL;
    THX_CHECK(thx_surface_create(ctx, s->name, s->role, &c));
    c->xyz = malloc((s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *c->xyz);
    c->tri = malloc((s->n_tris ? s->n_tris : 1) * 3 * sizeof *c->tri);
    if (!c->xyz || !c->tri) { thx_surface_destroy(&c); return thx_error(ctx, THX_ENOMEM, "out of memory (surface copy)"); }
    memcpy(c->xyz, s->xyz, s->n_nodes * 3 * sizeof *c->xyz);
    memcpy(c->tri, s->tri, s->n_tris * 3 * sizeof *c->tri);
    c->n_nodes = s->n_nodes;
    c->n_tris = s->n_tris;
    *out = c;
    return THX_OK;
}

/* The picture's surfaces made the session's again (after an edit, undo or redo); data whose rows
 * no longer match a re-laced surface are dropped from it, with a note. */
static thx_status sync_model(view_app *a)
{
    const thx_model *em = thx_edit_session_model(a->edit);
    thx_model *m = a->d.m;
    for (size_t k = 0; k < m->n_surfaces && k < em->n_surfaces; k++) {
        thx_surface *c = NULL;
        THX_CHECK(copy_surface(a->ctx, em->surf[k], &c));
        if (c->n_nodes != m->surf[k]->n_nodes && k < THX_PICTURE_SURFACES && a->d.series[k]) {
            /* the data were per node of the old lacing */
            for (int j = 0; j < a->d.n_sets[k]; j++) thx_series_destroy(&a->d.sets[k][j]);
            a->d.n_sets[k] = 0;
            a->d.series[k] = NULL;
            free(a->d.channel[k]);
            a->d.channel[k] = NULL;
            fprintf(stderr, "thorax view: %s was laced again: its data (per node of the old lacing) are no longer shown\n", c->name);
        }
        thx_surface_destroy(&m->surf[k]);
        m->surf[k] = c;
    }
    thx_picture_geometry_changed(&a->d);
    view_pick_prepare(a);
    int drop = 0;
    for (int k = 0; k < a->n_traces; k++)
        if (!a->d.series[a->traces[k].surface] || a->traces[k].node >= m->surf[a->traces[k].surface]->n_nodes) drop = 1;
    if (drop) a->n_traces = 0;
    view_redraw_all(a);
    view_plot_update(a);
    return THX_OK;
}

static void count_warnings(void *user, thx_log_level level, const char *message)
{
    (void)message;
    if (level >= THX_LOG_WARN) (*(int *)user)++;
}

/* Opens the session at the first edit: on the model directory the picture was read from. The
 * contours' repair says again what it said when the model was built: counted, not repeated. */
static int ensure_session(view_app *a)
{
    if (a->edit) return 0;
    if (!a->d.model_dir[0]) {
        view_set_info(a, "editing needs a model directory (surface files alone have no contours or log)");
        return -1;
    }
    thx_edit_session_opts eo;
    thx_edit_session_opts_default(&eo);
    eo.drop_volume = 1;
    thx_ctx *quiet = NULL;
    int warnings = 0;
    if (thx_ctx_create(&quiet) != THX_OK) return -1;
    thx_ctx_set_log(quiet, count_warnings, &warnings, THX_LOG_WARN);
    thx_status st = thx_edit_session_open(quiet, a->d.model_dir, NULL, &eo, &a->edit);
    if (st != THX_OK) {
        thx_error(a->ctx, st, "%s", thx_ctx_message(quiet));
        thx_ctx_destroy(&quiet);
        view_report(a, "edit");
        return -1;
    }
    thx_ctx_destroy(&quiet);
    if (warnings)
        fprintf(stderr, "thorax view: editing %s: its contours read and repaired as when it was built (%d repairs)\n",
                a->d.model_dir, warnings);
    const char *note = thx_edit_session_note(a->edit);
    if (a->d.m->volume)
        fprintf(stderr, "thorax view: editing %s: its volume mesh is saved with the model while the surfaces are as it was "
                        "built on; an edit kept moves it aside at the save (then: thorax mesh)\n", a->d.model_dir);
    if (note && *note) fprintf(stderr, "thorax view: editing %s: %s\n", a->d.model_dir, note);
    return 0;
}

static void report(view_app *a, const char *what, const thx_edit_result *r)
{
    view_set_info(a, "%s: %s%s%s", what, r->summary, r->note[0] ? "; " : "", r->note);
    if (a->vo->verbose >= 0) printf("edit: %s -> %s\n", what, r->summary);
    fflush(stdout);
}

/* Applies one edit; 0, or -1 after reporting (status 1). */
int view_edit_apply(view_app *a, const thx_edit *e)
{
    if (ensure_session(a)) { a->status = 1; return -1; }
    if (thx_edit_kind_is_layer(e->kind)) {
        const thx_model *em = thx_edit_session_model(a->edit);
        for (size_t k = 0; k < em->n_surfaces; k++)
            if (!strcmp(em->surf[k]->name, e->surface) && thx_edit_session_mesh_edits(a->edit, k))
                fprintf(stderr, "thorax view: lacing %s again discards the %zu mesh edit(s) made on it since its last lacing\n",
                        e->surface, thx_edit_session_mesh_edits(a->edit, k));
    }
    thx_edit_result r;
    char line[256];
    thx_edit_format(e, line, sizeof line);
    if (thx_edit_apply(a->ctx, a->edit, e, &r) != THX_OK) {
        view_report(a, "edit");
        a->status = 1;
        return -1;
    }
    report(a, line, &r);
    if (sync_model(a) != THX_OK) { view_report(a, "edit"); a->status = 1; return -1; }
    return 0;
}

/* An edit as a log line ("node_move torso 12 1 2 3", 1-based): parsed by the log reader itself. */
int view_edit_line(view_app *a, const char *text)
{
    char *log = g_strdup_printf("thorax-edits 1\n%s\nend\n", text);
    thx_edit_log *lg = NULL;
    thx_status st = thx_edit_log_parse(a->ctx, "edit", log, strlen(log), &lg);
    g_free(log);
    if (st != THX_OK) { view_report(a, "edit"); a->status = 1; return -1; }
    int rc = 0;
    for (size_t k = 0; k < lg->n_edits && !rc; k++) rc = view_edit_apply(a, &lg->edits[k]);
    if (lg->n_edits == 0) { view_set_info(a, "edit '%s': no edit on the line", text); a->status = 1; rc = -1; }
    thx_edit_log_destroy(&lg);
    return rc;
}

int view_edit_undo(view_app *a, int redo)
{
    if (!a->edit) { view_set_info(a, "%s: no edits yet", redo ? "redo" : "undo"); a->status = 1; return -1; }
    thx_edit_result r;
    if ((redo ? thx_edit_redo : thx_edit_undo)(a->ctx, a->edit, &r) != THX_OK) { view_report(a, redo ? "redo" : "undo"); a->status = 1; return -1; }
    report(a, redo ? "redo" : "undo", &r);
    return sync_model(a) == THX_OK ? 0 : -1;
}

int view_edit_save(view_app *a, const char *dir)
{
    if (!a->edit) { view_set_info(a, "save-model: no edits to save"); a->status = 1; return -1; }
    if (!dir[0]) dir = a->d.model_dir;
    if (thx_edit_session_save(a->ctx, a->edit, dir) != THX_OK) { view_report(a, "save-model"); a->status = 1; return -1; }
    const char *note = thx_edit_session_save_note(a->edit);
    if (note[0]) fprintf(stderr, "thorax view: save-model %s: %s\n", dir, note);
    view_set_info(a, "model saved to %s with its edit log (%zu edits in this session)%s%s", dir, thx_edit_undo_count(a->edit),
                  note[0] ? "; " : "", note);
    if (a->vo->verbose >= 0) printf("edit: saved %s\n", dir);
    fflush(stdout);
    return 0;
}

/* ---- edits on what was picked ---- */

/* The layer of the last picked node: its z (nodes of a layer lie in its plane). */
static int picked_layer(view_app *a, thx_edit_layer *l, const char **surface)
{
    if (a->n_picked == 0) { view_set_info(a, "pick a node of the layer first"); a->status = 1; return -1; }
    const view_pick *p = &a->picked[a->n_picked - 1];
    const thx_surface *s = a->d.m->surf[p->surface];
    *l = thx_edit_layer_z(s->xyz[3 * p->node + 2]);
    *surface = s->name;
    return 0;
}

int view_edit_picked(view_app *a, const char *what, double x)
{
    const view_pick *p = a->n_picked ? &a->picked[a->n_picked - 1] : NULL;
    if (!p) { view_set_info(a, "%s: pick something first (a click)", what); a->status = 1; return -1; }
    const char *name = a->d.m->surf[p->surface]->name;
    thx_edit e;
    if (!strcmp(what, "delete")) e = thx_edit_tri_delete(name, p->tri);
    else if (!strcmp(what, "flip")) e = thx_edit_tri_flip(name, p->tri);
    else if (!strcmp(what, "triangle")) {
        if (a->n_picked < 3) { view_set_info(a, "triangle: pick three nodes first (%d picked)", a->n_picked); a->status = 1; return -1; }
        const view_pick *q = &a->picked[a->n_picked - 3], *r = &a->picked[a->n_picked - 2];
        if (q->surface != p->surface || r->surface != p->surface) {
            view_set_info(a, "triangle: the three nodes picked last are not on one surface");
            a->status = 1;
            return -1;
        }
        e = thx_edit_tri_add(name, q->node, r->node, p->node);
    } else {
        thx_edit_layer l;
        const char *sname;
        if (picked_layer(a, &l, &sname)) return -1;
        if (!strcmp(what, "layer-x")) e = thx_edit_layer_move(sname, l, x, 0);
        else if (!strcmp(what, "layer-y")) e = thx_edit_layer_move(sname, l, 0, x);
        else if (!strcmp(what, "layer-rotate")) e = thx_edit_layer_rotate(sname, l, x);
        else e = thx_edit_layer_smooth(sname, l, x);
    }
    int rc = view_edit_apply(a, &e);
    if (!rc && (!strcmp(what, "delete") || thx_edit_kind_is_layer(e.kind))) a->n_picked = 0; /* the numbers changed */
    return rc;
}

/* Alt+drag: the node picked at the start follows the pointer in the plane facing the viewer;
 * the edit is made when the button is let go. */
void view_edit_drag(view_win *w, double dx, double dy, int done)
{
    view_app *a = w->app;
    if (a->n_picked == 0) return;
    view_pick *p = &a->picked[a->n_picked - 1];
    thx_surface *s = a->d.m->surf[p->surface];
    double r[3], u[3], b[3], mm = view_mm_per_pixel(w);
    view_camera_basis(w, r, u, b);
    double to[3];
    for (int k = 0; k < 3; k++) to[k] = p->start[k] + mm * (dx * r[k] - dy * u[k]);
    if (!done) { /* a preview on the picture's copy */
        memcpy(s->xyz + 3 * p->node, to, sizeof to);
        thx_picture_geometry_changed(&a->d);
        view_redraw_all(a);
        return;
    }
    memcpy(s->xyz + 3 * p->node, p->start, sizeof to); /* the edit moves it for real */
    if (fabs(dx) < 1 && fabs(dy) < 1) { view_redraw_all(a); return; }
    thx_edit e = thx_edit_node_move(s->name, p->node, thx_v3(to[0], to[1], to[2]));
    view_edit_apply(a, &e);
    memcpy(p->start, to, sizeof to);
}
