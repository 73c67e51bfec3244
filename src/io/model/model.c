/*
 * Model directories and map3d/SCIRun .pts/.fac surfaces (see thorax/io/model_dir.h).
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
 *  - The volume mesh (volume.pts, volume.tet, NAME.vmap, the "volume" and
 *    "regions" parts of model.json) is read and written by
 *    src/io/volume_io.c, called from thx_model_write / thx_model_read here.
 *
 *  - Surface names become file names (NAME.pts, NAME.fac): they must be
 *    non-empty, made of [A-Za-z0-9_.-], not start with '.', and be unique in a
 *    model. File names in a manifest must not contain '/' (a model directory
 *    is self-contained and cannot point outside itself).
 */
#include "thorax/io/model_dir.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"
#include "io/model/volume_io.h"

#define MODEL_FORMAT "thorax-model"
#define MODEL_VERSION 1

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
    if (m->frame.set) {
        char a[3];
        cJSON *fo = cJSON_AddObjectToObject(root, "frame");
        if (!fo || !cJSON_AddStringToObject(fo, "superior", thx_axis_name(m->frame.up, a)) ||
            !cJSON_AddStringToObject(fo, "anterior", thx_axis_name(m->frame.front, a)) ||
            !cJSON_AddStringToObject(fo, "left", thx_axis_name(thx_frame_left(&m->frame), a)))
            goto nomem;
    }
    if (m->volume) {
        st = thx_io_volume_manifest(ctx, m, root);
        if (st) goto fail;
        if (m->volume_check_json) { /* the verdict as it was read (thorax/check/verdict.h) */
            cJSON *ck = cJSON_Parse(m->volume_check_json), *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
            if (!cJSON_IsObject(ck) || !cJSON_IsObject(vo)) {
                cJSON_Delete(ck);
                st = thx_error(ctx, THX_EINPUT, "the volume check's verdict is not a JSON object");
                goto fail;
            }
            cJSON_AddItemToObject(vo, "check", ck);
        }
    }
    if (m->provenance_json || m->edit_log) {
        cJSON *prov = m->provenance_json ? cJSON_Parse(m->provenance_json) : cJSON_CreateObject();
        if (!prov || !cJSON_IsObject(prov)) {
            cJSON_Delete(prov);
            st = thx_error(ctx, THX_EINPUT, "model provenance is not a JSON object");
            goto fail;
        }
        cJSON_AddItemToObject(root, "provenance", prov);
        /* The edit log's record is the writer's: it names the file written beside the surfaces and
         * its hash, or nothing when the model has no log (a record copied from a model read earlier
         * must not name a file this directory does not hold). */
        cJSON_DeleteItemFromObjectCaseSensitive(prov, "edit_log");
        cJSON_DeleteItemFromObjectCaseSensitive(prov, "edit_log_sha256");
        if (m->edit_log) {
            char hex[65];
            thx_sha256_hex(m->edit_log, strlen(m->edit_log), hex);
            if (!cJSON_AddStringToObject(prov, "edit_log", THX_MODEL_EDIT_LOG) ||
                !cJSON_AddStringToObject(prov, "edit_log_sha256", hex))
                goto nomem;
        }
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
        if (!thx_name_ok(s->name, sizeof s->name))
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
        THX_CHECK(thx_surface_validate(ctx, s));
        if (m->volume && strcmp(s->name, "volume") == 0)
            return thx_error(ctx, THX_EINPUT,
                             "surface \"volume\": name is reserved for the volume mesh files (volume.pts, volume.tet)");
    }
    if (m->frame.set && !thx_frame_valid(&m->frame))
        return thx_error(ctx, THX_EINPUT, "model frame: the superior and anterior axes must be two different axes of +x -x +y -y +z -z");
    if (m->volume) THX_CHECK(thx_model_volume_validate(ctx, m, dir));
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
    if (m->edit_log) {
        thx_atomic_file lf;
        THX_TRY(join(ctx, pts, sizeof pts, tmp, THX_MODEL_EDIT_LOG));
        THX_TRY(thx_atomic_open(ctx, pts, &lf));
        fputs(m->edit_log, lf.f);
        THX_TRY(thx_atomic_commit(ctx, &lf));
    }
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

/* The keys each object of the manifest may hold (docs/formats.md). A key
 * outside its list is refused rather than ignored: a misspelt key ("interiour",
 * "fram") would otherwise drop what it carries without a word; a later format
 * that adds keys raises "version". */
