/*
 * Model directories and map3d/SCIRun .pts/.fac surfaces (see thorax/model.h).
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Coordinates are written "%.6f" in millimetres: a resolution of 1 nm, so a
 *    write/read round trip moves a node by at most 5e-7 mm, far below any
 *    anatomical or numerical meaning, while staying the plain fixed-point form
 *    map3d and SCIRun read. Values that round to zero are written as
 *    "0.000000", never "-0.000000", so output is byte-identical for inputs that
 *    differ only in the sign of a tiny value. Every consumer downstream of a
 *    model (check, mesh, solve) reads the files, so all of them see the same
 *    rounded coordinates. Non-finite coordinates are rejected on write.
 *
 *  - .fac index base. In a model directory .fac files are 1-based by
 *    definition (DESIGN.md) and are read strictly so. For a stand-alone
 *    .pts/.fac pair (thx_surface_read_ptsfac) the base is detected from the
 *    smallest and largest index and the node count n:
 *        min == 0                     -> 0-based (then max must be <= n-1)
 *        min >= 1 and max == n        -> 1-based (0-based would be out of range)
 *        otherwise (min >= 1, max < n) -> ambiguous: error naming the file and
 *                                       the line of the largest index
 *    (the brief's "min 1 and max n" rule, widened to min >= 1 because a
 *    1-based file whose node 1 is unused is still unambiguous). An empty .fac
 *    file has no base; 1 is reported.
 *
 *  - The volume mesh (volume.pts, volume.tet, NAME.vmap, the "volume" and
 *    "regions" parts of model.json) is read and written by
 *    src/io/volume_io.c, called from thx_model_write / thx_model_read here.
 *
 *  - Surface names become file names (NAME.pts, NAME.fac): they must be
 *    non-empty, made of [A-Za-z0-9_.-], not start with '.', and be unique in a
 *    model. File names in a manifest must not contain '/' (a model directory
 *    is self-contained and cannot point outside itself).
 */
#include "thorax/model.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fileio.h"
#include "io/volume_io.h"

#define MODEL_FORMAT "thorax-model"
#define MODEL_VERSION 1

/* ------------------------------------------------------------------ model */

thx_status thx_model_create(thx_ctx *ctx, thx_model **out)
{
    *out = NULL;
    thx_model *m = thx_calloc(ctx, 1, sizeof *m);
    if (!m) return THX_ENOMEM;
    *out = m;
    return THX_OK;
}

void thx_model_destroy(thx_model **m)
{
    if (!m || !*m) return;
    thx_model *p = *m;
    for (size_t i = 0; i < p->n_surfaces; i++) thx_surface_destroy(&p->surf[i]);
    free(p->surf);
    free(p->has_interior);
    free(p->interior);
    free(p->provenance_json);
    thx_volume_destroy(&p->volume);
    free(p);
    *m = NULL;
}

thx_status thx_model_add_surface(thx_ctx *ctx, thx_model *m, thx_surface **s)
{
    thx_surface *sf = *s;
    *s = NULL; /* ownership passes to the model now, whatever happens below */
    if (!sf) return thx_error(ctx, THX_EINTERNAL, "thx_model_add_surface: NULL surface");
    for (size_t i = 0; i < m->n_surfaces; i++)
        if (strcmp(m->surf[i]->name, sf->name) == 0) {
            thx_status st = thx_error(ctx, THX_EINPUT, "surface \"%s\": a surface of that name is already in the model", sf->name);
            thx_surface_destroy(&sf);
            return st;
        }
    /* The three per-surface arrays are grown one at a time; each keeps its old
     * contents on failure, and n_surfaces only grows once all three fit. */
    size_t n = m->n_surfaces + 1;
    thx_surface **ns = thx_realloc(ctx, m->surf, n * sizeof *ns);
    if (ns) m->surf = ns;
    int *nh = ns ? thx_realloc(ctx, m->has_interior, n * sizeof *nh) : NULL;
    if (nh) m->has_interior = nh;
    thx_vec3 *ni = nh ? thx_realloc(ctx, m->interior, n * sizeof *ni) : NULL;
    if (!ni) {
        thx_surface_destroy(&sf);
        return THX_ENOMEM;
    }
    m->interior = ni;
    m->surf[n - 1] = sf;
    m->has_interior[n - 1] = 0;
    m->interior[n - 1] = thx_v3(0, 0, 0);
    m->n_surfaces = n;
    return THX_OK;
}

