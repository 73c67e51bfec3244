/*
 * thorax field under mpirun (cli/cli_field.h; docs/design/parallel.md, "thorax field on the parts"):
 * a solution whose volume potentials are in parts for as many ranks (thorax forward --volume under
 * mpirun, thorax/fem/parts.h) is cut sort-last. Each rank reads the model's region table and its own
 * part alone (never volume.raw nor the volume mesh), cuts the part frame by frame with the same
 * request as one process, and keeps the triangles of the tetrahedra it owns; the ghosts around them
 * make each of those triangles, its vertices' bits and its neighbours' the whole's. Rank 0 gathers
 * the own triangles and puts the one process's mesh back together:
 *   - triangles in the order of their value or plane (tag), then of their tetrahedron's number in
 *     the whole, then of their order within it: each rank's list is in that order already and a
 *     tetrahedron is one rank's, so a sort on (tag, tetrahedron, rank, place) gives it;
 *   - vertices numbered in the order they are first used, a vertex cut by several ranks once: one
 *     vertex per (tag, coordinates' bits), the cut points being computed from the same bits by the
 *     same arithmetic on every rank (and two cut points of one tag never sharing their coordinates
 *     in a conforming mesh); the same key with another potential is refused as an internal error;
 *   - the contours computed there on the slices put together (they depend on the mesh alone).
 * What is global is agreed first: each frame's range over the regions cut (the values of a count or
 * percentages), every plane's span (the refusals of empty cuts) and the slices' tolerance scale
 * (thx_field_slice_scaled). Rank 0 alone claims and writes; a failure anywhere is agreed before it
 * writes, so that one message is printed (the lowest failing rank's) and every rank exits 1.
 */
#include <cjson/cJSON.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_field.h"
#include "cli/cli_share.h"
#include "thorax/core/fileio.h"
#include "thorax/fem/fem.h"
#include "thorax/fem/parts.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/solution_file.h"
#include "thorax/io/series_file.h"
#include "thorax/parallel/parallel.h"

static int g_stderr = -1; /* stderr while muted (cli_field_mute) */

void cli_field_mute(int mute)
{
    if (mute && g_stderr < 0 && thx_par_launched_rank() != 0) {
        int fd = open("/dev/null", O_WRONLY);
        fflush(stderr);
        if (fd >= 0 && (g_stderr = dup(2)) >= 0) dup2(fd, 2);
        if (fd >= 0) close(fd);
    } else if (!mute && g_stderr >= 0) {
        fflush(stderr);
        dup2(g_stderr, 2);
        close(g_stderr);
        g_stderr = -1;
    }
}

/* This rank's share of the solution. */
typedef struct {
    thx_model *m;     /* the model's surfaces and region table (no volume mesh) */
    thx_fem_part p;   /* this rank's part */
    thx_volume v;     /* the part as a volume: its nodes and tetrahedra, the model's regions */
    double *time;     /* per frame: the volume's times (the solution's surface series carries the same) */
    char unit[64];
} field_part;

static void part_free(field_part *P)
{
    thx_fem_part_free(&P->p);
    thx_model_destroy(&P->m);
    free(P->time);
    memset(P, 0, sizeof *P);
}

/* Reads solution.json, refuses a solution not in parts for size ranks, then reads the model's region
 * table, this rank's part and the frames' times. */
