/*
 * The partitioned forward problem's two library halves (thorax/fem/fem.h), without MPI:
 *  - thx_fem_partition on a block of tetrahedra with a skewed density (the nodes bunched towards one
 *    corner) and a hole of inactive nodes: every active node in one part, every inactive one in
 *    none; the parts' free nodes (rows) equal within one; every two parts separated by a plane (the
 *    parts are boxes: their boxes of nodes overlap nowhere inside); the same partition twice;
 *    1 part: everything in part 0; 0 parts refused;
 *  - thx_fem_partition_cuts: the same partition, with its cuts: each node off the cut planes in its
 *    own part's box, each tetrahedron's centroid in exactly one; the parts back to front from five
 *    eyes (around and inside the block): of any two parts, the one on the eye's side of the cut
 *    between them is listed later;
 *  - the volume in parts (thorax/fem/parts.h): 3 parts hold every used tetrahedron once and the
 *    whole's values; each written and read back the same; a changed byte or a short file refused;
 *  - thx_fem_assemble_rows: the rows asked for are the whole matrix's rows to the bit (columns and
 *    values), the others empty; the tetrahedra of a region left out are left out as before.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shapes.h"
#include "testlib.h"
#include "thorax/fem/fem.h"
#include "thorax/fem/parts.h"
#include "thorax/model/volume.h"

static thx_ctx *ctx;

/* n^3 cubes of 6 tetrahedra each on a grid x = (i / n)^1.5 * 100 (denser towards the origin), two
 * regions: the cubes with i + j + k < n in region 1, the rest region 0. */
static thx_volume *block(int n)
{
    thx_volume *v = NULL;
    if (thx_volume_create(ctx, &v) != THX_OK) return NULL;
    int m = n + 1;
    v->n_nodes = (size_t)m * m * m;
    v->n_tets = 6 * (size_t)n * n * n;
    v->xyz = malloc(3 * v->n_nodes * sizeof *v->xyz);
    v->tet = malloc(4 * v->n_tets * sizeof *v->tet);
    v->region = malloc(v->n_tets * sizeof *v->region);
    v->n_regions = 2;
    v->regions = calloc(2, sizeof *v->regions);
    for (int r = 0; r < 2; r++) {
        snprintf(v->regions[r].name, sizeof v->regions[r].name, "r%d", r);
        v->regions[r].sigma[0] = v->regions[r].sigma[4] = v->regions[r].sigma[8] = r ? 0.05 : 0.2;
    }
    shape_cube_grid(n, 1.0 / n, v->xyz, v->tet); /* on the unit cube, then bunched (the tetrahedra stay positive) */
    for (size_t i = 0; i < 3 * v->n_nodes; i++) v->xyz[i] = 100 * pow(v->xyz[i], 1.5);
    for (size_t t = 0; t < v->n_tets; t++) {
        size_t c = t / 6; /* cube (i, j, k) = c % n, c / n % n, c / n^2 */
        v->region[t] = (int32_t)(c % (size_t)n + c / (size_t)n % (size_t)n + c / ((size_t)n * (size_t)n)) < n;
    }
    return v;
}

static void test_partition(const thx_volume *v, const unsigned char *kind)
{
    size_t nn = v->n_nodes;
    int32_t *part = malloc(nn * sizeof *part), *again = malloc(nn * sizeof *again);
    for (int np = 1; np <= 7; np++) {
        CHECK_OK(ctx, thx_fem_partition(ctx, v, kind, np, part));
        CHECK_OK(ctx, thx_fem_partition(ctx, v, kind, np, again));
        CHECK(memcmp(part, again, nn * sizeof *part) == 0);
        size_t rows[8] = {0}, misplaced = 0;
        double lo[8][3], hi[8][3];
        for (int p = 0; p < np; p++)
            for (int c = 0; c < 3; c++) lo[p][c] = INFINITY, hi[p][c] = -INFINITY;
        for (size_t i = 0; i < nn; i++) {
            if (!kind[i]) { misplaced += part[i] != -1; continue; }
            if (part[i] < 0 || part[i] >= np) { misplaced++; continue; }
            rows[part[i]] += kind[i] == 1;
            for (int c = 0; c < 3; c++) {
                double x = v->xyz[3 * i + c];
                if (x < lo[part[i]][c]) lo[part[i]][c] = x;
                if (x > hi[part[i]][c]) hi[part[i]][c] = x;
            }
        }
        size_t rmin = rows[0], rmax = rows[0];
        for (int p = 1; p < np; p++) {
            if (rows[p] < rmin) rmin = rows[p];
            if (rows[p] > rmax) rmax = rows[p];
        }
        /* separated: for every two parts some axis on which one's box ends where the other's begins */
        int apart = 1;
        for (int p = 0; p < np; p++)
            for (int q = p + 1; q < np; q++) {
                int sep = 0;
                for (int c = 0; c < 3; c++) sep |= hi[p][c] <= lo[q][c] || hi[q][c] <= lo[p][c];
                apart &= sep;
            }
        printf("%d parts: free nodes per part %zu .. %zu, %zu nodes misplaced, boxes %s\n", np, rmin, rmax, misplaced,
               apart ? "apart" : "OVERLAPPING");
        CHECK(misplaced == 0);
        CHECK(rmax - rmin <= 1);
        CHECK(apart);
    }
    CHECK(thx_fem_partition(ctx, v, kind, 0, part) == THX_EINPUT);
    free(part);
    free(again);
}

