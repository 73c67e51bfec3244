/*
 * The direct path's cache (docs/design/parallel.md, "thorax's own direct path" and "The symbolic factor
 * kept"): what depends on a matrix's graph alone, computed on a first run and kept in the user's cache
 * directory for the next ones. Each file is written to a temporary name and renamed; each is read only
 * when its magic, its key, its sizes and its own SHA-256 match (and, for the symbolic factor, when its
 * structure is one), else ignored and computed again. Built into the solver module with
 * src/fem/cholesky.c, its one user. The directory and its size: thorax/core/cache.h.
 *  - ordering-KEY.bin: the fill-reducing ordering (METIS nested dissection), KEY the graph's SHA-256;
 *  - symbolic-KEY.bin: CHOLMOD's supernodal analysis with that ordering (its permutation, supernodes,
 *    their rows and values' places, the flop and nonzero counts), KEY the SHA-256 of the graph's key
 *    and the ordering.
 */
#ifndef THORAX_FEM_CHOL_CACHE_H
#define THORAX_FEM_CHOL_CACHE_H

#include <stddef.h>
#include <stdint.h>

/* The graph's key: SHA-256 of a tag, n, the nonzeros' count and the SHA-256 of two halves of rowp and col
 * (a full CSR's pattern), those two side by side. */
void thx_chol_graph_key(int64_t n, const int64_t *rowp, const int32_t *col, unsigned char key[32]);

/* The ordering kept for key: 1 and perm filled, or 0 (missing, another graph, damaged). */
int thx_chol_order_cached(const char *dir, int64_t n, const unsigned char key[32], int64_t *perm);
/* Keeps it; a note on failure (none on success). */
void thx_chol_order_keep(const char *dir, int64_t n, const unsigned char key[32], const int64_t *perm, char *note,
                         size_t note_n);

/* A supernodal symbolic factor (the layout of src/fem/multifrontal.h), its arrays in one block. */
typedef struct {
    int64_t nsuper;
    size_t ssize, xsize;        /* row indices, values */
    double flops, lnz;          /* CHOLMOD's counts for the factorization */
    int64_t *perm;              /* n: row i of the factor is row perm[i] of the matrix */
    int64_t *super, *pi, *px;   /* nsuper + 1 each */
    int64_t *rows;              /* ssize */
    int64_t *block;
} thx_chol_symbolic;

/* Its key: SHA-256 of a tag, the graph's key and the ordering it was analysed with. */
void thx_chol_symbolic_key(const unsigned char graph[32], int64_t n, const int64_t *order, unsigned char key[32]);
/* The symbolic factor kept for key: 1 and y filled, or 0 (y empty). */
int thx_chol_symbolic_cached(const char *dir, int64_t n, const unsigned char key[32], thx_chol_symbolic *y);
/* Keeps it; a note on failure (none on success). */
void thx_chol_symbolic_keep(const char *dir, int64_t n, const unsigned char key[32], const thx_chol_symbolic *y,
                            char *note, size_t note_n);
/* y as a copy of the arrays given (CHOLMOD's analysis); 0 when out of memory. */
int thx_chol_symbolic_copy(thx_chol_symbolic *y, int64_t n, int64_t nsuper, const int64_t *perm, const int64_t *super,
                           const int64_t *pi, const int64_t *px, const int64_t *rows, size_t ssize, size_t xsize);
void thx_chol_symbolic_free(thx_chol_symbolic *y);

#endif