static const char *const ROOT_KEYS[] = {"format", "version", "units", "surfaces", "frame", "volume", "regions", "provenance", NULL};
static const char *const SURFACE_KEYS[] = {"name", "role", "pts", "fac", "n_nodes", "n_tris", "interior", "vmap", NULL};
static const char *const FRAME_KEYS[] = {"superior", "anterior", "left", NULL};
static const char *const VOLUME_KEYS[] = {"pts",   "tet",         "n_nodes",     "n_tets",  "n_regions", "units",
                                          "index_base", "orientation", "node_tables", "steiner", "n_steiner", "check", NULL};
static const char *const REGION_KEYS[] = {"id", "name", "sigma", "units", "source", NULL};

/* Refuses a key of o outside `keys` or a key given twice (cJSON keeps both and
 * would read the first); `where` is "" or " surface 2 (\"torso\")" etc. */
static thx_status check_keys(thx_ctx *ctx, const char *mpath, const char *where, const cJSON *o,
                             const char *const *keys)
{
    for (const cJSON *c = o->child; c; c = c->next) {
        const char *k = c->string ? c->string : "";
        int known = 0;
        for (const char *const *p = keys; *p && !known; p++) known = strcmp(*p, k) == 0;
        if (!known) {
            char list[256];
            size_t n = 0;
            list[0] = '\0';
            for (const char *const *p = keys; *p && n < sizeof list; p++)
                n += (size_t)snprintf(list + n, sizeof list - n, "%s%s", p == keys ? "" : ", ", *p);
            return thx_error(ctx, THX_EINPUT, "%s:%s unknown key \"%.40s\" (known here: %s)", mpath, where, k, list);
        }
        for (const cJSON *d = o->child; d != c; d = d->next)
            if (d->string && strcmp(d->string, k) == 0)
                return thx_error(ctx, THX_EINPUT, "%s:%s key \"%s\" appears twice", mpath, where, k);
    }
    return THX_OK;
}

/* "frame": {"superior": AXIS, "anterior": AXIS[, "left": AXIS]} -> *f. */
static thx_status read_frame(thx_ctx *ctx, const char *mpath, const cJSON *jf, thx_frame *f)
{
    memset(f, 0, sizeof *f);
    if (!jf || cJSON_IsNull(jf)) return THX_OK;
    if (!cJSON_IsObject(jf))
        return thx_error(ctx, THX_EINPUT, "%s: \"frame\" must be an object {\"superior\": \"+z\", \"anterior\": \"+y\"}", mpath);
    THX_CHECK(check_keys(ctx, mpath, " \"frame\":", jf, FRAME_KEYS));
    static const char *const names[3] = {"superior", "anterior", "left"};
    thx_axis ax[3];
    for (int k = 0; k < 3; k++) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(jf, names[k]);
        if (!v && k == 2) break;
        if (!cJSON_IsString(v) || thx_axis_parse(v->valuestring, &ax[k]))
            return thx_error(ctx, THX_EINPUT, "%s: \"frame\".\"%s\" %s (one of \"+x\" \"-x\" \"+y\" \"-y\" \"+z\" \"-z\")",
                             mpath, names[k], !v ? "missing" : cJSON_IsString(v) ? "is not an axis" : "must be a string");
    }
    if (ax[0].axis == ax[1].axis)
        return thx_error(ctx, THX_EINPUT, "%s: \"frame\": \"superior\" and \"anterior\" must be two different axes", mpath);
    thx_frame r = {1, ax[0], ax[1]};
    if (cJSON_GetObjectItemCaseSensitive(jf, "left")) {
        thx_axis l = thx_frame_left(&r);
        char a[3], b[3];
        if (l.axis != ax[2].axis || l.sign != ax[2].sign)
            return thx_error(ctx, THX_EINPUT,
                             "%s: \"frame\".\"left\" is %s but superior x anterior is %s (the frame must be right-handed)",
                             mpath, thx_axis_name(ax[2], a), thx_axis_name(l, b));
    }
    *f = r;
    return THX_OK;
}

/* Keys, duplicates and value types of "volume" and the "regions" entries
 * (their meaning is checked by thx_io_volume_read). */
