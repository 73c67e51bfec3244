/*
 * A solution's volume potentials in parts (thorax/fem/parts.h): one part per rank of a bisection,
 * made, written and read back (docs/formats.md, "Partitioned volume potentials").
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <sys/types.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"
#include "thorax/fem/parts.h"

#define MAGIC "THXPART2"
#define HEAD 64
#define CUT_BYTES 24
/* bytes a node (number, coordinates), a tetrahedron (corners, region, number, owner) */
#define NODE_BYTES 28
#define TET_BYTES 28

void thx_fem_part_free(thx_fem_part *p)
{
    if (!p) return;
    free(p->cuts);
    free(p->node);
    free(p->xyz);
    free(p->tet);
    free(p->region);
    free(p->tet_id);
    free(p->owner);
    free(p->values);
    memset(p, 0, sizeof *p);
}

/* The arrays of a part of n nodes and t tetrahedra; THX_ENOMEM (p freed) when one cannot be had. */
static thx_status part_alloc(thx_ctx *ctx, thx_fem_part *p, size_t n, size_t t)
{
    size_t r = p->ranks > 1 ? (size_t)p->ranks - 1 : 1, nf = n * p->n_frames;
    p->cuts = thx_malloc(ctx, r * sizeof *p->cuts);
    p->node = thx_malloc(ctx, (n ? n : 1) * sizeof *p->node);
    p->xyz = thx_malloc(ctx, 3 * (n ? n : 1) * sizeof *p->xyz);
    p->tet = thx_malloc(ctx, 4 * (t ? t : 1) * sizeof *p->tet);
    p->region = thx_malloc(ctx, (t ? t : 1) * sizeof *p->region);
    p->tet_id = thx_malloc(ctx, (t ? t : 1) * sizeof *p->tet_id);
    p->owner = thx_malloc(ctx, (t ? t : 1) * sizeof *p->owner);
    p->values = thx_malloc(ctx, (nf ? nf : 1) * sizeof *p->values);
    if (p->cuts && p->node && p->xyz && p->tet && p->region && p->tet_id && p->owner && p->values) return THX_OK;
    thx_fem_part_free(p);
    return THX_ENOMEM;
}

thx_status thx_fem_part_make(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, const thx_fem_cut *cuts,
                             int ranks, int rank, const double *values, size_t n_frames, thx_fem_part *out)
{
    memset(out, 0, sizeof *out);
    if (ranks < 1 || rank < 0 || rank >= ranks) return thx_error(ctx, THX_EINPUT, "parts: part %d of %d", rank, ranks);
    if (v->n_tets > INT32_MAX || v->n_nodes > INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "parts: %zu nodes and %zu tetrahedra: more than a part's 32-bit numbers hold",
                         v->n_nodes, v->n_tets);
    size_t nn = v->n_nodes, nt = 0, n_own = 0;
    int32_t *local = thx_malloc(ctx, (nn ? nn : 1) * sizeof *local);
    int32_t *owner = thx_malloc(ctx, (v->n_tets ? v->n_tets : 1) * sizeof *owner); /* -1: not used */
    unsigned char *near = thx_calloc(ctx, nn ? nn : 1, 1);                          /* a node of an own tetrahedron */
    thx_status st = local && owner && near ? THX_OK : THX_ENOMEM;
    for (size_t t = 0; st == THX_OK && t < v->n_tets; t++) {
        int32_t r = v->region[t];
        owner[t] = -1;
        if (r < 0 || (size_t)r >= v->n_regions || (use_region && !use_region[r])) continue;
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int d = 0; d < 3; d++) c[d] += 0.25 * v->xyz[3 * (size_t)v->tet[4 * t + k] + d];
        owner[t] = thx_fem_cut_part(cuts, ranks, c);
        if (owner[t] != rank) continue;
        n_own++;
        for (int k = 0; k < 4; k++) near[v->tet[4 * t + k]] = 1;
    }
    /* the part: its own tetrahedra, every used one sharing a node with them, and every used one reaching
       into its box (a ray's piece in the box lies in one of these: sort-last's volume rendering); then
       their nodes */
    double box[2][3];
    thx_fem_cut_box(cuts, ranks, rank, box);
    for (size_t i = 0; st == THX_OK && i < nn; i++) local[i] = -1;
    for (size_t t = 0; st == THX_OK && t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        int into = 1; /* the tetrahedron's bounding box meets the part's box */
        for (int d = 0; d < 3 && into; d++) {
            double lo = INFINITY, hi = -INFINITY;
            for (int k = 0; k < 4; k++) {
                double x = v->xyz[3 * (size_t)q[k] + d];
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
            }
            into = hi >= box[0][d] && lo < box[1][d];
        }
        if (owner[t] < 0 || !(owner[t] == rank || near[q[0]] || near[q[1]] || near[q[2]] || near[q[3]] || into)) {
            owner[t] = -1 - (owner[t] >= 0); /* -2: used, not in this part */
            continue;
        }
        nt++;
        for (int k = 0; k < 4; k++) local[q[k]] = 0;
    }
    size_t n = 0;
    for (size_t i = 0; st == THX_OK && i < nn; i++)
        if (local[i] == 0) local[i] = (int32_t)n++;
    out->rank = (uint32_t)rank;
    out->ranks = (uint32_t)ranks;
    out->n_frames = n_frames;
    if (st == THX_OK) st = part_alloc(ctx, out, n, nt);
    if (st == THX_OK) {
        out->n_nodes = n;
        out->n_tets = nt;
        out->n_own = n_own;
        out->n_global = nn;
        out->n_global_tets = v->n_tets;
        if (ranks > 1) memcpy(out->cuts, cuts, ((size_t)ranks - 1) * sizeof *cuts);
        for (size_t i = 0; i < nn; i++)
            if (local[i] >= 0) {
                out->node[local[i]] = (int32_t)i;
                memcpy(out->xyz + 3 * (size_t)local[i], v->xyz + 3 * i, 3 * sizeof *v->xyz);
            }
        size_t k = 0;
        for (size_t t = 0; t < v->n_tets; t++) {
            if (owner[t] < 0) continue;
            for (int c = 0; c < 4; c++) out->tet[4 * k + c] = local[v->tet[4 * t + c]];
            out->region[k] = v->region[t];
            out->tet_id[k] = (int32_t)t;
            out->owner[k++] = owner[t];
        }
        for (size_t f = 0; f < n_frames; f++)
            for (size_t j = 0; j < n; j++) out->values[f * n + j] = values[f * nn + (size_t)out->node[j]];
    }
    free(local);
    free(owner);
    free(near);
    if (st != THX_OK) thx_fem_part_free(out);
    return st;
}