/* ------------------------------------------------------ small text helpers */

/* Names that are safe as file names on every system we care about. */
static int name_is_safe(const char *s)
{
    if (!s[0] || s[0] == '.') return 0;
    for (const char *p = s; *p; p++) {
        char c = *p;
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                 c == '.';
        if (!ok) return 0;
    }
    return 1;
}

/* Writes one coordinate "%.6f", with a value that rounds to zero as +0 (see top). */
void thx_io_put_coord(FILE *f, double v)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.6f", v);
    if (strcmp(buf, "-0.000000") == 0) fputs("0.000000", f);
    else fputs(buf, f);
}

/* Splits the NUL-terminated line at p (ending at '\n' or NUL) into at most
 * max whitespace-separated tokens; each token is NUL-terminated in place.
 * Returns the number of tokens found (max + 1 means "more than max"). *next
 * is set to the start of the following line or NULL at the end. */
thx_status thx_io_read_text(thx_ctx *ctx, const char *path, char **text)
{
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, text, &len));
    const char *nul = memchr(*text, '\0', len);
    if (!nul) return THX_OK;
    int line = 1;
    for (const char *p = *text; p < nul; p++) line += *p == '\n';
    free(*text);
    *text = NULL;
    return thx_error(ctx, THX_EINPUT, "%s:%d: a NUL byte in a text file (the file is binary or damaged)", path, line);
}

int thx_io_split_line(char *p, char **tok, int max, char **next)
{
    char *end = strchr(p, '\n');
    if (end) {
        *end = '\0';
        *next = end + 1;
    } else {
        *next = NULL;
    }
    int n = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\v' || *p == '\f') p++;
        if (!*p) break;
        if (n == max) return max + 1;
        tok[n++] = p;
        while (*p && !(*p == ' ' || *p == '\t' || *p == '\r' || *p == '\v' || *p == '\f')) p++;
        if (*p) *p++ = '\0';
    }
    return n;
}

/* ------------------------------------------------------------ .pts / .fac */

static thx_status read_pts(thx_ctx *ctx, const char *path, const char *name, double **xyz_out, size_t *n_out)
{
    char *text = NULL;
    thx_status st = thx_io_read_text(ctx, path, &text);
    if (st) return st;
    double *xyz = NULL;
    size_t n = 0, cap = 0;
    int line = 0;
    for (char *p = text, *next = NULL; p; p = next) {
        char *tok[3];
        line++;
        int nt = thx_io_split_line(p, tok, 3, &next);
        if (nt == 0) continue; /* blank lines are allowed anywhere */
        if (nt != 3) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": expected 3 coordinates (x y z), found %s", path,
                           line, name, nt > 3 ? "more" : nt == 1 ? "1" : "2");
            goto done;
        }
        if (n + 1 > cap) THX_TRY(thx_grow(ctx, (void **)&xyz, &cap, n + 1, 3 * sizeof *xyz));
        for (int k = 0; k < 3; k++) {
            char *end = NULL;
            errno = 0;
            double v = strtod(tok[k], &end);
            if (end == tok[k] || *end != '\0' || !isfinite(v)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": coordinate %d is not a finite number: \"%s\"",
                               path, line, name, k + 1, tok[k]);
                goto done;
            }
            xyz[3 * n + (size_t)k] = v;
        }
        n++;
    }
    if (n == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": no nodes", path, name);
        goto done;
    }
    *xyz_out = xyz;
    *n_out = n;
    xyz = NULL;
done:
    free(xyz);
    free(text);
    return st;
}

