/*
 * Reproducing a model from its contours and its edits (thorax/edit/edit.h): where a model's
 * contours are (recorded when `thorax surfaces` writes it, found again when a session opens it),
 * and the replay of an edit log on the surfaces built from them.
 */
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "edit/edit_impl.h"
#include "thorax/core/sha256.h"
#include "thorax/io/contours_file.h"
#include "thorax/io/model_dir.h"

/* ---- where the contours are ---------------------------------------------------------------------- */

/* The absolute path of path (resolved); when it does not exist and may_be_new, its parent's
 * resolved path and its own last name. 0, or -1. */
static int absolute(const char *path, int may_be_new, char out[PATH_MAX])
{
    if (realpath(path, out)) return 0;
    if (!may_be_new || errno != ENOENT) return -1;
    char tmp[PATH_MAX];
    size_t n = strlen(path);
    if (n == 0 || n >= sizeof tmp) return -1;
    memcpy(tmp, path, n + 1);
    while (n > 1 && tmp[n - 1] == '/') tmp[--n] = '\0';
    char *slash = strrchr(tmp, '/');
    const char *base = slash ? slash + 1 : tmp;
    char parent[PATH_MAX];
    if (!slash) snprintf(parent, sizeof parent, ".");
    else if (slash == tmp) snprintf(parent, sizeof parent, "/");
    else {
        *slash = '\0';
        snprintf(parent, sizeof parent, "%s", tmp);
    }
    char rp[PATH_MAX];
    if (!realpath(parent, rp)) return -1;
    if (!*base || !strcmp(base, ".") || !strcmp(base, "..")) return -1;
    if ((size_t)snprintf(out, PATH_MAX, "%s%s%s", rp, strcmp(rp, "/") ? "/" : "", base) >= PATH_MAX) return -1;
    return 0;
}

/* The path of `to` relative to the directory `from` (both absolute, resolved). 0, or -1. */
static int relative(const char *from, const char *to, char *out, size_t cap)
{
    /* the longest common prefix of whole components */
    size_t i = 0, common = 0;
    for (;; i++) {
        char a = from[i], b = to[i];
        if ((a == '/' || a == '\0') && (b == '/' || b == '\0')) common = i;
        if (a != b || a == '\0') break;
    }
    const char *up = from + common, *down = to + common;
    size_t at = 0;
    out[0] = '\0';
    for (const char *p = up; *p; p++)
        if (*p == '/' && p[1] && p[1] != '/') {
            int k = snprintf(out + at, cap - at, "../");
            if (k < 0 || (size_t)k >= cap - at) return -1;
            at += (size_t)k;
        }
    while (*down == '/') down++;
    int k = snprintf(out + at, cap - at, "%s", down);
    if (k < 0 || (size_t)k >= cap - at) return -1;
    return out[0] ? 0 : -1;
}

thx_status thx_edit_record_contours(thx_ctx *ctx, cJSON *prov, const char *contours_path, const char *model_dir,
                                    char sha256_out[65])
{
    char hex[65];
    THX_CHECK(thx_sha256_file(ctx, contours_path, hex));
    if (sha256_out) memcpy(sha256_out, hex, 65);
    if (!cJSON_AddStringToObject(prov, "input_sha256", hex)) return thx_error(ctx, THX_ENOMEM, "out of memory");
    char a[PATH_MAX], b[PATH_MAX], rel[PATH_MAX];
    if (absolute(contours_path, 0, a) == 0 && absolute(model_dir, 1, b) == 0 && relative(b, a, rel, sizeof rel) == 0)
        if (!cJSON_AddStringToObject(prov, "input_from_model", rel)) return thx_error(ctx, THX_ENOMEM, "out of memory");
    return THX_OK;
}