static thx_status part_open(thx_ctx *ctx, const char *sol, int rank, int size, field_part *P)
{
    memset(P, 0, sizeof *P);
    char path[4400];
    snprintf(path, sizeof path, "%s/solution.json", sol);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    const cJSON *fmt = cJSON_GetObjectItem(j, "format"), *mo = cJSON_GetObjectItem(j, "model");
    const cJSON *files = cJSON_GetObjectItem(j, "files"), *vp = cJSON_GetObjectItem(j, "volume_parts");
    const cJSON *rk = cJSON_GetObjectItem(vp, "ranks"), *man = cJSON_GetObjectItem(vp, "manifest");
    /* the times: a series of the same frames beside the volume (forward copies one time axis to all) */
    const cJSON *ts = cJSON_GetObjectItem(files, "torso");
    if (!cJSON_IsString(ts)) ts = cJSON_GetObjectItem(files, "electrodes");
    thx_status st = THX_OK;
    thx_series *s = NULL;
    if (!j || !cJSON_IsString(fmt) || strcmp(fmt->valuestring, "thorax-solution") != 0 || !cJSON_IsString(mo))
        st = thx_error(ctx, THX_EINPUT, "%s: not a thorax solution (no \"format\": \"thorax-solution\" and \"model\")", path);
    else if (!vp)
        st = thx_error(ctx, THX_EINPUT, "%s: the volume potentials are whole (no parts: thorax forward ran in one "
                       "process); under mpirun, thorax field cuts a solution whose volume is in parts for as many ranks "
                       "(thorax forward --volume under mpirun -np N): run it without mpirun", sol);
    else if (!cJSON_IsNumber(rk) || rk->valuedouble != size)
        st = thx_error(ctx, THX_EINPUT, "%s: the volume potentials are in parts for %g ranks, and this run has %d: run thorax "
                       "field under mpirun -np %g (each rank cuts its part), or without mpirun (thorax field has no other "
                       "way to share its work)", sol, cJSON_IsNumber(rk) ? rk->valuedouble : NAN, size,
                       cJSON_IsNumber(rk) ? rk->valuedouble : NAN);
    else if (!cJSON_IsString(ts) || strchr(ts->valuestring, '/'))
        st = thx_error(ctx, THX_EINPUT, "%s: no torso or electrodes series (\"files\"), whose times the volume's are", path);
    if (st == THX_OK) st = thx_model_read_regions_only(ctx, mo->valuestring, &P->m);
    if (st == THX_OK && !P->m->volume)
        st = thx_error(ctx, THX_EINPUT, "%s: the solution's model %s has no volume mesh", path, mo->valuestring);
    if (st == THX_OK)
        st = thx_fem_part_open(ctx, sol, cJSON_IsString(man) ? man->valuestring : NULL, rank, size, P->m->volume->n_regions,
                               &P->p, P->unit, sizeof P->unit);
    if (st == THX_OK) {
        snprintf(path, sizeof path, "%s/%s", sol, ts->valuestring);
        st = thx_series_read(ctx, path, THX_SERIES_AUTO, &s);
    }
    if (st == THX_OK && s->n_frames != P->p.n_frames)
        st = thx_error(ctx, THX_EINPUT, "%s: %zu frames, the volume's parts %zu", path, s->n_frames, P->p.n_frames);
    if (st == THX_OK && !(P->time = thx_malloc(ctx, s->n_frames * sizeof *P->time))) st = THX_ENOMEM;
    if (st == THX_OK) memcpy(P->time, s->time, s->n_frames * sizeof *P->time);
    thx_series_destroy(&s);
    cJSON_Delete(j);
    if (st != THX_OK) {
        part_free(P);
        return st;
    }
    /* the part as a volume: the model's regions, the part's nodes and tetrahedra (the part owns them) */
    P->v.n_regions = P->m->volume->n_regions;
    P->v.regions = P->m->volume->regions;
    P->v.n_nodes = P->p.n_nodes;
    P->v.xyz = P->p.xyz;
    P->v.n_tets = P->p.n_tets;
    P->v.tet = P->p.tet;
    P->v.region = P->p.region;
    return THX_OK;
}

/* st, noted in *mine when it is this rank's first failure: what a rank carries into a collective is
 * its own; what comes out may be another rank's, which that rank reports. */
static thx_status own(thx_status *mine, thx_status st)
{
    if (st != THX_OK && *mine == THX_OK) *mine = st;
    return st;
}

/* Collective: v[0..n) replaced by its largest over the ranks, 64 at a time (thx_par_max's most). The
 * first call agrees on st: a failure anywhere ends it there on every rank. */
static thx_status max_all(thx_ctx *ctx, thx_status st, double *v, size_t n)
{
    size_t k = 0;
    do {
        int m = n - k > 64 ? 64 : (int)(n - k);
        st = thx_par_max(ctx, st, m ? v + k : NULL, m);
        k += (size_t)m;
    } while (st == THX_OK && k < n);
    return st;
}

/*
 * One rank's own triangles of a frame, as sent to rank 0 (native byte order: the ranks run the same
 * binary): nv and nt (uint64), nv vertices (x, y, z, potential: float64), nt triangles (tag,
 * tetrahedron's number in the whole, three vertex numbers: int32), nt |J| (float64).
 */
#define WIRE_HEAD 16
#define WIRE_VERT 32
#define WIRE_TRI 28

/* Packs the triangles of mi (tags 0..) and ms (tags ni..) whose tetrahedron the rank owns, their
 * vertices numbered in the order of first use, |J| of their tetrahedra from jm. */
