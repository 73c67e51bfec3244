/*
 * The edit session (thorax/edit/edit.h): a model, its contours, the edits applied (after the base
 * a loaded log brought), the undo stack (what each edit replaced) and the redo stack (edits undone),
 * the check after each step, and saving the model with its log.
 *
 * Invariants: the model is the base model with the undo stack's edits applied in order; the
 * contours are the contours the base model was built from, with every layer edit of the base and of
 * the undo stack applied; mesh_edits[k] counts the mesh edits on surface k since its last lacing.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "edit/edit_impl.h"
#include "thorax/io/model_dir.h"

void thx_edit_session_opts_default(thx_edit_session_opts *o)
{
    memset(o, 0, sizeof *o);
    thx_check_opts_default(&o->check);
}

/* ---- the check after an edit -------------------------------------------------------------------- */

static size_t add(char *buf, size_t cap, size_t at, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static size_t add(char *buf, size_t cap, size_t at, const char *fmt, ...)
{
    if (at >= cap) return at;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf + at, cap - at, fmt, ap);
    va_end(ap);
    return n < 0 ? at : at + (size_t)n;
}

void thx_edit_check_summary(const thx_surface_report *r, char *buf, size_t cap)
{
    size_t at = add(buf, cap, 0, "%s: %s: ", r->name, r->ok ? "passes" : "FAILS");
    if (r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX)) {
        add(buf, cap, at, "%s", r->n_reasons ? r->reasons[0] : "no triangles");
        return;
    }
    if (r->n_boundary_edges)
        at = add(buf, cap, at, "%zu open edge%s (first %d-%d)", r->n_boundary_edges, r->n_boundary_edges == 1 ? "" : "s",
                 r->ex_boundary_edge[0] + 1, r->ex_boundary_edge[1] + 1);
    else at = add(buf, cap, at, "closed");
    if (r->n_nonmanifold_edges)
        at = add(buf, cap, at, ", %zu edge%s in 3 or more triangles (first %d-%d)", r->n_nonmanifold_edges,
                 r->n_nonmanifold_edges == 1 ? "" : "s", r->ex_nonmanifold_edge[0] + 1, r->ex_nonmanifold_edge[1] + 1);
    if (r->n_nonmanifold_vertices)
        at = add(buf, cap, at, ", %zu non-manifold node%s (first %d)", r->n_nonmanifold_vertices,
                 r->n_nonmanifold_vertices == 1 ? "" : "s", r->ex_nonmanifold_vertex + 1);
    if (r->n_inconsistent_edges)
        at = add(buf, cap, at, ", orientation: %zu edge%s traversed twice the same way (first %d-%d)",
                 r->n_inconsistent_edges, r->n_inconsistent_edges == 1 ? "" : "s", r->ex_inconsistent_edge[0] + 1,
                 r->ex_inconsistent_edge[1] + 1);
    else if (r->failures & THX_CHECKF_VOLUME) at = add(buf, cap, at, ", orientation: normals point inward");
    else at = add(buf, cap, at, ", orientation ok");
    if (isnan(r->solid_angle_rel_err)) at = add(buf, cap, at, ", no solid angle (no interior point)");
    else if (r->solid_angle_rel_err <= r->solid_angle_tol)
        at = add(buf, cap, at, ", solid angle 4pi within %.2g", r->solid_angle_rel_err);
    else
        at = add(buf, cap, at, ", solid angle %.6g x 4pi (off by %.2g, tolerance %.2g)", r->solid_angle / (4 * M_PI),
                 r->solid_angle_rel_err, r->solid_angle_tol);
    if (r->n_duplicate_tris)
        at = add(buf, cap, at, ", %zu duplicate triangle%s", r->n_duplicate_tris, r->n_duplicate_tris == 1 ? "" : "s");
    if (r->n_degenerate_tris)
        at = add(buf, cap, at, ", %zu degenerate triangle%s (first %zu)", r->n_degenerate_tris,
                 r->n_degenerate_tris == 1 ? "" : "s", r->ex_degenerate_tri + 1);
    if (r->n_unused_nodes)
        at = add(buf, cap, at, ", %zu unused node%s (first %d)", r->n_unused_nodes, r->n_unused_nodes == 1 ? "" : "s",
                 r->ex_unused_node + 1);
    if (!r->intersections_checked) at = add(buf, cap, at, ", self-intersections not checked");
    else if (r->n_intersecting_pairs)
        at = add(buf, cap, at, ", %zu self-intersecting triangle pair%s (first %zu-%zu)", r->n_intersecting_pairs,
                 r->n_intersecting_pairs == 1 ? "" : "s", r->pairs[0][0] + 1, r->pairs[0][1] + 1);
    else at = add(buf, cap, at, ", no self-intersections");
    if (r->failures & THX_CHECKF_QUALITY) at = add(buf, cap, at, ", triangle quality below the bound");
    add(buf, cap, at, " (%zu nodes, %zu triangles)", r->n_nodes, r->n_tris);
}

