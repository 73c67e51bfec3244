/*
 * The volume mesh of a model directory, its region (conductivity) table and
 * node tables (paper 3.3), and the entry point of the volume exports (written by export_vtk.c, export_msh.c).
 * Layouts in docs/formats.md, "Volume mesh files"; the public entry points
 * are thx_model_write / thx_model_read and thx_volume_export (thorax/io/model_dir.h).
 *
 * Files (all text, one item a line, 1-based node and region numbers):
 *   volume.pts   "x y z", mm, "%.17g": exactly the doubles that were tetrahedralized
 *   volume.tet   "a b c d r": four volume node numbers, then the region
 *                number (the region's "id" in model.json's "regions")
 *   NAME.vmap    per surface, one line per surface node: its volume node
 *   volume.steiner  the nodes the mesher added on the surfaces, one a line:
 *                "node surface triangle b0 b1 b2" (1-based numbers, then the
 *                barycentric coordinates in that triangle, "%.17g")
 *
 * Decisions:
 *  - Reading checks structure, not geometry: numbers in range, four distinct
 *    nodes per tetrahedron, region numbers in the table, node tables
 *    consistent, conductivities symmetric positive definite. Orientation,
 *    coincident nodes and element quality are the volume checker's
 *    (src/check/check_volume*.c), as surface orientation is `thorax check`'s:
 *    a faulty mesh can still be saved, read back and inspected.
 *  - Node tables. A surface node IS a volume node (no duplicate nodes): its
 *    coordinates in NAME.pts ("%.6f") and volume.pts ("%.17g", the mesher's
 *    binary grid) agree within 1e-6 mm, on writing and on reading. Each volume node is on at most one surface node (the reverse
 *    table thx_volume.node_surf/node_snode has one slot per volume node);
 *    the reverse table is not stored but rebuilt on reading, and a reverse
 *    table present in memory is checked against the forward one on writing.
 *  - Conductivity tensors: symmetric within 1e-12 of the largest entry
 *    (a rotated tensor R D R^T may miss exact symmetry by rounding) and
 *    positive definite by a Cholesky factorization of the symmetric part;
 *    an isotropic region in memory must be exactly sigma[0] * identity.
 *    JSON numbers are printed by cJSON so that they read back bit-exactly.
 *  - Gmsh: one volume entity and one physical group per region, both tagged
 *    with the region id; node tags are volume node numbers and element tags
 *    volume.tet line numbers. Gmsh classifies every node on one entity:
 *    here the lowest-numbered region whose tetrahedra use it (region 1 for
 *    a node no tetrahedron uses); elements refer to nodes by tag across
 *    entities, which Gmsh reads.
 *  - Output is deterministic; every file is written atomically.
 */
#include "io/model/volume_io.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/io/export_data.h"
#define VOLUME_PTS "volume.pts"
#define VOLUME_TET "volume.tet"
#define VOLUME_STEINER "volume.steiner"

static const char orientation_text[] =
    "right-handed: for each line \"a b c d region\" of volume.tet, ((b - a) x (c - a)) . (d - a) > 0 "
    "(the VTK and Gmsh convention)";
static const char node_tables_text[] =
    "each surface's \"vmap\" file NAME.vmap: line i holds the volume node number of surface node i (1-based)";

/* ------------------------------------------------------------ manifest */

