/*
 * The stiffness matrix kept between runs (thorax/fem/fem.h, thx_fem_assemble_kept; docs/design/parallel.md,
 * "The stiffness matrix kept"). The matrix depends on the nodes, the tetrahedra, their regions, the regions'
 * conductivities and the regions used, nothing else; its file in the user's cache directory
 * (thorax/core/cache.h) is stiffness-KEY.bin with KEY the SHA-256 of all of them. A file is used only when
 * it reads back whole (magic, key, sizes, the SHA-256 of each array) and is a stiffness matrix (rows in
 * order, columns ascending and in range, values finite, each row summing to zero within rounding with a
 * positive diagonal, symmetric by a test with two fixed vectors); otherwise the matrix is assembled again and
 * the file replaced.
 *
 * File: "THXSTF01", KEY (32), n and nnz (u64 each), row (n + 1 int64), col (nnz int32), val (nnz double),
 * then the SHA-256 of row, of col and of val (32 each).
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "thorax/core/cache.h"
#include "thorax/core/fileio.h"
#include "thorax/core/hash.h"
#include "thorax/core/sha256.h"
#include "thorax/fem/fem.h"

static const char k_magic[8] = {'T', 'H', 'X', 'S', 'T', 'F', '0', '1'};

static void sha(const void *p, size_t n, unsigned char out[32])
{
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, p, n);
    thx_sha256_final(&h, out);
}

/* SHA-256 of what the assembly reads: the large arrays hashed side by side, then the whole. */
static void matrix_key(const thx_volume *v, const unsigned char *use_region, unsigned char key[32])
{
    unsigned char d[3][32];
    const void *p[3] = {v->xyz, v->tet, v->region};
    size_t b[3] = {3 * v->n_nodes * sizeof *v->xyz, 4 * v->n_tets * sizeof *v->tet, v->n_tets * sizeof *v->region};
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < 3; i++) sha(p[i], b[i], d[i]);
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    static const char tag[] = "thorax stiffness matrix: linear tetrahedra, rows in Morton order, v1";
    thx_sha256_update(&h, tag, sizeof tag);
    uint64_t sz[3] = {v->n_nodes, v->n_tets, v->n_regions};
    thx_sha256_update(&h, sz, sizeof sz);
    thx_sha256_update(&h, d, sizeof d);
    for (size_t r = 0; r < v->n_regions; r++) {
        unsigned char use = !use_region || use_region[r];
        thx_sha256_update(&h, v->regions[r].sigma, sizeof v->regions[r].sigma);
        thx_sha256_update(&h, &use, 1);
    }
    thx_sha256_final(&h, key);
}

/* A number in [-1, 1) from i alone: the same vectors in every run and every thread. */
static double probe(uint64_t i) { return thx_hash_signed_unit(i); }

/* 1 when K is a stiffness matrix of order n as the assembly makes it: rows in order; columns ascending
   and in range; values finite; each nonempty row with a positive diagonal and summing to zero within
   rounding (the element matrices' rows do); symmetric: y^T K x = x^T K y for two fixed vectors of the
   form above, within rounding (one pass, no search: a value moved across the diagonal, a row's entries
   shifted, a row or a column lost all show). */
static int matrix_valid(const thx_csr *K, int64_t n)
{
    const int64_t *row = K->row;
    const int32_t *col = K->col;
    const double *val = K->val;
    if (row[0] != 0) return 0;
    for (int64_t i = 0; i < n; i++)
        if (row[i + 1] < row[i]) return 0;
    int bad = 0;
    double yKx = 0, xKy = 0, mag = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(| : bad) reduction(+ : yKx, xKy, mag)
    for (int64_t i = 0; i < n; i++) {
        if (bad) continue;
        double sum = 0, abs_sum = 0, diag = 0, u = 0, w = 0, m = 0;
        for (int64_t e = row[i]; e < row[i + 1]; e++) {
            int32_t j = col[e];
            double a = val[e];
            if (j < 0 || j >= n || (e > row[i] && j <= col[e - 1]) || !isfinite(a)) { bad = 1; break; }
            sum += a;
            abs_sum += fabs(a);
            if (j == i) diag = a;
            double xj = probe((uint64_t)j), yj = probe((uint64_t)j + (uint64_t)n);
            u += a * xj;
            w += a * yj;
            m += fabs(a) * (fabs(xj) + fabs(yj));
        }
        if (bad) continue;
        if (row[i + 1] > row[i] && (!(diag > 0) || fabs(sum) > 1e-9 * abs_sum)) { bad = 1; continue; }
        yKx += probe((uint64_t)i + (uint64_t)n) * u;
        xKy += probe((uint64_t)i) * w;
        mag += m;
    }
    return !bad && fabs(yKx - xKy) <= 1e-11 * mag;
}

/* The kept matrix, or 0 (missing, another matrix, damaged; K empty then). The rows and columns are read
   and hashed on one thread, the values on another (the reading, its pages and the hashes were 0.05 s of
   the high phantom's, on one thread). */