/* Reads a .fac file of n_nodes nodes. want_base is 0 or 1 to require that
 * base, or -1 to detect it (rules at the top of this file). The triangles are
 * returned 0-based. */
static thx_status read_fac(thx_ctx *ctx, const char *path, const char *name, size_t n_nodes, int want_base,
                           int32_t **tri_out, size_t *n_out, int *base_out)
{
    char *text = NULL;
    thx_status st = thx_io_read_text(ctx, path, &text);
    if (st) return st;
    int32_t *tri = NULL;
    size_t n = 0, cap = 0;
    long lo = LONG_MAX, hi = LONG_MIN;
    int lo_line = 0, hi_line = 0, line = 0;
    for (char *p = text, *next = NULL; p; p = next) {
        char *tok[3];
        line++;
        int nt = thx_io_split_line(p, tok, 3, &next);
        if (nt == 0) continue;
        if (nt != 3) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": expected 3 node numbers, found %s", path, line,
                           name, nt > 3 ? "more" : nt == 1 ? "1" : "2");
            goto done;
        }
        if (n + 1 > cap) THX_TRY(thx_grow(ctx, (void **)&tri, &cap, n + 1, 3 * sizeof *tri));
        for (int k = 0; k < 3; k++) {
            char *end = NULL;
            errno = 0;
            long v = strtol(tok[k], &end, 10);
            if (end == tok[k] || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > INT32_MAX) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %d is not an integer: \"%s\"",
                               path, line, name, k + 1, tok[k]);
                goto done;
            }
            if (v < lo) { lo = v; lo_line = line; }
            if (v > hi) { hi = v; hi_line = line; }
            tri[3 * n + (size_t)k] = (int32_t)v;
        }
        n++;
    }
    int base = 1;
    if (n > 0) {
        long nn = (long)n_nodes;
        if (want_base >= 0) base = want_base;
        else if (lo == 0) base = 0;
        else if (lo >= 1 && hi == nn) base = 1;
        else if (lo >= 1 && hi < nn) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s:%d: surface \"%s\": cannot tell whether node numbers are 0- or 1-based: they run "
                           "%ld..%ld for %zu nodes (0-based needs a 0, 1-based may reach %zu)",
                           path, hi_line, name, lo, hi, n_nodes, n_nodes);
            goto done;
        }
        /* else: lo < 0 or hi > n, reported as out of range below with base 1
         * when lo >= 1 (the likelier intent) and 0 otherwise. */
        else base = lo >= 1 ? 1 : 0;
        if (lo < base) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %ld out of range %d..%ld (%d-based, %zu nodes)",
                           path, lo_line, name, lo, base, nn - 1 + base, base, n_nodes);
            goto done;
        }
        if (hi > nn - 1 + base) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %ld out of range %d..%ld (%d-based, %zu nodes)",
                           path, hi_line, name, hi, base, nn - 1 + base, base, n_nodes);
            goto done;
        }
        for (size_t i = 0; i < 3 * n; i++) tri[i] -= base;
    }
    *tri_out = tri;
    *n_out = n;
    if (base_out) *base_out = base;
    tri = NULL;
done:
    free(tri);
    free(text);
    return st;
}

static thx_status read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                              int want_base, thx_surface **out, int *base)
{
    *out = NULL;
    thx_surface *s = NULL;
    thx_status st;
    THX_TRY(thx_surface_create(ctx, name, role, &s));
    THX_TRY(read_pts(ctx, pts, name, &s->xyz, &s->n_nodes));
    THX_TRY(read_fac(ctx, fac, name, s->n_nodes, want_base, &s->tri, &s->n_tris, base));
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    return st;
}

thx_status thx_surface_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                                   thx_surface **out, int *base)
{
    return read_ptsfac(ctx, pts, fac, name, role, -1, out, base);
}

/* The checks every writer makes before touching a file: arrays present,
 * coordinates finite, triangle indices within 0..n_nodes-1. */