/* n bytes to the file and the hash; 0, or -1 */
static int put(FILE *f, thx_sha256_ctx *h, const void *p, size_t n)
{
    thx_sha256_update(h, p, n);
    return n && fwrite(p, 1, n, f) != n ? -1 : 0;
}

thx_status thx_fem_part_write(thx_ctx *ctx, const char *path, const thx_fem_part *p)
{
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    unsigned char head[HEAD];
    memset(head, 0, sizeof head);
    memcpy(head, MAGIC, 8);
    uint64_t sizes[5] = {p->n_nodes, p->n_tets, p->n_frames, p->n_global, p->n_global_tets};
    memcpy(head + 8, &p->rank, 4);
    memcpy(head + 12, &p->ranks, 4);
    memcpy(head + 16, sizes, sizeof sizes);
    int bad = put(af.f, &h, head, sizeof head);
    for (uint32_t k = 0; k + 1 < p->ranks && !bad; k++) {
        unsigned char c[CUT_BYTES];
        int32_t iv[4] = {p->cuts[k].lo, p->cuts[k].mid, p->cuts[k].hi, p->cuts[k].axis};
        memcpy(c, iv, 16);
        memcpy(c + 16, &p->cuts[k].at, 8);
        bad = put(af.f, &h, c, sizeof c);
    }
    if (!bad) bad = put(af.f, &h, p->node, p->n_nodes * sizeof *p->node);
    if (!bad) bad = put(af.f, &h, p->xyz, 3 * p->n_nodes * sizeof *p->xyz);
    if (!bad) bad = put(af.f, &h, p->tet, 4 * p->n_tets * sizeof *p->tet);
    if (!bad) bad = put(af.f, &h, p->region, p->n_tets * sizeof *p->region);
    if (!bad) bad = put(af.f, &h, p->tet_id, p->n_tets * sizeof *p->tet_id);
    if (!bad) bad = put(af.f, &h, p->owner, p->n_tets * sizeof *p->owner);
    if (!bad) bad = put(af.f, &h, p->values, p->n_frames * p->n_nodes * sizeof *p->values);
    unsigned char digest[32];
    thx_sha256_final(&h, digest);
    if (!bad) bad = fwrite(digest, 1, 32, af.f) != 32;
    if (bad) {
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: cannot write the part", path);
    }
    return thx_atomic_commit(ctx, &af);
}

/* n bytes of f into p, hashed; 0, or -1 when the file ends first */
static int get(FILE *f, thx_sha256_ctx *h, void *p, size_t n)
{
    if (n && fread(p, 1, n, f) != n) return -1;
    thx_sha256_update(h, p, n);
    return 0;
}