/* The strict check of surface k into res (when not NULL). A failed check is a finding, not an
 * error: the context's message is cleared. */
static thx_status check_surface(thx_ctx *ctx, thx_edit_session *s, size_t k, thx_edit_result *res)
{
    if (!res) return THX_OK;
    const thx_model *m = s->m;
    thx_surface_report_free(&res->check);
    thx_status st = thx_surface_check(ctx, m->surf[k], m->has_interior[k] ? &m->interior[k] : NULL, &s->opts.check,
                                      &res->check);
    if (st == THX_ECHECK) {
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    if (st != THX_OK) return st;
    res->surface = k;
    res->check_ok = res->check.ok;
    thx_edit_check_summary(&res->check, res->summary, sizeof res->summary);
    return THX_OK;
}

/* ---- life ---------------------------------------------------------------------------------------- */

void thx_edit_session_destroy(thx_edit_session **sp)
{
    if (!sp || !*sp) return;
    thx_edit_session *s = *sp;
    for (size_t i = 0; i < s->n_undo; i++) edit_undo_clear(&s->undo[i]);
    free(s->undo);
    free(s->redo);
    free(s->mesh_edits);
    free(s->base_text);
    thx_model_destroy(&s->m);
    thx_contours_destroy(&s->c);
    edit_kept_free(s);
    free(s);
    *sp = NULL;
}

/* Takes the loaded log m->edit_log as the session's base: its layer edits applied to the contours,
 * its mesh edits counted per surface. */
static thx_status take_base(thx_ctx *ctx, thx_edit_session *s)
{
    thx_edit_log *log = NULL;
    THX_CHECK(thx_edit_log_parse(ctx, "edits.txt (the model's edit log)", s->m->edit_log, strlen(s->m->edit_log), &log));
    thx_status st = THX_OK;
    if (log->has_contours && s->contours_sha256[0] && strcmp(log->contours_sha256, s->contours_sha256) != 0) {
        st = thx_error(ctx, THX_EINPUT,
                       "%s:%d: the model's edits were made on contours of SHA-256 %s, but %s has %s: the layer edits "
                       "would not start from the same layers",
                       log->path, log->contours_line, log->contours_sha256, s->contours_name, s->contours_sha256);
        goto done;
    }
    for (size_t i = 0; i < log->n_edits; i++) {
        const thx_edit *e = &log->edits[i];
        long k = edit_find_surface(s->m, e->surface);
        if (k < 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: the model has no surface \"%s\"", log->path, e->line, e->surface);
            goto done;
        }
        if (!thx_edit_kind_is_layer(e->kind)) {
            s->mesh_edits[k]++;
            continue;
        }
        s->mesh_edits[k] = 0;
        if (!s->c) continue; /* no contours: no layer edits later either */
        size_t cs, layer;
        thx_loop *old = NULL;
        size_t n_old = 0;
        st = edit_layer_locate(ctx, s->c, e, &cs, &layer);
        if (st == THX_OK) st = edit_layer_transform(ctx, s->c, cs, layer, e, &old, &n_old);
        edit_loops_free(old, n_old);
        if (st != THX_OK) {
            char msg[1024];
            snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
            st = thx_error(ctx, st, "%s:%d: %s", log->path, e->line, msg);
            goto done;
        }
    }
    s->n_base = log->n_edits;
    s->base_text = thx_malloc(ctx, log->end_offset + 1);
    if (!s->base_text) { st = THX_ENOMEM; goto done; }
    memcpy(s->base_text, log->text, log->end_offset);
    s->base_text[log->end_offset] = '\0';
done:
    thx_edit_log_destroy(&log);
    return st;
}

