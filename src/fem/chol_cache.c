/*
 * The direct path's cache (src/fem/chol_cache.h): the fill-reducing ordering and the symbolic factor of
 * a matrix's graph, kept in the user's cache directory between runs.
 */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "fem/chol_cache.h"
#include "thorax/core/cache.h"
#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"

static const char k_magic[8] = {'T', 'H', 'X', 'O', 'R', 'D', '0', '1'};


/* The graph's key: SHA-256 of a tag, n, nnz and two digests, of rowp with col's first h entries and of
   col's rest, h such that the two are of about the same length: hashed side by side (the high phantom's
   20 MB, 0.012 s on one thread). */
void thx_chol_graph_key(int64_t n, const int64_t *rowp, const int32_t *col, unsigned char key[32])
{
    const int64_t nnz = rowp[n];
    int64_t h = nnz / 2 - (n + 1);
    h = h < 0 ? 0 : h > nnz ? nnz : h;
    unsigned char d[2][32];
#pragma omp parallel for num_threads(2) schedule(static, 1)
    for (int k = 0; k < 2; k++) {
        thx_sha256_ctx c;
        thx_sha256_init(&c);
        if (k == 0) {
            thx_sha256_update(&c, rowp, (size_t)(n + 1) * sizeof *rowp);
            thx_sha256_update(&c, col, (size_t)h * sizeof *col);
        } else
            thx_sha256_update(&c, col + h, (size_t)(nnz - h) * sizeof *col);
        thx_sha256_final(&c, d[k]);
    }
    thx_sha256_ctx c;
    thx_sha256_init(&c);
    static const char tag[] = "thorax ordering: METIS nested dissection of a CSR graph, v2 (two digests)";
    thx_sha256_update(&c, tag, sizeof tag);
    thx_sha256_update(&c, &n, sizeof n);
    thx_sha256_update(&c, &nnz, sizeof nnz);
    thx_sha256_update(&c, d, sizeof d);
    thx_sha256_final(&c, key);
}

static void cache_path(char *buf, size_t n, const char *dir, const unsigned char key[32], const char *what)
{
    thx_cache_path(buf, n, dir, what, key);
}

/* 1 when perm (n entries) is a permutation of 0..n-1 */
static int is_permutation(const int64_t *perm, int64_t n)
{
    unsigned char *seen = calloc((size_t)(n ? n : 1), 1);
    if (!seen) return 0;
    int ok = 1;
    for (int64_t i = 0; i < n && ok; i++) {
        if (perm[i] < 0 || perm[i] >= n || seen[perm[i]]) ok = 0;
        else seen[perm[i]] = 1;
    }
    free(seen);
    return ok;
}

/* The cached ordering, or 0 (missing, another graph, damaged: the caller computes it again). */
static int order_read(const char *path, int64_t n, const unsigned char key[32], int64_t *perm)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char magic[8];
    uint64_t nn = 0;
    unsigned char k2[32], sum[32], sum2[32];
    int ok = fread(magic, 1, 8, f) == 8 && !memcmp(magic, k_magic, 8) && fread(&nn, sizeof nn, 1, f) == 1 &&
             nn == (uint64_t)n && fread(k2, 1, 32, f) == 32 && !memcmp(k2, key, 32) &&
             fread(perm, sizeof *perm, (size_t)n, f) == (size_t)n && fread(sum, 1, 32, f) == 32 && fgetc(f) == EOF;
    fclose(f);
    if (!ok) return 0;
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, perm, (size_t)n * sizeof *perm);
    thx_sha256_final(&h, sum2);
    return !memcmp(sum, sum2, 32) && is_permutation(perm, n);
}

/* Writes the ordering atomically (a temporary file renamed); a note on failure, none on success. */
static void order_write(const char *dir, const char *path, int64_t n, const unsigned char key[32], const int64_t *perm,
                        char *note, size_t note_n)
{
    thx_cache_file cf;
    if (!thx_cache_create(&cf, dir, path, 8 + 8 + 32 + 8 * (uint64_t)n + 32, "the ordering", note, note_n)) return;
    FILE *f = cf.f;
    unsigned char sum[32];
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, perm, (size_t)n * sizeof *perm);
    thx_sha256_final(&h, sum);
    uint64_t nn = (uint64_t)n;
    int ok = fwrite(k_magic, 1, 8, f) == 8 && fwrite(&nn, sizeof nn, 1, f) == 1 && fwrite(key, 1, 32, f) == 32 &&
             fwrite(perm, sizeof *perm, (size_t)n, f) == (size_t)n && fwrite(sum, 1, 32, f) == 32;
    thx_cache_commit(&cf, ok, dir, path, "the ordering", note, note_n);
}


int thx_chol_order_cached(const char *dir, int64_t n, const unsigned char key[32], int64_t *perm)
{
    char path[4200];
    cache_path(path, sizeof path, dir, key, "ordering");
    int hit = order_read(path, n, key, perm);
    if (hit) thx_cache_used(path);
    return hit;
}