static thx_status pack(thx_ctx *ctx, const field_part *P, const thx_field_mesh *mi, const thx_field_mesh *ms, size_t ni,
                       const double *jm, unsigned char **buf, size_t *len)
{
    const thx_field_mesh *mesh[2] = {mi, ms};
    int32_t *map[2] = {NULL, NULL};
    size_t nt = 0, nv = 0;
    *buf = NULL;
    for (int q = 0; q < 2; q++) {
        map[q] = thx_malloc(ctx, (mesh[q]->n_points + 1) * sizeof *map[q]);
        if (!map[q]) {
            free(map[0]);
            return THX_ENOMEM;
        }
        for (size_t i = 0; i < mesh[q]->n_points; i++) map[q][i] = -1;
        for (size_t t = 0; t < mesh[q]->n_tris; t++) {
            if ((uint32_t)P->p.owner[mesh[q]->cell[t]] != P->p.rank) continue;
            nt++;
            for (int c = 0; c < 3; c++) {
                int32_t *x = &map[q][mesh[q]->tri[3 * t + c]];
                if (*x < 0) *x = (int32_t)nv++;
            }
        }
    }
    *len = WIRE_HEAD + WIRE_VERT * nv + WIRE_TRI * nt;
    unsigned char *b = *buf = thx_malloc(ctx, *len);
    if (!b) {
        free(map[0]);
        free(map[1]);
        return THX_ENOMEM;
    }
    uint64_t head[2] = {nv, nt};
    memcpy(b, head, sizeof head);
    unsigned char *vb = b + WIRE_HEAD, *tb = vb + WIRE_VERT * nv, *jb = tb + 20 * nt;
    size_t k = 0;
    for (int q = 0; q < 2; q++) {
        const thx_field_mesh *m = mesh[q];
        for (size_t i = 0; i < m->n_points; i++) {
            if (map[q][i] < 0) continue;
            double x[4] = {m->xyz[3 * i], m->xyz[3 * i + 1], m->xyz[3 * i + 2], m->value[i]};
            memcpy(vb + WIRE_VERT * (size_t)map[q][i], x, sizeof x);
        }
        for (size_t t = 0; t < m->n_tris; t++) {
            int32_t cell = m->cell[t];
            if ((uint32_t)P->p.owner[cell] != P->p.rank) continue;
            int32_t r[5] = {m->tag[t] + (q ? (int32_t)ni : 0), P->p.tet_id[cell], map[q][m->tri[3 * t]],
                            map[q][m->tri[3 * t + 1]], map[q][m->tri[3 * t + 2]]};
            memcpy(tb + 20 * k, r, sizeof r);
            memcpy(jb + 8 * k, &jm[cell], 8);
            k++;
        }
    }
    free(map[0]);
    free(map[1]);
    return THX_OK;
}

/* A triangle as rank 0 orders them. */
typedef struct {
    int32_t tag, tet, rank;
    uint32_t at;
} tri_ref;

static int by_place(const void *pa, const void *pb)
{
    const tri_ref *a = pa, *b = pb;
    if (a->tag != b->tag) return a->tag < b->tag ? -1 : 1;
    if (a->tet != b->tet) return a->tet < b->tet ? -1 : 1;
    if (a->rank != b->rank) return a->rank < b->rank ? -1 : 1;
    return (a->at > b->at) - (a->at < b->at);
}

/* One vertex of the mesh put together: its tag and coordinates' bits, its number in its mesh. */
typedef struct {
    uint64_t x[3];
    int32_t tag, idx; /* idx < 0: empty */
} vert_key;

static vert_key *vert_slot(vert_key *h, size_t mask, int32_t tag, const uint64_t x[3])
{
    uint64_t z = (uint64_t)(uint32_t)tag * 0x9E3779B97F4A7C15ull ^ x[0] * 0xC2B2AE3D27D4EB4Full ^
                 x[1] * 0x165667B19E3779F9ull ^ x[2] * 0x27D4EB2F165667C5ull;
    z ^= z >> 31;
    for (size_t i = (size_t)z & mask;; i = (i + 1) & mask)
        if (h[i].idx < 0 || (h[i].tag == tag && !memcmp(h[i].x, x, sizeof h[i].x))) return &h[i];
}

/* Rank 0: the ranks' own triangles (all, counts[r] bytes from rank r) into the one process's
 * isosurface mesh mi (tags 0..ni-1) and slice mesh ms (tags from 0), jg[tetrahedron] their |J|. */
