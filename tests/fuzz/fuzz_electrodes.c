/*
 * Fuzz harness: an electrodes file (thx_electrodes_read).
 * Properties of an accepted set: at least one electrode and no more than the
 * file's bytes can hold (an electrode line "A 1 0 0 0" takes at least 10
 * bytes), names NUL-terminated and unique, 0-based nodes >= 0 or THX_ELECTRODE_OFF_NODE (a "-"), finite
 * positions, and a write/read round trip that keeps names, nodes and the
 * positions to the written precision.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("e.txt", data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_electrodes *e = NULL;
    if (thx_electrodes_read(ctx, path, &e) == THX_OK) {
        FUZZ_ASSERT(e->n >= 1 && e->n <= size / 10);
        FUZZ_ASSERT(memchr(e->surface, 0, sizeof e->surface));
        for (size_t i = 0; i < e->n; i++) {
            FUZZ_ASSERT(memchr(e->name[i], 0, sizeof e->name[i]) && e->name[i][0]);
            FUZZ_ASSERT((e->node[i] >= 0 || e->node[i] == THX_ELECTRODE_OFF_NODE) && e->node[i] < INT32_MAX);
            for (int k = 0; k < 3; k++) FUZZ_ASSERT(isfinite(e->xyz[3 * i + k]));
            for (size_t j = 0; j < i; j++) FUZZ_ASSERT(strcmp(e->name[i], e->name[j]) != 0);
        }
        char p[512];
        snprintf(p, sizeof p, "%s/r.txt", fuzz_dir());
        FUZZ_ASSERT(thx_electrodes_write(ctx, e, p) == THX_OK);
        thx_electrodes *r = NULL;
        FUZZ_ASSERT(thx_electrodes_read(ctx, p, &r) == THX_OK);
        FUZZ_ASSERT(r->n == e->n && !strcmp(r->surface, e->surface));
        for (size_t i = 0; i < e->n; i++) {
            FUZZ_ASSERT(!strcmp(r->name[i], e->name[i]) && r->node[i] == e->node[i]);
            for (int k = 0; k < 3; k++)
                FUZZ_ASSERT(fabs(r->xyz[3 * i + k] - e->xyz[3 * i + k]) <= 5e-7 * (1 + fabs(e->xyz[3 * i + k])));
        }
        thx_electrodes_destroy(&r);
    }
    thx_electrodes_destroy(&e);
    thx_ctx_destroy(&ctx);
    return 0;
}
