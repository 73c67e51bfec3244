/* thorax export --solution DIR | --data SERIES: potentials (and currents) per frame for ParaView
 * (.vtu, .vtp, .vtk and a .pvd collection) and Gmsh (.msh with $NodeData views). The writers are
 * the io layer's (thorax/io/export_data.h); here the series are read and matched to the model,
 * the frames chosen, the currents computed (thx_fem_currents, as thorax forward does) and every
 * output claimed before anything is written. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/cli.h"
#include "thorax/core/fileio.h"
#include "cli/cli_export.h"
#include "thorax/fem/fem.h"
#include "thorax/io/export_data.h"
#include "thorax/io/series_file.h"

/* What is exported: the volume's potentials and/or each surface's, over one time axis. */
typedef struct {
    thx_series *vol;          /* volume nodes x frames, or NULL */
    thx_series **surf;        /* per surface: its nodes x frames (owned), or NULL */
    const thx_series *axis;   /* the series whose frames and times are exported */
    unsigned char *use;       /* regions whose tetrahedra carry currents (the problem's domain) */
    char unit[32];
} sources;

static thx_status join(thx_ctx *ctx, char *out, size_t size, const char *dir, const char *file)
{
    if ((size_t)snprintf(out, size, "%s/%s", dir, file) >= size)
        return thx_error(ctx, THX_EINPUT, "%s/%s: path too long", dir, file);
    return THX_OK;
}

/* A series whose rows must be n (the volume's or a surface's nodes). */
static thx_status check_rows(thx_ctx *ctx, const thx_series *s, const char *path, size_t n, const char *what)
{
    if (s->n_rows != n)
        return thx_error(ctx, THX_EINPUT, "%s: %zu rows, but %s has %zu nodes", path, s->n_rows, what, n);
    return THX_OK;
}

/* The surface series taken from the volume's potentials through the node table. */
static thx_status from_volume(thx_ctx *ctx, const thx_model *m, const thx_series *vol, size_t s, thx_series **out)
{
    const thx_volume *v = m->volume;
    THX_CHECK(thx_series_create(ctx, v->surf_n_nodes[s], vol->n_frames, out));
    thx_series *o = *out;
    for (size_t f = 0; f < vol->n_frames; f++) {
        for (size_t i = 0; i < o->n_rows; i++) o->v[f * o->n_rows + i] = vol->v[f * vol->n_rows + (size_t)v->surf_node[s][i]];
        o->time[f] = vol->time[f];
    }
    snprintf(o->unit, sizeof o->unit, "%s", vol->unit);
    snprintf(o->time_unit, sizeof o->time_unit, "%s", vol->time_unit);
    return THX_OK;
}

/* --solution DIR: solution.json's volume and torso series (and the epicardial input, on the
 * heart surface, when there is no volume series and the file is still there). */
