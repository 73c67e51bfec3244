/* thx_pages_zeroed and thx_pages_free (thorax/core/pages.h): a block of at least the size asked for,
 * page-aligned, all zeros and already present (touching it faults no page in), on 1 and 2 threads; an empty
 * request is one page; the block written and given back. */
#include <stdint.h>
#include <stdio.h>
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
    thx_pages one;
    CHECK(thx_pages_zeroed(&one, 0, 1) == 0 && one.bytes == page);
    thx_pages_free(&one);
    thx_pages_free(&one); /* an empty block: nothing */
    return tl_finish();
}