thx_status thx_edit_session_create(thx_ctx *ctx, thx_model **model, thx_contours **contours,
                                   const thx_edit_recipe *recipe, const char *contours_name,
                                   const char *contours_sha256, const thx_edit_session_opts *o,
                                   thx_edit_session **out)
{
    *out = NULL;
    thx_model *m = *model;
    thx_contours *c = contours ? *contours : NULL;
    *model = NULL;
    if (contours) *contours = NULL;
    thx_status st = THX_OK;
    thx_edit_session *s = NULL;
    if (!m) {
        thx_contours_destroy(&c);
        return thx_error(ctx, THX_EINTERNAL, "thx_edit_session_create: no model");
    }
    if (c && !recipe) {
        st = thx_error(ctx, THX_EINPUT, "contours without the recipe they were built with: layer edits impossible");
        goto fail;
    }
    if (contours_sha256 && (strlen(contours_sha256) != 64 || strspn(contours_sha256, "0123456789abcdef") != 64)) {
        st = thx_error(ctx, THX_EINPUT, "contours SHA-256 \"%.80s\" is not 64 lowercase hex digits", contours_sha256);
        goto fail;
    }
    s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) { st = THX_ENOMEM; goto fail; }
    s->m = m;
    s->c = c;
    m = NULL;
    c = NULL;
    if (o) s->opts = *o;
    else thx_edit_session_opts_default(&s->opts);
    if (recipe) {
        s->has_recipe = 1;
        s->recipe = *recipe;
    }
    snprintf(s->contours_name, sizeof s->contours_name, "%s", contours_name ? contours_name : "");
    snprintf(s->contours_sha256, sizeof s->contours_sha256, "%s", contours_sha256 ? contours_sha256 : "");
    if (!s->c) snprintf(s->note, sizeof s->note, "no contours: mesh edits only");
    if (s->m->volume) {
        if (!s->opts.drop_volume) {
            st = thx_error(ctx, THX_EINPUT,
                           "the model has a volume mesh built on these surfaces: an edit would leave it inconsistent; "
                           "edit the surfaces model (before thorax mesh), or drop the volume and mesh again");
            goto fail;
        }
        THX_TRY(edit_keep_volume(ctx, s)); /* kept apart: saved again while the surfaces are as it was built on */
    }
    s->mesh_edits = thx_calloc(ctx, s->m->n_surfaces ? s->m->n_surfaces : 1, sizeof *s->mesh_edits);
    if (!s->mesh_edits) { st = THX_ENOMEM; goto fail; }
    if (s->m->edit_log) THX_TRY(take_base(ctx, s));
    *out = s;
    return THX_OK;
done:
fail:
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    thx_edit_session_destroy(&s);
    return st;
}

/* ---- edits, undo, redo ------------------------------------------------------------------------- */

/* The edit's name for messages: "LOG:LINE: tri_delete torso 9000" or "tri_delete torso 9000". */
static void edit_label(const thx_edit *e, const char *log_path, char *buf, size_t cap)
{
    char line[256];
    thx_edit_format(e, line, sizeof line);
    if (e->line > 0 && log_path) snprintf(buf, cap, "%s:%d: %s", log_path, e->line, line);
    else snprintf(buf, cap, "%s", line);
}