thx_status thx_io_volume_manifest(thx_ctx *ctx, const thx_model *m, cJSON *root)
{
    const thx_volume *v = m->volume;
    cJSON *surfs = cJSON_GetObjectItemCaseSensitive(root, "surfaces");
    for (size_t i = 0; i < m->n_surfaces; i++) {
        cJSON *o = cJSON_GetArrayItem(surfs, (int)i);
        char fname[96];
        snprintf(fname, sizeof fname, "%s.vmap", m->surf[i]->name);
        if (!o || !cJSON_AddStringToObject(o, "vmap", fname)) goto nomem;
    }
    cJSON *vo = cJSON_AddObjectToObject(root, "volume");
    if (!vo || !cJSON_AddStringToObject(vo, "pts", VOLUME_PTS) || !cJSON_AddStringToObject(vo, "tet", VOLUME_TET) ||
        !cJSON_AddNumberToObject(vo, "n_nodes", (double)v->n_nodes) ||
        !cJSON_AddNumberToObject(vo, "n_tets", (double)v->n_tets) ||
        !cJSON_AddNumberToObject(vo, "n_regions", (double)v->n_regions) || !cJSON_AddStringToObject(vo, "units", "mm") ||
        !cJSON_AddNumberToObject(vo, "index_base", 1) || !cJSON_AddStringToObject(vo, "orientation", orientation_text) ||
        !cJSON_AddStringToObject(vo, "node_tables", node_tables_text) ||
        !cJSON_AddStringToObject(vo, "steiner", VOLUME_STEINER) ||
        !cJSON_AddNumberToObject(vo, "n_steiner", (double)v->n_steiner))
        goto nomem;
    cJSON *regs = cJSON_AddArrayToObject(root, "regions");
    if (!regs) goto nomem;
    for (size_t k = 0; k < v->n_regions; k++) {
        const thx_region *r = &v->regions[k];
        cJSON *o = cJSON_CreateObject();
        if (!o) goto nomem;
        cJSON_AddItemToArray(regs, o);
        if (!cJSON_AddNumberToObject(o, "id", (double)(k + 1)) || !cJSON_AddStringToObject(o, "name", r->name))
            goto nomem;
        if (!r->anisotropic) {
            if (!cJSON_AddNumberToObject(o, "sigma", r->sigma[0])) goto nomem;
        } else {
            cJSON *rows = cJSON_AddArrayToObject(o, "sigma");
            if (!rows) goto nomem;
            for (int i = 0; i < 3; i++) {
                cJSON *row = cJSON_CreateDoubleArray(r->sigma + 3 * i, 3);
                if (!row) goto nomem;
                cJSON_AddItemToArray(rows, row);
            }
        }
        if (!cJSON_AddStringToObject(o, "units", "S/m") || !cJSON_AddStringToObject(o, "source", r->source)) goto nomem;
    }
    return THX_OK;
nomem:
    return thx_error(ctx, THX_ENOMEM, "out of memory building model.json");
}

/* --------------------------------------------------------------- write */

static thx_status join(thx_ctx *ctx, char *out, size_t size, const char *dir, const char *file)
{
    if ((size_t)snprintf(out, size, "%s/%s", dir, file) >= size)
        return thx_error(ctx, THX_EIO, "%s/%s: path too long", dir, file);
    return THX_OK;
}

thx_status thx_io_volume_write_files(thx_ctx *ctx, const thx_model *m, const char *dir)
{
    const thx_volume *v = m->volume;
    char path[4200];
    thx_atomic_file af;
    THX_CHECK(join(ctx, path, sizeof path, dir, VOLUME_PTS));
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    /* exactly (shortest round-trip form): what was tetrahedralized is what is read back */
    for (size_t i = 0; i < v->n_nodes; i++)
        fprintf(af.f, "%.17g %.17g %.17g\n", v->xyz[3 * i] + 0.0, v->xyz[3 * i + 1] + 0.0, v->xyz[3 * i + 2] + 0.0);
    THX_CHECK(thx_atomic_commit(ctx, &af));
    THX_CHECK(join(ctx, path, sizeof path, dir, VOLUME_TET));
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        fprintf(af.f, "%ld %ld %ld %ld %ld\n", (long)q[0] + 1, (long)q[1] + 1, (long)q[2] + 1, (long)q[3] + 1,
                (long)v->region[t] + 1);
    }
    THX_CHECK(thx_atomic_commit(ctx, &af));
    THX_CHECK(join(ctx, path, sizeof path, dir, VOLUME_STEINER));
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *r = &v->steiner[k];
        fprintf(af.f, "%ld %ld %ld %.17g %.17g %.17g\n", (long)r->node + 1, (long)r->surf + 1, (long)r->tri + 1,
                r->bary[0], r->bary[1], r->bary[2]);
    }
    THX_CHECK(thx_atomic_commit(ctx, &af));
    for (size_t s = 0; s < m->n_surfaces; s++) {
        char fname[96];
        snprintf(fname, sizeof fname, "%s.vmap", m->surf[s]->name);
        THX_CHECK(join(ctx, path, sizeof path, dir, fname));
        THX_CHECK(thx_atomic_open(ctx, path, &af));
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) fprintf(af.f, "%ld\n", (long)v->surf_node[s][i] + 1);
        THX_CHECK(thx_atomic_commit(ctx, &af));
    }
    return THX_OK;
}