static thx_status check_volume_keys(thx_ctx *ctx, const char *mpath, const cJSON *root)
{
    const cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    if (cJSON_IsObject(vo)) {
        THX_CHECK(check_keys(ctx, mpath, " \"volume\":", vo, VOLUME_KEYS));
        static const char *const strs[] = {"pts", "tet", "units", "orientation", "node_tables", "steiner"};
        for (size_t k = 0; k < sizeof strs / sizeof *strs; k++) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(vo, strs[k]);
            if (v && !cJSON_IsString(v))
                return thx_error(ctx, THX_EINPUT, "%s: \"volume\".\"%s\" must be a string", mpath, strs[k]);
        }
        const cJSON *ck = cJSON_GetObjectItemCaseSensitive(vo, "check");
        if (ck && !cJSON_IsObject(ck))
            return thx_error(ctx, THX_EINPUT, "%s: \"volume\".\"check\" must be an object (the volume check's verdict, "
                             "thorax/check/verdict.h)", mpath);
        static const char *const nums[] = {"n_nodes", "n_tets", "n_regions", "index_base", "n_steiner"};
        for (size_t k = 0; k < sizeof nums / sizeof *nums; k++) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(vo, nums[k]);
            size_t n;
            if (v && thx_io_json_count(vo, nums[k], &n))
                return thx_error(ctx, THX_EINPUT, "%s: \"volume\".\"%s\" must be a count (a whole number >= 0)", mpath,
                                 nums[k]);
        }
    }
    const cJSON *regs = cJSON_GetObjectItemCaseSensitive(root, "regions");
    if (cJSON_IsArray(regs)) {
        int k = 0;
        const cJSON *r;
        cJSON_ArrayForEach(r, regs)
        {
            k++;
            char where[48];
            snprintf(where, sizeof where, " region %d:", k);
            if (cJSON_IsObject(r)) THX_CHECK(check_keys(ctx, mpath, where, r, REGION_KEYS));
        }
    }
    return THX_OK;
}

/* The edit log a model's provenance names ("edit_log": a file in the directory, "edit_log_sha256":
 * its hash) into m->edit_log: text without NUL bytes, at most 64 MiB, whose hash is the recorded one
 * (a log changed by hand no longer describes the surfaces beside it). */
static thx_status read_edit_log(thx_ctx *ctx, const char *dir, const char *mpath, const cJSON *prov, thx_model *m)
{
    const cJSON *jl = cJSON_GetObjectItemCaseSensitive(prov, "edit_log");
    const cJSON *jh = cJSON_GetObjectItemCaseSensitive(prov, "edit_log_sha256");
    if (!jl && !jh) return THX_OK;
    if (!cJSON_IsString(jl) || !thx_io_file_name_ok(jl->valuestring))
        return thx_error(ctx, THX_EINPUT, "%s: \"provenance\".\"edit_log\" must name a file in the model directory",
                         mpath);
    size_t nh = cJSON_IsString(jh) ? strlen(jh->valuestring) : 0;
    if (nh != 64 || strspn(jh->valuestring, "0123456789abcdef") != 64)
        return thx_error(ctx, THX_EINPUT,
                         "%s: \"provenance\".\"edit_log_sha256\" must be the log's SHA-256, 64 lowercase hex digits",
                         mpath);
    char path[4200];
    THX_CHECK(join(ctx, path, sizeof path, dir, jl->valuestring));
    struct stat sb;
    if (lstat(path, &sb) != 0 || !S_ISREG(sb.st_mode))
        return thx_error(ctx, THX_EINPUT, "%s: the edit log model.json names is missing or not a regular file", path);
    if (sb.st_size > (64 << 20))
        return thx_error(ctx, THX_EINPUT, "%s: %lld bytes: larger than any edit log (64 MiB)", path, (long long)sb.st_size);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        thx_status st = thx_error(ctx, THX_EINPUT, "%s:%d: NUL byte at byte offset %zu (not a text file)", path,
                                  line_of(text, nul), (size_t)(nul - text));
        free(text);
        return st;
    }
    char hex[65];
    thx_sha256_hex(text, len, hex);
    if (strcmp(hex, jh->valuestring) != 0) {
        free(text);
        return thx_error(ctx, THX_EINPUT,
                         "%s: its SHA-256 is %s but model.json records %s: the log was changed after the model was "
                         "written, so it no longer describes these surfaces",
                         path, hex, jh->valuestring);
    }
    m->edit_log = text;
    return THX_OK;
}