static int kept_read(const char *path, int64_t n, const unsigned char key[32], thx_csr *K)
{
    memset(K, 0, sizeof *K);
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    char magic[8];
    unsigned char k2[32], sums[3][32];
    uint64_t hdr[2] = {0, 0}; /* n, nnz */
    unsigned char head[8 + 32 + sizeof hdr];
    struct stat sb;
    int ok = fstat(fd, &sb) == 0 && thx_read_exact(fd, head, sizeof head, 0);
    if (ok) {
        memcpy(magic, head, 8);
        memcpy(k2, head + 8, 32);
        memcpy(hdr, head + 40, sizeof hdr);
        ok = !memcmp(magic, k_magic, 8) && !memcmp(k2, key, 32) && hdr[0] == (uint64_t)n && hdr[1] <= ((uint64_t)1 << 40);
    }
    /* the sizes the header claims must be the file's own before anything is allocated for them */
    ok = ok && (uint64_t)sb.st_size == sizeof head + 8 * (hdr[0] + 1) + 12 * hdr[1] + 3 * 32;
    size_t nnz = ok ? (size_t)hdr[1] : 0;
    if (ok) {
        K->row = malloc(((size_t)n + 1) * sizeof *K->row);
        K->col = malloc((nnz ? nnz : 1) * sizeof *K->col);
        K->val = malloc((nnz ? nnz : 1) * sizeof *K->val);
        ok = K->row && K->col && K->val;
    }
    if (ok) {
        unsigned char d[3][32];
        const size_t b[3] = {((size_t)n + 1) * sizeof *K->row, nnz * sizeof *K->col, nnz * sizeof *K->val};
        const off_t at[4] = {(off_t)sizeof head, (off_t)(sizeof head + b[0]), (off_t)(sizeof head + b[0] + b[1]),
                             (off_t)(sizeof head + b[0] + b[1] + b[2])};
        int got[2] = {0, 0};
#pragma omp parallel for num_threads(2) schedule(static, 1)
        for (int t = 0; t < 2; t++) {
            if (t == 0) {
                got[0] = thx_read_exact(fd, K->row, b[0], at[0]) && thx_read_exact(fd, K->col, b[1], at[1]);
                if (got[0]) {
                    sha(K->row, b[0], d[0]);
                    sha(K->col, b[1], d[1]);
                }
            } else {
                got[1] = thx_read_exact(fd, K->val, b[2], at[2]) && thx_read_exact(fd, sums, sizeof sums, at[3]);
                if (got[1]) sha(K->val, b[2], d[2]);
            }
        }
        ok = got[0] && got[1] && !memcmp(d, sums, sizeof d) && K->row[n] == (int64_t)nnz;
    }
    close(fd);
    if (ok) {
        K->n_rows = K->n_cols = (int32_t)n;
        ok = matrix_valid(K, n);
    }
    if (!ok) thx_csr_free(K);
    return ok;
}

/* Writes K atomically (a temporary file renamed); a note on failure, none on success. */
static void kept_write(const char *dir, const char *path, const unsigned char key[32], const thx_csr *K, char *note,
                       size_t note_n)
{
    const size_t n = (size_t)K->n_rows, nnz = (size_t)K->row[n];
    thx_cache_file cf;
    if (!thx_cache_create(&cf, dir, path, 8 + 32 + 16 + 8 * ((uint64_t)n + 1) + 12 * (uint64_t)nnz + 3 * 32,
                          "the stiffness matrix", note, note_n))
        return;
    FILE *f = cf.f;
    unsigned char d[3][32];
    const void *p[3] = {K->row, K->col, K->val};
    size_t b[3] = {(n + 1) * sizeof *K->row, nnz * sizeof *K->col, nnz * sizeof *K->val};
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < 3; i++) sha(p[i], b[i], d[i]);
    uint64_t hdr[2] = {n, nnz};
    int ok = fwrite(k_magic, 1, 8, f) == 8 && fwrite(key, 1, 32, f) == 32 && fwrite(hdr, sizeof *hdr, 2, f) == 2 &&
             fwrite(K->row, sizeof *K->row, n + 1, f) == n + 1 && fwrite(K->col, sizeof *K->col, nnz, f) == nnz &&
             fwrite(K->val, sizeof *K->val, nnz, f) == nnz && fwrite(d, 1, sizeof d, f) == sizeof d;
    thx_cache_commit(&cf, ok, dir, path, "the stiffness matrix", note, note_n);
}

thx_status thx_fem_assemble_kept(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, thx_csr *K,
                                 thx_fem_assembly_info *info)
{
    thx_fem_assembly_info inf;
    memset(&inf, 0, sizeof inf);
    double t0 = thx_wtime();
    char dir[4096], path[4200];
    const char *cd = thx_cache_dir(dir, sizeof dir);
    unsigned char key[32];
    thx_status st = THX_OK;
    if (cd && v->n_nodes <= INT32_MAX) {
        matrix_key(v, use_region, key);
        thx_cache_path(path, sizeof path, cd, "stiffness", key);
        inf.kept = kept_read(path, (int64_t)v->n_nodes, key, K);
        if (inf.kept) thx_cache_used(path);
    } else if (!cd)
        snprintf(inf.note, sizeof inf.note, "no cache directory (HOME, XDG_CACHE_HOME and THORAX_CACHE_DIR unset)");
    if (!inf.kept) {
        st = thx_fem_assemble(ctx, v, use_region, K);
        if (st == THX_OK && cd && v->n_nodes <= INT32_MAX) kept_write(cd, path, key, K, inf.note, sizeof inf.note);
    }
    inf.seconds = thx_wtime() - t0;
    if (info) *info = inf;
    return st;
}