static thx_status rebuild(thx_ctx *ctx, const unsigned char *all, const size_t *counts, int size, size_t ni,
                          size_t n_global_tets, thx_field_mesh *mi, thx_field_mesh *ms, double *jg)
{
    thx_status st = THX_OK;
    const unsigned char **at = thx_calloc(ctx, (size_t)size, sizeof *at);
    uint64_t (*head)[2] = thx_calloc(ctx, (size_t)size, sizeof *head);
    int32_t **gv = thx_calloc(ctx, (size_t)size, sizeof *gv);
    tri_ref *ref = NULL;
    vert_key *h = NULL;
    if (!at || !head || !gv) {
        st = THX_ENOMEM;
        goto done;
    }
    size_t nt = 0, nv = 0, n_iso = 0, off = 0;
    for (int r = 0; r < size; r++) {
        at[r] = all + off;
        if (counts[r] < WIRE_HEAD) {
            st = thx_error(ctx, THX_EINTERNAL, "field parts: rank %d sent %zu bytes, not its triangles", r, counts[r]);
            goto done;
        }
        memcpy(head[r], at[r], sizeof head[r]);
        if (head[r][0] > counts[r] / WIRE_VERT || head[r][1] > counts[r] / WIRE_TRI ||
            WIRE_HEAD + WIRE_VERT * head[r][0] + WIRE_TRI * head[r][1] != counts[r]) {
            st = thx_error(ctx, THX_EINTERNAL, "field parts: rank %d's %zu bytes are not %llu vertices and %llu triangles", r,
                           counts[r], (unsigned long long)head[r][0], (unsigned long long)head[r][1]);
            goto done;
        }
        if (!(gv[r] = thx_malloc(ctx, (head[r][0] + 1) * sizeof *gv[r]))) {
            st = THX_ENOMEM;
            goto done;
        }
        for (uint64_t i = 0; i < head[r][0]; i++) gv[r][i] = -1;
        nv += head[r][0];
        nt += head[r][1];
        off += counts[r];
    }
    if (nt > INT32_MAX / 3 || nv > INT32_MAX) {
        st = thx_error(ctx, THX_EINPUT, "field parts: %zu triangles, %zu vertices: too many", nt, nv);
        goto done;
    }
    ref = thx_malloc(ctx, (nt + 1) * sizeof *ref);
    size_t hn = 1024;
    while (hn < 2 * nv + 16) hn *= 2;
    h = thx_malloc(ctx, hn * sizeof *h);
    if (!ref || !h) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < hn; i++) h[i].idx = -1;
    size_t k = 0;
    for (int r = 0; r < size; r++) {
        const unsigned char *tb = at[r] + WIRE_HEAD + WIRE_VERT * head[r][0];
        for (uint64_t t = 0; t < head[r][1]; t++) {
            int32_t x[5];
            memcpy(x, tb + 20 * t, sizeof x);
            if (x[0] < 0 || x[1] < 0 || (size_t)x[1] >= n_global_tets) {
                st = thx_error(ctx, THX_EINTERNAL, "field parts: rank %d's triangle %llu: tag %d, tetrahedron %d", r,
                               (unsigned long long)t + 1, x[0], x[1]);
                goto done;
            }
            for (int c = 2; c < 5; c++)
                if (x[c] < 0 || (uint64_t)x[c] >= head[r][0]) {
                    st = thx_error(ctx, THX_EINTERNAL, "field parts: rank %d's triangle %llu names vertex %d of %llu", r,
                                   (unsigned long long)t + 1, x[c], (unsigned long long)head[r][0]);
                    goto done;
                }
            ref[k++] = (tri_ref){x[0], x[1], r, (uint32_t)t};
            n_iso += (size_t)x[0] < ni;
        }
    }
    qsort(ref, nt, sizeof *ref, by_place);
    for (size_t i = 1; i < nt; i++)
        if (ref[i].tag == ref[i - 1].tag && ref[i].tet == ref[i - 1].tet && ref[i].rank != ref[i - 1].rank) {
            st = thx_error(ctx, THX_EINTERNAL, "field parts: tetrahedron %d cut by ranks %d and %d (the parts overlap)",
                           ref[i].tet, ref[i - 1].rank, ref[i].rank);
            goto done;
        }
    thx_field_mesh_clear(mi);
    thx_field_mesh_clear(ms);
    THX_TRY(thx_field_mesh_reserve(ctx, mi, nv, n_iso));
    THX_TRY(thx_field_mesh_reserve(ctx, ms, nv, nt - n_iso));
    for (size_t i = 0; i < nt; i++) {
        const tri_ref *q = &ref[i];
        int iso = (size_t)q->tag < ni;
        thx_field_mesh *m = iso ? mi : ms;
        const unsigned char *vb = at[q->rank] + WIRE_HEAD, *tb = vb + WIRE_VERT * head[q->rank][0];
        int32_t x[5];
        memcpy(x, tb + 20 * (size_t)q->at, sizeof x);
        size_t t = m->n_tris++;
        for (int c = 0; c < 3; c++) {
            int32_t *g = &gv[q->rank][x[2 + c]];
            if (*g < 0) {
                double p[4];
                uint64_t bits[3];
                memcpy(p, vb + WIRE_VERT * (size_t)x[2 + c], sizeof p);
                memcpy(bits, p, sizeof bits);
                vert_key *s = vert_slot(h, hn - 1, q->tag, bits);
                if (s->idx < 0) { /* a new vertex of its mesh */
                    memcpy(s->x, bits, sizeof bits);
                    s->tag = q->tag;
                    s->idx = (int32_t)m->n_points++;
                    memcpy(m->xyz + 3 * (size_t)s->idx, p, 3 * sizeof *p);
                    m->value[s->idx] = p[3];
                } else if (memcmp(&m->value[s->idx], &p[3], sizeof p[3]) != 0) {
                    st = thx_error(ctx, THX_EINTERNAL, "field parts: the cut point (%.17g, %.17g, %.17g) of rank %d has "
                                   "potential %.17g, another rank's %.17g", p[0], p[1], p[2], q->rank, p[3],
                                   m->value[s->idx]);
                    goto done;
                }
                *g = s->idx;
            }
            m->tri[3 * t + c] = *g;
        }
        m->tag[t] = iso ? q->tag : q->tag - (int32_t)ni;
        m->cell[t] = q->tet;
        memcpy(&jg[q->tet], tb + 20 * head[q->rank][1] + 8 * (size_t)q->at, sizeof *jg);
    }