static thx_status model_read(thx_ctx *ctx, const char *dir, int regions_only, thx_model **out)
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
    cJSON *root = NULL;
    const char *end = NULL;
    {
        /* cJSON stops at a NUL and would accept "{...}\0anything" */
        const char *nul = memchr(text, '\0', len);
        if (nul) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: NUL byte at byte offset %zu (not a text file)", mpath,
                           line_of(text, nul), (size_t)(nul - text));
            goto done;
        }
    }
    /* len + 1: cJSON's trailing-garbage check needs the terminating NUL in range. */
    root = cJSON_ParseWithLengthOpts(text, len + 1, &end, 1);
    if (!root) {
        st = thx_error(ctx, THX_EINPUT, "%s:%d: not valid JSON", mpath, line_of(text, end ? end : text));
        goto done;
    }
    if (!cJSON_IsObject(root)) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a JSON object", mpath);
        goto done;
    }
    THX_TRY(check_keys(ctx, mpath, "", root, ROOT_KEYS));
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
        st = thx_error(ctx, THX_EINPUT, "%s: \"version\": model format version %g; this thorax reads version %d", mpath,
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
    const cJSON *prov = cJSON_GetObjectItemCaseSensitive(root, "provenance");
    if (prov && !cJSON_IsNull(prov) && !cJSON_IsObject(prov)) {
        st = thx_error(ctx, THX_EINPUT, "%s: \"provenance\" must be an object", mpath);
        goto done;
    }
    THX_TRY(check_volume_keys(ctx, mpath, root));
    THX_TRY(thx_model_create(ctx, &m));
    THX_TRY(read_frame(ctx, mpath, cJSON_GetObjectItemCaseSensitive(root, "frame"), &m->frame));
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
        if (!cJSON_IsString(name) || !thx_name_ok(name->valuestring, sizeof m->surf[0]->name) || strlen(name->valuestring) > 56 ||
            strcmp(name->valuestring, "model.json") == 0) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: surface %d: \"name\" missing or not a valid surface name (letters, digits, '_', '-', "
                           "'.', not starting with '.', at most 56 characters, not \"model.json\")",
                           mpath, idx);
            goto done;
        }
        const char *nm = name->valuestring;
        {
            char where[96];
            snprintf(where, sizeof where, " surface %d (\"%s\"):", idx, nm);
            THX_TRY(check_keys(ctx, mpath, where, o, SURFACE_KEYS));
        }
        const cJSON *role = cJSON_GetObjectItemCaseSensitive(o, "role");
        thx_role r;
        if (!cJSON_IsString(role) || thx_role_parse(role->valuestring, &r) != 0) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): \"role\" missing or unknown%s%.40s%s", mpath, idx, nm,
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
        const cJSON *jm = cJSON_GetObjectItemCaseSensitive(o, "vmap");
        if (jm && !cJSON_IsString(jm)) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): \"vmap\" must be a file name", mpath, idx, nm);
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
        for (size_t j = 0; j < m->n_surfaces; j++)
            if (strcmp(m->surf[j]->name, nm) == 0) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface %d (\"%s\"): a surface of that name appears twice", mpath, idx, nm);
                goto done;
            }
        THX_TRY(join(ctx, pts, sizeof pts, dir, jp->valuestring));
        THX_TRY(join(ctx, fac, sizeof fac, dir, jf->valuestring));
        /* Model directories are 1-based by definition: read strictly. */
        THX_TRY(thx_io_read_ptsfac(ctx, pts, fac, nm, r, 1, &s, NULL));
        if (s->n_nodes != nn) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": manifest says %zu nodes (\"n_nodes\") but %s has %zu",
                           mpath, nm, nn, pts, s->n_nodes);
            goto done;
        }
        if (s->n_tris != nt) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": manifest says %zu triangles (\"n_tris\") but %s has %zu",
                           mpath, nm, nt, fac, s->n_tris);
            goto done;
        }
        st = thx_model_add_surface(ctx, m, &s);
        if (st) goto done;
        m->has_interior[m->n_surfaces - 1] = has_in;
        m->interior[m->n_surfaces - 1] = in;
    }
    THX_TRY(thx_io_volume_read(ctx, dir, mpath, root, m, regions_only));
    {
        const cJSON *ck = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "volume"), "check");
        if (m->volume && cJSON_IsObject(ck) && !(m->volume_check_json = cJSON_PrintUnformatted(ck))) {
            st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", mpath);
            goto done;
        }
    }
    if (prov && !cJSON_IsNull(prov)) THX_TRY(read_edit_log(ctx, dir, mpath, prov, m));
    if (prov && !cJSON_IsNull(prov)) {
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

thx_status thx_model_read(thx_ctx *ctx, const char *dir, thx_model **out) { return model_read(ctx, dir, 0, out); }

thx_status thx_model_read_regions_only(thx_ctx *ctx, const char *dir, thx_model **out) { return model_read(ctx, dir, 1, out); }