thx_status thx_fem_part_read(thx_ctx *ctx, const char *path, thx_fem_part *out)
{
    /* read straight into the part's arrays, hashed on the way (a part may be most of a rank's memory:
       no second copy of the file) */
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open the part", path);
    thx_status st = THX_OK;
    unsigned char head[HEAD], *cutb = NULL;
    uint64_t sz[5];
    uint32_t rank = 0, ranks = 0;
    size_t len = 0;
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    if (fseeko(f, 0, SEEK_END) == 0) {
        off_t e = ftello(f);
        len = e > 0 ? (size_t)e : 0;
    }
    rewind(f);
    size_t got = fread(head, 1, sizeof head, f);
    thx_sha256_update(&h, head, got);
    if (got >= 8 && memcmp(head, "THXPART1", 8) == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: a volume part of the first format (no ghost tetrahedra): run thorax forward "
                       "--volume under mpirun again to write it in this thorax's", path);
        goto done;
    }
    if (got < HEAD || len < HEAD + 32 || memcmp(head, MAGIC, 8) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a thorax volume part (magic %s expected)", path, MAGIC);
        goto done;
    }
    memcpy(&rank, head + 8, 4);
    memcpy(&ranks, head + 12, 4);
    memcpy(sz, head + 16, sizeof sz);
    /* the sizes must give the file's length exactly (each bounded first, so the sum cannot wrap) */
    if (ranks < 1 || rank >= ranks || ranks > (1u << 24) || sz[0] > len || sz[1] > len || sz[2] > len || sz[3] > INT32_MAX ||
        sz[4] > INT32_MAX || sz[0] > sz[3] || sz[1] > sz[4] || (sz[0] && sz[2] > len / 8 / sz[0]) ||
        (uint64_t)HEAD + CUT_BYTES * ((uint64_t)ranks - 1) + NODE_BYTES * sz[0] + TET_BYTES * sz[1] + 8 * sz[2] * sz[0] + 32 !=
            len) {
        st = thx_error(ctx, THX_EINPUT, "%s: part %u of %u with %llu nodes, %llu tetrahedra, %llu frames does not fill the "
                       "file's %zu bytes (cut short, or not a part)", path, rank, ranks, (unsigned long long)sz[0],
                       (unsigned long long)sz[1], (unsigned long long)sz[2], len);
        goto done;
    }
    out->rank = rank;
    out->ranks = ranks;
    out->n_frames = sz[2];
    size_t n = sz[0], t = sz[1], r = ranks - 1;
    if ((st = part_alloc(ctx, out, n, t)) != THX_OK) goto done;
    out->n_nodes = n, out->n_tets = t, out->n_global = sz[3], out->n_global_tets = sz[4];
    cutb = thx_malloc(ctx, CUT_BYTES * (r ? r : 1));
    unsigned char digest[32], want[32];
    if (!cutb) { st = THX_ENOMEM; goto done; }
    if (get(f, &h, cutb, CUT_BYTES * r) || get(f, &h, out->node, n * 4) || get(f, &h, out->xyz, n * 24) ||
        get(f, &h, out->tet, t * 16) || get(f, &h, out->region, t * 4) || get(f, &h, out->tet_id, t * 4) ||
        get(f, &h, out->owner, t * 4) || get(f, &h, out->values, n * out->n_frames * 8) || fread(want, 1, 32, f) != 32) {
        st = thx_error(ctx, THX_EINPUT, "%s: the part ends before its %zu bytes (changed while read?)", path, len);
        goto done;
    }
    thx_sha256_final(&h, digest);
    if (memcmp(digest, want, 32) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: the part's checksum does not match its bytes (damaged)", path);
        goto done;
    }
    const unsigned char *q = cutb;
    for (size_t k = 0; k < r; k++, q += CUT_BYTES) {
        int32_t iv[4];
        memcpy(iv, q, 16);
        out->cuts[k] = (thx_fem_cut){.lo = iv[0], .mid = iv[1], .hi = iv[2], .axis = iv[3]};
        memcpy(&out->cuts[k].at, q + 16, 8);
        if (iv[3] < 0 || iv[3] > 2 || iv[0] < 0 || iv[0] >= iv[1] || iv[1] >= iv[2] || (uint32_t)iv[2] > ranks) {
            st = thx_error(ctx, THX_EINPUT, "%s: cut %zu (parts %d, %d, %d, axis %d) is not a bisection's", path, k + 1, iv[0],
                           iv[1], iv[2], iv[3]);
            goto done;
        }
    }
    for (size_t i = 0; i < n; i++)
        if (out->node[i] < 0 || (size_t)out->node[i] >= out->n_global || (i && out->node[i] <= out->node[i - 1])) {
            st = thx_error(ctx, THX_EINPUT, "%s: node %zu's global number %d is out of range or not ascending", path, i + 1,
                           out->node[i]);
            goto done;
        }
    for (size_t k = 0; k < 4 * t; k++)
        if (out->tet[k] < 0 || (size_t)out->tet[k] >= n) {
            st = thx_error(ctx, THX_EINPUT, "%s: tetrahedron %zu names node %d of the part's %zu", path, k / 4 + 1,
                           out->tet[k] + 1, n);
            goto done;
        }
    for (size_t k = 0; k < t; k++) {
        if (out->tet_id[k] < 0 || (size_t)out->tet_id[k] >= out->n_global_tets || (k && out->tet_id[k] <= out->tet_id[k - 1])) {
            st = thx_error(ctx, THX_EINPUT, "%s: tetrahedron %zu's global number %d is out of range or not ascending", path,
                           k + 1, out->tet_id[k]);
            goto done;
        }
        if (out->owner[k] < 0 || (uint32_t)out->owner[k] >= ranks) {
            st = thx_error(ctx, THX_EINPUT, "%s: tetrahedron %zu's owner %d is not one of the %u parts", path, k + 1,
                           out->owner[k], ranks);
            goto done;
        }
        out->n_own += (uint32_t)out->owner[k] == rank;
    }