done:
    for (int r = 0; gv && r < size; r++) free(gv[r]);
    free(gv);
    free(at);
    free(head);
    free(ref);
    free(h);
    return st;
}

/* Rank 0's cut of a frame from the gathered triangles, as make_frame (cmd_field.c) makes it from the
 * whole: the isosurfaces, then the slices with their contours, tags after the isosurfaces'. */
static thx_status frame_whole(thx_ctx *ctx, const cli_field_request *rq, const unsigned char *all, const size_t *counts,
                              int size, size_t ni, double lo, double hi, size_t n_global_tets, thx_field_mesh *out,
                              double *jg, double **cv, size_t *nc)
{
    thx_field_mesh *mi = NULL, *ms = NULL;
    thx_status st = THX_OK;
    THX_TRY(thx_field_mesh_create(ctx, &mi));
    THX_TRY(thx_field_mesh_create(ctx, &ms));
    THX_TRY(rebuild(ctx, all, counts, size, ni, n_global_tets, mi, ms, jg));
    thx_field_mesh_clear(out);
    THX_TRY(thx_field_mesh_append(ctx, out, mi, 0));
    if (rq->n_planes) {
        if (rq->contours) {
            THX_TRY(cli_field_values(ctx, rq->contours, "contour", lo, hi, cv, nc));
            THX_TRY(thx_field_contours(ctx, ms, *cv, *nc));
        }
        THX_TRY(thx_field_mesh_append(ctx, out, ms, (int32_t)ni));
    }
done:
    thx_field_mesh_destroy(&mi);
    thx_field_mesh_destroy(&ms);
    return st;
}

/* This rank's cut of a frame (phi on the part's nodes, the agreed range [lo, hi] of its regions),
 * its own triangles packed for rank 0; the isosurfaces' values in *iso (ni). */
