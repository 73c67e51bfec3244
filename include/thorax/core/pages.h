/*
 * thorax/core/pages.h — large blocks of zeros whose pages are in memory before they are used.
 *
 * A page of fresh memory costs a fault on its first touch: about 2 microseconds each on this project's
 * virtual machines, 0.45 CPU-seconds for the 730 MB of the high phantom's factor written front by front.
 * Asked of the kernel for a whole block at once (MADV_POPULATE_WRITE, Linux 5.14), the same pages cost
 * about half as much, and the block is known to hold zeros, so the factorization need not clear it
 * (docs/design/parallel.md, "The factor's pages asked for at once").
 */
#ifndef THORAX_CORE_PAGES_H
#define THORAX_CORE_PAGES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    void *p;      /* the block (page-aligned), or NULL */
    size_t bytes; /* its length as mapped (a whole number of pages) */
} thx_pages;

/* At least bytes bytes of zeros, their pages made present by `threads` threads (OpenMP) sharing the
 * block; where the kernel cannot (an older kernel, another system), by writing zeros. Returns 0, or
 * -1 with out->p NULL when no memory could be had. */
int thx_pages_zeroed(thx_pages *out, size_t bytes, int threads);

/* The pages under [p, p + bytes) made present for writing, their contents unchanged (the whole pages the
 * range touches: they must all be this process's, as any block from malloc is). For memory known to hold
 * zeros (fresh from calloc) that is about to be written: the kernel's work without a fault per page, and
 * no pass of zeros over it. Returns 0, or -1 where the kernel cannot (nothing done: the caller writes its
 * zeros itself). */
int thx_pages_present(void *p, size_t bytes);

/* The block made bytes long (moved if it must), its pages kept with their contents; the pages added are
 * fresh (zeros, not yet present). Returns 0, or -1 with the block as it was. */
int thx_pages_grow(thx_pages *pg, size_t bytes);

/* The block given back to the system (nothing for a NULL block); out is emptied. */
void thx_pages_free(thx_pages *pg);

#ifdef __cplusplus
}
#endif

#endif
