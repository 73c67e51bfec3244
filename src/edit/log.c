/*
 * The edit log (thorax/edit/edit.h; docs/formats.md, "Edit logs"): its text, and its strict reader.
 *
 *   thorax-edits 1
 *   # comments anywhere, from '#' to the end of the line
 *   contours sha256:HEX PATH          the contour file (SHA-256 of its bytes, its path)
 *   build spacing=11 smoothing=2 ...  the surfaces build's options (the recipe)
 *   node_move torso 18 12.5 -3.25 100
 *   ...
 *   end
 *
 * The reader is bounded: 64 MiB, lines of at most 4096 bytes, memory a small multiple of the file
 * (the edits array grows geometrically, one edit per line at most); nothing is returned half-read.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "edit/edit_impl.h"
#include "thorax/model/volume.h"

#define LOG_MAGIC "thorax-edits"
#define LOG_VERSION 1
#define LOG_MAX_BYTES (64u << 20)
#define LOG_MAX_LINE 4096
#define LOG_MAX_TOKENS 32

/* ---- writing ----------------------------------------------------------------------------------- */

typedef struct {
    char *p;
    size_t n, cap;
    int failed;
} sbuf;

static void sb_add(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_add(sbuf *b, const char *fmt, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->p ? b->p + b->n : NULL, b->p ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) { b->failed = 1; return; }
        if (b->p && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = b->cap ? b->cap : 1024;
        while (cap <= b->n + (size_t)k) cap *= 2;
        char *q = realloc(b->p, cap);
        if (!q) { b->failed = 1; return; }
        b->p = q;
        b->cap = cap;
    }
}

/* The recipe as the `build` line's words (after "build"). */
static void recipe_words(sbuf *b, const thx_edit_recipe *r)
{
    for (int f = 0; f < EDIT_RECIPE_NFIELDS; f++) {
        char v[96];
        edit_recipe_format(r, f, v, sizeof v);
        sb_add(b, " %s=%s", edit_recipe_field_name(f), v);
    }
}

thx_status thx_edit_log_text(thx_ctx *ctx, const char *contours_name, const char *contours_sha256,
                             const thx_edit_recipe *recipe, const thx_edit *edits, size_t n, const char *comment,
                             char **text)
{
    *text = NULL;
    if (contours_name && (strpbrk(contours_name, "#\n\r") || strlen(contours_name) >= 1024))
        return thx_error(ctx, THX_EINPUT,
                         "contour file name \"%.80s\" cannot go into an edit log (a '#', a line break, or 1024 "
                         "characters or more)",
                         contours_name);
    sbuf b = {0};
    sb_add(&b, "%s %d\n", LOG_MAGIC, LOG_VERSION);
    if (comment) sb_add(&b, "# %s\n", comment);
    if (contours_sha256) sb_add(&b, "contours sha256:%s %s\n", contours_sha256, contours_name && *contours_name ? contours_name : "-");
    if (recipe) {
        sb_add(&b, "build");
        recipe_words(&b, recipe);
        sb_add(&b, "\n");
    }
    for (size_t i = 0; i < n; i++) {
        char line[512];
        thx_edit_format(&edits[i], line, sizeof line);
        sb_add(&b, "%s\n", line);
    }
    sb_add(&b, "end\n");
    if (b.failed) {
        free(b.p);
        return thx_error(ctx, THX_ENOMEM, "out of memory writing an edit log");
    }
    *text = b.p;
    return THX_OK;
}

/* ---- reading ----------------------------------------------------------------------------------- */

void thx_edit_log_destroy(thx_edit_log **log)
{
    if (!log || !*log) return;
    free((*log)->edits);
    free((*log)->text);
    free(*log);
    *log = NULL;
}

int edit_parse_real(const char *s, double *out)
{
    const char *p = s;
    if (*p == '+' || *p == '-') p++;
    size_t d = strspn(p, "0123456789");
    p += d;
    if (*p == '.') {
        size_t f = strspn(p + 1, "0123456789");
        p += 1 + f;
        d += f;
    }
    if (!d) return -1;
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-') p++;
        size_t x = strspn(p, "0123456789");
        if (!x) return -1;
        p += x;
    }
    if (*p) return -1;
    errno = 0;
    double v = strtod(s, NULL);
    if (!isfinite(v)) return -1;
    *out = v;
    return 0;
}