/* ---------------------------------------------------------------- read */

/* A whole decimal integer token within 32 bits (an optional sign, then digits: what strtol takes from a
   token with no blanks, without its locale and its cost: a third of the 1.8 million-line volume.tet's
   reading went to strtol). */
static int parse_long(const char *tok, long *out)
{
    const char *p = tok;
    int neg = *p == '-';
    if (*p == '-' || *p == '+') p++;
    if (*p < '0' || *p > '9') return -1;
    long v = 0;
    for (; *p >= '0' && *p <= '9'; p++) {
        v = 10 * v + (*p - '0');
        if (v > (long)INT32_MAX + 1) return -1;
    }
    if (*p != '\0') return -1;
    v = neg ? -v : v;
    if (v < INT32_MIN || v > INT32_MAX) return -1;
    *out = v;
    return 0;
}

/* One piece of volume.tet's lines: its tetrahedra and regions into *tet, *reg (the piece holds their count
   and its first fault). */
static void tets_parse(thx_io_piece *pc, size_t n_nodes, size_t n_regions, int32_t **tet, int32_t **reg)
{
    size_t cap = 0;
    for (char *p = pc->begin, *next = NULL; p && p < pc->end; p = next) {
        char *tok[5];
        pc->lines++;
        int nt = thx_io_split_line(p, tok, 5, &next);
        if (nt == 0) continue;
        if (nt != 5) {
            pc->bad_line = pc->lines;
            snprintf(pc->why, sizeof pc->why, "expected 5 numbers (4 node numbers, then a region number), found %s",
                     nt > 5 ? "more" : nt == 1 ? "1" : nt == 2 ? "2" : nt == 3 ? "3" : "4");
            return;
        }
        if (pc->n + 1 > cap) {
            size_t c2 = cap ? 2 * cap : 4096;
            int32_t *t = realloc(*tet, 4 * c2 * sizeof *t);
            if (t) *tet = t;
            int32_t *r = t ? realloc(*reg, c2 * sizeof *r) : NULL;
            if (r) *reg = r;
            if (!t || !r) {
                pc->bad_line = -1;
                return;
            }
            cap = c2;
        }
        long val[5];
        for (int k = 0; k < 5; k++)
            if (parse_long(tok[k], &val[k])) {
                pc->bad_line = pc->lines;
                snprintf(pc->why, sizeof pc->why, "%s is not an integer: \"%.60s\"", k < 4 ? "a node number" : "the region number",
                         tok[k]);
                return;
            }
        for (int k = 0; k < 4; k++) {
            if (val[k] < 1 || (size_t)val[k] > n_nodes) {
                pc->bad_line = pc->lines;
                snprintf(pc->why, sizeof pc->why, "node number %ld out of range 1..%zu (the nodes of %s)", val[k], n_nodes,
                         VOLUME_PTS);
                return;
            }
            for (int j = 0; j < k; j++)
                if (val[j] == val[k]) {
                    pc->bad_line = pc->lines;
                    snprintf(pc->why, sizeof pc->why, "node %ld appears twice in the tetrahedron", val[k]);
                    return;
                }
            (*tet)[4 * pc->n + (size_t)k] = (int32_t)(val[k] - 1);
        }
        if (val[4] < 1 || (size_t)val[4] > n_regions) {
            pc->bad_line = pc->lines;
            snprintf(pc->why, sizeof pc->why, "region %ld out of range 1..%zu (the \"regions\" of model.json)", val[4],
                     n_regions);
            return;
        }
        (*reg)[pc->n] = (int32_t)(val[4] - 1);
        pc->n++;
    }
}