static thx_status read_solution(thx_ctx *ctx, const thx_model *m, const char *dir, sources *S)
{
    char path[4400], *text = NULL;
    size_t len = 0;
    THX_CHECK(join(ctx, path, sizeof path, dir, "solution.json"));
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_Parse(text);
    free(text);
    thx_status st = THX_OK;
    const cJSON *fmt = j ? cJSON_GetObjectItemCaseSensitive(j, "format") : NULL;
    const cJSON *files = j ? cJSON_GetObjectItemCaseSensitive(j, "files") : NULL;
    const cJSON *problem = j ? cJSON_GetObjectItemCaseSensitive(j, "problem") : NULL;
    if (!j || !cJSON_IsString(fmt) || strcmp(fmt->valuestring, "thorax-solution") != 0 || !cJSON_IsObject(files)) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a thorax solution (\"format\": \"thorax-solution\" and \"files\" expected)",
                       path);
        goto done;
    }
    const char *prob = cJSON_IsString(problem) ? problem->valuestring : "";
    if (strstr(prob, "transfer")) {
        st = thx_error(ctx, THX_EINPUT, "%s: a transfer matrix, not potentials: apply it first (thorax forward --transfer)",
                       path);
        goto done;
    }
    int defib = strcmp(prob, "defibrillation") == 0;
    const cJSON *fv = cJSON_GetObjectItemCaseSensitive(files, "volume");
    const cJSON *ft = cJSON_GetObjectItemCaseSensitive(files, "torso");
    if (cJSON_IsString(fv)) {
        if (!m->volume) {
            st = thx_error(ctx, THX_EINPUT, "%s: the solution has volume potentials but the model has no volume mesh", path);
            goto done;
        }
        THX_TRY(join(ctx, path, sizeof path, dir, fv->valuestring));
        THX_TRY(thx_series_read(ctx, path, THX_SERIES_AUTO, &S->vol));
        THX_TRY(check_rows(ctx, S->vol, path, m->volume->n_nodes, "the model's volume mesh"));
        for (size_t s = 0; s < m->n_surfaces; s++) THX_TRY(from_volume(ctx, m, S->vol, s, &S->surf[s]));
        S->axis = S->vol;
        /* the domain of the currents: thorax forward leaves the heart's interior out */
        for (size_t r = 0; r < m->volume->n_regions; r++)
            S->use[r] = defib || strcmp(m->volume->regions[r].name, "heart") != 0;
    } else if (cJSON_IsString(ft)) {
        size_t outer = m->n_surfaces;
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (m->surf[s]->role == THX_ROLE_OUTER) outer = s;
        if (outer == m->n_surfaces) {
            st = thx_error(ctx, THX_EINPUT, "%s: the model has no outer surface for the solution's torso series", path);
            goto done;
        }
        THX_TRY(join(ctx, path, sizeof path, dir, ft->valuestring));
        THX_TRY(thx_series_read(ctx, path, THX_SERIES_AUTO, &S->surf[outer]));
        char what[128];
        snprintf(what, sizeof what, "surface \"%.60s\"", m->surf[outer]->name);
        THX_TRY(check_rows(ctx, S->surf[outer], path, m->surf[outer]->n_nodes, what));
        S->axis = S->surf[outer];
        const cJSON *epi = cJSON_GetObjectItemCaseSensitive(j, "epicardial");
        for (size_t s = 0; s < m->n_surfaces && cJSON_IsString(epi); s++) {
            if (m->surf[s]->role != THX_ROLE_HEART) continue;
            thx_series *h = NULL;
            struct stat sb;
            if (stat(epi->valuestring, &sb) != 0) {
                thx_log(ctx, THX_LOG_WARN, "%s: not found: the heart surface's potentials are left out",
                        epi->valuestring);
                break;
            }
            THX_TRY(thx_series_read(ctx, epi->valuestring, THX_SERIES_AUTO, &h));
            if (h->n_rows == m->surf[s]->n_nodes && h->n_frames == S->axis->n_frames) S->surf[s] = h;
            else {
                thx_log(ctx, THX_LOG_WARN, "%s: %zu rows x %zu frames does not match surface \"%s\" (%zu nodes) and the "
                        "solution (%zu frames): left out", epi->valuestring, h->n_rows, h->n_frames, m->surf[s]->name,
                        m->surf[s]->n_nodes, S->axis->n_frames);
                thx_series_destroy(&h);
            }
            break;
        }
    } else {
        st = thx_error(ctx, THX_EINPUT, "%s/solution.json: no \"volume\" or \"torso\" series in \"files\"", dir);
        goto done;
    }
    snprintf(S->unit, sizeof S->unit, "%s", S->axis->unit);
done:
    cJSON_Delete(j);
    return st;
}

