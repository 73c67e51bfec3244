/*
 * The ranks of a run under mpirun (thorax/parallel/parallel.h): the launcher's environment read
 * here, the MPI calls made through the solver module's table (src/parallel/mpi_module.h), and
 * sort-first's gather of the pixels each rank drew.
 */
#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "parallel/mpi_module.h"
#include "thorax/core/module.h"
#include "thorax/parallel/parallel.h"

_Static_assert(sizeof(size_t) == sizeof(unsigned long long), "gather_size sends size_t as MPI_UNSIGNED_LONG_LONG");

static const thx_par_mpi *volatile g_api;
static int g_rank = 0, g_size = 1, g_started = 0, g_running = 0;
static int g_origin = -1; /* the rank of the first failure the ranks agreed on (thx_par_failed_first) */

/* A positive count from the environment variable name; -1 when unset, 0 when not a count. */
static long env_count(const char *name)
{
    const char *s = getenv(name);
    if (!s) return -1;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    return end == s || *end || errno || v < 1 || v > INT_MAX ? 0 : v;
}

int thx_par_launched(void)
{
    static const char *names[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};
    for (int k = 0; k < 3; k++) {
        long v = env_count(names[k]);
        if (v >= 0) return (int)v;
    }
    return 1;
}

int thx_par_launched_rank(void)
{
    static const char *names[] = {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"};
    for (int k = 0; k < 3; k++) {
        const char *s = getenv(names[k]);
        if (s) return atoi(s);
    }
    return 0;
}

/* MPI's failure rc as THX_ESOLVER in ctx, doing what. */
static thx_status mpi_fail(thx_ctx *ctx, int rc, const char *what)
{
    char why[512];
    g_api->error_string(rc, why, sizeof why);
    return thx_error(ctx, THX_ESOLVER, "MPI, %s (rank %d of %d): %s", what, g_rank, g_size, why);
}

thx_status thx_par_start(thx_ctx *ctx, int *rank, int *size)
{
    int n = thx_par_launched();
    if (n == 0)
        return thx_error(ctx, THX_EINPUT, "the launcher's rank count (OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_SIZE) is not a "
                         "positive number");
    if (n > 1 && !g_running) {
        if (!thx_solver_module_table(ctx, "thx_par_mpi_get", THX_PAR_MPI_ABI, (const void *volatile *)&g_api))
            return thx_error(ctx, THX_ESOLVER, "started by mpirun with %d ranks, but MPI cannot be reached: %s", n,
                             thx_ctx_message(ctx));
        int rc = g_api->init(&g_rank, &g_size, &g_started);
        if (rc) return mpi_fail(ctx, rc, "starting");
        g_running = 1;
        if (g_size != n)
            return thx_error(ctx, THX_ESOLVER, "the launcher started %d ranks, but MPI's world has %d (two launchers' "
                             "environments?)", n, g_size);
    }
    if (rank) *rank = g_rank;
    if (size) *size = g_size;
    return THX_OK;
}

int thx_par_rank(void) { return g_rank; }
int thx_par_size(void) { return g_size; }

void thx_par_end(void)
{
    if (g_running && g_started) g_api->finalize();
    g_running = 0;
}

thx_status thx_par_agree(thx_ctx *ctx, thx_status st, int *failed_rank)
{
    if (failed_rank) *failed_rank = st != THX_OK ? g_rank : -1;
    if (!g_running) return st;
    int first = st != THX_OK ? g_rank : INT_MAX;
    int rc = g_api->min_int(&first, 1);
    if (rc) return st != THX_OK ? st : mpi_fail(ctx, rc, "agreeing on the ranks' results");
    if (failed_rank) *failed_rank = first == INT_MAX ? -1 : first;
    if (first == INT_MAX) return st;
    /* the first agreement that meets a failure meets only the ranks' own (every one before it agreed on
       success): its lowest failed rank is the one whose message is the story, later ones echo it */
    if (g_origin < 0) g_origin = first;
    /* the first failed rank's status, to every rank (the failed ones too: a collective) */
    int code = g_rank == first ? (int)st : 0;
    rc = g_api->max_int(&code, 1);
    if (st != THX_OK) return st;
    if (rc) return mpi_fail(ctx, rc, "agreeing on the ranks' results");
    return thx_error(ctx, code > 0 ? (thx_status)code : THX_EINTERNAL, "rank %d of %d failed (its message above)", first, g_size);
}

thx_status thx_par_bcast(thx_ctx *ctx, void *buf, size_t n, int root)
{
    if (!g_running) return THX_OK;
    int rc = g_api->bcast(buf, n, root);
    return rc ? mpi_fail(ctx, rc, "broadcasting") : THX_OK;
}

thx_status thx_par_sum(thx_ctx *ctx, long long *v, int n)
{
    if (!g_running) return THX_OK;
    int rc = g_api->sum_ll(v, n);
    return rc ? mpi_fail(ctx, rc, "summing over the ranks") : THX_OK;
}

thx_status thx_par_barrier(thx_ctx *ctx)
{
    if (!g_running) return THX_OK;
    int rc = g_api->barrier();
    return rc ? mpi_fail(ctx, rc, "waiting for every rank") : THX_OK;
}

thx_status thx_par_gather(thx_ctx *ctx, thx_status st, const void *send, size_t n, void **all, size_t **counts)
{
    *all = NULL;
    *counts = NULL;
    if (!g_running || g_size == 1) {
        if (st != THX_OK) return st;
        *all = thx_malloc(ctx, n ? n : 1);
        *counts = thx_malloc(ctx, sizeof **counts);
        if (!*all || !*counts) {
            free(*all);
            free(*counts);
            *all = NULL;
            *counts = NULL;
            return THX_ENOMEM;
        }
        if (n) memcpy(*all, send, n);
        **counts = n;
        return THX_OK;
    }
    size_t *cnt = NULL, total = 0;
    unsigned char *buf = NULL;
    if (st == THX_OK && g_rank == 0 && !(cnt = thx_calloc(ctx, (size_t)g_size, sizeof *cnt))) st = THX_ENOMEM;
    THX_TRY(thx_par_agree(ctx, st, NULL));
    int rc = g_api->gather_size(n, cnt, 0);
    if (rc) {
        st = mpi_fail(ctx, rc, "gathering the sizes");
        goto done;
    }
    if (g_rank == 0) {
        for (int r = 0; r < g_size; r++) total += cnt[r];
        if (!(buf = malloc(total ? total : 1))) st = thx_error(ctx, THX_ENOMEM, "out of memory (%zu bytes gathered)", total);
    }
    THX_TRY(thx_par_agree(ctx, st, NULL));
    rc = g_api->gatherv(send, n, buf, cnt, 0);
    if (rc) {
        st = mpi_fail(ctx, rc, "gathering");
        goto done;
    }
    if (g_rank == 0) {
        *all = buf;
        *counts = cnt;
        buf = NULL;
        cnt = NULL;
    }
done:
    free(buf);
    free(cnt);
    return st;
}

/* A rank's share of a picture, as sent: n_runs, then n_runs (first pixel, pixel count) pairs, then
 * the runs' pixels, 4 bytes each. */
typedef struct {
    uint64_t n_runs;
} share_head;

/* Packs the pixels where own[] is set; NULL with THX_ENOMEM in ctx. */
static unsigned char *pack(thx_ctx *ctx, const unsigned char *rgba, const unsigned char *own, size_t n_pix, size_t *len)
{
    size_t n_runs = 0, n_own = 0;
    for (size_t i = 0; i < n_pix; i++) {
        n_runs += own[i] && (i == 0 || !own[i - 1]);
        n_own += own[i] != 0;
    }
    *len = sizeof(share_head) + n_runs * 2 * sizeof(uint32_t) + 4 * n_own;
    unsigned char *buf = thx_malloc(ctx, *len);
    if (!buf) return NULL;
    share_head hd = {n_runs};
    memcpy(buf, &hd, sizeof hd);
    uint32_t *runs = (uint32_t *)(buf + sizeof hd);
    unsigned char *px = buf + sizeof hd + n_runs * 2 * sizeof(uint32_t);
    size_t r = 0;
    for (size_t i = 0; i < n_pix;) {
        if (!own[i]) { i++; continue; }
        size_t j = i;
        while (j < n_pix && own[j]) j++;
        runs[2 * r] = (uint32_t)i;
        runs[2 * r + 1] = (uint32_t)(j - i);
        memcpy(px, rgba + 4 * i, 4 * (j - i));
        px += 4 * (j - i);
        r++;
        i = j;
    }
    return buf;
}

/* Rank 0: rank r's share (len bytes) into rgba, every pixel checked against own (overlap, bounds). */
static thx_status unpack(thx_ctx *ctx, int r, const unsigned char *buf, size_t len, unsigned char *rgba, unsigned char *own,
                         size_t n_pix)
{
    share_head hd;
    if (len < sizeof hd) return thx_error(ctx, THX_EINTERNAL, "sort-first: rank %d sent %zu bytes, not a share", r, len);
    memcpy(&hd, buf, sizeof hd);
    if (hd.n_runs > (len - sizeof hd) / (2 * sizeof(uint32_t)))
        return thx_error(ctx, THX_EINTERNAL, "sort-first: rank %d's share names %llu runs in %zu bytes", r,
                         (unsigned long long)hd.n_runs, len);
    const unsigned char *runs = buf + sizeof hd, *px = runs + hd.n_runs * 2 * sizeof(uint32_t), *end = buf + len;
    for (uint64_t k = 0; k < hd.n_runs; k++) {
        uint32_t rr[2];
        memcpy(rr, runs + 8 * k, sizeof rr);
        size_t first = rr[0], n = rr[1];
        if (first > n_pix || n > n_pix - first || (size_t)(end - px) < 4 * n)
            return thx_error(ctx, THX_EINTERNAL, "sort-first: rank %d's run %llu (pixels %zu + %zu) leaves the %zu-pixel "
                             "picture or its share", r, (unsigned long long)k, first, n, n_pix);
        for (size_t i = first; i < first + n; i++) {
            if (own[i])
                return thx_error(ctx, THX_EINTERNAL, "sort-first: pixel %zu drawn by rank %d and by another rank", i, r);
            own[i] = 1;
        }
        memcpy(rgba + 4 * first, px, 4 * n);
        px += 4 * n;
    }
    if (px != end) return thx_error(ctx, THX_EINTERNAL, "sort-first: rank %d sent %zu bytes more than its runs", r, (size_t)(end - px));
    return THX_OK;
}

thx_status thx_par_gather_pixels(thx_ctx *ctx, unsigned char *rgba, unsigned char *own, int w, int h)
{
    if (!g_running || g_size == 1) return THX_OK;
    size_t n_pix = (size_t)w * (size_t)h;
    thx_status st = THX_OK;
    size_t len = 0, *counts = NULL, total = 0;
    unsigned char *buf = NULL, *all = NULL;
    if (n_pix > UINT32_MAX) st = thx_error(ctx, THX_EINPUT, "sort-first: a %d x %d picture (at most 2^32 pixels)", w, h);
    if (st == THX_OK) buf = pack(ctx, rgba, own, n_pix, &len);
    if (st == THX_OK && !buf) st = THX_ENOMEM;
    if (st == THX_OK && g_rank == 0 && !(counts = thx_calloc(ctx, (size_t)g_size, sizeof *counts))) st = THX_ENOMEM;
    /* every rank knows of any failure before the gather */
    THX_TRY(thx_par_agree(ctx, st, NULL));
    int rc = g_api->gather_size(len, counts, 0);
    if (rc) { st = mpi_fail(ctx, rc, "gathering the shares' sizes"); goto done; }
    int ok = 1;
    if (g_rank == 0) {
        for (int r = 0; r < g_size; r++) total += counts[r];
        all = malloc(total ? total : 1);
        ok = all != NULL;
    }
    THX_TRY(thx_par_agree(ctx, ok ? THX_OK : thx_error(ctx, THX_ENOMEM, "sort-first: out of memory (%zu bytes of shares)", total), NULL));
    rc = g_api->gatherv(buf, len, all, counts, 0);
    if (rc) { st = mpi_fail(ctx, rc, "gathering the pixels"); goto done; }
    if (g_rank == 0) {
        size_t at = counts[0];
        for (int r = 1; r < g_size && st == THX_OK; r++) {
            st = unpack(ctx, r, all + at, counts[r], rgba, own, n_pix);
            at += counts[r];
        }
    }
done:
    free(buf);
    free(all);
    free(counts);
    return st;
}

/* One composite (the ranks agree on any failure first, so that none waits in IceT for one gone). */
static thx_status composite(thx_ctx *ctx, int mode, void *color, float *depth, int w, int h, const int *order)
{
    if (!g_running || g_size == 1) return THX_OK;
    if (w <= 0 || h <= 0 || (size_t)w * (size_t)h > (size_t)INT_MAX / 16)
        return thx_par_agree(ctx, thx_error(ctx, THX_EINPUT, "sort-last: a %d x %d picture cannot be composited", w, h), NULL);
    char why[512] = "";
    int rc = g_api->composite(mode, w, h, NULL, NULL, NULL, why, sizeof why);
    thx_status st = rc ? thx_error(ctx, THX_ESOLVER, "sort-last compositing (rank %d of %d): %s", g_rank, g_size, why) : THX_OK;
    THX_CHECK(thx_par_agree(ctx, st, NULL));
    rc = g_api->composite(mode, w, h, color, depth, order, why, sizeof why);
    st = rc ? thx_error(ctx, THX_ESOLVER, "sort-last compositing (rank %d of %d): %s", g_rank, g_size, why) : THX_OK;
    return thx_par_agree(ctx, st, NULL);
}

thx_status thx_par_composite_depth(thx_ctx *ctx, unsigned char *rgba, float *depth, int w, int h)
{
    return composite(ctx, THX_PAR_COMPOSITE_DEPTH, rgba, depth, w, h, NULL);
}

thx_status thx_par_composite_blend(thx_ctx *ctx, float *rgba, int w, int h, const int *order)
{
    if (g_running && g_size > 1) { /* every rank once */
        unsigned char *seen = calloc((size_t)g_size, 1);
        int ok = seen != NULL;
        for (int k = 0; ok && k < g_size; k++) {
            ok = order[k] >= 0 && order[k] < g_size && !seen[order[k]];
            if (ok) seen[order[k]] = 1;
        }
        free(seen);
        if (!ok)
            return thx_par_agree(ctx, thx_error(ctx, THX_EINTERNAL, "sort-last: the blending order does not name every rank "
                                                "once"), NULL);
    }
    return composite(ctx, THX_PAR_COMPOSITE_BLEND, rgba, NULL, w, h, order);
}

thx_status thx_par_max(thx_ctx *ctx, thx_status st, double *v, int n)
{
    if (!g_running || g_size == 1) return st;
    if (n < 0 || n > 64) return thx_par_agree(ctx, thx_error(ctx, THX_EINTERNAL, "thx_par_max: %d values (at most 64)", n), NULL);
    THX_CHECK(thx_par_agree(ctx, st, NULL));
    double buf[64];
    if (n) memcpy(buf, v, (size_t)n * sizeof *v);
    int rc = g_api->max_dbl(buf, n);
    if (rc) return mpi_fail(ctx, rc, "the largest values over the ranks");
    if (n) memcpy(v, buf, (size_t)n * sizeof *v);
    return THX_OK;
}

int thx_par_failed_first(void) { return g_origin; }
