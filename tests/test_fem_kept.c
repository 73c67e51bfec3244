/*
 * The stiffness matrix kept between runs (thx_fem_assemble_kept, thorax/fem/fem.h) and the cache
 * directory's trim (thorax/core/cache.h), in a scratch cache directory:
 *  - the first call assembles and keeps, the second reads the file back: the same matrix as
 *    thx_fem_assemble's, to the bit, both times;
 *  - another conductivity, or another region left out, is another matrix (another file);
 *  - a file cut short, a byte spoiled, a header claiming 2^39 entries, a run of NULs, and files whole but
 *    wrong (a value changed, two values of a row swapped, their checksums written anew) are not used: the
 *    matrix is assembled again, the same bits;
 *  - THORAX_CACHE_MAX below the matrix's size: nothing kept, a note says why;
 *  - the trim removes the least recently used of thorax's files first, keeps the one just written and
 *    never touches a file of another name.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/cache.h"
#include "thorax/core/sha256.h"
#include "thorax/fem/fem.h"

#define N 6 /* nodes a side */

/* A lattice of N^3 nodes, each cube cut into 6 tetrahedra (positively oriented), two regions by x. */
static thx_volume *lattice(thx_ctx *ctx, double s0, double s1)
{
    thx_volume *v = NULL;
    CHECK_OK(ctx, thx_volume_create(ctx, &v));
    v->n_nodes = N * N * N;
    v->xyz = malloc(3 * v->n_nodes * sizeof *v->xyz);
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            for (int k = 0; k < N; k++) {
                size_t q = (size_t)((i * N + j) * N + k);
                v->xyz[3 * q] = i * 2.0 + 0.1 * j;
                v->xyz[3 * q + 1] = j * 2.0;
                v->xyz[3 * q + 2] = k * 2.0 + 0.05 * i;
            }
    const size_t nc = (N - 1) * (N - 1) * (N - 1);
    v->n_tets = 6 * nc;
    v->tet = malloc(4 * v->n_tets * sizeof *v->tet);
    v->region = malloc(v->n_tets * sizeof *v->region);
    /* the cube's corners c[b] (b = 4x + 2y + z); six tetrahedra around the diagonal 0-7 */
    static const int path[6][2] = {{1, 3}, {3, 2}, {2, 6}, {6, 4}, {4, 5}, {5, 1}};
    size_t t = 0;
    for (int i = 0; i < N - 1; i++)
        for (int j = 0; j < N - 1; j++)
            for (int k = 0; k < N - 1; k++) {
                int32_t c[8];
                for (int b = 0; b < 8; b++)
                    c[b] = (int32_t)(((i + (b >> 2 & 1)) * N + (j + (b >> 1 & 1))) * N + (k + (b & 1)));
                for (int p = 0; p < 6; p++, t++) {
                    int32_t *q = v->tet + 4 * t;
                    q[0] = c[0];
                    q[1] = c[path[p][0]];
                    q[2] = c[path[p][1]];
                    q[3] = c[7];
                    double g[4][3];
                    if (thx_fem_tet_gradients(v->xyz, q, g) < 0) {
                        int32_t x = q[1];
                        q[1] = q[2];
                        q[2] = x;
                    }
                    v->region[t] = i < (N - 1) / 2 ? 0 : 1;
                }
            }
    v->n_regions = 2;
    v->regions = calloc(2, sizeof *v->regions);
    const double s[2] = {s0, s1};
    for (int r = 0; r < 2; r++) {
        snprintf(v->regions[r].name, sizeof v->regions[r].name, "r%d", r);
        v->regions[r].sigma[0] = v->regions[r].sigma[4] = v->regions[r].sigma[8] = s[r];
    }
    return v;
}

/* 1 when A and B are the same matrix to the bit. */
static int same(const thx_csr *A, const thx_csr *B)
{
    if (A->n_rows != B->n_rows || memcmp(A->row, B->row, ((size_t)A->n_rows + 1) * sizeof *A->row)) return 0;
    size_t nnz = (size_t)A->row[A->n_rows];
    return !memcmp(A->col, B->col, nnz * sizeof *A->col) && !memcmp(A->val, B->val, nnz * sizeof *A->val);
}