static thx_status frame_part(thx_ctx *ctx, const field_part *P, const cli_field_request *rq, const double *phi, double lo,
                             double hi, double scale, double *jt, double *jm, double **iso, size_t *ni,
                             unsigned char **buf, size_t *len)
{
    thx_field_mesh *mi = NULL, *ms = NULL;
    thx_status st = THX_OK;
    if (!(lo <= hi)) return thx_error(ctx, THX_EINPUT, "no tetrahedron in the regions chosen");
    THX_TRY(thx_field_mesh_create(ctx, &mi));
    THX_TRY(thx_field_mesh_create(ctx, &ms));
    if (rq->iso) {
        THX_TRY(cli_field_values(ctx, rq->iso, "equipotential surface", lo, hi, iso, ni));
        THX_TRY(thx_field_isosurface(ctx, &P->v, phi, *iso, *ni, rq->use, mi));
    }
    if (rq->n_planes) THX_TRY(thx_field_slice_scaled(ctx, &P->v, phi, rq->plane, rq->n_planes, rq->use, scale, ms));
    thx_fem_currents(&P->v, rq->use, phi, jt, NULL);
    for (size_t t = 0; t < P->v.n_tets; t++)
        jm[t] = sqrt(jt[3 * t] * jt[3 * t] + jt[3 * t + 1] * jt[3 * t + 1] + jt[3 * t + 2] * jt[3 * t + 2]);
    st = pack(ctx, P, mi, ms, *ni, jm, buf, len);
done:
    thx_field_mesh_destroy(&mi);
    thx_field_mesh_destroy(&ms);
    return st;
}