/* --data SERIES: rows = the volume's nodes or one surface's (--surface decides between equals). */
static thx_status read_data(thx_ctx *ctx, const thx_model *m, const char *path, const char *const *only, int n_only,
                            sources *S)
{
    thx_series *d = NULL;
    THX_CHECK(thx_series_read(ctx, path, THX_SERIES_AUTO, &d));
    thx_status st = THX_OK;
    size_t match[64], nm = 0;
    int vol = m->volume && d->n_rows == m->volume->n_nodes && n_only == 0;
    for (size_t s = 0; s < m->n_surfaces && nm < 64; s++) {
        int wanted = n_only == 0;
        for (int k = 0; k < n_only && !wanted; k++) wanted = strcmp(m->surf[s]->name, only[k]) == 0;
        if (wanted && d->n_rows == m->surf[s]->n_nodes) match[nm++] = s;
    }
    if (vol && nm == 0) {
        S->vol = d;
        d = NULL;
        for (size_t s = 0; s < m->n_surfaces; s++) THX_TRY(from_volume(ctx, m, S->vol, s, &S->surf[s]));
        S->axis = S->vol;
        for (size_t r = 0; r < m->volume->n_regions; r++) S->use[r] = 1;
    } else if (!vol && nm == 1) {
        S->surf[match[0]] = d;
        S->axis = d;
        d = NULL;
    } else if (vol || nm > 1) {
        char names[512] = "";
        size_t o = 0;
        if (vol) o += (size_t)snprintf(names + o, sizeof names - o, " the volume mesh,");
        for (size_t k = 0; k < nm && o < sizeof names; k++)
            o += (size_t)snprintf(names + o, sizeof names - o, " \"%s\",", m->surf[match[k]]->name);
        st = thx_error(ctx, THX_EINPUT, "%s: %zu rows match more than one node set (%.400s): name the surface with --surface",
                       path, d->n_rows, names);
    } else {
        char counts[1024] = "";
        size_t o = 0;
        if (m->volume) o += (size_t)snprintf(counts + o, sizeof counts - o, " volume %zu,", m->volume->n_nodes);
        for (size_t s = 0; s < m->n_surfaces && o < sizeof counts; s++)
            o += (size_t)snprintf(counts + o, sizeof counts - o, " %s %zu,", m->surf[s]->name, m->surf[s]->n_nodes);
        if (o && o < sizeof counts) counts[o - 1] = '\0';
        st = thx_error(ctx, THX_EINPUT, "%s: %zu rows match no node set of the model%s (nodes:%.900s)", path, d->n_rows,
                       n_only ? " among the --surface names" : "", counts);
    }
    if (st == THX_OK) snprintf(S->unit, sizeof S->unit, "%s", S->axis->unit);
done:
    thx_series_destroy(&d);
    return st;
}

/* The msh view's values: frame k of the selection. */
typedef struct {
    const thx_series *s;
    const size_t *frame;
} view_src;

static void view_values(void *user, size_t k, double *out)
{
    const view_src *u = user;
    memcpy(out, u->s->v + u->frame[k] * u->s->n_rows, u->s->n_rows * sizeof *out);
}

