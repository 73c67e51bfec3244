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
#endif