int cli_field_parts(const char *cmd, const char *sol, cli_field_request *rq, const char *const *regions, int n_regions,
                    const char *frames, const char *out, int verbose)
{
    int rc = cli_share_start(cmd, &verbose);
    if (rc) return rc;
    thx_ctx *ctx = cli_ctx(verbose);
    int rank = thx_par_rank(), size = thx_par_size();
    field_part P;
    cli_field_files files = {0};
    unsigned char *use = NULL, *sel = NULL;
    size_t *frame = NULL, nsel = 0, tris = 0;
    double *times = NULL, *red = NULL, *jt = NULL, *jm = NULL, *jg = NULL;
    thx_field_mesh *mesh = NULL;
    double t0 = thx_wtime();
    thx_status st = part_open(ctx, sol, rank, size, &P), mine = THX_OK;
    if (st == THX_OK) {
        use = thx_calloc(ctx, P.v.n_regions + 1, 1);
        sel = thx_calloc(ctx, P.p.n_frames + 1, 1);
        frame = thx_calloc(ctx, P.p.n_frames + 1, sizeof *frame);
        times = thx_calloc(ctx, P.p.n_frames + 1, sizeof *times);
        jt = thx_malloc(ctx, 3 * (P.v.n_tets + 1) * sizeof *jt);
        jm = thx_malloc(ctx, (P.v.n_tets + 1) * sizeof *jm);
        if (!use || !sel || !frame || !times || !jt || !jm) st = THX_ENOMEM;
    }
    if (st == THX_OK) st = cli_field_use(ctx, sol, &P.v, regions, n_regions, use);
    /* the parts hold the regions the heart-surface problem solves (thorax forward's rule, cli_parts.c) */
    for (size_t r = 0; st == THX_OK && r < P.v.n_regions; r++)
        if (use[r] && !strcmp(P.v.regions[r].name, "heart"))
            st = thx_error(ctx, THX_EINPUT, "%s: its parts hold no tetrahedron of region \"heart\" (the heart-surface "
                           "problem leaves it out): cut it with one process (without mpirun)", sol);
    st = thx_par_agree(ctx, own(&mine, st), NULL); /* every rank has its part, or none goes on */
    if (st != THX_OK) goto end;
    rq->use = use;
    /* (the same line and files on every rank: a usage error is every rank's, told by rank 0) */
    if (cli_parse_frames(frames, P.p.n_frames, sel)) {
        if (rank == 0)
            cli_usage_error(cmd, "--frame '%s': 1-based frames 1..%zu of %s, as N, A:B[:STEP] items separated by commas, "
                            "or all", frames, P.p.n_frames, sol);
        rc = 2;
        goto usage;
    }
    for (size_t f = 0; f < P.p.n_frames; f++)
        if (sel[f]) {
            times[nsel] = P.time[f];
            frame[nsel++] = f;
        }
    /* agreed: each frame's range over the regions cut, each plane's span, the slices' tolerance scale
       (as largest values: -least, largest) */
    size_t nr = 2 * nsel + 2 * rq->n_planes + 1;
    red = thx_malloc(ctx, 2 * nr * sizeof *red);
    if (!red) st = THX_ENOMEM;
    for (size_t k = 0; st == THX_OK && k < nsel; k++) {
        cli_field_range(&P.v, P.p.values + frame[k] * P.p.n_nodes, use, &red[2 * k], &red[2 * k + 1]);
        red[2 * k] = -red[2 * k];
    }
    for (size_t p = 0; st == THX_OK && p < rq->n_planes; p++) {
        double *s = red + 2 * nsel + 2 * p;
        thx_field_plane_span(&P.v, use, &rq->plane[p], &s[0], &s[1]);
        s[0] = -s[0];
    }
    if (st == THX_OK) red[nr - 1] = thx_field_slice_scale(&P.v);
    st = max_all(ctx, own(&mine, st), red, st == THX_OK ? nr : 0);
    if (st != THX_OK) goto end;
    /* (as cli_field_check_empty takes them, after the reduced values: lows, highs, spans) */
    double *lo = red + nr, *hi = lo + nsel, *span = hi + nsel, scale = red[nr - 1];
    for (size_t k = 0; k < nsel; k++) lo[k] = -red[2 * k], hi[k] = red[2 * k + 1];
    for (size_t p = 0; p < rq->n_planes; p++) span[2 * p] = -red[2 * nsel + 2 * p], span[2 * p + 1] = red[2 * nsel + 2 * p + 1];
    st = cli_field_check_empty(ctx, sol, frame, nsel, rq, lo, hi, span);
    if (st == THX_OK) st = cli_field_files_name(ctx, out, frame, nsel, P.p.n_frames, &files);
    st = thx_par_agree(ctx, own(&mine, st), NULL);
    if (st == THX_EINPUT && files.single && nsel > 1) {
        if (rank == 0) cli_usage_error(cmd, "%s", thx_ctx_message(ctx));
        rc = 2;
        goto usage;
    }
    if (st != THX_OK) goto end;
    /* rank 0 claims every file before any is written, and alone writes */
    if (rank == 0) {
        st = cli_field_files_claim(ctx, &files);
        if (st == THX_OK && !(jg = thx_calloc(ctx, P.p.n_global_tets + 1, sizeof *jg))) st = THX_ENOMEM;
        if (st == THX_OK) st = thx_field_mesh_create(ctx, &mesh);
    }
    t0 = thx_wtime();
    for (size_t k = 0; k < nsel; k++) {
        double *iso = NULL, *cv = NULL;
        size_t ni = 0, nc = 0, len = 0, *counts = NULL;
        unsigned char *buf = NULL;
        void *all = NULL;
        if (st == THX_OK)
            st = frame_part(ctx, &P, rq, P.p.values + frame[k] * P.p.n_nodes, lo[k], hi[k], scale, jt, jm, &iso, &ni, &buf,
                            &len);
        /* agreed first (this frame's cuts, and rank 0's writing of the frame before): every rank goes on, or none */
        const void *send = buf ? (const void *)buf : (const void *)"";
        thx_status sg = thx_par_gather(ctx, own(&mine, st), send, buf ? len : 0, &all, &counts);
        st = sg;
        if (st == THX_OK && rank == 0)
            st = frame_whole(ctx, rq, all, counts, size, ni, lo[k], hi[k], P.p.n_global_tets, mesh, jg, &cv, &nc);
        int go = 0;
        if (sg == THX_OK) { /* (every rank here, or none) */
            st = thx_par_agree(ctx, own(&mine, st), NULL);
            go = st == THX_OK;
        }
        /* rank 0 writes; its failure is agreed on by the next gather, or at the end */
        if (go && rank == 0)
            st = own(&mine, cli_field_write(ctx, sol, &files, k, frame[k], mesh, iso, ni, rq->n_planes, cv, jg, times[k],
                                            &tris));
        free(buf);
        free(all);
        free(counts);
        free(iso);
        free(cv);
        if (!go) break;
    }
    if (st == THX_OK && rank == 0) st = own(&mine, cli_field_pvd(ctx, &files, times, nsel));
    if (st == THX_OK) thx_log(ctx, THX_LOG_INFO, "%zu frames, %zu triangles, %.2f s", nsel, tris, thx_wtime() - t0);
end:
    /* the lowest rank whose own step failed speaks (not one that learnt of it from a collective) */
    rc = cli_share_end(ctx, cmd, mine);
    if (!rc && st != THX_OK) rc = cli_fail(ctx, cmd, st); /* (a collective's own failure: MPI's) */
    goto done;
usage:
    thx_par_end();
done:
    cli_field_files_free(&files);
    part_free(&P);
    free(use);
    free(sel);
    free(frame);
    free(times);
    free(red);
    free(jt);
    free(jm);
    free(jg);
    thx_field_mesh_destroy(&mesh);
    thx_ctx_destroy(&ctx);
    return rc;
}