/* volume.tet: "a b c d r" per line, 1-based; returned 0-based. Parsed in pieces, a thread each (the high
   phantom's 1.8 million lines: 0.22 s in one). */
static thx_status read_tets(thx_ctx *ctx, const char *path, size_t n_nodes, size_t n_regions, thx_volume *v)
{
    char *text = NULL;
    THX_CHECK(thx_io_read_text(ctx, path, &text));
    thx_io_piece pc[THX_IO_PIECES_MAX];
    int32_t *ptet[THX_IO_PIECES_MAX] = {NULL}, *preg[THX_IO_PIECES_MAX] = {NULL};
    size_t np = thx_io_cut_for_threads(text, pc), n = 0;
#pragma omp parallel for schedule(static, 1) num_threads((int)np) if (np > 1)
    for (size_t k = 0; k < np; k++) tets_parse(&pc[k], n_nodes, n_regions, &ptet[k], &preg[k]);
    thx_status st = thx_io_pieces_verdict(ctx, path, pc, np, &n);
    int32_t *tet = NULL, *reg = NULL;
    if (st == THX_OK && np == 1) {
        tet = ptet[0];
        reg = preg[0];
        ptet[0] = preg[0] = NULL;
    } else if (st == THX_OK) {
        tet = malloc(4 * (n ? n : 1) * sizeof *tet);
        reg = malloc((n ? n : 1) * sizeof *reg);
        if (!tet || !reg) st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
        size_t at[THX_IO_PIECES_MAX];
        for (size_t k = 0, a = 0; k < np; a += pc[k].n, k++) at[k] = a;
        /* the pieces put together by the threads that parsed them (one thread: 0.03 s of the high phantom's) */
#pragma omp parallel for schedule(static, 1) num_threads((int)np)
        for (size_t k = 0; k < np; k++) {
            if (!tet || !reg || !pc[k].n) continue; /* (no room), a piece of blank lines */
            memcpy(tet + 4 * at[k], ptet[k], 4 * pc[k].n * sizeof *tet);
            memcpy(reg + at[k], preg[k], pc[k].n * sizeof *reg);
        }
    }
    for (size_t k = 0; k < np; k++) {
        free(ptet[k]);
        free(preg[k]);
    }
    free(text);
    if (st != THX_OK) {
        free(tet);
        free(reg);
        return st;
    }
    v->tet = tet;
    v->region = reg;
    v->n_tets = n;
    return THX_OK;
}

/* volume.steiner: "node surface triangle b0 b1 b2" per line (numbers 1-based); n_want records. */
static thx_status read_steiner(thx_ctx *ctx, const char *path, const thx_model *m, size_t n_nodes, size_t n_want,
                               thx_volume *v)
{
    char *text = NULL;
    THX_CHECK(thx_io_read_text(ctx, path, &text));
    thx_status st = THX_OK;
    thx_steiner *rec = NULL;
    size_t n = 0, cap = 0;
    int line = 0;
    for (char *p = text, *next = NULL; p; p = next) {
        char *tok[6];
        line++;
        int nt = thx_io_split_line(p, tok, 6, &next);
        if (nt == 0) continue;
        if (nt != 6) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 6 fields (node surface triangle b0 b1 b2)", path, line);
            goto done;
        }
        if (n >= n_want) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: more records than the %zu the manifest announces", path, line, n_want);
            goto done;
        }
        if (n + 1 > cap) THX_TRY(thx_grow(ctx, (void **)&rec, &cap, n + 1, sizeof *rec));
        long node, surf, tri;
        if (parse_long(tok[0], &node) || parse_long(tok[1], &surf) || parse_long(tok[2], &tri)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: node, surface and triangle must be integers", path, line);
            goto done;
        }
        if (node < 1 || (size_t)node > n_nodes) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: node %ld out of range 1..%zu", path, line, node, n_nodes);
            goto done;
        }
        if (surf < 1 || (size_t)surf > m->n_surfaces) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface %ld out of range 1..%zu", path, line, surf, m->n_surfaces);
            goto done;
        }
        if (tri < 1 || (size_t)tri > m->surf[surf - 1]->n_tris) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: triangle %ld out of range 1..%zu (surface \"%s\")", path, line, tri,
                           m->surf[surf - 1]->n_tris, m->surf[surf - 1]->name);
            goto done;
        }
        thx_steiner *r = &rec[n];
        r->node = (int32_t)(node - 1);
        r->surf = (int32_t)(surf - 1);
        r->tri = (int32_t)(tri - 1);
        for (int k = 0; k < 3; k++) {
            char *end = NULL;
            r->bary[k] = strtod(tok[3 + k], &end);
            if (end == tok[3 + k] || *end != '\0' || !isfinite(r->bary[k])) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: barycentric coordinate %d is not a finite number", path, line, k + 1);
                goto done;
            }
        }
        n++;
    }
    if (n != n_want) {
        st = thx_error(ctx, THX_EINPUT, "%s: %zu records, the manifest announces %zu", path, n, n_want);
        goto done;
    }
    v->steiner = rec;
    v->n_steiner = n;
    rec = NULL;