static thx_status check_surface(thx_ctx *ctx, const thx_surface *s)
{
    if ((s->n_nodes && !s->xyz) || (s->n_tris && !s->tri))
        return thx_error(ctx, THX_EINTERNAL, "surface \"%s\": counts set but arrays missing", s->name);
    for (size_t i = 0; i < 3 * s->n_nodes; i++)
        if (!isfinite(s->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": node %zu has a non-finite coordinate", s->name, i / 3 + 1);
    if (s->n_nodes > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "surface \"%s\": too many nodes (%zu)", s->name, s->n_nodes);
    for (size_t i = 0; i < 3 * s->n_tris; i++)
        if (s->tri[i] < 0 || (size_t)s->tri[i] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": triangle %zu has node index %ld out of range 0..%zu (0-based)",
                             s->name, i / 3 + 1, (long)s->tri[i], s->n_nodes - 1);
    return THX_OK;
}

thx_status thx_surface_write_ptsfac(thx_ctx *ctx, const thx_surface *s, const char *pts, const char *fac)
{
    THX_CHECK(check_surface(ctx, s));
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, pts, &af));
    for (size_t i = 0; i < s->n_nodes; i++) {
        thx_io_put_coord(af.f, s->xyz[3 * i]);
        fputc(' ', af.f);
        thx_io_put_coord(af.f, s->xyz[3 * i + 1]);
        fputc(' ', af.f);
        thx_io_put_coord(af.f, s->xyz[3 * i + 2]);
        fputc('\n', af.f);
    }
    THX_CHECK(thx_atomic_commit(ctx, &af));
    THX_CHECK(thx_atomic_open(ctx, fac, &af));
    for (size_t t = 0; t < s->n_tris; t++)
        fprintf(af.f, "%ld %ld %ld\n", (long)s->tri[3 * t] + 1, (long)s->tri[3 * t + 1] + 1, (long)s->tri[3 * t + 2] + 1);
    return thx_atomic_commit(ctx, &af);
}

/* ------------------------------------------------------------ model write */

static thx_status join(thx_ctx *ctx, char *out, size_t size, const char *dir, const char *file)
{
    if ((size_t)snprintf(out, size, "%s/%s", dir, file) >= size)
        return thx_error(ctx, THX_EIO, "%s/%s: path too long", dir, file);
    return THX_OK;
}

/* Builds the manifest (schema in docs/formats.md; example in tests/test_model.c). */
static thx_status build_manifest(thx_ctx *ctx, const thx_model *m, cJSON **out)
{
    thx_status st = THX_OK;
    cJSON *root = cJSON_CreateObject();
    if (!root) return thx_error(ctx, THX_ENOMEM, "out of memory building model.json");
    cJSON *arr = NULL;
    if (!cJSON_AddStringToObject(root, "format", MODEL_FORMAT) || !cJSON_AddNumberToObject(root, "version", MODEL_VERSION) ||
        !cJSON_AddStringToObject(root, "units", "mm") || !(arr = cJSON_AddArrayToObject(root, "surfaces")))
        goto nomem;
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const thx_surface *s = m->surf[i];
        char fname[96];
        cJSON *o = cJSON_CreateObject();
        if (!o) goto nomem;
        cJSON_AddItemToArray(arr, o);
        if (!cJSON_AddStringToObject(o, "name", s->name) || !cJSON_AddStringToObject(o, "role", thx_role_name(s->role)))
            goto nomem;
        snprintf(fname, sizeof fname, "%s.pts", s->name);
        if (!cJSON_AddStringToObject(o, "pts", fname)) goto nomem;
        snprintf(fname, sizeof fname, "%s.fac", s->name);
        if (!cJSON_AddStringToObject(o, "fac", fname)) goto nomem;
        if (!cJSON_AddNumberToObject(o, "n_nodes", (double)s->n_nodes) ||
            !cJSON_AddNumberToObject(o, "n_tris", (double)s->n_tris))
            goto nomem;
        if (m->has_interior && m->has_interior[i]) {
            thx_vec3 p = m->interior[i];
            if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) {
                st = thx_error(ctx, THX_EINPUT, "surface \"%s\": interior point is not finite", s->name);
                goto fail;
            }
            const double v[3] = {p.x, p.y, p.z};
            cJSON *a = cJSON_CreateDoubleArray(v, 3);
            if (!a) goto nomem;
            cJSON_AddItemToObject(o, "interior", a);
        }
    }
    if (m->volume) {
        st = thx_io_volume_manifest(ctx, m, root);
        if (st) goto fail;
    }
    if (m->provenance_json) {
        cJSON *prov = cJSON_Parse(m->provenance_json);
        if (!prov || !cJSON_IsObject(prov)) {
            cJSON_Delete(prov);
            st = thx_error(ctx, THX_EINPUT, "model provenance is not a JSON object");
            goto fail;
        }
        cJSON_AddItemToObject(root, "provenance", prov);
    }
    *out = root;
    return THX_OK;
