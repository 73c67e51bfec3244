/* The context: last error message and log sink (see thorax/core/core.h). */
#include "thorax/core/core.h"
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct thx_ctx {
    char message[2048];
    thx_log_fn log_fn;
    void *log_user;
    thx_log_level log_min;
    char **inputs;        /* the running command's input files and directories (thx_ctx_add_input) */
    size_t n_inputs;
};

thx_status thx_ctx_create(thx_ctx **out)
{
    *out = calloc(1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

void thx_ctx_destroy(thx_ctx **ctx)
{
    if (!ctx || !*ctx) return;
    for (size_t i = 0; i < (*ctx)->n_inputs; i++) free((*ctx)->inputs[i]);
    free((*ctx)->inputs);
    free(*ctx);
    *ctx = NULL;
}

thx_status thx_ctx_add_input(thx_ctx *ctx, const char *path)
{
    if (!path) return THX_OK;
    char **q = realloc(ctx->inputs, (ctx->n_inputs + 1) * sizeof *q);
    if (!q) return thx_error(ctx, THX_ENOMEM, "out of memory");
    ctx->inputs = q;
    size_t n = strlen(path) + 1;
    if (!(q[ctx->n_inputs] = malloc(n))) return thx_error(ctx, THX_ENOMEM, "out of memory");
    memcpy(q[ctx->n_inputs++], path, n);
    return THX_OK;
}

const char *const *thx_ctx_inputs(const thx_ctx *ctx, size_t *n)
{
    *n = ctx->n_inputs;
    return (const char *const *)ctx->inputs;
}

void thx_ctx_set_log(thx_ctx *ctx, thx_log_fn fn, void *user, thx_log_level min_level)
{
    ctx->log_fn = fn;
    ctx->log_user = user;
    ctx->log_min = min_level;
}

thx_status thx_error(thx_ctx *ctx, thx_status code, const char *fmt, ...)
{
    /* formatted apart, then copied: an argument may be the message already there (a caller quoting
       the reason a call below gave), which vsnprintf must not read while it writes over it */
    char text[sizeof ctx->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    memcpy(ctx->message, text, sizeof text);
    return code;
}

const char *thx_ctx_message(const thx_ctx *ctx) { return ctx->message; }

void thx_ctx_clear(thx_ctx *ctx) { ctx->message[0] = '\0'; }

void thx_log(thx_ctx *ctx, thx_log_level level, const char *fmt, ...)
{
    if (!ctx->log_fn || level < ctx->log_min) return;
    char buf[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    ctx->log_fn(ctx->log_user, level, buf);
}

const char *thx_status_name(thx_status s)
{
    switch (s) {
    case THX_OK: return "ok";
    case THX_ENOMEM: return "out of memory";
    case THX_EIO: return "i/o error";
    case THX_EINPUT: return "input error";
    case THX_EGEOM: return "geometry error";
    case THX_ESOLVER: return "solver error";
    case THX_EINTERNAL: return "internal error";
    case THX_ECHECK: return "check failed";
    }
    return "unknown error";
}

void *thx_malloc(thx_ctx *ctx, size_t size)
{
    void *p = malloc(size ? size : 1);
    if (!p) thx_error(ctx, THX_ENOMEM, "out of memory (%zu bytes)", size);
    return p;
}

void *thx_calloc(thx_ctx *ctx, size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size ? size : 1);
    if (!p) thx_error(ctx, THX_ENOMEM, "out of memory (%zu x %zu bytes)", n, size);
    return p;
}

void *thx_realloc(thx_ctx *ctx, void *p, size_t size)
{
    void *q = realloc(p, size ? size : 1);
    if (!q) thx_error(ctx, THX_ENOMEM, "out of memory (%zu bytes)", size);
    return q;
}

thx_status thx_grow(thx_ctx *ctx, void **arr, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return THX_OK;
    /* The doubling and the byte count must not wrap (a count read from a file can be anything). */
    if (elem == 0 || need > SIZE_MAX / 2 / elem)
        return thx_error(ctx, THX_ENOMEM, "out of memory: %zu items of %zu bytes", need, elem);
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need) ncap *= 2;
    void *q = thx_realloc(ctx, *arr, ncap * elem);
    if (!q) return THX_ENOMEM;
    *arr = q;
    *cap = ncap;
    return THX_OK;
}

double thx_wtime(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