done:
    free(rec);
    free(text);
    return st;
}

/* NAME.vmap of surface s: one volume node number per line. Fills
 * v->surf_node[s] and the reverse table, checking coordinates and that no
 * volume node is used twice. vpts is volume.pts's path (for messages). */
static thx_status read_vmap(thx_ctx *ctx, const char *path, const char *vpts, const thx_model *m, size_t s, thx_volume *v)
{
    const thx_surface *sf = m->surf[s];
    char *text = NULL;
    THX_CHECK(thx_io_read_text(ctx, path, &text));
    thx_status st = THX_OK;
    int32_t *map = thx_malloc(ctx, (sf->n_nodes ? sf->n_nodes : 1) * sizeof *map);
    if (!map) {
        free(text);
        return THX_ENOMEM;
    }
    size_t n = 0;
    int line = 0;
    for (char *p = text, *next = NULL; p; p = next) {
        char *tok[1];
        line++;
        int nt = thx_io_split_line(p, tok, 1, &next);
        if (nt == 0) continue;
        long w;
        if (nt != 1 || parse_long(tok[0], &w)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": expected one volume node number", path, line, sf->name);
            goto done;
        }
        if (n == sf->n_nodes) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": more lines than the surface's %zu nodes", path, line,
                           sf->name, sf->n_nodes);
            goto done;
        }
        if (w < 1 || (size_t)w > v->n_nodes) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" node %zu: volume node %ld out of range 1..%zu", path,
                           line, sf->name, n + 1, w, v->n_nodes);
            goto done;
        }
        size_t vi = (size_t)w - 1;
        const double *a = sf->xyz + 3 * n, *b = v->xyz + 3 * vi;
        if (!thx_volume_same_node(a, b)) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s:%d: surface \"%s\" node %zu is volume node %ld but the coordinates differ by more than 1e-6 mm: "
                           "(%.6f, %.6f, %.6f) in %s.pts vs (%.6f, %.6f, %.6f) at %s:%ld",
                           path, line, sf->name, n + 1, w, a[0], a[1], a[2], sf->name, b[0], b[1], b[2], vpts, w);
            goto done;
        }
        if (v->node_surf[vi] >= 0) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s:%d: surface \"%s\" node %zu is volume node %ld, which is already node %ld of surface "
                           "\"%s\" (a volume node lies on one surface node at most)",
                           path, line, sf->name, n + 1, w, (long)v->node_snode[vi] + 1, m->surf[v->node_surf[vi]]->name);
            goto done;
        }
        v->node_surf[vi] = (int32_t)s;
        v->node_snode[vi] = (int32_t)n;
        map[n++] = (int32_t)vi;
    }
    if (n != sf->n_nodes) {
        st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": %zu lines for the surface's %zu nodes", path, sf->name, n,
                       sf->n_nodes);
        goto done;
    }
    v->surf_node[s] = map;
    map = NULL;
done:
    free(map);
    free(text);
    return st;
}

