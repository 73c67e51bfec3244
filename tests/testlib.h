/* Minimal test harness: each check is counted; a test program exits non-zero
 * if any check failed and prints "N passed, N failed". */
#ifndef THORAX_TESTLIB_H
#define THORAX_TESTLIB_H
#include <math.h>
#include <stdio.h>

extern int tl_pass, tl_fail;
void tl_report_fail(const char *file, int line, const char *what);
int tl_finish(void);

#define CHECK(cond)                                                            \
    do {                                                                       \
        if (cond) tl_pass++;                                                   \
        else { tl_fail++; tl_report_fail(__FILE__, __LINE__, #cond); }         \
    } while (0)
#define CHECK_NEAR(a, b, tol)                                                  \
    do {                                                                       \
        double tl_a_ = (a), tl_b_ = (b), tl_t_ = (tol);                        \
        if (fabs(tl_a_ - tl_b_) <= tl_t_) tl_pass++;                           \
        else {                                                                 \
            tl_fail++;                                                         \
            fprintf(stderr, "%s:%d: %s = %.17g, expected %s = %.17g (tol %g)\n", \
                    __FILE__, __LINE__, #a, tl_a_, #b, tl_b_, tl_t_);          \
        }                                                                      \
    } while (0)
/* A thx_status call that must succeed; prints the context's message if not. */
#define CHECK_OK(ctx, expr)                                                    \
    do {                                                                       \
        thx_status tl_s_ = (expr);                                             \
        if (tl_s_ == THX_OK) tl_pass++;                                        \
        else {                                                                 \
            tl_fail++;                                                         \
            fprintf(stderr, "%s:%d: %s failed: %s\n", __FILE__, __LINE__, #expr, \
                    thx_ctx_message(ctx));                                     \
        }                                                                      \
    } while (0)

/* ---- a scratch directory for a test program's files ---- */
#include <stddef.h>
#include "thorax/core/core.h"
extern char tl_scratch[1024];
/* Makes NAME.XXXXXX in the working directory as tl_scratch; 0, or -1 (printed). */
int tl_scratch_make(const char *name);
/* tl_finish(); then removes tl_scratch if every check passed, else says where its files are kept.
 * Returns tl_finish's exit code. */
int tl_scratch_finish(const char *name);
/* tl_scratch/file (eight rotating buffers: up to eight such paths may be in use at once). */
const char *tl_path(const char *file);
/* rel under the directory of the source file here (pass __FILE__: the tests' data, tests/data/..., and
 * the setup's ../../shared/data beside the checkout); eight rotating buffers, as tl_path. */
const char *tl_src_path(const char *here, const char *rel);
/* Writes the bytes or the text to path; exits the test on failure. */
void tl_write_bytes(const char *path, const void *data, size_t n);
void tl_write_text(const char *path, const char *text);
/* The file's bytes (NUL-terminated, *len without it; len may be NULL), or NULL. */
char *tl_slurp(thx_ctx *ctx, const char *path, size_t *len);
int tl_exists(const char *path);
/* Whether a file or directory whose name starts with prefix ("" for any) and holds ".tmp" or ".old"
 * is left in tl_scratch (a leaked temporary); each one found is named on stderr. */
int tl_leftover_tmp(const char *prefix);
/* Whether ctx's message holds needle; if not, both are printed. */
int tl_msg_has(thx_ctx *ctx, const char *needle);
/* The built-in phantom's surfaces at the default settings (thx_phantom_contours, then
 * thx_surfaces_build), as several tests start from them; NULL after a failed check. */
struct thx_model;
struct thx_model *tl_phantom_surfaces(thx_ctx *ctx);
#endif