/* A 1-based index 1..2^31-1 in plain digits, as 0-based. 0, or -1. */
static int parse_index(const char *s, size_t *out)
{
    size_t n = strspn(s, "0123456789");
    if (!n || s[n] || n > 10) return -1;
    unsigned long long v = strtoull(s, NULL, 10);
    if (v < 1 || v > 2147483647ull) return -1;
    *out = (size_t)(v - 1);
    return 0;
}

typedef struct {
    thx_ctx *ctx;
    const char *path;
    int line;
} rd;

static thx_status bad(const rd *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status bad(const rd *r, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(r->ctx, THX_EINPUT, "%s:%d: %s", r->path, r->line, msg);
}

static thx_status layer_spec(const rd *r, const char *word, const char *tok, thx_edit_layer *L)
{
    if (strncmp(tok, "z=", 2) == 0) {
        if (edit_parse_real(tok + 2, &L->z))
            return bad(r, "%s: \"%.40s\": the layer's z must be a decimal number (z=120.5)", word, tok);
        L->by_index = 0;
        return THX_OK;
    }
    if (strncmp(tok, "layer=", 6) == 0) {
        if (parse_index(tok + 6, &L->index))
            return bad(r, "%s: \"%.40s\": the layer's number must be 1..2147483647 (layer=3)", word, tok);
        L->by_index = 1;
        return THX_OK;
    }
    return bad(r, "%s: \"%.40s\": a layer is z=Z (its height, mm) or layer=N (its number on the surface, from 1)", word,
               tok);
}

/* One edit from its words. */
static thx_status parse_edit(const rd *r, char **tok, int nt, thx_edit *e)
{
    thx_edit_kind k;
    if (thx_edit_kind_parse(tok[0], &k))
        return bad(r, "unknown word \"%.40s\" (an edit is node_move, tri_delete, tri_add, tri_flip, layer_move, "
                      "layer_rotate or layer_smooth; or contours, build, end)",
                   tok[0]);
    static const int NVAL[THX_EDIT_KIND_COUNT] = {4, 1, 3, 1, 3, 2, 2};
    static const char *const ARGS[THX_EDIT_KIND_COUNT] = {
        "SURFACE NODE X Y Z", "SURFACE TRIANGLE", "SURFACE NODE NODE NODE", "SURFACE TRIANGLE",
        "SURFACE z=Z|layer=N DX DY", "SURFACE z=Z|layer=N DEGREES", "SURFACE z=Z|layer=N MM"};
    if (nt != 2 + NVAL[k])
        return bad(r, "%s: %d value%s after the word, %d needed (%s %s)", tok[0], nt - 1, nt - 1 == 1 ? "" : "s",
                   1 + NVAL[k], tok[0], ARGS[k]);
    memset(e, 0, sizeof *e);
    e->kind = k;
    e->line = r->line;
    if (!thx_name_ok(tok[1], sizeof e->surface))
        return bad(r, "%s: \"%.40s\" is not a surface name (letters, digits, '_', '-', '.', at most 63, not starting "
                      "with '.')",
                   tok[0], tok[1]);
    snprintf(e->surface, sizeof e->surface, "%s", tok[1]);
    switch (k) {
    case THX_EDIT_NODE_MOVE:
        if (parse_index(tok[2], &e->node)) return bad(r, "%s %s: node \"%.40s\" must be 1..2147483647", tok[0], tok[1], tok[2]);
        for (int i = 0; i < 3; i++)
            if (edit_parse_real(tok[3 + i], &e->v[i]))
                return bad(r, "%s %s: %c = \"%.40s\" is not a finite decimal number", tok[0], tok[1], "xyz"[i], tok[3 + i]);
        break;
    case THX_EDIT_TRI_DELETE:
    case THX_EDIT_TRI_FLIP:
        if (parse_index(tok[2], &e->tri))
            return bad(r, "%s %s: triangle \"%.40s\" must be 1..2147483647", tok[0], tok[1], tok[2]);
        break;
    case THX_EDIT_TRI_ADD:
        for (int i = 0; i < 3; i++)
            if (parse_index(tok[2 + i], &e->nodes[i]))
                return bad(r, "%s %s: node \"%.40s\" must be 1..2147483647", tok[0], tok[1], tok[2 + i]);
        if (e->nodes[0] == e->nodes[1] || e->nodes[1] == e->nodes[2] || e->nodes[0] == e->nodes[2])
            return bad(r, "%s %s: a triangle needs three different nodes (%s %s %s)", tok[0], tok[1], tok[2], tok[3], tok[4]);
        break;
    default:
        THX_CHECK(layer_spec(r, tok[0], tok[2], &e->layer));
        for (int i = 0; i < NVAL[k] - 1; i++)
            if (edit_parse_real(tok[3 + i], &e->v[i]))
                return bad(r, "%s %s: \"%.40s\" is not a finite decimal number", tok[0], tok[1], tok[3 + i]);
        if (k == THX_EDIT_LAYER_SMOOTH && !(e->v[0] > 0))
            return bad(r, "%s %s: the smoothing bandwidth must be > 0 mm (%s)", tok[0], tok[1], tok[3]);
        break;
    }
    return THX_OK;
}

/* The `build` line: every option of the recipe once, nothing else. */
static thx_status parse_build(const rd *r, char **tok, int nt, thx_edit_recipe *rec)
{
    int seen[EDIT_RECIPE_NFIELDS] = {0};
    edit_recipe_default(rec);
    for (int i = 1; i < nt; i++) {
        char *eq = strchr(tok[i], '=');
        if (!eq) return bad(r, "build: \"%.40s\" is not OPTION=VALUE", tok[i]);
        *eq = '\0';
        int f = edit_recipe_field(tok[i]);
        if (f < 0) return bad(r, "build: unknown option \"%.40s\"", tok[i]);
        if (seen[f]) return bad(r, "build: option \"%s\" given twice", tok[i]);
        seen[f] = 1;
        if (edit_recipe_parse(rec, f, eq + 1))
            return bad(r, "build: %s=\"%.40s\" is not a valid value (%s)", tok[i], eq + 1, edit_recipe_field_help(f));
    }
    for (int f = 0; f < EDIT_RECIPE_NFIELDS; f++)
        if (!seen[f]) return bad(r, "build: option \"%s\" missing (every option of the build is recorded)", edit_recipe_field_name(f));
    return THX_OK;
}

static int is_hex64(const char *s)
{
    return strlen(s) == 64 && strspn(s, "0123456789abcdef") == 64;
}

thx_status thx_edit_log_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_edit_log **out)
{
    *out = NULL;
    rd r = {ctx, name && *name ? name : "<edits>", 0};
    if (len > LOG_MAX_BYTES)
        return thx_error(ctx, THX_EINPUT, "%s: %zu bytes: larger than any edit log (64 MiB)", r.path, len);
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        int line = 1;
        for (const char *q = text; q < nul; q++) line += *q == '\n';
        return thx_error(ctx, THX_EINPUT, "%s:%d: NUL byte at byte offset %zu (not a text file)", r.path, line,
                         (size_t)(nul - text));
    }
    thx_edit_log *log = thx_calloc(ctx, 1, sizeof *log);
    if (!log) return THX_ENOMEM;
    snprintf(log->path, sizeof log->path, "%s", r.path);
    r.path = log->path;
    thx_status st = THX_OK;
    size_t cap = 0;
    log->text = thx_malloc(ctx, len + 1);
    if (!log->text) { st = THX_ENOMEM; goto done; }
    memcpy(log->text, text, len);
    log->text[len] = '\0';
    log->len = len;
    int state = 0; /* 0: before the first line, 1: header and edits, 2: after `end` */
    char buf[LOG_MAX_LINE + 2];
    for (size_t at = 0; at < len;) {
        const char *eol = memchr(text + at, '\n', len - at);
        size_t n = eol ? (size_t)(eol - (text + at)) : len - at;
        size_t line_start = at;
        r.line++;
        at += n + (eol ? 1 : 0);
        if (n > LOG_MAX_LINE) {
            st = bad(&r, "line of %zu bytes (at most %d)", n, LOG_MAX_LINE);
            goto done;
        }
        memcpy(buf, text + line_start, n);
        buf[n] = '\0';
        char *hash = strchr(buf, '#');
        if (hash) *hash = '\0';
        /* the raw rest of a `contours` line (the path may hold spaces) */
        char raw[LOG_MAX_LINE + 2];
        memcpy(raw, buf, strlen(buf) + 1);
        char *tok[LOG_MAX_TOKENS];
        int nt = 0;
        for (char *p = strtok(buf, " \t\r\v\f"); p; p = strtok(NULL, " \t\r\v\f")) {
            if (nt == LOG_MAX_TOKENS) {
                st = bad(&r, "more than %d words on a line", LOG_MAX_TOKENS);
                goto done;
            }
            tok[nt++] = p;
        }
        if (!nt) continue;
        if (state == 0) {
            if (strcmp(tok[0], LOG_MAGIC) != 0) {
                st = bad(&r, "not a thorax edit log: the first line must be \"%s %d\"", LOG_MAGIC, LOG_VERSION);
                goto done;
            }
            if (nt != 2 || strcmp(tok[1], "1") != 0) {
                st = bad(&r, "edit log version \"%.20s\": this thorax reads version %d", nt > 1 ? tok[1] : "",
                         LOG_VERSION);
                goto done;
            }
            state = 1;
            continue;
        }
        if (state == 2) {
            st = bad(&r, "text after 'end' (only comments may follow it)");
            goto done;
        }
        if (strcmp(tok[0], "end") == 0) {
            if (nt != 1) {
                st = bad(&r, "end: nothing may follow it on its line");
                goto done;
            }
            log->end_offset = line_start;
            state = 2;
            continue;
        }
        if (strcmp(tok[0], "contours") == 0 || strcmp(tok[0], "build") == 0) {
            int is_c = tok[0][0] == 'c';
            if (log->n_edits) {
                st = bad(&r, "%s: header lines come before the first edit", tok[0]);
                goto done;
            }
            if (is_c ? log->has_contours : log->has_recipe) {
                st = bad(&r, "%s: given twice (first on line %d)", tok[0], is_c ? log->contours_line : log->recipe_line);
                goto done;
            }
            if (is_c) {
                if (nt < 3 || strncmp(tok[1], "sha256:", 7) != 0 || !is_hex64(tok[1] + 7)) {
                    st = bad(&r, "contours: needs \"contours sha256:HEX PATH\" (HEX: 64 lowercase hex digits, the "
                                 "SHA-256 of the contour file)");
                    goto done;
                }
                memcpy(log->contours_sha256, tok[1] + 7, 65);
                /* the path: everything after the hash's word, trimmed */
                char *p = raw + (tok[2] - buf);
                size_t pl = strlen(p);
                while (pl && strchr(" \t\r\v\f", p[pl - 1])) p[--pl] = '\0';
                if (pl >= sizeof log->contours_path) {
                    st = bad(&r, "contours: path of %zu characters (at most %zu)", pl, sizeof log->contours_path - 1);
                    goto done;
                }
                memcpy(log->contours_path, p, pl + 1);
                log->has_contours = 1;
                log->contours_line = r.line;
            } else {
                THX_TRY(parse_build(&r, tok, nt, &log->recipe));
                log->has_recipe = 1;
                log->recipe_line = r.line;
            }
            continue;
        }
        if (thx_grow(ctx, (void **)&log->edits, &cap, log->n_edits + 1, sizeof *log->edits) != THX_OK) {
            st = THX_ENOMEM;
            goto done;
        }
        THX_TRY(parse_edit(&r, tok, nt, &log->edits[log->n_edits]));
        log->n_edits++;
    }
    if (state == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: empty: not a thorax edit log (its first line is \"%s %d\")", r.path,
                       LOG_MAGIC, LOG_VERSION);
        goto done;
    }
    if (state != 2) {
        st = thx_error(ctx, THX_EINPUT, "%s:%d: truncated edit log (no 'end' line)", r.path, r.line);
        goto done;
    }
    *out = log;
    log = NULL;
done:
    thx_edit_log_destroy(&log);
    return st;
}

thx_status thx_edit_log_read(thx_ctx *ctx, const char *path, thx_edit_log **out)
{
    *out = NULL;
    struct stat sb;
    if (stat(path, &sb) != 0) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    if (!S_ISREG(sb.st_mode)) return thx_error(ctx, THX_EIO, "%s: not a regular file", path);
    if ((unsigned long long)sb.st_size > LOG_MAX_BYTES)
        return thx_error(ctx, THX_EINPUT, "%s: %lld bytes: larger than any edit log (64 MiB)", path,
                         (long long)sb.st_size);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_status st = thx_edit_log_parse(ctx, path, text, len, out);
    free(text);
    return st;
}