done:
    fclose(f);
    free(cutb);
    if (st != THX_OK) thx_fem_part_free(out);
    return st;
}

thx_status thx_fem_part_open(thx_ctx *ctx, const char *solution_dir, const char *manifest, int rank, int ranks,
                             size_t n_regions, thx_fem_part *out, char *unit, size_t unit_size)
{
    memset(out, 0, sizeof *out);
    /* one file directly in DIR/parts: a manifest elsewhere could make a rank read any file */
    if (!manifest || strchr(manifest, '/') != strrchr(manifest, '/') || strncmp(manifest, "parts/", 6) != 0)
        return thx_error(ctx, THX_EINPUT, "%s/solution.json: \"volume_parts\": \"manifest\" must be parts/parts.json",
                         solution_dir);
    char path[4400];
    if ((size_t)snprintf(path, sizeof path, "%s/%s", solution_dir, manifest) >= sizeof path)
        return thx_error(ctx, THX_EINPUT, "%s: the path is too long", solution_dir);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    const cJSON *fmt = cJSON_GetObjectItem(j, "format"), *ver = cJSON_GetObjectItem(j, "version");
    const cJSON *rk = cJSON_GetObjectItem(j, "ranks"), *files = cJSON_GetObjectItem(j, "files");
    const cJSON *file = cJSON_GetArrayItem(files, rank), *un = cJSON_GetObjectItem(j, "unit");
    thx_status st = THX_OK;
    if (!cJSON_IsString(fmt) || strcmp(fmt->valuestring, "thorax-parts") || !cJSON_IsNumber(ver))
        st = thx_error(ctx, THX_EINPUT, "%s: not the manifest of a solution's parts (format \"thorax-parts\")", path);
    else if (ver->valuedouble != 2)
        st = thx_error(ctx, THX_EINPUT, "%s: parts of version %g; this thorax reads version 2 (run thorax forward --volume "
                       "under mpirun again)", path, ver->valuedouble);
    else if (!cJSON_IsNumber(rk) || rk->valuedouble != ranks || cJSON_GetArraySize(files) != ranks || !cJSON_IsString(file) ||
             strchr(file->valuestring, '/') || !strcmp(file->valuestring, "..") || !strcmp(file->valuestring, "."))
        st = thx_error(ctx, THX_EINPUT, "%s: not %d parts, one file each", path, ranks);
    else if (!cJSON_IsString(un) || strlen(un->valuestring) >= unit_size)
        st = thx_error(ctx, THX_EINPUT, "%s: \"unit\" missing, not a string or too long", path);
    char ppath[4500];
    if (st == THX_OK) {
        snprintf(unit, unit_size, "%s", un->valuestring);
        *strrchr(path, '/') = '\0';
        snprintf(ppath, sizeof ppath, "%s/%s", path, file->valuestring);
    }
    cJSON_Delete(j);
    if (st != THX_OK) return st;
    THX_CHECK(thx_fem_part_read(ctx, ppath, out));
    if (out->rank != (uint32_t)rank || out->ranks != (uint32_t)ranks)
        st = thx_error(ctx, THX_EINPUT, "%s: part %u of %u, where rank %d of %d reads it", ppath, out->rank + 1, out->ranks,
                       rank, ranks);
    for (size_t t = 0; st == THX_OK && t < out->n_tets; t++)
        if (out->region[t] < 0 || (size_t)out->region[t] >= n_regions)
            st = thx_error(ctx, THX_EINPUT, "%s: tetrahedron %zu's region %d is not one of the model's %zu", ppath, t + 1,
                           out->region[t] + 1, n_regions);
    if (st == THX_OK && out->n_frames == 0) st = thx_error(ctx, THX_EINPUT, "%s: a part without frames", ppath);
    if (st != THX_OK) thx_fem_part_free(out);
    return st;
}