/* The one stiffness-*.bin in dir (its path into out), or 0 when there is not exactly one. */
static int the_file(const char *dir, char *out, size_t n)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "ls %s/stiffness-*.bin 2>/dev/null", dir);
    FILE *p = popen(cmd, "r");
    int k = 0;
    char line[1200];
    while (p && fgets(line, sizeof line, p)) {
        line[strcspn(line, "\n")] = 0;
        if (!k) snprintf(out, n, "%s", line);
        k++;
    }
    if (p) pclose(p);
    return k == 1;
}

/* The file's val array changed by f, and its checksum written anew (a file whole but wrong). */
static void rewrite(thx_ctx *ctx, const char *path, size_t n, void (*f)(double *val, const int64_t *row, size_t n))
{
    size_t len = 0;
    unsigned char *b = (unsigned char *)tl_slurp(ctx, path, &len);
    CHECK(b != NULL);
    if (!b) return;
    uint64_t nnz;
    memcpy(&nnz, b + 48, 8);
    int64_t *row = malloc((n + 1) * sizeof *row);
    memcpy(row, b + 56, (n + 1) * 8);
    size_t off_val = 56 + 8 * (n + 1) + 4 * nnz;
    double *val = malloc(nnz * sizeof *val);
    memcpy(val, b + off_val, nnz * 8);
    f(val, row, n);
    memcpy(b + off_val, val, nnz * 8);
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, val, nnz * 8);
    thx_sha256_final(&h, b + len - 32);
    tl_write_bytes(path, b, len);
    free(row);
    free(val);
    free(b);
}

static void change_one(double *val, const int64_t *row, size_t n)
{
    (void)n;
    val[row[7] + 1] *= 1.001; /* row 8's second entry: its row no longer sums to zero */
}