/* One entry of the "regions" array (k 0-based) into r. */
static thx_status read_region(thx_ctx *ctx, const char *mpath, size_t k, const cJSON *o, thx_region *r)
{
    memset(r, 0, sizeof *r);
    if (!cJSON_IsObject(o)) return thx_error(ctx, THX_EINPUT, "%s: region %zu: not a JSON object", mpath, k + 1);
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(o, "id");
    if (!cJSON_IsNumber(id) || id->valuedouble != (double)(k + 1))
        return thx_error(ctx, THX_EINPUT, "%s: region %zu: \"id\" must be %zu (ids run 1, 2, ... in the order listed)",
                         mpath, k + 1, k + 1);
    const cJSON *nm = cJSON_GetObjectItemCaseSensitive(o, "name");
    if (!cJSON_IsString(nm) || !thx_name_ok(nm->valuestring, sizeof r->name))
        return thx_error(ctx, THX_EINPUT,
                         "%s: region %zu: \"name\" missing, longer than 31 characters or not made of letters, digits, "
                         "'_', '-', '.'",
                         mpath, k + 1);
    snprintf(r->name, sizeof r->name, "%s", nm->valuestring);
    const cJSON *un = cJSON_GetObjectItemCaseSensitive(o, "units");
    if (!cJSON_IsString(un) || strcmp(un->valuestring, "S/m") != 0)
        return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): \"units\" must be \"S/m\"", mpath, k + 1, r->name);
    const cJSON *src = cJSON_GetObjectItemCaseSensitive(o, "source");
    if (!cJSON_IsString(src) || strlen(src->valuestring) >= sizeof r->source)
        return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): \"source\" must be a string of at most %zu bytes", mpath,
                         k + 1, r->name, sizeof r->source - 1);
    snprintf(r->source, sizeof r->source, "%s", src->valuestring);
    const cJSON *sg = cJSON_GetObjectItemCaseSensitive(o, "sigma");
    if (cJSON_IsNumber(sg)) {
        double s = sg->valuedouble;
        if (!isfinite(s) || !(s > 0))
            return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): conductivity %g S/m is not positive", mpath, k + 1,
                             r->name, s);
        r->sigma[0] = r->sigma[4] = r->sigma[8] = s;
        r->anisotropic = 0;
        return THX_OK;
    }
    int ok = cJSON_IsArray(sg) && cJSON_GetArraySize(sg) == 3;
    for (int i = 0; ok && i < 3; i++) {
        const cJSON *row = cJSON_GetArrayItem(sg, i);
        ok = cJSON_IsArray(row) && cJSON_GetArraySize(row) == 3;
        for (int j = 0; ok && j < 3; j++) {
            const cJSON *e = cJSON_GetArrayItem(row, j);
            ok = cJSON_IsNumber(e);
            if (ok) r->sigma[3 * i + j] = e->valuedouble;
        }
    }
    if (!ok)
        return thx_error(ctx, THX_EINPUT,
                         "%s: region %zu (\"%s\"): \"sigma\" must be a number (isotropic) or a 3x3 array of numbers "
                         "(tensor), in S/m",
                         mpath, k + 1, r->name);
    r->anisotropic = 1;
    char why[160];
    if (!thx_tensor_spd(r->sigma, why, sizeof why))
        return thx_error(ctx, THX_EINPUT, "%s: region %zu (\"%s\"): conductivity tensor %s", mpath, k + 1, r->name, why);
    return THX_OK;
}