nomem:
    st = thx_error(ctx, THX_ENOMEM, "out of memory building model.json");
fail:
    cJSON_Delete(root);
    return st;
}

thx_status thx_model_write(thx_ctx *ctx, const thx_model *m, const char *dir)
{
    thx_outdir od;
    THX_CHECK(thx_outdir_claim(ctx, &od, dir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, NULL, 0));
    return thx_model_write_claimed(ctx, m, &od);
}

thx_status thx_model_write_claimed(thx_ctx *ctx, const thx_model *m, thx_outdir *od)
{
    const char *dir = od->dir;
    /* Validate everything before creating anything on disk. */
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const thx_surface *s = m->surf[i];
        if (!name_is_safe(s->name))
            return thx_error(ctx, THX_EINPUT,
                             "surface \"%s\": name is not usable as a file name (use letters, digits, '_', '-', '.'; "
                             "not starting with '.')",
                             s->name);
        if (strcmp(s->name, "model.json") == 0 || strlen(s->name) > 56)
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": name is reserved or too long", s->name);
        for (size_t j = 0; j < i; j++)
            if (strcmp(m->surf[j]->name, s->name) == 0)
                return thx_error(ctx, THX_EINPUT, "surface \"%s\": two surfaces have this name", s->name);
        if (s->n_nodes == 0) return thx_error(ctx, THX_EINPUT, "surface \"%s\": has no nodes", s->name);
        if (s->role < 0 || s->role >= THX_ROLE_COUNT)
            return thx_error(ctx, THX_EINPUT, "surface \"%s\": invalid role %d", s->name, (int)s->role);
        THX_CHECK(check_surface(ctx, s));
        if (m->volume && strcmp(s->name, "volume") == 0)
            return thx_error(ctx, THX_EINPUT,
                             "surface \"volume\": name is reserved for the volume mesh files (volume.pts, volume.tet)");
    }
    if (m->volume) THX_CHECK(thx_io_volume_validate(ctx, m, dir));
    cJSON *root = NULL;
    THX_CHECK(build_manifest(ctx, m, &root));
    char *json = cJSON_Print(root);
    cJSON_Delete(root);
    if (!json) return thx_error(ctx, THX_ENOMEM, "out of memory printing model.json");

    thx_status st = THX_OK;
    char pts[4400], fac[4400];
    const char *tmp = od->tmp;
    int have_tmp = 0;
    THX_TRY(thx_outdir_begin(ctx, od));
    have_tmp = 1;
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const thx_surface *s = m->surf[i];
        char f1[96], f2[96];
        snprintf(f1, sizeof f1, "%s.pts", s->name);
        snprintf(f2, sizeof f2, "%s.fac", s->name);
        THX_TRY(join(ctx, pts, sizeof pts, tmp, f1));
        THX_TRY(join(ctx, fac, sizeof fac, tmp, f2));
        THX_TRY(thx_surface_write_ptsfac(ctx, s, pts, fac));
    }
    if (m->volume) THX_TRY(thx_io_volume_write_files(ctx, m, tmp));
    THX_TRY(join(ctx, pts, sizeof pts, tmp, "model.json"));
    thx_atomic_file af;
    THX_TRY(thx_atomic_open(ctx, pts, &af));
    fputs(json, af.f);
    fputc('\n', af.f);
    THX_TRY(thx_atomic_commit(ctx, &af));
    have_tmp = 0; /* thx_outdir_commit removes tmp itself on failure */
    THX_TRY(thx_outdir_commit(ctx, od));