int cli_export_data(const cli_export_request *rq)
{
    const char *cmd = "export";
    thx_ctx *ctx = cli_ctx(rq->verbose);
    thx_model *m = NULL;
    sources S;
    memset(&S, 0, sizeof S);
    int rc = 0;
    size_t *frame = NULL, nsel = 0;
    unsigned char *sel = NULL;
    double *times = NULL, *jt = NULL;
    char **names = NULL;
    size_t n_names = 0;
    thx_msh_view *views = NULL;
    view_src *vs = NULL;
    thx_status st = thx_model_read(ctx, rq->model_dir, &m);
    if (st) goto fail;
    S.surf = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *S.surf);
    S.use = thx_calloc(ctx, m->volume && m->volume->n_regions ? m->volume->n_regions : 1, 1);
    if (!S.surf || !S.use) {
        st = THX_ENOMEM;
        goto fail;
    }
    if (rq->solution) st = read_solution(ctx, m, rq->solution, &S);
    else st = read_data(ctx, m, rq->data, rq->only, rq->n_only, &S);
    if (st) goto fail;
    const char *src = rq->solution ? rq->solution : rq->data;
    thx_export_format fmt = rq->fmt;
    int volume_fmt = fmt == THX_EXPORT_VTU || fmt == THX_EXPORT_MSH;
    if (volume_fmt && !m->volume) {
        st = thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh for a %s export (make one with `thorax mesh`)",
                       rq->model_dir, fmt == THX_EXPORT_VTU ? "vtu" : "msh");
        goto fail;
    }
    if (fmt == THX_EXPORT_VTU && !S.vol) {
        st = thx_error(ctx, THX_EINPUT, "%s: the data are on surfaces, not on the volume's nodes: export them as vtp, vtk "
                       "or msh", src);
        goto fail;
    }
    /* the frames */
    size_t nf = S.axis->n_frames;
    sel = thx_malloc(ctx, nf);
    frame = thx_malloc(ctx, nf * sizeof *frame);
    times = thx_malloc(ctx, nf * sizeof *times);
    if (!sel || !frame || !times) {
        st = THX_ENOMEM;
        goto fail;
    }
    if (cli_parse_frames(rq->frames ? rq->frames : "all", nf, sel)) {
        rc = cli_usage_error(cmd, "--frames '%s': 1-based frames 1..%zu of %s, as A:B[:STEP] items separated by commas, "
                             "or all", rq->frames, nf, src);
        goto end;
    }
    for (size_t f = 0; f < nf; f++)
        if (sel[f]) {
            frame[nsel] = f;
            times[nsel++] = S.axis->time[f];
        }
    int width = 4;
    for (size_t x = nf; x >= 10000; x /= 10) width++;
    /* the files: NAME_FFFF.EXT per frame and NAME.pvd (vtu, vtp), or volume.msh */
    size_t n_targets = 0, targets[65];
    if (fmt == THX_EXPORT_VTU || fmt == THX_EXPORT_MSH) targets[n_targets++] = m->n_surfaces; /* the volume */
    else
        for (size_t s = 0; s < m->n_surfaces && n_targets < 64; s++) {
            int wanted = rq->n_only == 0;
            for (int k = 0; k < rq->n_only && !wanted; k++) wanted = strcmp(m->surf[s]->name, rq->only[k]) == 0;
            if (wanted && S.surf[s]) targets[n_targets++] = s;
        }
    if (!n_targets) {
        st = thx_error(ctx, THX_EINPUT, "%s: no surface named by --surface carries data", src);
        goto fail;
    }
    static const char *const ext_of[] = {"vtk", "vtp", "obj", "stl", "ply", "vtu", "msh"};
    size_t per = fmt == THX_EXPORT_MSH ? 1 : nsel + (fmt != THX_EXPORT_VTK);
    names = thx_calloc(ctx, n_targets * per, sizeof *names);
    if (!names) {
        st = THX_ENOMEM;
        goto fail;
    }
    for (size_t q = 0; q < n_targets; q++) {
        const char *stem = targets[q] == m->n_surfaces ? "volume" : m->surf[targets[q]]->name;
        for (size_t k = 0; k < per; k++) {
            char nm[256];
            if (fmt == THX_EXPORT_MSH) snprintf(nm, sizeof nm, "%s.msh", stem);
            else if (k == nsel) snprintf(nm, sizeof nm, "%s.pvd", stem);
            else snprintf(nm, sizeof nm, "%s_%0*zu.%s", stem, width, frame[k] + 1, ext_of[fmt]);
            names[n_names] = strdup(nm);
            if (!names[n_names++]) {
                st = thx_error(ctx, THX_ENOMEM, "out of memory");
                goto fail;
            }
        }
    }
    /* every file is claimed before any is written: one refused, none written */
    for (size_t i = 0; i < n_names; i++) {
        char path[4400];
        THX_TRY(join(ctx, path, sizeof path, rq->out_dir, names[i]));
        size_t l = strlen(names[i]);
        st = l > 4 && !strcmp(names[i] + l - 4, ".pvd") ? thx_export_pvd_claim(ctx, path) : thx_export_claim(ctx, fmt, path);
        if (st) goto fail;
    }
    if (thx_make_dirs(rq->out_dir) != 0) {
        st = thx_error(ctx, THX_EIO, "%s: cannot create directory: %s", rq->out_dir, strerror(errno));
        goto fail;
    }
    double t0 = thx_wtime();
    char path[4400];
    if (fmt == THX_EXPORT_MSH) {
        /* one view of the volume's potentials, or one per surface carrying data */
        views = thx_calloc(ctx, m->n_surfaces + 1, sizeof *views);
        vs = thx_calloc(ctx, m->n_surfaces + 1, sizeof *vs);
        char (*vname)[160] = thx_calloc(ctx, m->n_surfaces + 1, sizeof *vname);
        if (!views || !vs || !vname) {
            free(vname);
            st = THX_ENOMEM;
            goto fail;
        }
        size_t nv = 0;
        char unit[48] = "";
        if (S.unit[0]) snprintf(unit, sizeof unit, " (%s)", S.unit);
        for (size_t s = 0; s <= m->n_surfaces; s++) {
            const thx_series *x = s == m->n_surfaces ? S.vol : S.vol ? NULL : S.surf[s];
            if (!x) continue;
            vs[nv] = (view_src){x, frame};
            if (s == m->n_surfaces) snprintf(vname[nv], sizeof vname[nv], "potential%s", unit);
            else snprintf(vname[nv], sizeof vname[nv], "potential on %.64s%s", m->surf[s]->name, unit);
            views[nv] = (thx_msh_view){.name = vname[nv], .on_cells = 0, .n_comp = 1, .n = x->n_rows,
                                       .ids = s == m->n_surfaces ? NULL : m->volume->surf_node[s], .n_frames = nsel,
                                       .time = times, .values = view_values, .user = &vs[nv]};
            nv++;
        }
        THX_TRY(join(ctx, path, sizeof path, rq->out_dir, names[0]));
        st = thx_volume_export_msh(ctx, m, views, nv, path);
        free(vname);
        if (st) goto fail;
        thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu frames)", path, nsel);
    } else {
        if (S.vol) {
            jt = thx_malloc(ctx, 3 * (m->volume->n_tets ? m->volume->n_tets : 1) * sizeof *jt);
            if (!jt) {
                st = THX_ENOMEM;
                goto fail;
            }
        }
        for (size_t q = 0, i = 0; q < n_targets; q++) {
            size_t s = targets[q];
            const thx_series *x = s == m->n_surfaces ? S.vol : S.surf[s];
            for (size_t k = 0; k < nsel; k++, i++) {
                size_t f = frame[k];
                thx_export_array pt = {"potential", 1, x->v + f * x->n_rows}, ce = {"current_density", 3, jt};
                thx_export_frame fr = {.has_time = 1, .time = times[k], .point = &pt, .n_point = 1};
                THX_TRY(join(ctx, path, sizeof path, rq->out_dir, names[i]));
                if (s == m->n_surfaces) {
                    thx_fem_currents(m->volume, S.use, x->v + f * x->n_rows, jt, NULL);
                    fr.cell = &ce;
                    fr.n_cell = 1;
                    st = thx_volume_export_vtu(ctx, m, &fr, path);
                } else {
                    st = thx_surface_export_data(ctx, m, s, fmt, &fr, path);
                }
                if (st) goto fail;
            }
            if (fmt != THX_EXPORT_VTK) { /* the collection last: it names only files that are there */
                THX_TRY(join(ctx, path, sizeof path, rq->out_dir, names[i]));
                st = thx_export_pvd(ctx, path, (const char *const *)(names + i - nsel), times, nsel);
                if (st) goto fail;
                i++;
            }
            thx_log(ctx, THX_LOG_INFO, "wrote %s/%s_*.%s (%zu frames)%s", rq->out_dir,
                    s == m->n_surfaces ? "volume" : m->surf[s]->name, ext_of[fmt], nsel,
                    fmt != THX_EXPORT_VTK ? " and its .pvd" : "");
        }
    }
    thx_log(ctx, THX_LOG_INFO, "%zu files, %.2f s", n_names, thx_wtime() - t0);
    goto end;
done:
fail:
    rc = cli_fail(ctx, cmd, st);
end:
    for (size_t i = 0; i < n_names; i++) free(names[i]);
    free(names);
    free(views);
    free(vs);
    free(sel);
    free(frame);
    free(times);
    free(jt);
    thx_series_destroy(&S.vol);
    for (size_t s = 0; S.surf && m && s < m->n_surfaces; s++) thx_series_destroy(&S.surf[s]);
    free(S.surf);
    free(S.use);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
