/* thx_pages_zeroed and thx_pages_free (thorax/core/pages.h): a block of at least the size asked for,
 * page-aligned, all zeros and already present (touching it faults no page in), on 1 and 2 threads; an empty
 * request is one page; the block written and given back. thx_pages_present: a range of malloc's memory,
 * not page-aligned, made present with its bytes unchanged. thx_pages_grow: a block made longer keeps its
 * bytes, the part added is zeros; an empty block grows from nothing. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/pages.h"

static long minor_faults(void)
{
    struct rusage r;
    getrusage(RUSAGE_SELF, &r);
    return r.ru_minflt;
}

int main(void)
{
    const size_t page = (size_t)sysconf(_SC_PAGESIZE);
    for (int threads = 1; threads <= 2; threads++) {
        const size_t bytes = ((size_t)40 << 20) + 12345; /* 40 MB and a piece: more than one of its 8 MB pieces */
        thx_pages pg;
        CHECK(thx_pages_zeroed(&pg, bytes, threads) == 0);
        CHECK(pg.p != NULL && pg.bytes >= bytes && pg.bytes % page == 0 && (uintptr_t)pg.p % page == 0);
        long before = minor_faults();
        const unsigned char *b = pg.p;
        size_t nonzero = 0;
        for (size_t i = 0; i < pg.bytes; i++) nonzero += b[i] != 0;
        memset(pg.p, 0xab, pg.bytes);
        long faults = minor_faults() - before;
        printf("%d thread(s): %zu bytes, %zu nonzero, %ld page faults reading and writing %zu pages\n", threads, pg.bytes,
               nonzero, faults, pg.bytes / page);
        CHECK(nonzero == 0);
        /* present already: the pass over 10,000 pages faults in none of them, where a block fresh from mmap
           would fault in every one (the kernel may refuse the populate on an old kernel: then the block was
           written instead, present just the same). Under AddressSanitizer the pass also touches its shadow,
           an eighth of the block's pages, for the first time: the bound leaves room for that alone. */
        CHECK(faults < (long)(pg.bytes / page) / 4);
        thx_pages_free(&pg);
        CHECK(pg.p == NULL && pg.bytes == 0);
    }
    /* present: 20 MB of malloc's, from an odd address, written first then made present: unchanged, and a pass
       over the fresh part after it faults in few pages */
    {
        const size_t n = ((size_t)20 << 20) + 333;
        unsigned char *m = malloc(n);
        CHECK(m != NULL);
        if (m) {
            for (size_t i = 0; i < n / 2; i++) m[i] = (unsigned char)(i * 7 + 1);
            CHECK(thx_pages_present(m + 5, n - 5) == 0);
            CHECK(thx_pages_present(m, 0) == 0);
            size_t bad = 0;
            for (size_t i = 0; i < n / 2; i++) bad += m[i] != (unsigned char)(i * 7 + 1);
            CHECK(bad == 0);
            long before = minor_faults();
            memset(m + n / 2, 0x5a, n - n / 2);
            long faults = minor_faults() - before;
            printf("present: %zu bytes of malloc's unchanged, %ld page faults writing the %zu pages after\n", n, faults,
                   (n - n / 2) / page);
            CHECK(faults < (long)((n - n / 2) / page) / 4);
            free(m);
        }
    }
    /* grow: 3 pages written, made 5 MB: the 3 pages kept, the rest zeros; then an empty block grown */
    {
        thx_pages g;
        CHECK(thx_pages_zeroed(&g, 3 * page, 1) == 0);
        memset(g.p, 0x77, 3 * page);
        CHECK(thx_pages_grow(&g, (size_t)5 << 20) == 0 && g.bytes >= ((size_t)5 << 20) && g.bytes % page == 0);
        const unsigned char *b = g.p;
        size_t bad = 0;
        for (size_t i = 0; i < g.bytes; i++) bad += b[i] != (i < 3 * page ? 0x77 : 0);
        CHECK(bad == 0);
        CHECK(thx_pages_grow(&g, page) == 0 && g.bytes >= ((size_t)5 << 20)); /* never shrinks */
        thx_pages_free(&g);
        thx_pages e = {NULL, 0};
        CHECK(thx_pages_grow(&e, 100) == 0 && e.p != NULL && e.bytes == page && ((unsigned char *)e.p)[99] == 0);
        thx_pages_free(&e);
    }
    thx_pages one;
    CHECK(thx_pages_zeroed(&one, 0, 1) == 0 && one.bytes == page);
    thx_pages_free(&one);
    thx_pages_free(&one); /* an empty block: nothing */
    return tl_finish();
}