done:
    if (have_tmp) thx_outdir_abort(od);
    free(json);
    return st;
}

/* ------------------------------------------------------------- model read */

/* 1-based line of position pos in text (for JSON syntax errors). */
static int line_of(const char *text, const char *pos)
{
    int line = 1;
    for (const char *p = text; p < pos && *p; p++)
        if (*p == '\n') line++;
    return line;
}

int thx_io_json_count(const cJSON *o, const char *key, size_t *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsNumber(v)) return -1;
    double d = v->valuedouble;
    if (!(d >= 0) || d != floor(d) || d > (double)INT32_MAX) return -1;
    *out = (size_t)d;
    return 0;
}

int thx_io_file_name_ok(const char *s)
{
    return s[0] && !strchr(s, '/') && strcmp(s, ".") != 0 && strcmp(s, "..") != 0;
}

thx_status thx_model_read(thx_ctx *ctx, const char *dir, thx_model **out)
{
    *out = NULL;
    char mpath[4200], pts[4200], fac[4200];
    THX_CHECK(join(ctx, mpath, sizeof mpath, dir, "model.json"));
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, mpath, &text, &len));

    thx_status st = THX_OK;
    thx_model *m = NULL;
    thx_surface *s = NULL;
    const char *end = NULL;
    /* len + 1: cJSON's trailing-garbage check needs the terminating NUL in range. */
    cJSON *root = cJSON_ParseWithLengthOpts(text, len + 1, &end, 1);
    if (!root) {
        st = thx_error(ctx, THX_EINPUT, "%s:%d: not valid JSON", mpath, line_of(text, end ? end : text));
        goto done;
    }
    if (!cJSON_IsObject(root)) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a JSON object", mpath);
        goto done;
    }
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
    if (!cJSON_IsString(fmt) || strcmp(fmt->valuestring, MODEL_FORMAT) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: \"format\" must be \"%s\"", mpath, MODEL_FORMAT);
        goto done;
    }
    const cJSON *ver = cJSON_GetObjectItemCaseSensitive(root, "version");
    if (!cJSON_IsNumber(ver)) {
        st = thx_error(ctx, THX_EINPUT, "%s: \"version\" missing or not a number", mpath);
        goto done;
    }
    if (ver->valuedouble != MODEL_VERSION) {
        st = thx_error(ctx, THX_EINPUT, "%s: model format version %g; this thorax reads version %d", mpath,
                       ver->valuedouble, MODEL_VERSION);
        goto done;
    }
    const cJSON *units = cJSON_GetObjectItemCaseSensitive(root, "units");
    if (!cJSON_IsString(units) || strcmp(units->valuestring, "mm") != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: \"units\" must be \"mm\"", mpath);
        goto done;
    }
    const cJSON *surfs = cJSON_GetObjectItemCaseSensitive(root, "surfaces");
    if (!cJSON_IsArray(surfs)) {
        st = thx_error(ctx, THX_EINPUT, "%s: \"surfaces\" missing or not an array", mpath);
        goto done;
    }
    THX_TRY(thx_model_create(ctx, &m));
    int idx = 0;
    const cJSON *o;
    cJSON_ArrayForEach(o, surfs)
    {
        idx++;
        if (!cJSON_IsObject(o)) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d: not a JSON object", mpath, idx);
            goto done;
        }
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(o, "name");
        if (!cJSON_IsString(name) || !name_is_safe(name->valuestring) || strlen(name->valuestring) > 56) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d: \"name\" missing or not a valid surface name", mpath, idx);
            goto done;
        }
        const char *nm = name->valuestring;
        const cJSON *role = cJSON_GetObjectItemCaseSensitive(o, "role");
        thx_role r;
        if (!cJSON_IsString(role) || thx_role_parse(role->valuestring, &r) != 0) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): \"role\" missing or unknown%s%s%s", mpath, idx, nm,
                           cJSON_IsString(role) ? " (\"" : "", cJSON_IsString(role) ? role->valuestring : "",
                           cJSON_IsString(role) ? "\")" : "");
            goto done;
        }
        const cJSON *jp = cJSON_GetObjectItemCaseSensitive(o, "pts");
        const cJSON *jf = cJSON_GetObjectItemCaseSensitive(o, "fac");
        if (!cJSON_IsString(jp) || !thx_io_file_name_ok(jp->valuestring) || !cJSON_IsString(jf) ||
            !thx_io_file_name_ok(jf->valuestring)) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: surface %d (\"%s\"): \"pts\" and \"fac\" must name files in the model directory", mpath,
                           idx, nm);
            goto done;
        }
        size_t nn, nt;
        if (thx_io_json_count(o, "n_nodes", &nn) || thx_io_json_count(o, "n_tris", &nt)) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): \"n_nodes\" and \"n_tris\" must be counts", mpath,
                           idx, nm);
            goto done;
        }
        const cJSON *ji = cJSON_GetObjectItemCaseSensitive(o, "interior");
        int has_in = 0;
        thx_vec3 in = thx_v3(0, 0, 0);
        if (ji && !cJSON_IsNull(ji)) {
            double v[3];
            int ok = cJSON_IsArray(ji) && cJSON_GetArraySize(ji) == 3;
            for (int k = 0; ok && k < 3; k++) {
                const cJSON *e = cJSON_GetArrayItem(ji, k);
                ok = cJSON_IsNumber(e) && isfinite(e->valuedouble);
                if (ok) v[k] = e->valuedouble;
            }
            if (!ok) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): \"interior\" must be [x, y, z]", mpath, idx, nm);
                goto done;
            }
            has_in = 1;
            in = thx_v3(v[0], v[1], v[2]);
        }
        THX_TRY(join(ctx, pts, sizeof pts, dir, jp->valuestring));
        THX_TRY(join(ctx, fac, sizeof fac, dir, jf->valuestring));
        /* Model directories are 1-based by definition: read strictly. */
        THX_TRY(read_ptsfac(ctx, pts, fac, nm, r, 1, &s, NULL));
        if (s->n_nodes != nn) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": manifest says %zu nodes but %s has %zu", mpath, nm, nn, pts,
                           s->n_nodes);
            goto done;
        }
        if (s->n_tris != nt) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": manifest says %zu triangles but %s has %zu", mpath, nm, nt,
                           fac, s->n_tris);
            goto done;
        }
        st = thx_model_add_surface(ctx, m, &s);
        if (st == THX_EINPUT) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): a surface of that name appears twice", mpath, idx, nm);
            goto done;
        }
        if (st) goto done;
        m->has_interior[m->n_surfaces - 1] = has_in;
        m->interior[m->n_surfaces - 1] = in;
    }
    THX_TRY(thx_io_volume_read(ctx, dir, mpath, root, m));
    const cJSON *prov = cJSON_GetObjectItemCaseSensitive(root, "provenance");
    if (prov && !cJSON_IsNull(prov)) {
        if (!cJSON_IsObject(prov)) {
            st = thx_error(ctx, THX_EINPUT, "%s: \"provenance\" must be an object", mpath);
            goto done;
        }
        m->provenance_json = cJSON_PrintUnformatted(prov);
        if (!m->provenance_json) {
            st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", mpath);
            goto done;
        }
    }
    *out = m;
    m = NULL;
done:
    thx_surface_destroy(&s);
    thx_model_destroy(&m);
    cJSON_Delete(root);
    free(text);
    return st;
}