/* The cuts: every node off the cut planes in its own part's box, every centroid in one part, and the
 * order back to front from eyes around and inside the block: for any two parts, the one on the eye's
 * side of the cut between them comes later. */
static void test_cuts(const thx_volume *v, const unsigned char *kind)
{
    size_t nn = v->n_nodes;
    int32_t *part = malloc(nn * sizeof *part), *plain = malloc(nn * sizeof *plain);
    for (int np = 1; np <= 7; np++) {
        thx_fem_cut cuts[8];
        CHECK_OK(ctx, thx_fem_partition_cuts(ctx, v, kind, np, part, cuts));
        CHECK_OK(ctx, thx_fem_partition(ctx, v, kind, np, plain));
        CHECK(memcmp(part, plain, nn * sizeof *part) == 0);
        size_t off = 0, on_plane = 0, centroid_bad = 0;
        for (size_t i = 0; i < nn; i++) {
            if (part[i] < 0) continue;
            int at_plane = 0;
            for (int k = 0; k < np - 1; k++) at_plane |= v->xyz[3 * i + cuts[k].axis] == cuts[k].at;
            if (at_plane) { on_plane++; continue; }
            off += thx_fem_cut_part(cuts, np, v->xyz + 3 * i) != part[i];
        }
        size_t count[8] = {0};
        for (size_t t = 0; t < v->n_tets; t++) {
            double c[3] = {0, 0, 0};
            for (int k = 0; k < 4; k++)
                for (int d = 0; d < 3; d++) c[d] += 0.25 * v->xyz[3 * (size_t)v->tet[4 * t + k] + d];
            int p = thx_fem_cut_part(cuts, np, c);
            if (p < 0 || p >= np) centroid_bad++;
            else count[p]++;
        }
        int wrong_order = 0;
        const double eyes[5][3] = {{-500, 50, 50}, {50, 700, -20}, {40, 40, 40}, {150, -300, 400}, {10, 90, 60}};
        for (int e = 0; e < 5; e++) {
            int order[8], seen[8] = {0};
            thx_fem_cut_order(cuts, np, eyes[e], order);
            for (int a = 0; a < np; a++) seen[order[a]]++;
            for (int q = 0; q < np; q++) wrong_order += seen[q] != 1;
            for (int a = 0; a < np; a++)
                for (int b = a + 1; b < np; b++) {
                    int p = order[a], q = order[b]; /* p drawn before q: q must not be behind p */
                    for (int k = 0; k < np - 1; k++) {
                        const thx_fem_cut *c = &cuts[k];
                        if (p < c->lo || p >= c->hi || q < c->lo || q >= c->hi || (p < c->mid) == (q < c->mid)) continue;
                        int eye_below = eyes[e][c->axis] < c->at, q_below = q < c->mid;
                        wrong_order += eye_below != q_below; /* q, drawn later, on the eye's side */
                    }
                }
        }
        printf("%d parts: %zu nodes off their box (%zu on a cut plane), %zu centroids outside, tetrahedra per part", np,
               off, on_plane, centroid_bad);
        for (int p = 0; p < np; p++) printf(" %zu", count[p]);
        printf("; %d pairs out of order\n", wrong_order);
        CHECK(off == 0 && centroid_bad == 0 && wrong_order == 0);
    }
    free(part);
    free(plain);
}