thx_status thx_io_volume_read(thx_ctx *ctx, const char *dir, const char *mpath, const cJSON *root, thx_model *m, int regions_only)
{
    const cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    const cJSON *regs = cJSON_GetObjectItemCaseSensitive(root, "regions");
    const cJSON *surfs = cJSON_GetObjectItemCaseSensitive(root, "surfaces");
    if (!vo || cJSON_IsNull(vo)) {
        /* Readers ignore keys they do not use (docs/formats.md); the region
         * table and node tables only mean something with a volume. */
        if (regs && !cJSON_IsNull(regs))
            thx_log(ctx, THX_LOG_WARN, "%s: \"regions\" ignored: the model has no \"volume\"", mpath);
        for (size_t i = 0; i < m->n_surfaces; i++)
            if (cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(surfs, (int)i), "vmap"))
                thx_log(ctx, THX_LOG_WARN, "%s: surface %zu (\"%s\"): \"vmap\" ignored: the model has no \"volume\"",
                        mpath, i + 1, m->surf[i]->name);
        return THX_OK;
    }
    if (!cJSON_IsObject(vo)) return thx_error(ctx, THX_EINPUT, "%s: \"volume\" must be an object", mpath);
    const cJSON *jp = cJSON_GetObjectItemCaseSensitive(vo, "pts");
    const cJSON *jt = cJSON_GetObjectItemCaseSensitive(vo, "tet");
    if (!cJSON_IsString(jp) || !thx_io_file_name_ok(jp->valuestring) || !cJSON_IsString(jt) ||
        !thx_io_file_name_ok(jt->valuestring))
        return thx_error(ctx, THX_EINPUT, "%s: volume: \"pts\" and \"tet\" must name files in the model directory", mpath);
    size_t nn, nt, nr;
    if (thx_io_json_count(vo, "n_nodes", &nn) || thx_io_json_count(vo, "n_tets", &nt))
        return thx_error(ctx, THX_EINPUT, "%s: volume: \"n_nodes\" and \"n_tets\" must be counts", mpath);
    const cJSON *ju = cJSON_GetObjectItemCaseSensitive(vo, "units");
    if (ju && !(cJSON_IsString(ju) && strcmp(ju->valuestring, "mm") == 0))
        return thx_error(ctx, THX_EINPUT, "%s: volume: \"units\" must be \"mm\"", mpath);
    const cJSON *jb = cJSON_GetObjectItemCaseSensitive(vo, "index_base");
    if (jb && !(cJSON_IsNumber(jb) && jb->valuedouble == 1))
        return thx_error(ctx, THX_EINPUT, "%s: volume: \"index_base\" must be 1 (volume files are 1-based)", mpath);
    if (!cJSON_IsArray(regs) || cJSON_GetArraySize(regs) == 0)
        return thx_error(ctx, THX_EINPUT, "%s: \"regions\" (the conductivity table) missing, empty or not an array", mpath);
    nr = (size_t)cJSON_GetArraySize(regs);
    if (cJSON_GetObjectItemCaseSensitive(vo, "n_regions")) {
        size_t want;
        if (thx_io_json_count(vo, "n_regions", &want) || want != nr)
            return thx_error(ctx, THX_EINPUT, "%s: volume: \"n_regions\" is not the %zu entries of \"regions\"", mpath, nr);
    }
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const cJSON *jm = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(surfs, (int)i), "vmap");
        if (!cJSON_IsString(jm) || !thx_io_file_name_ok(jm->valuestring))
            return thx_error(ctx, THX_EINPUT, "%s: surface %zu (\"%s\"): \"vmap\" (its node table) must name a file in the "
                             "model directory",
                             mpath, i + 1, m->surf[i]->name);
    }

    thx_status st = THX_OK;
    thx_volume *v = NULL;
    char path[4200], vpts[4200];
    THX_TRY(thx_volume_create(ctx, &v));
    v->regions = thx_calloc(ctx, nr, sizeof *v->regions);
    if (!v->regions) {
        st = THX_ENOMEM;
        goto done;
    }
    v->n_regions = nr;
    for (size_t k = 0; k < nr; k++) {
        THX_TRY(read_region(ctx, mpath, k, cJSON_GetArrayItem(regs, (int)k), &v->regions[k]));
        for (size_t j = 0; j < k; j++)
            if (strcmp(v->regions[j].name, v->regions[k].name) == 0) {
                st = thx_error(ctx, THX_EINPUT, "%s: regions %zu and %zu are both named \"%s\"", mpath, j + 1, k + 1,
                               v->regions[k].name);
                goto done;
            }
    }
    if (regions_only) { /* (a rank of sort-last, which reads its part of the volume elsewhere) */
        thx_volume_destroy(&m->volume);
        m->volume = v;
        return THX_OK;
    }
    THX_TRY(join(ctx, vpts, sizeof vpts, dir, jp->valuestring));
    THX_TRY(thx_io_read_xyz(ctx, vpts, "", &v->xyz, &v->n_nodes)); /* volume.pts */
    if (v->n_nodes == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: volume: no nodes", vpts);
        goto done;
    }
    if (v->n_nodes != nn) {
        st = thx_error(ctx, THX_EINPUT, "%s: volume: manifest says %zu nodes but %s has %zu", mpath, nn, vpts, v->n_nodes);
        goto done;
    }
    THX_TRY(join(ctx, path, sizeof path, dir, jt->valuestring));
    THX_TRY(read_tets(ctx, path, v->n_nodes, nr, v));
    if (v->n_tets == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: volume: no tetrahedra", path);
        goto done;
    }
    if (v->n_tets != nt) {
        st = thx_error(ctx, THX_EINPUT, "%s: volume: manifest says %zu tetrahedra but %s has %zu", mpath, nt, path,
                       v->n_tets);
        goto done;
    }
    /* Node tables: forward from the files, reverse rebuilt here. */
    v->node_surf = thx_malloc(ctx, v->n_nodes * sizeof *v->node_surf);
    v->node_snode = thx_malloc(ctx, v->n_nodes * sizeof *v->node_snode);
    v->surf_n_nodes = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *v->surf_n_nodes);
    v->surf_node = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *v->surf_node);
    if (!v->node_surf || !v->node_snode || !v->surf_n_nodes || !v->surf_node) {
        st = THX_ENOMEM;
        goto done;
    }
    v->n_surfaces = m->n_surfaces;
    for (size_t w = 0; w < v->n_nodes; w++) v->node_surf[w] = v->node_snode[w] = -1;
    for (size_t i = 0; i < m->n_surfaces; i++) {
        if (strcmp(m->surf[i]->name, "volume") == 0) {
            st = thx_error(ctx, THX_EINPUT, "%s: surface \"volume\": name is reserved for the volume mesh files", mpath);
            goto done;
        }
        const cJSON *jm = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(surfs, (int)i), "vmap");
        THX_TRY(join(ctx, path, sizeof path, dir, jm->valuestring));
        v->surf_n_nodes[i] = m->surf[i]->n_nodes;
        THX_TRY(read_vmap(ctx, path, vpts, m, i, v));
    }
    /* Steiner nodes (absent in volumes written before they existed, and in imported meshes) */
    {
        const cJSON *js = cJSON_GetObjectItemCaseSensitive(vo, "steiner");
        size_t n_st = 0;
        if (js) {
            if (!cJSON_IsString(js) || !thx_io_file_name_ok(js->valuestring) || thx_io_json_count(vo, "n_steiner", &n_st)) {
                st = thx_error(ctx, THX_EINPUT, "%s: volume: \"steiner\" must name a file in the model directory, with "
                               "\"n_steiner\" its record count", mpath);
                goto done;
            }
            THX_TRY(join(ctx, path, sizeof path, dir, js->valuestring));
            THX_TRY(read_steiner(ctx, path, m, v->n_nodes, n_st, v));
        }
    }
    {
        /* the same structural checks as before writing */
        thx_model tmp = *m;
        tmp.volume = v;
        THX_TRY(thx_model_volume_validate(ctx, &tmp, mpath));
    }
    thx_volume_destroy(&m->volume);
    m->volume = v;
    v = NULL;
done:
    thx_volume_destroy(&v);
    return st;
}

/* -------------------------------------------------------------- export */

/* The writers are src/io/export_vtk.c and src/io/export_msh.c (thorax/io/export_data.h): the
 * geometry-only export is the data export with no data. */
thx_status thx_volume_export(thx_ctx *ctx, const thx_model *m, thx_export_format fmt, const char *path)
{
    if (!m->volume) return thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh to export", path);
    if (fmt == THX_EXPORT_VTU) return thx_volume_export_vtu(ctx, m, NULL, path);
    if (fmt == THX_EXPORT_MSH) return thx_volume_export_msh(ctx, m, NULL, 0, path);
    return thx_error(ctx, THX_EINPUT, "%s: not a volume export format (vtu or msh)", path);
}