thx_status edit_rebase_contours(thx_ctx *ctx, thx_edit_session *s, const char *dir)
{
    if (!s->contours_name[0] || !s->m->provenance_json) return THX_OK;
    char a[PATH_MAX], b[PATH_MAX], rel[PATH_MAX];
    if (absolute(s->contours_name, 0, a) != 0 || absolute(dir, 1, b) != 0 || relative(b, a, rel, sizeof rel) != 0) return THX_OK;
    cJSON *prov = cJSON_Parse(s->m->provenance_json);
    if (!prov) return THX_OK;
    const cJSON *old = cJSON_GetObjectItemCaseSensitive(prov, "input_from_model");
    if (cJSON_IsString(old) && !strcmp(old->valuestring, rel)) { cJSON_Delete(prov); return THX_OK; }
    cJSON *v = cJSON_CreateString(rel);
    int ok = v && (cJSON_HasObjectItem(prov, "input_from_model") ? cJSON_ReplaceItemInObjectCaseSensitive(prov, "input_from_model", v)
                                                                   : cJSON_AddItemToObject(prov, "input_from_model", v));
    if (!ok) cJSON_Delete(v);
    char *text = ok ? cJSON_PrintUnformatted(prov) : NULL;
    cJSON_Delete(prov);
    if (!text) return thx_error(ctx, THX_ENOMEM, "out of memory (the model's provenance)");
    free(s->m->provenance_json); /* as thx_model_read made it: cJSON's text, freed with free */
    s->m->provenance_json = text;
    return THX_OK;
}

/* A string member of a JSON object, or NULL. */
static const char *jstr(const cJSON *o, const char *key)
{
    const cJSON *v = o ? cJSON_GetObjectItemCaseSensitive(o, key) : NULL;
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static int regular_file(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* The contours read and repaired as the build did. */
static thx_status read_contours(thx_ctx *ctx, const char *path, const thx_edit_recipe *r, thx_contours **out)
{
    thx_contours *c = NULL;
    THX_CHECK(thx_contours_read_raw(ctx, path, &c));
    /* quiet: these repairs were reported (and recorded in model.json) when the model was built;
       replaying them must not print one line per repair again (a dense loop: tens of thousands) */
    thx_repair_log rlog = {0};
    rlog.quiet = 1;
    thx_status st = thx_contours_repair(ctx, c, &r->repair, &rlog);
    thx_repair_log_free(&rlog);
    if (st != THX_OK) thx_contours_destroy(&c);
    *out = c;
    return st;
}

thx_status thx_edit_session_open(thx_ctx *ctx, const char *model_dir, const char *contours_path,
                                 const thx_edit_session_opts *o, thx_edit_session **out)
{
    *out = NULL;
    thx_model *m = NULL;
    thx_contours *c = NULL;
    cJSON *prov = NULL;
    THX_CHECK(thx_model_read(ctx, model_dir, &m));
    thx_status st = THX_OK;
    char where[4200], note[768] = "", path[8500] = "", sha[65] = "";
    snprintf(where, sizeof where, "%s/model.json", model_dir);
    thx_edit_recipe rec;
    int has_rec = thx_edit_recipe_from_provenance(ctx, m->provenance_json, where, &rec) == THX_OK;
    if (!has_rec) {
        snprintf(note, sizeof note, "%s: mesh edits only", thx_ctx_message(ctx));
        thx_ctx_clear(ctx);
    }
    prov = m->provenance_json ? cJSON_Parse(m->provenance_json) : NULL;
    const char *input = jstr(prov, "input"), *from_model = jstr(prov, "input_from_model");
    const char *recorded = jstr(prov, "input_sha256");
    if (contours_path) {
        if (!has_rec) {
            st = thx_error(ctx, THX_EINPUT, "%s", note);
            goto done;
        }
        THX_TRY(thx_sha256_file(ctx, contours_path, sha));
        if (recorded && strcmp(recorded, sha) != 0) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: SHA-256 %s, but %s was built from contours of SHA-256 %s (%s): layer edits would "
                           "rebuild its surfaces from other layers",
                           contours_path, sha, model_dir, recorded, input ? input : "?");
            goto done;
        }
        snprintf(path, sizeof path, "%s", contours_path);
    } else if (has_rec && recorded) {
        char cand[2][8500];
        int nc = 0;
        if (from_model) snprintf(cand[nc++], sizeof cand[0], "%s/%s", model_dir, from_model);
        if (input) snprintf(cand[nc++], sizeof cand[0], "%s", input);
        for (int k = 0; k < nc && !path[0]; k++) {
            if (!regular_file(cand[k]) || thx_sha256_file(ctx, cand[k], sha) != THX_OK) {
                thx_ctx_clear(ctx);
                continue;
            }
            if (strcmp(sha, recorded) == 0) memcpy(path, cand[k], strlen(cand[k]) + 1);
        }
        if (!path[0])
            snprintf(note, sizeof note,
                     "the contour file the model was built from (%s, SHA-256 %.12s...) was not found unchanged: mesh "
                     "edits only (open the session with its path)",
                     input ? input : "?", recorded);
    } else if (has_rec && cJSON_GetObjectItemCaseSensitive(prov, "image") && input) {
        /* built straight from a label map (thorax surfaces LABELS --label ...): no contour file */
        snprintf(note, sizeof note,
                 "the model was built straight from the label map %s, without a contour file: mesh edits only "
                 "(thorax digitize writes its contours; build from them to edit layers)", input);
    } else if (has_rec) {
        snprintf(note, sizeof note,
                 "the model does not record its contours' SHA-256 (built before thorax recorded it): mesh edits only "
                 "(open the session with the contours' path)");
    }
    if (path[0]) THX_TRY(read_contours(ctx, path, &rec, &c));
    thx_edit_session *s = NULL;
    THX_TRY(thx_edit_session_create(ctx, &m, &c, has_rec ? &rec : NULL, path[0] ? path : NULL, path[0] ? sha : NULL,
                                    o, &s));
    if (note[0]) snprintf(s->note, sizeof s->note, "%s", note);
    snprintf(s->source_dir, sizeof s->source_dir, "%s", model_dir);
    *out = s;
done:
    cJSON_Delete(prov);
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    return st;
}