static void test_rows(const thx_volume *v, const unsigned char *use_region)
{
    size_t nn = v->n_nodes;
    thx_csr K, R;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, use_region, &K));
    unsigned char *rows = malloc(nn);
    for (size_t i = 0; i < nn; i++) rows[i] = (i * 7919) % 5 < 2; /* about 2 rows in 5, scattered */
    CHECK_OK(ctx, thx_fem_assemble_rows(ctx, v, use_region, rows, &R));
    size_t same = 0, empty = 0, wrong = 0;
    for (size_t i = 0; i < nn; i++) {
        int64_t a = K.row[i], b = R.row[i], na = K.row[i + 1] - a, nb = R.row[i + 1] - b;
        if (!rows[i]) { if (nb == 0) empty++; else wrong++; continue; }
        if (na == nb && memcmp(K.col + a, R.col + b, (size_t)na * sizeof *K.col) == 0 &&
            memcmp(K.val + a, R.val + b, (size_t)na * sizeof *K.val) == 0)
            same++;
        else
            wrong++;
    }
    printf("rows asked for: %zu the same to the bit; rows not asked for: %zu empty; %zu wrong\n", same, empty, wrong);
    CHECK(wrong == 0);
    CHECK(same + empty == nn && same > 0 && empty > 0);
    thx_csr_free(&K);
    thx_csr_free(&R);
    free(rows);
}

/* The volume in parts: made for 3 ranks, every used tetrahedron in one part and each part's values
 * the whole's; written and read back equal; a byte changed, or the file cut short, refused by name. */