int cli_field_streamlines_parts(const char *cmd, const char *sol, const thx_seed_spec *specs, int n_specs,
                                const thx_stream_opts *so, int frame, double tubes, int sides, int caps, const char *out,
                                int verbose)
{
    int rc = cli_share_start(cmd, &verbose);
    if (rc) return rc;
    thx_ctx *ctx = cli_ctx(verbose);
    int rank = thx_par_rank(), size = thx_par_size();
    field_part P;
    unsigned char *use = NULL, *own_t = NULL;
    thx_streamlines *sl = NULL;
    thx_stream_tubes *T = NULL;
    double t0 = thx_wtime();
    thx_status st = part_open(ctx, sol, rank, size, &P), mine = THX_OK;
    if (st == THX_OK) {
        use = thx_calloc(ctx, P.v.n_regions + 1, 1);
        own_t = thx_malloc(ctx, P.v.n_tets + 1);
        if (!use || !own_t) st = THX_ENOMEM;
    }
    if (st == THX_OK) st = thx_solution_domain(ctx, sol, &P.v, use); /* the regions the solution covers */
    for (int k = 0; st == THX_OK && k < n_specs; k++) /* random seeds are drawn over the whole volume at once */
        if (specs[k].kind == THX_SEED_REGION || specs[k].kind == THX_SEED_DENSITY)
            st = thx_error(ctx, THX_EINPUT, "--seed %s: %s seeds are drawn at random over the whole volume, not on %s's parts "
                           "(each rank its own): give point:, line: or sphere: seeds (the default is density:100), or run it "
                           "without mpirun", specs[k].text, specs[k].kind == THX_SEED_REGION ? "region" : "density", sol);
    if (st == THX_OK && (size_t)frame > P.p.n_frames)
        st = thx_error(ctx, THX_EINPUT, "%s: --frame %d: the volume potentials have %zu frames", sol, frame, P.p.n_frames);
    st = thx_par_agree(ctx, own(&mine, st), NULL); /* every rank has its part, or none goes on */
    if (st != THX_OK) goto end;
    for (size_t t = 0; t < P.v.n_tets; t++) own_t[t] = (uint32_t)P.p.owner[t] == P.p.rank;
    thx_stream_part part = {own_t, P.p.node, P.p.tet_id, P.p.owner, rank};
    double t1 = thx_wtime();
    const double *phi = P.p.values + (size_t)(frame - 1) * P.p.n_nodes;
    double *jn = malloc((3 * P.v.n_nodes + 1) * sizeof *jn); /* J at the part's nodes (its tetrahedra round them) */
    if (!jn) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK) thx_fem_currents(&P.v, use, phi, NULL, jn);
    st = thx_streamlines_trace_parts(ctx, &P.v, &part, use, phi, jn, specs, n_specs, so, sol, st, &sl);
    free(jn);
    if (st != THX_OK && thx_par_failed_first() == rank) own(&mine, st); /* (this rank's failure: it speaks) */
    double t2 = thx_wtime();
    if (st == THX_OK && rank == 0) { /* rank 0 holds the lines, and alone writes */
        if (tubes > 0) st = own(&mine, thx_stream_tubes_make(ctx, sl, tubes, sides, caps, &T));
        if (st == THX_OK) st = own(&mine, thx_streamlines_write(ctx, sl, T, out));
        size_t count[THX_STOP_COUNT] = {0};
        for (size_t l = 0; st == THX_OK && l < sl->n_lines; l++) count[sl->stop[l]]++;
        if (st == THX_OK)
            thx_log(ctx, THX_LOG_INFO,
                    "wrote %s: %zu lines, %zu points (%s); stops: %zu boundary, %zu low_current, %zu max_length, %zu max_steps, "
                    "%zu loop; frame %d; tracing on %d parts %.3f s (%zu steps, %zu evaluations), all %.2f s",
                    out, sl->n_lines, sl->n_points, T ? "as tubes" : "lines", count[0], count[1], count[2], count[3], count[4],
                    frame, size, t2 - t1, sl->n_steps, sl->n_evals, thx_wtime() - t0);
    }
end:
    rc = cli_share_end(ctx, cmd, mine); /* the lowest rank whose own step failed speaks; exit 1 on every rank */
    if (!rc && st != THX_OK) rc = cli_fail(ctx, cmd, st);
    thx_stream_tubes_destroy(&T);
    thx_streamlines_destroy(&sl);
    part_free(&P);
    free(use);
    free(own_t);
    thx_ctx_destroy(&ctx);
    return rc;
}
