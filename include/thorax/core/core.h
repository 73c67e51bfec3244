/*
 * thorax/core/core.h — the context, status codes and small utilities every module uses.
 *
 * Invariants:
 *  - Every fallible library call takes a thx_ctx * first and returns a thx_status.
 *    On failure the context holds one human-readable message naming file, line
 *    and object where they are known ("c.txt:42: surface \"lung_l\" layer 17: ...").
 *  - The library never prints and never exits; the CLI decides.
 *  - Units: millimetres; indices 0-based in memory.
 */
#ifndef THORAX_CORE_H
#define THORAX_CORE_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_OK = 0,
    THX_ENOMEM = 1,    /* allocation failed */
    THX_EIO = 2,       /* a file could not be read or written */
    THX_EINPUT = 3,    /* malformed or inconsistent input */
    THX_EGEOM = 4,     /* geometry that cannot be processed (degenerate, self-intersecting) */
    THX_ESOLVER = 5,   /* a numerical solver failed */
    THX_EINTERNAL = 6, /* an invariant of thorax itself was broken: a bug */
    THX_ECHECK = 7     /* a model failed its invariant checks */
} thx_status;

typedef enum { THX_LOG_DEBUG = 0, THX_LOG_INFO = 1, THX_LOG_WARN = 2 } thx_log_level;

typedef void (*thx_log_fn)(void *user, thx_log_level level, const char *message);

/* Opaque context: last error, log sink. Not shared between threads while a call runs. */
typedef struct thx_ctx thx_ctx;

/* Creates a context with no log sink (messages are dropped). Caller destroys it. */
thx_status thx_ctx_create(thx_ctx **out);
/* Destroys *ctx (NULL accepted) and sets *ctx to NULL. */
void thx_ctx_destroy(thx_ctx **ctx);
/* Directs log messages at or above min_level to fn(user, level, message). */
void thx_ctx_set_log(thx_ctx *ctx, thx_log_fn fn, void *user, thx_log_level min_level);

/* Records an error message (printf format) in ctx and returns code, so that
 * `return thx_error(ctx, THX_EINPUT, "%s:%d: ...", path, line);` reads naturally. An argument may be
 * thx_ctx_message(ctx) itself (the message is formatted before it is replaced). */
thx_status thx_error(thx_ctx *ctx, thx_status code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The last error message ("" if none). Owned by ctx, valid until the next call. */
const char *thx_ctx_message(const thx_ctx *ctx);
/* Records a file the running command reads: no single-file output (thx_output_claim in
 * thorax/core/fileio.h) may replace it. The CLI registers each command's input files; directory
 * outputs name their inputs explicitly (a mesh may be written into its own model). */
thx_status thx_ctx_add_input(thx_ctx *ctx, const char *path);
/* The inputs recorded so far (n of them; owned by ctx). */
const char *const *thx_ctx_inputs(const thx_ctx *ctx, size_t *n);
/* Clears the last error message. */
void thx_ctx_clear(thx_ctx *ctx);
/* Logs a message (printf format) through the context's sink. */
void thx_log(thx_ctx *ctx, thx_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Name of a status code ("input error", ...). Static storage. */
const char *thx_status_name(thx_status s);

/* Propagate a failure: returns from the enclosing function. */
#define THX_CHECK(expr)                   \
    do {                                  \
        thx_status thx_s_ = (expr);       \
        if (thx_s_ != THX_OK) return thx_s_; \
    } while (0)
/* Propagate a failure through cleanup: needs `thx_status st` and a `done:` label. */
#define THX_TRY(expr)                     \
    do {                                  \
        st = (expr);                      \
        if (st != THX_OK) goto done;      \
    } while (0)

/* malloc/calloc/realloc that record THX_ENOMEM in ctx on failure (returning NULL). */
void *thx_malloc(thx_ctx *ctx, size_t size);
void *thx_calloc(thx_ctx *ctx, size_t n, size_t size);
void *thx_realloc(thx_ctx *ctx, void *p, size_t size);
/* Grows *arr (element size elem) so it holds at least need elements; *cap is updated. */
thx_status thx_grow(thx_ctx *ctx, void **arr, size_t *cap, size_t need, size_t elem);

/* Monotonic wall clock in seconds. */
double thx_wtime(void);

/* Optimal string alignment distance between a and b (insertions, deletions, substitutions,
 * adjacent swaps), for "did you mean" suggestions; 64 when either is longer than 63 bytes. */
size_t thx_name_distance(const char *a, const char *b);

#ifdef __cplusplus
}
#endif
#endif
