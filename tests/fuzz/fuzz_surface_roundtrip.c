/*
 * Fuzz harness: every surface writer round-trips what it accepts, or refuses it (issue 24:
 * coordinates of 1e56 and more were cut at 63 characters, and STL wrote inf, which thorax then
 * refused). The input's bytes are the 12 coordinates of a tetrahedron, as raw doubles (zeros
 * past the end of the input); the tetrahedron is written by each writer (thx_surface_export
 * as vtk, vtp, obj, ply and stl; thx_surface_write_ptsfac) and read back by thorax's own reader
 * of that format (thx_surface_read_file). Properties:
 *  - a non-finite coordinate is refused by every writer, and no file is left;
 *  - finite coordinates are accepted by every text writer, and STL accepts them exactly when
 *    every one is within float32's range;
 *  - what a writer accepted reads back: the same triangles, each corner where it was: exactly
 *    from 1e15 mm on ("%.17g"), within 5e-7 mm plus half an ulp below ("%.6f", the model's
 *    resolution), and as the nearest float in STL.
 */
#include <float.h>
#include <math.h>
#include <unistd.h>

#include "fuzz.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/surface_read.h"
#include "thorax/model/model.h"

static const int32_t tet[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

/* Whether b is what the writer's text makes of a. */
static int same_text(double a, double b)
{
    if (fabs(a) >= 1e15) return a == b;
    return fabs(a - b) <= 5e-7 + fabs(a) * DBL_EPSILON;
}

static void check_back(thx_ctx *ctx, const thx_surface *s, const char *path, const char *fac, thx_import_format fmt,
                       int stl)
{
    thx_surface *r = NULL;
    thx_surface_read_info info;
    thx_status st = thx_surface_read_file(ctx, path, fac, fmt, "t", THX_ROLE_OUTER, &r, &info);
    if (st != THX_OK) fprintf(stderr, "%s: not read back: %s\n", path, thx_ctx_message(ctx));
    FUZZ_ASSERT(st == THX_OK);
    FUZZ_ASSERT(r->n_tris == 4);
    for (size_t t = 0; t < 4; t++)
        for (int k = 0; k < 3; k++) {
            const double *a = s->xyz + 3 * (size_t)s->tri[3 * t + (size_t)k];
            const double *b = r->xyz + 3 * (size_t)r->tri[3 * t + (size_t)k];
            for (int c = 0; c < 3; c++) {
                int ok = stl ? (double)(float)a[c] == b[c] : same_text(a[c], b[c]);
                if (!ok) fprintf(stderr, "%s: triangle %zu corner %d: %.17g read back as %.17g\n", path, t, k, a[c], b[c]);
                FUZZ_ASSERT(ok);
            }
        }
    thx_surface_destroy(&r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    thx_ctx *ctx = fuzz_ctx();
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "t", THX_ROLE_OUTER, &s) != THX_OK) abort();
    s->xyz = malloc(12 * sizeof *s->xyz);
    s->tri = malloc(12 * sizeof *s->tri);
    if (!s->xyz || !s->tri) abort();
    s->n_nodes = 4;
    s->n_tris = 4;
    memset(s->xyz, 0, 12 * sizeof *s->xyz);
    memcpy(s->xyz, data, size < 12 * sizeof(double) ? size : 12 * sizeof(double));
    memcpy(s->tri, tet, sizeof tet);
    int finite = 1, in_float = 1;
    for (int i = 0; i < 12; i++) {
        finite &= isfinite(s->xyz[i]) != 0;
        in_float &= isfinite((float)s->xyz[i]) != 0;
    }
    static const struct {
        thx_export_format ex;
        thx_import_format im;
        const char *ext;
    } fmts[] = {{THX_EXPORT_VTK, THX_IMPORT_VTK, "vtk"},
                {THX_EXPORT_VTP, THX_IMPORT_VTP, "vtp"},
                {THX_EXPORT_OBJ, THX_IMPORT_OBJ, "obj"},
                {THX_EXPORT_PLY, THX_IMPORT_PLY, "ply"},
                {THX_EXPORT_STL, THX_IMPORT_STL, "stl"}};
    char path[1200], fac[1200];
    for (size_t f = 0; f < sizeof fmts / sizeof fmts[0]; f++) {
        snprintf(path, sizeof path, "%s/rt.%s", fuzz_dir(), fmts[f].ext);
        unlink(path);
        int stl = fmts[f].ex == THX_EXPORT_STL;
        thx_status st = thx_surface_export(ctx, s, fmts[f].ex, path);
        FUZZ_ASSERT((st == THX_OK) == (finite && (!stl || in_float)));
        if (st != THX_OK) {
            FUZZ_ASSERT(access(path, F_OK) != 0);
            continue;
        }
        check_back(ctx, s, path, NULL, fmts[f].im, stl);
    }
    snprintf(path, sizeof path, "%s/rt.pts", fuzz_dir());
    snprintf(fac, sizeof fac, "%s/rt.fac", fuzz_dir());
    unlink(path);
    thx_status st = thx_surface_write_ptsfac(ctx, s, path, fac);
    FUZZ_ASSERT((st == THX_OK) == finite);
    if (st == THX_OK) check_back(ctx, s, path, fac, THX_IMPORT_PTSFAC, 0);
    else FUZZ_ASSERT(access(path, F_OK) != 0);
    thx_surface_destroy(&s);
    thx_ctx_destroy(&ctx);
    return 0;
}