thx_status edit_session_apply(thx_ctx *ctx, thx_edit_session *s, const thx_edit *e, const char *log_path,
                              thx_edit_result *res)
{
    thx_edit_result local;
    thx_edit_result *r = res ? res : &local;
    memset(r, 0, sizeof *r);
    if (thx_grow(ctx, (void **)&s->undo, &s->cap_undo, s->n_undo + 1, sizeof *s->undo) != THX_OK) return THX_ENOMEM;
    edit_undo *u = &s->undo[s->n_undo];
    thx_status st = edit_op_apply(ctx, s->m, s->c, s->has_recipe ? &s->recipe : NULL, e, u, r);
    if (st != THX_OK) {
        char label[1400], msg[1024];
        snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
        edit_label(e, log_path, label, sizeof label);
        edit_undo_clear(u);
        return thx_error(ctx, st, "%s: %s", label, msg);
    }
    s->n_undo++;
    size_t k = u->surf;
    u->old_mesh_edits = s->mesh_edits[k];
    if (thx_edit_kind_is_layer(e->kind)) {
        r->discarded = s->mesh_edits[k];
        s->mesh_edits[k] = 0;
        if (r->discarded) {
            size_t n = strlen(r->note);
            snprintf(r->note + n, sizeof r->note - n, "%s%zu earlier node/triangle edit%s on it discarded by the re-lace",
                     n ? "; " : "", r->discarded, r->discarded == 1 ? "" : "s");
        }
    } else {
        s->mesh_edits[k]++;
    }
    if (res) return check_surface(ctx, s, k, res);
    return THX_OK;
}

thx_status thx_edit_apply(thx_ctx *ctx, thx_edit_session *s, const thx_edit *e, thx_edit_result *res)
{
    THX_CHECK(edit_session_apply(ctx, s, e, NULL, res));
    s->n_redo = 0; /* a new edit: what was undone cannot be redone on top of it */
    return THX_OK;
}

thx_status thx_edit_undo(thx_ctx *ctx, thx_edit_session *s, thx_edit_result *res)
{
    if (!s->n_undo)
        return thx_error(ctx, THX_EINPUT, s->n_base ? "nothing to undo (the edits of the loaded log are the start)"
                                                    : "nothing to undo");
    if (thx_grow(ctx, (void **)&s->redo, &s->cap_redo, s->n_redo + 1, sizeof *s->redo) != THX_OK) return THX_ENOMEM;
    edit_undo *u = &s->undo[s->n_undo - 1];
    size_t k = u->surf;
    thx_edit e = u->e;
    s->mesh_edits[k] = u->old_mesh_edits;
    edit_op_undo(s->m, s->c, u);
    s->n_undo--;
    s->redo[s->n_redo++] = e;
    if (res) {
        memset(res, 0, sizeof *res);
        res->kind = e.kind;
        memcpy(res->note, "undone: ", 8);
        thx_edit_format(&e, res->note + 8, sizeof res->note - 8);
        return check_surface(ctx, s, k, res);
    }
    return THX_OK;
}

thx_status thx_edit_redo(thx_ctx *ctx, thx_edit_session *s, thx_edit_result *res)
{
    if (!s->n_redo) return thx_error(ctx, THX_EINPUT, "nothing to redo");
    thx_edit e = s->redo[s->n_redo - 1];
    THX_CHECK(edit_session_apply(ctx, s, &e, NULL, res));
    s->n_redo--;
    return THX_OK;
}

size_t thx_edit_undo_count(const thx_edit_session *s) { return s->n_undo; }
size_t thx_edit_redo_count(const thx_edit_session *s) { return s->n_redo; }
const thx_model *thx_edit_session_model(const thx_edit_session *s) { return s->m; }
const thx_contours *thx_edit_session_contours(const thx_edit_session *s) { return s->c; }
const char *thx_edit_session_note(const thx_edit_session *s) { return s->note; }