static void swap_two(double *val, const int64_t *row, size_t n)
{
    (void)n;
    /* row 40's first and last entries swapped: its sum unchanged, the matrix no longer symmetric */
    int64_t a = row[40], b = row[41] - 1;
    double x = val[a];
    val[a] = val[b];
    val[b] = x;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    if (tl_scratch_make("test_fem_kept")) return 1;
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/cache", tl_scratch);
    setenv("THORAX_CACHE_DIR", dir, 1);
    unsetenv("THORAX_CACHE_MAX");

    thx_volume *v = lattice(ctx, 0.2, 0.05);
    const size_t n = v->n_nodes;
    thx_csr K0, K;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K0));
    thx_fem_assembly_info inf;

    /* 1. assembled and kept, then read back: the same bits */
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
    CHECK(!inf.kept && !inf.note[0] && same(&K, &K0));
    thx_csr_free(&K);
    char path[1200];
    CHECK(the_file(dir, path, sizeof path));
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
    CHECK(inf.kept && same(&K, &K0));
    thx_csr_free(&K);

    /* 2. the key: another conductivity, another region left out, other node positions */
    v->regions[1].sigma[0] = v->regions[1].sigma[4] = v->regions[1].sigma[8] = 0.06;
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
    CHECK(!inf.kept);
    thx_csr K1;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K1));
    CHECK(same(&K, &K1) && !same(&K, &K0));
    thx_csr_free(&K);
    thx_csr_free(&K1);
    v->regions[1].sigma[0] = v->regions[1].sigma[4] = v->regions[1].sigma[8] = 0.05;
    const unsigned char use[2] = {1, 0};
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, use, &K, &inf));
    CHECK(!inf.kept);
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, use, &K1));
    CHECK(same(&K, &K1));
    thx_csr_free(&K);
    thx_csr_free(&K1);
    v->xyz[3 * 100] += 0.01;
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
    CHECK(!inf.kept);
    thx_csr_free(&K);
    v->xyz[3 * 100] -= 0.01;
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf)); /* the first file again */
    CHECK(inf.kept && same(&K, &K0));
    thx_csr_free(&K);

    /* 3. damaged files are not used, and are replaced */
    size_t len = 0;
    char *good = tl_slurp(ctx, path, &len);
    CHECK(good != NULL && len > 200);
    for (int damage = 0; damage < 6 && good; damage++) {
        if (damage == 0) tl_write_bytes(path, good, len - 9);    /* cut short */
        else if (damage == 4 || damage == 5) {                    /* the header claims 2^39 entries; a NUL run */
            char *c = malloc(len);
            memcpy(c, good, len);
            if (damage == 4) {
                uint64_t big = (uint64_t)1 << 39;
                memcpy(c + 48, &big, 8);
            } else
                memset(c + 56, 0, 64); /* row[0..7] zero: row lengths and checksums wrong */
            tl_write_bytes(path, c, len);
            free(c);
        }
        else if (damage == 1) {                                   /* a byte of the values spoiled */
            good[len - 200] ^= 0x10;
            tl_write_bytes(path, good, len);
            good[len - 200] ^= 0x10;
        } else {
            tl_write_bytes(path, good, len);
            rewrite(ctx, path, n, damage == 2 ? change_one : swap_two);
        }
        CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
        CHECK(!inf.kept && same(&K, &K0));
        thx_csr_free(&K);
        size_t len2 = 0;
        char *now = tl_slurp(ctx, path, &len2);
        CHECK(now && len2 == len && !memcmp(now, good, len)); /* written anew */
        free(now);
        CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
        CHECK(inf.kept && same(&K, &K0));
        thx_csr_free(&K);
    }
    free(good);

    /* 4. a limit below the matrix's size: nothing kept, a note */
    char dir2[1200];
    snprintf(dir2, sizeof dir2, "%s/small", tl_scratch);
    setenv("THORAX_CACHE_DIR", dir2, 1);
    setenv("THORAX_CACHE_MAX", "1K", 1);
    CHECK(thx_cache_max_bytes() == 1024);
    CHECK_OK(ctx, thx_fem_assemble_kept(ctx, v, NULL, &K, &inf));
    CHECK(!inf.kept && strstr(inf.note, "THORAX_CACHE_MAX") && same(&K, &K0));
    thx_csr_free(&K);
    char none[1200];
    CHECK(!the_file(dir2, none, sizeof none));
    setenv("THORAX_CACHE_MAX", "12x", 1);
    CHECK(thx_cache_max_bytes() == (uint64_t)4 << 30); /* does not parse: the default */
    setenv("THORAX_CACHE_MAX", "3M", 1);
    CHECK(thx_cache_max_bytes() == (uint64_t)3 << 20);
    const char *bad_max[] = {"-1", " 5", "+5", "99999999999999999999999", "", "G"};
    for (size_t i = 0; i < sizeof bad_max / sizeof *bad_max; i++) {
        setenv("THORAX_CACHE_MAX", bad_max[i], 1);
        CHECK(thx_cache_max_bytes() == (uint64_t)4 << 30);
    }
    setenv("THORAX_CACHE_MAX", "17179869184G", 1); /* 2^34 G: past 64 bits */
    CHECK(thx_cache_max_bytes() == UINT64_MAX);
    unsetenv("THORAX_CACHE_MAX");

    /* 5. the trim: least recently used first, the file just written kept, other names never */
    char dir3[1200], p[1300];
    snprintf(dir3, sizeof dir3, "%s/trim", tl_scratch);
    mkdir(dir3, 0755);
    unsigned char key[32];
    char names[4][1300];
    for (int i = 0; i < 4; i++) {
        memset(key, i + 1, sizeof key);
        thx_cache_path(names[i], sizeof names[i], dir3, i == 3 ? "ordering" : "stiffness", key);
        char blob[1000];
        memset(blob, i, sizeof blob);
        tl_write_bytes(names[i], blob, sizeof blob);
        struct timeval tv[2] = {{1000000 + 100 * i, 0}, {1000000 + 100 * i, 0}}; /* file i used at time i */
        utimes(names[i], tv);
    }
    snprintf(p, sizeof p, "%s/notes.txt", dir3);
    tl_write_text(p, "a user's file, 20 bytes");
    char other[1300];
    snprintf(other, sizeof other, "%s/stiffness-0123.bin", dir3);
    tl_write_text(other, "not one of thorax's names");
    thx_cache_used(names[0]); /* the oldest used now: the newest */
    CHECK(thx_cache_trim(dir3, 2500, names[3]) == 2); /* 4000 bytes of ours: the two least recent go */
    CHECK(tl_exists(names[0]) && !tl_exists(names[1]) && !tl_exists(names[2]) && tl_exists(names[3]));
    CHECK(tl_exists(p) && tl_exists(other));
    CHECK(thx_cache_trim(dir3, 0, names[3]) == 1); /* the one just written stays even at 0 */
    CHECK(!tl_exists(names[0]) && tl_exists(names[3]) && tl_exists(p) && tl_exists(other));

    thx_csr_free(&K0);
    thx_volume_destroy(&v);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_fem_kept");
}