void thx_chol_order_keep(const char *dir, int64_t n, const unsigned char key[32], const int64_t *perm, char *note,
                         size_t note_n)
{
    char path[4200];
    cache_path(path, sizeof path, dir, key, "ordering");
    order_write(dir, path, n, key, perm, note, note_n);
}

/* ------------------------------------------------------------------ the symbolic factor */

static const char k_sym_magic[8] = {'T', 'H', 'X', 'S', 'Y', 'M', '0', '1'};

void thx_chol_symbolic_key(const unsigned char graph[32], int64_t n, const int64_t *order, unsigned char key[32])
{
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    static const char tag[] = "thorax symbolic factor: CHOLMOD's supernodal analysis, its default amalgamation, "
                              "the ordering given and postordered, v1";
    thx_sha256_update(&h, tag, sizeof tag);
    thx_sha256_update(&h, graph, 32);
    thx_sha256_update(&h, &n, sizeof n);
    thx_sha256_update(&h, order, (size_t)n * sizeof *order);
    thx_sha256_final(&h, key);
}

void thx_chol_symbolic_free(thx_chol_symbolic *y)
{
    free(y->block);
    memset(y, 0, sizeof *y);
}

/* 1 when y is a supernodal symbolic factor of order n: supernodes covering 0..n-1 in order, their rows
   ascending and in range with their own columns first, the values' places their rows x columns, perm a
   permutation. (That the rows hold the matrix's pattern is checked by the factorization itself.) */
static int symbolic_valid(const thx_chol_symbolic *y, int64_t n)
{
    const int64_t ns = y->nsuper;
    if (ns < (n > 0) || y->super[0] != 0 || y->super[ns] != n || y->pi[0] != 0 || y->px[0] != 0 ||
        y->pi[ns] != (int64_t)y->ssize || y->px[ns] != (int64_t)y->xsize)
        return 0;
    for (int64_t s = 0; s < ns; s++) {
        int64_t k = y->super[s + 1] - y->super[s], r = y->pi[s + 1] - y->pi[s];
        if (k < 1 || r < k || y->px[s + 1] - y->px[s] != r * k) return 0;
        const int64_t *rw = y->rows + y->pi[s];
        for (int64_t t = 0; t < r; t++) {
            if (t < k ? rw[t] != y->super[s] + t : rw[t] <= rw[t - 1] || rw[t] >= n) return 0;
        }
    }
    return is_permutation(y->perm, n);
}

/* the arrays of y in one block: perm (n), super, pi, px (nsuper + 1 each), rows (ssize) */
static int symbolic_alloc(thx_chol_symbolic *y, int64_t n)
{
    size_t ns = (size_t)y->nsuper, m = (size_t)n + 3 * (ns + 1) + y->ssize;
    y->block = malloc((m ? m : 1) * sizeof *y->block);
    if (!y->block) return 0;
    y->perm = y->block;
    y->super = y->perm + n;
    y->pi = y->super + ns + 1;
    y->px = y->pi + ns + 1;
    y->rows = y->px + ns + 1;
    return 1;
}

int thx_chol_symbolic_cached(const char *dir, int64_t n, const unsigned char key[32], thx_chol_symbolic *y)
{
    memset(y, 0, sizeof *y);
    char path[4200];
    cache_path(path, sizeof path, dir, key, "symbolic");
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    uint64_t hdr[4] = {0}; /* n, nsuper, ssize, xsize */
    double counts[2];      /* flops, nonzeros */
    unsigned char head[8 + 32 + sizeof hdr + sizeof counts], sum[32];
    struct stat sb;
    int ok = fstat(fd, &sb) == 0 && thx_read_exact(fd, head, sizeof head, 0) && !memcmp(head, k_sym_magic, 8) &&
             !memcmp(head + 8, key, 32);
    if (ok) {
        memcpy(hdr, head + 40, sizeof hdr);
        memcpy(counts, head + 40 + sizeof hdr, sizeof counts);
        ok = hdr[0] == (uint64_t)n && hdr[1] <= (uint64_t)n + 1 && hdr[2] <= ((uint64_t)1 << 40);
    }
    /* the sizes the header claims must be the file's own before anything is allocated for them */
    ok = ok && (uint64_t)sb.st_size == sizeof head + 8 * (hdr[0] + 3 * (hdr[1] + 1) + hdr[2]) + 32;
    if (ok) {
        y->nsuper = (int64_t)hdr[1];
        y->ssize = (size_t)hdr[2];
        y->xsize = (size_t)hdr[3];
        y->flops = counts[0];
        y->lnz = counts[1];
        ok = symbolic_alloc(y, n);
    }
    if (ok) {
        /* read in two halves side by side, then the checksum on one thread and the structure's check on the
           other (the three were 0.04 s of the high phantom's, one after the other) */
        const size_t m = (size_t)n + 3 * ((size_t)y->nsuper + 1) + y->ssize, bytes = m * sizeof *y->block;
        const size_t half = bytes / 2 / 8 * 8;
        int got[2] = {0, 0}, valid = 0;
        unsigned char sum2[32];
#pragma omp parallel num_threads(2)
        {
            int t = 2; /* 0, 1: a thread of two; 2: alone, both parts */
#ifdef _OPENMP
            if (omp_get_num_threads() > 1) t = omp_get_thread_num();
#endif
            if (t != 1) got[0] = thx_read_exact(fd, y->block, half, (off_t)sizeof head);
            if (t != 0)
                got[1] = thx_read_exact(fd, (char *)y->block + half, bytes - half, (off_t)(sizeof head + half)) &&
                         thx_read_exact(fd, sum, sizeof sum, (off_t)(sizeof head + bytes));
#pragma omp barrier
            if (got[0] && got[1]) {
                if (t != 1) {
                    thx_sha256_ctx h;
                    thx_sha256_init(&h);
                    thx_sha256_update(&h, hdr, sizeof hdr);
                    thx_sha256_update(&h, counts, sizeof counts);
                    thx_sha256_update(&h, y->block, bytes);
                    thx_sha256_final(&h, sum2);
                }
                if (t != 0) valid = symbolic_valid(y, n);
            }
        }
        ok = got[0] && got[1] && !memcmp(sum, sum2, 32) && valid;
    }
    close(fd);
    if (!ok) thx_chol_symbolic_free(y);
    else thx_cache_used(path);
    return ok;
}