/* ---- replay (the session's side: the log becomes its base) --------------------------------------- */

thx_status thx_edit_replay(thx_ctx *ctx, thx_edit_session *s, const thx_edit_log *log, thx_edit_replay_fn fn,
                           void *user)
{
    if (s->n_undo || s->base_text)
        return thx_error(ctx, THX_EINPUT, "%s: a log is replayed on the model as built, not on one already edited",
                         log->path);
    if (log->has_contours && s->contours_sha256[0] && strcmp(log->contours_sha256, s->contours_sha256) != 0)
        return thx_error(ctx, THX_EINPUT,
                         "%s:%d: the log was made on contours of SHA-256 %s (%s), but %s has %s: its edits would not "
                         "apply to the same surfaces",
                         log->path, log->contours_line, log->contours_sha256, log->contours_path,
                         s->contours_name[0] ? s->contours_name : "the contours given", s->contours_sha256);
    if (log->has_recipe && s->has_recipe) {
        char what[256];
        if (!thx_edit_recipe_same(&s->recipe, &log->recipe, what, sizeof what))
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: the log was made on surfaces built with other options (%s): node and triangle "
                             "numbers would not mean the same; build with the log's options",
                             log->path, log->recipe_line, what);
    }
    if (!log->has_contours)
        thx_log(ctx, THX_LOG_WARN, "%s: no 'contours' line: not checked that the log was made on these contours",
                log->path);
    if (!log->has_recipe)
        thx_log(ctx, THX_LOG_WARN, "%s: no 'build' line: not checked that the log was made with these options",
                log->path);
    thx_edit_result *r = thx_malloc(ctx, sizeof *r);
    if (!r) return THX_ENOMEM;
    memset(r, 0, sizeof *r);
    thx_status st = THX_OK;
    for (size_t i = 0; i < log->n_edits && st == THX_OK; i++) {
        st = edit_session_apply(ctx, s, &log->edits[i], log->path, fn ? r : NULL);
        if (st == THX_OK && fn) fn(user, log, &log->edits[i], r);
    }
    free(r);
    if (st != THX_OK) return st;
    /* the log is now the base: its text as given, its edits not undoable */
    s->base_text = thx_malloc(ctx, log->end_offset + 1);
    if (!s->base_text) return THX_ENOMEM;
    memcpy(s->base_text, log->text, log->end_offset);
    s->base_text[log->end_offset] = '\0';
    for (size_t i = 0; i < s->n_undo; i++) edit_undo_clear(&s->undo[i]);
    s->n_undo = 0;
    s->n_redo = 0;
    s->n_base = log->n_edits;
    return THX_OK;
}