static void test_parts(const thx_volume *v, const unsigned char *use, const unsigned char *kind)
{
    const int np = 3, nf = 2;
    size_t nn = v->n_nodes;
    int32_t *part = malloc(nn * sizeof *part);
    double *values = malloc(nf * nn * sizeof *values);
    thx_fem_cut cuts[2];
    for (size_t i = 0; i < nf * nn; i++) values[i] = sin(0.001 * (double)i) + (double)(i / nn);
    CHECK_OK(ctx, thx_fem_partition_cuts(ctx, v, kind, np, part, cuts));
    size_t used = 0, in_parts = 0, wrong = 0;
    for (size_t t = 0; t < v->n_tets; t++) used += use[v->region[t]] != 0;
    for (int r = 0; r < np; r++) {
        thx_fem_part p, q;
        CHECK_OK(ctx, thx_fem_part_make(ctx, v, use, cuts, np, r, values, nf, &p));
        in_parts += p.n_own;
        /* the ghosts: exactly the used tetrahedra of other parts that share a node with an own one or
           whose bounding box meets the part's box, each with its owner; the numbers ascending */
        unsigned char *near = calloc(nn, 1), *in = calloc(v->n_tets, 1);
        size_t own = 0, ghosts_wrong = 0;
        for (size_t k = 0; k < p.n_tets; k++) {
            in[p.tet_id[k]] = 1;
            CHECK(k == 0 || p.tet_id[k] > p.tet_id[k - 1]);
            CHECK(p.region[k] == v->region[p.tet_id[k]]);
            for (int c = 0; c < 4; c++) CHECK(p.node[p.tet[4 * k + c]] == v->tet[4 * (size_t)p.tet_id[k] + c]);
            if (p.owner[k] != r) continue;
            own++;
            for (int c = 0; c < 4; c++) near[p.node[p.tet[4 * k + c]]] = 1;
        }
        CHECK(own == p.n_own);
        for (size_t t = 0; t < v->n_tets; t++) {
            const int32_t *c4 = v->tet + 4 * t;
            double box[2][3], lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            thx_fem_cut_box(cuts, np, r, box);
            for (int c = 0; c < 4; c++)
                for (int d = 0; d < 3; d++) lo[d] = fmin(lo[d], v->xyz[3 * (size_t)c4[c] + d]), hi[d] = fmax(hi[d], v->xyz[3 * (size_t)c4[c] + d]);
            int into = 1;
            for (int d = 0; d < 3; d++) into &= hi[d] >= box[0][d] && lo[d] < box[1][d];
            int want = use[v->region[t]] && (near[c4[0]] || near[c4[1]] || near[c4[2]] || near[c4[3]] || into);
            ghosts_wrong += want != in[t];
        }
        for (size_t k = 0; k < p.n_tets; k++) {
            double c[3] = {0, 0, 0};
            for (int j = 0; j < 4; j++)
                for (int d = 0; d < 3; d++) c[d] += 0.25 * p.xyz[3 * (size_t)p.tet[4 * k + j] + d];
            ghosts_wrong += thx_fem_cut_part(cuts, np, c) != p.owner[k];
        }
        printf("part %d: %zu own tetrahedra, %zu ghosts, %zu wrong\n", r, p.n_own, p.n_tets - p.n_own, ghosts_wrong);
        CHECK(ghosts_wrong == 0 && p.n_tets > p.n_own);
        free(near);
        free(in);
        for (size_t f = 0; f < (size_t)nf; f++)
            for (size_t j = 0; j < p.n_nodes; j++) wrong += p.values[f * p.n_nodes + j] != values[f * nn + (size_t)p.node[j]];
        char name[32];
        snprintf(name, sizeof name, "part_%d.bin", r);
        CHECK_OK(ctx, thx_fem_part_write(ctx, tl_path(name), &p));
        CHECK_OK(ctx, thx_fem_part_read(ctx, tl_path(name), &q));
        CHECK(q.rank == (uint32_t)r && q.ranks == (uint32_t)np && q.n_nodes == p.n_nodes && q.n_tets == p.n_tets &&
              q.n_frames == p.n_frames && q.n_global == nn);
        CHECK(!memcmp(q.node, p.node, p.n_nodes * 4) && !memcmp(q.xyz, p.xyz, p.n_nodes * 24) &&
              !memcmp(q.tet, p.tet, p.n_tets * 16) && !memcmp(q.region, p.region, p.n_tets * 4) &&
              !memcmp(q.tet_id, p.tet_id, p.n_tets * 4) && !memcmp(q.owner, p.owner, p.n_tets * 4) && q.n_own == p.n_own &&
              q.n_global_tets == v->n_tets &&
              !memcmp(q.values, p.values, p.n_nodes * nf * 8) && !memcmp(q.cuts, cuts, sizeof cuts));
        thx_fem_part_free(&q);
        if (r == 1) { /* damaged: a byte of the values changed; the file cut short */
            size_t len = 0;
            char *b = tl_slurp(ctx, tl_path(name), &len);
            b[len - 40] ^= 1;
            tl_write_bytes(tl_path("bad.bin"), b, len);
            CHECK(thx_fem_part_read(ctx, tl_path("bad.bin"), &q) == THX_EINPUT);
            CHECK(strstr(thx_ctx_message(ctx), "checksum") != NULL);
            tl_write_bytes(tl_path("short.bin"), b, len - 9);
            CHECK(thx_fem_part_read(ctx, tl_path("short.bin"), &q) == THX_EINPUT);
            CHECK(strstr(thx_ctx_message(ctx), "does not fill") != NULL);
            printf("a damaged part: %s\n", thx_ctx_message(ctx));
            memcpy(b, "THXPART1", 8); /* the first format, without ghosts: refused with the advice */
            tl_write_bytes(tl_path("old.bin"), b, len);
            CHECK(thx_fem_part_read(ctx, tl_path("old.bin"), &q) == THX_EINPUT);
            CHECK(strstr(thx_ctx_message(ctx), "first format") != NULL && strstr(thx_ctx_message(ctx), "forward") != NULL);
            free(b);
        }
        thx_fem_part_free(&p);
    }
    printf("3 parts: %zu tetrahedra of %zu used, %zu values not the whole's\n", in_parts, used, wrong);
    CHECK(in_parts == used && wrong == 0);
    free(part);
    free(values);
}

int main(void)
{
    if (tl_scratch_make("test_fem_partition") != 0) return 1;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_volume *v = block(12);
    unsigned char use[2] = {1, 0}; /* region 1 (the corner) left out: its inner nodes inactive */
    unsigned char *kind = NULL;
    CHECK_OK(ctx, thx_fem_active_nodes(ctx, v, use, &kind));
    size_t inactive = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        if (kind[i] && v->xyz[3 * i + 2] == 0) kind[i] = 2; /* the bottom face prescribed */
        inactive += !kind[i];
    }
    CHECK(inactive > 0);
    test_partition(v, kind);
    test_cuts(v, kind);
    test_rows(v, use);
    test_rows(v, NULL);
    test_parts(v, use, kind);
    free(kind);
    thx_volume_destroy(&v);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_fem_partition");
}