size_t thx_edit_session_mesh_edits(const thx_edit_session *s, size_t k)
{
    return k < s->m->n_surfaces ? s->mesh_edits[k] : 0;
}

/* ---- the log and saving ------------------------------------------------------------------------ */

thx_status thx_edit_session_log_text(thx_ctx *ctx, const thx_edit_session *s, char **text)
{
    *text = NULL;
    thx_edit *edits = thx_malloc(ctx, (s->n_undo ? s->n_undo : 1) * sizeof *edits);
    if (!edits) return THX_ENOMEM;
    for (size_t i = 0; i < s->n_undo; i++) {
        edits[i] = s->undo[i].e;
        edits[i].line = 0;
    }
    thx_status st;
    /* the path is informative in the log: characters its line cannot hold become '?' */
    char name[sizeof s->contours_name];
    memcpy(name, s->contours_name, sizeof name);
    for (char *p = name; *p; p++)
        if (*p == '#' || *p == '\n' || *p == '\r') *p = '?';
    if (!s->base_text) {
        st = thx_edit_log_text(ctx, name[0] ? name : NULL,
                               s->contours_sha256[0] ? s->contours_sha256 : NULL, s->has_recipe ? &s->recipe : NULL,
                               edits, s->n_undo, "edits of the model's surfaces (thorax/edit/edit.h); replay: thorax "
                                                 "surfaces CONTOURS --edits THIS -o MODEL",
                               text);
    } else {
        /* the loaded log as it was, then this session's edits */
        char *tail = NULL;
        st = thx_edit_log_text(ctx, NULL, NULL, NULL, edits, s->n_undo, NULL, &tail);
        if (st == THX_OK) {
            /* tail = "thorax-edits 1\n" + edits + "end\n": keep all after its first line */
            const char *after = strchr(tail, '\n');
            after = after ? after + 1 : tail;
            size_t nb = strlen(s->base_text), na = strlen(after);
            *text = thx_malloc(ctx, nb + na + 2);
            if (!*text) st = THX_ENOMEM;
            else {
                memcpy(*text, s->base_text, nb);
                size_t at = nb;
                if (nb && s->base_text[nb - 1] != '\n') (*text)[at++] = '\n';
                memcpy(*text + at, after, na + 1);
            }
        }
        free(tail);
    }
    free(edits);
    return st;
}

thx_status thx_edit_session_write_log(thx_ctx *ctx, const thx_edit_session *s, const char *path)
{
    char *text = NULL;
    THX_CHECK(thx_edit_session_log_text(ctx, s, &text));
    thx_atomic_file af;
    size_t n_in = 0;
    const char *const *in = thx_ctx_inputs(ctx, &n_in);
    thx_status st = thx_atomic_open_output(ctx, path, "thorax-edits", 12, in, n_in, &af);
    if (st == THX_OK) {
        fputs(text, af.f);
        st = thx_atomic_commit(ctx, &af);
        if (st != THX_OK) thx_atomic_abort(&af);
    }
    free(text);
    return st;
}

/* Puts the log into the model (m->edit_log) for writing. */
static thx_status set_model_log(thx_ctx *ctx, thx_edit_session *s)
{
    char *text = NULL;
    THX_CHECK(thx_edit_session_log_text(ctx, s, &text));
    free(s->m->edit_log);
    s->m->edit_log = text;
    return THX_OK;
}

thx_status edit_session_set_log(thx_ctx *ctx, thx_edit_session *s) { return set_model_log(ctx, s); }

thx_status thx_edit_session_finish(thx_ctx *ctx, thx_edit_session **sp, thx_model **model, thx_contours **contours)
{
    *model = NULL;
    if (contours) *contours = NULL;
    thx_edit_session *s = *sp;
    thx_status st = set_model_log(ctx, s);
    if (st == THX_OK) {
        *model = s->m;
        s->m = NULL;
        if (contours) {
            *contours = s->c;
            s->c = NULL;
        }
    }
    thx_edit_session_destroy(sp);
    return st;
}