void thx_chol_symbolic_keep(const char *dir, int64_t n, const unsigned char key[32], const thx_chol_symbolic *y,
                            char *note, size_t note_n)
{
    char path[4200];
    cache_path(path, sizeof path, dir, key, "symbolic");
    thx_cache_file cf;
    if (!thx_cache_create(&cf, dir, path, 8 + 32 + 4 * 8 + 2 * 8 + 8 * ((uint64_t)n + 3 * ((uint64_t)y->nsuper + 1) + y->ssize) + 32,
                          "the symbolic factor", note, note_n))
        return;
    FILE *f = cf.f;
    uint64_t hdr[4] = {(uint64_t)n, (uint64_t)y->nsuper, (uint64_t)y->ssize, (uint64_t)y->xsize};
    double counts[2] = {y->flops, y->lnz};
    size_t ns = (size_t)y->nsuper;
    unsigned char sum[32];
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, hdr, sizeof hdr);
    thx_sha256_update(&h, counts, sizeof counts);
    thx_sha256_update(&h, y->perm, (size_t)n * sizeof *y->perm);
    thx_sha256_update(&h, y->super, (ns + 1) * sizeof *y->super);
    thx_sha256_update(&h, y->pi, (ns + 1) * sizeof *y->pi);
    thx_sha256_update(&h, y->px, (ns + 1) * sizeof *y->px);
    thx_sha256_update(&h, y->rows, y->ssize * sizeof *y->rows);
    thx_sha256_final(&h, sum);
    int ok = fwrite(k_sym_magic, 1, 8, f) == 8 && fwrite(key, 1, 32, f) == 32 && fwrite(hdr, sizeof *hdr, 4, f) == 4 &&
             fwrite(counts, sizeof *counts, 2, f) == 2 && fwrite(y->perm, sizeof *y->perm, (size_t)n, f) == (size_t)n &&
             fwrite(y->super, sizeof *y->super, ns + 1, f) == ns + 1 && fwrite(y->pi, sizeof *y->pi, ns + 1, f) == ns + 1 &&
             fwrite(y->px, sizeof *y->px, ns + 1, f) == ns + 1 && fwrite(y->rows, sizeof *y->rows, y->ssize, f) == y->ssize &&
             fwrite(sum, 1, 32, f) == 32;
    thx_cache_commit(&cf, ok, dir, path, "the symbolic factor", note, note_n);
}

int thx_chol_symbolic_copy(thx_chol_symbolic *y, int64_t n, int64_t nsuper, const int64_t *perm, const int64_t *super,
                           const int64_t *pi, const int64_t *px, const int64_t *rows, size_t ssize, size_t xsize)
{
    memset(y, 0, sizeof *y);
    y->nsuper = nsuper;
    y->ssize = ssize;
    y->xsize = xsize;
    if (!symbolic_alloc(y, n)) return 0;
    size_t ns = (size_t)nsuper;
    memcpy(y->perm, perm, (size_t)n * sizeof *perm);
    memcpy(y->super, super, (ns + 1) * sizeof *super);
    memcpy(y->pi, pi, (ns + 1) * sizeof *pi);
    memcpy(y->px, px, (ns + 1) * sizeof *px);
    memcpy(y->rows, rows, ssize * sizeof *rows);
    return 1;
}
