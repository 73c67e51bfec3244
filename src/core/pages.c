/* Large blocks of zeros whose pages are in memory before they are used (thorax/core/pages.h). */
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "thorax/core/pages.h"

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23 /* Linux 5.14 */
#endif

static size_t page_size(void)
{
    long ps = sysconf(_SC_PAGESIZE);
    return ps > 0 ? (size_t)ps : 4096;
}

/* bytes (at least 1) rounded up to whole pages into *n; -1 when that overflows */
static int whole_pages(size_t bytes, size_t *n)
{
    const size_t page = page_size();
    size_t m = (bytes ? bytes : 1) + page - 1;
    if (m < bytes) return -1;
    *n = m - m % page;
    return 0;
}

int thx_pages_zeroed(thx_pages *out, size_t bytes, int threads)
{
    out->p = NULL;
    out->bytes = 0;
    size_t n;
    if (whole_pages(bytes, &n)) return -1;
    void *p = mmap(NULL, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return -1;
    /* in pieces of 8 MB dealt to the threads: the kernel's work per page is the same, and a thread is not
       held in one call for long */
    const size_t piece = (size_t)8 << 20;
    const size_t np = (n + piece - 1) / piece;
    int T = threads > 1 ? threads : 1;
    (void)T;
#pragma omp parallel for num_threads(T) schedule(dynamic, 1)
    for (size_t k = 0; k < np; k++) {
        char *a = (char *)p + k * piece;
        size_t len = k + 1 < np ? piece : n - k * piece;
        if (madvise(a, len, MADV_POPULATE_WRITE) != 0) memset(a, 0, len); /* zero already: written to be present */
    }
    out->p = p;
    out->bytes = n;
    return 0;
}

int thx_pages_present(void *p, size_t bytes)
{
    if (!bytes) return 0;
    uintptr_t page = page_size(), a = (uintptr_t)p, b = a + bytes;
    a -= a % page;
    b += (page - b % page) % page;
    return madvise((void *)a, b - a, MADV_POPULATE_WRITE) == 0 ? 0 : -1;
}

int thx_pages_grow(thx_pages *pg, size_t bytes)
{
    size_t n;
    if (whole_pages(bytes, &n)) return -1;
    if (!pg->p) {
        void *p = mmap(NULL, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) return -1;
        pg->p = p;
        pg->bytes = n;
        return 0;
    }
    if (n <= pg->bytes) return 0;
    void *q = mremap(pg->p, pg->bytes, n, MREMAP_MAYMOVE);
    if (q == MAP_FAILED) return -1;
    pg->p = q;
    pg->bytes = n;
    return 0;
}

void thx_pages_free(thx_pages *pg)
{
    if (pg->p) munmap(pg->p, pg->bytes);
    pg->p = NULL;
    pg->bytes = 0;
}
