/*
 * Tests of images, colour maps, scaling models and 2D annotation
 * (src/render/image.c, colormap.c, annotate.c; thorax/render/image.h): PNG round
 * trips (RGBA and opaque RGB, byte-identical rewrites, VTK's own PNG reader),
 * failed writes leave nothing, bad files are refused; the maps' end points and
 * middles, CIELAB lightness monotone from the ends to the middle of the
 * diverging maps and along viridis, Moreland's cool-warm against VTK's own
 * diverging interpolation; the scaling models' limits, symmetry, monotonicity
 * and exact inverses, bands; text inside its box and nowhere else; lines,
 * colour bars and signal traces where they should be, NaN gaps left open.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/fileio.h"
#include "thorax/render/image.h"
static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

static thx_raster *new_image(int w, int h, unsigned char r, unsigned char g, unsigned char b)
{
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, w, h, &img));
    if (!img) exit(1);
    const unsigned char c[4] = {r, g, b, 255};
    thx_raster_fill(img, c);
    return img;
}

static unsigned char *px(thx_raster *img, int i, int j) { return img->rgba + 4 * ((size_t)j * img->w + i); }

/* CIELAB L* of an 8-bit sRGB colour, written here independently of colormap.c. */
static double lstar(const unsigned char c[3])
{
    double lin[3];
    for (int k = 0; k < 3; k++) {
        double v = c[k] / 255.0;
        lin[k] = v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
    }
    double y = 0.2126729 * lin[0] + 0.7151522 * lin[1] + 0.0721750 * lin[2];
    return y > 216.0 / 24389.0 ? 116 * cbrt(y) - 16 : y * 24389.0 / 27.0;
}

static int same_rgb(const unsigned char a[3], int r, int g, int b, int tol)
{
    return abs(a[0] - r) <= tol && abs(a[1] - g) <= tol && abs(a[2] - b) <= tol;
}

static double seg_dist(double px_, double py_, double x0, double y0, double x1, double y1)
{
    double dx = x1 - x0, dy = y1 - y0, l2 = dx * dx + dy * dy;
    double s = l2 > 0 ? ((px_ - x0) * dx + (py_ - y0) * dy) / l2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    return hypot(px_ - (x0 + s * dx), py_ - (y0 + s * dy));
}

/* ------------------------------------------------------------- images and PNG */

static void test_image_basic(void)
{
    thx_raster *img = (thx_raster *)&img;
    CHECK(thx_raster_create(ctx, 0, 10, &img) == THX_EINPUT && img == NULL);
    CHECK(thx_raster_create(ctx, 10, -1, &img) == THX_EINPUT && img == NULL);
    CHECK(thx_raster_create(ctx, 100000, 100000, &img) == THX_EINPUT && img == NULL);
    CHECK_OK(ctx, thx_raster_create(ctx, 3, 2, &img));
    CHECK(img && img->w == 3 && img->h == 2);
    if (!img) return;
    int zero = 1;
    for (int i = 0; i < 24; i++) zero &= img->rgba[i] == 0;
    CHECK(zero); /* transparent black */
    const unsigned char c[4] = {1, 2, 3, 4};
    thx_raster_fill(img, c);
    CHECK(memcmp(px(img, 2, 1), c, 4) == 0 && memcmp(px(img, 0, 0), c, 4) == 0);
    thx_raster_destroy(&img);
    CHECK(img == NULL);
    thx_raster_destroy(&img);
    thx_raster_destroy(NULL);
}

/* The IHDR of a PNG file: width, height, bit depth, colour type. */
static int png_header(const char *path, unsigned *w, unsigned *h, int *depth, int *ctype)
{
    unsigned char b[33];
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
    if (n != sizeof b || memcmp(b, sig, 8) || memcmp(b + 12, "IHDR", 4)) return 0;
    *w = (unsigned)b[16] << 24 | (unsigned)b[17] << 16 | (unsigned)b[18] << 8 | b[19];
    *h = (unsigned)b[20] << 24 | (unsigned)b[21] << 16 | (unsigned)b[22] << 8 | b[23];
    *depth = b[24];
    *ctype = b[25];
    return 1;
}

static int same_file(const char *a, const char *b)
{
    char *ta = NULL, *tb = NULL;
    size_t na = 0, nb = 0;
    int same = thx_read_file(ctx, a, &ta, &na) == THX_OK && thx_read_file(ctx, b, &tb, &nb) == THX_OK && na == nb &&
               memcmp(ta, tb, na) == 0;
    free(ta);
    free(tb);
    return same;
}

static void test_png(void)
{
    /* RGBA with every alpha, odd size */
    thx_raster *a = NULL, *b = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 37, 23, &a));
    if (!a) return;
    for (int j = 0; j < a->h; j++)
        for (int i = 0; i < a->w; i++) {
            unsigned char *p = px(a, i, j);
            p[0] = (unsigned char)(7 * i + j), p[1] = (unsigned char)(13 * j), p[2] = (unsigned char)(i * j);
            p[3] = (unsigned char)((i + 37 * j) % 256);
        }
    CHECK_OK(ctx, thx_raster_write_png(ctx, a, tl_path("rgba.png")));
    unsigned w = 0, h = 0;
    int depth = 0, ctype = -1;
    CHECK(png_header(tl_path("rgba.png"), &w, &h, &depth, &ctype) && w == 37 && h == 23 && depth == 8 && ctype == 6);
    CHECK_OK(ctx, thx_raster_read_png(ctx, tl_path("rgba.png"), &b));
    CHECK(b && b->w == 37 && b->h == 23 && memcmp(a->rgba, b->rgba, 4 * 37 * 23) == 0);
    thx_raster_destroy(&b);

    /* opaque: written as RGB, read back with alpha 255 */
    for (int i = 0; i < a->w * a->h; i++) a->rgba[4 * i + 3] = 255;
    CHECK_OK(ctx, thx_raster_write_png(ctx, a, tl_path("rgb.png")));
    CHECK(png_header(tl_path("rgb.png"), &w, &h, &depth, &ctype) && w == 37 && h == 23 && depth == 8 && ctype == 2);
    CHECK_OK(ctx, thx_raster_read_png(ctx, tl_path("rgb.png"), &b));
    CHECK(b && b->w == 37 && b->h == 23 && memcmp(a->rgba, b->rgba, 4 * 37 * 23) == 0);
    thx_raster_destroy(&b);

    /* the same image twice: the same bytes */
    CHECK_OK(ctx, thx_raster_write_png(ctx, a, tl_path("rgb2.png")));
    CHECK(same_file(tl_path("rgb.png"), tl_path("rgb2.png")));

    /* VTK's PNG reader sees the size, three components and the pixels (VTK's rows run bottom up) */
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "/usr/bin/python3 -c \"import vtk, sys\n"
             "r = vtk.vtkPNGReader(); r.SetFileName(sys.argv[1]); r.Update(); o = r.GetOutput()\n"
             "d = o.GetDimensions(); n = o.GetNumberOfScalarComponents()\n"
             "p = [int(o.GetScalarComponentAsDouble(5, 23 - 1 - 3, 0, k)) for k in range(3)]\n"
             "sys.exit(0 if d[0] == 37 and d[1] == 23 and n == 3 and p == [%d, %d, %d] else 1)\" '%s' 2>/dev/null",
             px(a, 5, 3)[0], px(a, 5, 3)[1], px(a, 5, 3)[2], tl_path("rgb.png"));
    int rc = system(cmd);
    CHECK(rc == 0);
    if (rc != 0) fprintf(stderr, "VTK did not read %s as expected\n", tl_path("rgb.png"));

    /* a grey PNG written by VTK reads as grey RGBA (VTK's first row is the image's bottom) */
    snprintf(cmd, sizeof cmd,
             "/usr/bin/python3 -c \"import vtk, sys\n"
             "im = vtk.vtkImageData(); im.SetDimensions(3, 2, 1); im.AllocateScalars(vtk.VTK_UNSIGNED_CHAR, 1)\n"
             "for i, v in enumerate([0, 1, 127, 128, 200, 255]): im.GetPointData().GetScalars().SetValue(i, v)\n"
             "w = vtk.vtkPNGWriter(); w.SetFileName(sys.argv[1]); w.SetInputData(im); w.Write()\" '%s' 2>/dev/null",
             tl_path("grey.png"));
    CHECK(system(cmd) == 0);
    CHECK(png_header(tl_path("grey.png"), &w, &h, &depth, &ctype) && w == 3 && h == 2 && depth == 8 && ctype == 0);
    CHECK_OK(ctx, thx_raster_read_png(ctx, tl_path("grey.png"), &b));
    if (b) {
        const int want[6] = {128, 200, 255, 0, 1, 127};
        int grey = b->w == 3 && b->h == 2;
        for (int i = 0; grey && i < 6; i++)
            grey &= b->rgba[4 * i] == want[i] && b->rgba[4 * i + 1] == want[i] && b->rgba[4 * i + 2] == want[i] &&
                    b->rgba[4 * i + 3] == 255;
        CHECK(grey);
        thx_raster_destroy(&b);
    }

    /* a write into a directory that does not exist: an error, nothing written */
    thx_ctx_clear(ctx);
    CHECK(thx_raster_write_png(ctx, a, tl_path("no/such/dir/x.png")) == THX_EIO);
    CHECK(strstr(thx_ctx_message(ctx), "no/such/dir/x.png") != NULL);
    CHECK(!tl_exists(tl_path("no/such/dir/x.png")) && !tl_exists(tl_path("no")));
    CHECK(!tl_leftover_tmp(""));

    /* reads that must fail */
    b = (thx_raster *)&b;
    CHECK(thx_raster_read_png(ctx, tl_path("missing.png"), &b) == THX_EIO && b == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "missing.png") != NULL);
    FILE *f = fopen(tl_path("text.png"), "w");
    if (f) {
        fputs("this is not a picture\n", f);
        fclose(f);
    }
    b = (thx_raster *)&b;
    CHECK(thx_raster_read_png(ctx, tl_path("text.png"), &b) == THX_EINPUT && b == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "not a PNG") != NULL);
    /* truncated after the header */
    char *data = NULL;
    size_t len = 0;
    CHECK_OK(ctx, thx_read_file(ctx, tl_path("rgb.png"), &data, &len));
    f = fopen(tl_path("cut.png"), "wb");
    if (f && data) {
        fwrite(data, 1, len / 2, f);
        fclose(f);
    }
    free(data);
    b = (thx_raster *)&b;
    CHECK(thx_raster_read_png(ctx, tl_path("cut.png"), &b) == THX_EINPUT && b == NULL);
    thx_raster_destroy(&a);
}

/* ------------------------------------------------------------- colour maps */

static void test_colormap_names(void)
{
    const char *names[] = {"ecg", "ecg-green", "coolwarm", "viridis", "gray", "jet"};
    for (int i = 0; i < 6; i++) {
        thx_colormap c = THX_CMAP_JET;
        CHECK(thx_colormap_parse(names[i], &c) == 0 && (int)c == i);
        CHECK(strcmp(thx_colormap_name(c), names[i]) == 0);
    }
    thx_colormap c = THX_CMAP_VIRIDIS;
    CHECK(thx_colormap_parse("rainbow", &c) == -1 && c == THX_CMAP_VIRIDIS);
    CHECK(thx_colormap_parse(NULL, &c) == -1);
    CHECK(THX_CMAP_ECG == 0); /* the default */
}

static void eval(thx_colormap c, double t, unsigned char rgb[3]) { thx_colormap_eval(c, t, rgb); }

/* L* along a map: rises from t = 0 to the middle and falls from the middle to t = 1 (8-bit
   rounding allowed for), by at least `depth` overall. */
static int diverging_lightness(thx_colormap c, double depth)
{
    const int n = 200;
    double prev = -1;
    unsigned char rgb[3];
    for (int i = 0; i <= n; i++) {
        eval(c, (double)i / n, rgb);
        double l = lstar(rgb);
        if (i > 0 && ((i <= n / 2 && l < prev - 0.2) || (i > n / 2 && l > prev + 0.2))) {
            fprintf(stderr, "%s: L* %.2f after %.2f at t = %g\n", thx_colormap_name(c), l, prev, (double)i / n);
            return 0;
        }
        prev = l;
    }
    unsigned char e0[3], m[3], e1[3];
    eval(c, 0, e0), eval(c, 0.5, m), eval(c, 1, e1);
    return lstar(m) - lstar(e0) > depth && lstar(m) - lstar(e1) > depth;
}

static void test_colormaps(void)
{
    unsigned char rgb[3], rgb2[3];
    /* ECG: blue - white - red, the same lightness on both sides */
    eval(THX_CMAP_ECG, 0, rgb);
    CHECK(rgb[2] > 200 && rgb[2] > rgb[0] + 150 && rgb[2] > rgb[1] + 100);
    eval(THX_CMAP_ECG, 0.5, rgb);
    CHECK(same_rgb(rgb, 255, 255, 255, 0));
    eval(THX_CMAP_ECG, 1, rgb);
    CHECK(rgb[0] > 150 && rgb[0] > rgb[1] + 150 && rgb[0] > rgb[2] + 150);
    eval(THX_CMAP_ECG, 0.25, rgb); /* halfway to blue: a light blue */
    CHECK(rgb[2] == 255 && rgb[0] < rgb[2] && rgb[1] < rgb[2] && lstar(rgb) > 60 && lstar(rgb) < 80);
    for (int i = 0; i <= 20; i++) {
        eval(THX_CMAP_ECG, i / 40.0, rgb);
        eval(THX_CMAP_ECG, 1 - i / 40.0, rgb2);
        CHECK_NEAR(lstar(rgb), lstar(rgb2), 1.0);
    }
    /* ECG_GREEN: green - white - red */
    eval(THX_CMAP_ECG_GREEN, 0, rgb);
    CHECK(rgb[1] > 80 && rgb[1] > rgb[0] + 80 && rgb[1] > rgb[2] + 80);
    eval(THX_CMAP_ECG_GREEN, 0.5, rgb);
    CHECK(same_rgb(rgb, 255, 255, 255, 0));
    eval(THX_CMAP_ECG_GREEN, 1, rgb);
    CHECK(rgb[0] > 150 && rgb[0] > rgb[1] + 150 && rgb[0] > rgb[2] + 150);
    for (int i = 0; i <= 20; i++) {
        eval(THX_CMAP_ECG_GREEN, i / 40.0, rgb);
        eval(THX_CMAP_ECG_GREEN, 1 - i / 40.0, rgb2);
        CHECK_NEAR(lstar(rgb), lstar(rgb2), 1.0);
    }
    /* Moreland's published end points and grey middle (221, 221, 221) */
    eval(THX_CMAP_COOLWARM, 0, rgb);
    CHECK(same_rgb(rgb, 59, 76, 192, 0));
    eval(THX_CMAP_COOLWARM, 1, rgb);
    CHECK(same_rgb(rgb, 180, 4, 38, 0));
    eval(THX_CMAP_COOLWARM, 0.5, rgb);
    CHECK(same_rgb(rgb, 221, 221, 221, 1));
    /* diverging maps: L* rises to the middle and falls after it */
    CHECK(diverging_lightness(THX_CMAP_ECG, 50));
    CHECK(diverging_lightness(THX_CMAP_ECG_GREEN, 50));
    CHECK(diverging_lightness(THX_CMAP_COOLWARM, 40));
    /* viridis: the published table's ends and middle, L* strictly rising */
    eval(THX_CMAP_VIRIDIS, 0, rgb);
    CHECK(same_rgb(rgb, 68, 1, 84, 0));
    eval(THX_CMAP_VIRIDIS, 1, rgb);
    CHECK(same_rgb(rgb, 253, 231, 37, 0));
    eval(THX_CMAP_VIRIDIS, 128.0 / 255.0, rgb);
    CHECK(same_rgb(rgb, 33, 145, 140, 0));
    double prev = -1;
    int rising = 1;
    for (int i = 0; i <= 64; i++) {
        eval(THX_CMAP_VIRIDIS, i / 64.0, rgb);
        double l = lstar(rgb);
        rising &= l > prev;
        prev = l;
    }
    CHECK(rising);
    /* gray and jet */
    eval(THX_CMAP_GRAY, 0, rgb);
    CHECK(same_rgb(rgb, 0, 0, 0, 0));
    eval(THX_CMAP_GRAY, 1, rgb);
    CHECK(same_rgb(rgb, 255, 255, 255, 0));
    eval(THX_CMAP_GRAY, 0.5, rgb);
    CHECK(same_rgb(rgb, 128, 128, 128, 0));
    eval(THX_CMAP_JET, 0, rgb);
    CHECK(same_rgb(rgb, 0, 0, 128, 0));
    eval(THX_CMAP_JET, 0.5, rgb);
    CHECK(same_rgb(rgb, 128, 255, 128, 0));
    eval(THX_CMAP_JET, 1, rgb);
    CHECK(same_rgb(rgb, 128, 0, 0, 0));
    /* clamped; NaN does not crash */
    for (int c = 0; c < 6; c++) {
        eval((thx_colormap)c, -3, rgb), eval((thx_colormap)c, 0, rgb2);
        CHECK(memcmp(rgb, rgb2, 3) == 0);
        eval((thx_colormap)c, 7, rgb), eval((thx_colormap)c, 1, rgb2);
        CHECK(memcmp(rgb, rgb2, 3) == 0);
        eval((thx_colormap)c, NAN, rgb);
    }
    /* a table is the map sampled at i / (n - 1) */
    unsigned char table[3 * 33];
    int same = 1;
    for (int c = 0; c < 6; c++) {
        thx_colormap_table((thx_colormap)c, 33, table);
        for (int i = 0; i < 33; i++) {
            eval((thx_colormap)c, i / 32.0, rgb);
            same &= memcmp(rgb, table + 3 * i, 3) == 0;
        }
    }
    CHECK(same);
}

/* Cool-warm against VTK's own implementation of Moreland's diverging interpolation. */
static void test_coolwarm_vtk(void)
{
    const int n = 21;
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "/usr/bin/python3 -c \"import vtk\n"
             "f = vtk.vtkColorTransferFunction(); f.SetColorSpaceToDiverging()\n"
             "f.AddRGBPoint(0, 59 / 255, 76 / 255, 192 / 255); f.AddRGBPoint(1, 180 / 255, 4 / 255, 38 / 255)\n"
             "for i in range(%d): print(' '.join('%%.6f' %% c for c in f.GetColor(i / %d)))\" 2>/dev/null",
             n, n - 1);
    FILE *p = popen(cmd, "r");
    CHECK(p != NULL);
    if (!p) return;
    int got = 0, agree = 1;
    double r, g, b;
    while (got < n && fscanf(p, "%lf %lf %lf", &r, &g, &b) == 3) {
        unsigned char rgb[3];
        eval(THX_CMAP_COOLWARM, (double)got / (n - 1), rgb);
        if (fabs(rgb[0] - 255 * r) > 1.5 || fabs(rgb[1] - 255 * g) > 1.5 || fabs(rgb[2] - 255 * b) > 1.5) {
            fprintf(stderr, "coolwarm at t = %g: %d %d %d, VTK %.1f %.1f %.1f\n", (double)got / (n - 1), rgb[0],
                    rgb[1], rgb[2], 255 * r, 255 * g, 255 * b);
            agree = 0;
        }
        got++;
    }
    CHECK(pclose(p) == 0 && got == n);
    CHECK(agree);
}

/* ------------------------------------------------------------- scaling models */

static void test_scales(void)
{
    thx_scale s = {THX_SCALE_LINEAR, -2, 6, 0, THX_MAPPING_TRUE};
    CHECK(thx_scale_apply(&s, -2) == 0 && thx_scale_apply(&s, 6) == 1 && thx_scale_apply(&s, 2) == 0.5);
    CHECK_NEAR(thx_scale_apply(&s, 0), 0.25, 1e-15);
    CHECK(thx_scale_apply(&s, -100) == 0 && thx_scale_apply(&s, 100) == 1); /* clamped */
    CHECK(isnan(thx_scale_apply(&s, NAN)) && isnan(thx_scale_invert(&s, NAN)));
    CHECK(thx_scale_invert(&s, 0) == -2 && thx_scale_invert(&s, 1) == 6 && thx_scale_invert(&s, 0.5) == 2);

    /* limits from data: min/max of the finite values, or symmetric about zero */
    const double v[6] = {-1, 3, NAN, INFINITY, 0.5, -INFINITY};
    thx_scale_from_data(&s, THX_SCALE_LINEAR, v, 6, 0);
    CHECK(s.model == THX_SCALE_LINEAR && s.lo == -1 && s.hi == 3);
    thx_scale_from_data(&s, THX_SCALE_LINEAR, v, 6, 1);
    CHECK(s.lo == -3 && s.hi == 3 && thx_scale_apply(&s, 0) == 0.5);
    thx_scale_from_data(&s, THX_SCALE_LOG, v, 6, 1);
    CHECK(s.model == THX_SCALE_LOG && s.k == 10 && thx_scale_apply(&s, 0) == 0.5);
    thx_scale_from_data(&s, THX_SCALE_EXP, v, 6, 1);
    CHECK(s.model == THX_SCALE_EXP && s.k == 3 && thx_scale_apply(&s, 0) == 0.5);
    const double nans[2] = {NAN, NAN};
    thx_scale_from_data(&s, THX_SCALE_LINEAR, nans, 2, 0);
    CHECK(s.lo == -1 && s.hi == 1);
    thx_scale_from_data(&s, THX_SCALE_LINEAR, NULL, 0, 1);
    CHECK(s.lo == -1 && s.hi == 1);
    const double zeros[3] = {0, 0, 0};
    thx_scale_from_data(&s, THX_SCALE_LINEAR, zeros, 3, 1);
    CHECK(s.lo == -1 && s.hi == 1 && thx_scale_apply(&s, 0) == 0.5);

    /* log and exp: odd about the middle, monotone, log above linear and exp below it on the upper
       half, and exact inverses; over symmetric and lopsided ranges and several strengths */
    const thx_scale_model models[2] = {THX_SCALE_LOG, THX_SCALE_EXP};
    const double ranges[3][2] = {{-5, 5}, {-2, 6}, {10, 10.5}};
    const double ks[3] = {0, 1, 5}; /* 0: the default */
    int odd = 1, mono = 1, side = 1, inv = 1, ends = 1;
    for (int m = 0; m < 2; m++)
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++) {
                thx_scale sc = {models[m], ranges[r][0], ranges[r][1], ks[q], THX_MAPPING_TRUE};
                double c = 0.5 * (sc.lo + sc.hi), h = 0.5 * (sc.hi - sc.lo);
                ends &= thx_scale_apply(&sc, sc.lo) == 0 && thx_scale_apply(&sc, sc.hi) == 1 &&
                        thx_scale_apply(&sc, c) == 0.5;
                double prev = -1;
                for (int i = 0; i <= 1000; i++) {
                    double val = sc.lo + (sc.hi - sc.lo) * i / 1000.0;
                    double t = thx_scale_apply(&sc, val);
                    if (!(t > prev)) mono = 0;
                    prev = t;
                    double d = val - c;
                    double tm = thx_scale_apply(&sc, c - d);
                    if (fabs((t - 0.5) + (tm - 0.5)) > 1e-15) odd = 0;
                    double lin = 0.5 + 0.5 * d / h;
                    if (d > 0 && d < h && (models[m] == THX_SCALE_LOG ? !(t > lin) : !(t < lin))) side = 0;
                    double back = thx_scale_invert(&sc, t);
                    if (fabs(back - val) > 1e-12) {
                        if (inv) fprintf(stderr, "model %d [%g, %g] k %g: %.17g -> %.17g -> %.17g\n", (int)models[m],
                                         sc.lo, sc.hi, sc.k, val, t, back);
                        inv = 0;
                    }
                }
            }
    CHECK(ends);
    CHECK(mono);
    CHECK(odd);
    CHECK(side);
    CHECK(inv);
    /* the header's formula, literally */
    thx_scale sl = {THX_SCALE_LOG, -4, 4, 10, THX_MAPPING_TRUE};
    CHECK_NEAR(thx_scale_apply(&sl, 1), 0.5 * (log(1 + 10 * 0.25) / log(11) + 1), 1e-15);
    thx_scale se = {THX_SCALE_EXP, -4, 4, 3, THX_MAPPING_TRUE};
    CHECK_NEAR(thx_scale_apply(&se, -2), 0.5 * (-(exp(3 * 0.5) - 1) / (exp(3) - 1) + 1), 1e-15);

    /* bands: n values (b + 0.5) / n, the last band closed */
    for (int n = 1; n <= 12; n += 11) {
        int seen[12] = {0}, exact = 1;
        for (int i = 0; i <= 10000; i++) {
            double t = i / 10000.0, q = thx_scale_band(t, n);
            int b = (int)floor(q * n);
            if (b < 0 || b >= n || q != (b + 0.5) / n || (t < 1 && b != (int)floor(t * n))) exact = 0;
            else seen[b] = 1;
        }
        int distinct = 0;
        for (int b = 0; b < n; b++) distinct += seen[b];
        CHECK(exact && distinct == n);
        CHECK(thx_scale_band(1, n) == (n - 0.5) / n && thx_scale_band(0, n) == 0.5 / n);
    }
    CHECK(thx_scale_band(0.3, 0) == 0.3 && isnan(thx_scale_band(NAN, 4)));
    /* positions outside [0, 1] are the ends: the last band, the range's limits, the map's end colours */
    CHECK(thx_scale_band(1.5, 4) == 3.5 / 4 && thx_scale_band(-0.5, 4) == 0.5 / 4);
    thx_scale lin = {THX_SCALE_LINEAR, -2, 6, 0, THX_MAPPING_TRUE};
    CHECK(thx_scale_invert(&lin, 1.5) == 6 && thx_scale_invert(&lin, -0.5) == -2);
    for (int c = 0; c < 6; c++) {
        unsigned char e0[3], e1[3], o0[3], o1[3];
        thx_colormap_eval((thx_colormap)c, 0, e0);
        thx_colormap_eval((thx_colormap)c, 1, e1);
        thx_colormap_eval((thx_colormap)c, -0.7, o0);
        thx_colormap_eval((thx_colormap)c, 1.7, o1);
        CHECK(!memcmp(e0, o0, 3) && !memcmp(e1, o1, 3));
    }
    unsigned char g[3];
    thx_colormap_eval(THX_CMAP_GRAY, 1.7, g);
    CHECK(g[0] == 255 && g[1] == 255 && g[2] == 255);
    thx_colormap_eval(THX_CMAP_JET, 0.75, g); /* jet's red channel saturates at t = 0.75 */
    CHECK(g[0] == 255);
}

/* ------------------------------------------------------------- text */

#define DEJAVU "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"

/* The box of pixels that differ from the background colour bg; 0 if none. */
static int changed_box(thx_raster *img, const unsigned char bg[4], int *x0, int *y0, int *x1, int *y1, long *count)
{
    *x0 = *y0 = 1 << 30, *x1 = *y1 = -1, *count = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = 0; i < img->w; i++)
            if (memcmp(px(img, i, j), bg, 4)) {
                if (i < *x0) *x0 = i;
                if (i > *x1) *x1 = i;
                if (j < *y0) *y0 = j;
                if (j > *y1) *y1 = j;
                (*count)++;
            }
    return *count > 0;
}

static void test_text(void)
{
    thx_font *f = (thx_font *)&f;
    /* errors name what is missing */
    thx_ctx_clear(ctx);
    CHECK(thx_font_open(ctx, "/no/such/font.ttf", 16, &f) == THX_EIO && f == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "/no/such/font.ttf") && strstr(thx_ctx_message(ctx), "No such file"));
    FILE *tf = fopen(tl_path("fake.ttf"), "w");
    if (tf) {
        fputs("not a font\n", tf);
        fclose(tf);
    }
    f = (thx_font *)&f;
    CHECK(thx_font_open(ctx, tl_path("fake.ttf"), 16, &f) == THX_EINPUT && f == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "not a font") != NULL);
    CHECK(thx_font_open(ctx, NULL, 0, &f) == THX_EINPUT && f == NULL);
    thx_font_close(&f);
    thx_font_close(NULL);

    /* the default sans-serif face, and DejaVu Sans by its path when installed */
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 20, &f));
    if (!f) return;
    if (tl_exists(DEJAVU)) {
        thx_font *g = NULL;
        CHECK_OK(ctx, thx_font_open(ctx, DEJAVU, 20, &g));
        CHECK(g && thx_font_height(g) == thx_font_height(f)); /* Debian's default is DejaVu Sans */
        thx_font_close(&g);
        CHECK(g == NULL);
    }
    int fh = thx_font_height(f);
    CHECK(fh >= 20 && fh <= 30);
    int wh = thx_text_width(f, "Hg"), whg = thx_text_width(f, "Hgg"), wl = thx_text_width(f, "Hg Hg Hg Hg");
    CHECK(thx_text_width(f, "") == 0 && thx_text_width(f, "H") > 0);
    CHECK(wh > 15 && wh < 40 && whg > wh && wl > 3 * wh);
    CHECK(thx_text_width(f, "\xce\xbcV") > thx_text_width(f, "V")); /* µV in UTF-8 */
    CHECK(thx_text_width(f, "a\xff\xc3") > 0);                       /* malformed: no crash */

    /* "Hg" on its baseline: pixels change inside [x, x + width] x [y - ascender, y + descender]
       (a pixel of slack) and nowhere else; H rises above the baseline, g hangs below it */
    const unsigned char bg[4] = {0, 0, 0, 255}, white[4] = {255, 255, 255, 255};
    thx_raster *img = new_image(120, 60, 0, 0, 0);
    const int x = 30, y = 35;
    thx_draw_text(img, f, x, y, "Hg", white);
    int x0, y0, x1, y1;
    long count;
    CHECK(changed_box(img, bg, &x0, &y0, &x1, &y1, &count));
    CHECK(x0 >= x - 1 && x1 <= x + wh + 1 && y0 >= y - fh && y1 <= y + fh / 2);
    CHECK(y0 < y - 10 && y1 > y + 2);       /* cap height above, descender below */
    CHECK(x0 <= x + 3 && x1 >= x + wh - 4); /* spans the advance */
    CHECK(count > 60);
    int full = 0, partial = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = 0; i < img->w; i++) {
            int v = px(img, i, j)[0];
            full += v == 255, partial += v > 0 && v < 255;
        }
    CHECK(full > 20 && partial > 10); /* solid stems and antialiased edges */
    /* longer text reaches further right */
    thx_raster_fill(img, bg);
    thx_draw_text(img, f, x, y, "Hgg", white);
    int x1b = 0;
    CHECK(changed_box(img, bg, &x0, &y0, &x1b, &y1, &count) && x1b > x1 + 5);
    /* clipped at the image's edges without harm */
    thx_draw_text(img, f, -10, 5, "Hg Hg Hg Hg Hg Hg Hg Hg", white);
    thx_draw_text(img, f, 100, 70, "Hg", white);
    thx_raster_destroy(&img);
    thx_font_close(&f);
}

/* ------------------------------------------------------------- lines and rectangles */

static void test_lines(void)
{
    const unsigned char white[4] = {255, 255, 255, 255}, half[4] = {255, 255, 255, 128};
    thx_raster *img = new_image(64, 32, 0, 0, 0);
    /* a horizontal line through pixel centres, one pixel wide, covers exactly its row */
    thx_draw_line(img, 5.5, 10.5, 50.5, 10.5, 1, white);
    int row = 1, others = 1;
    for (int i = 6; i <= 50; i++) row &= px(img, i, 10)[0] == 255;
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 64; i++)
            if (j != 10 && px(img, i, j)[0] != 0) others = 0;
    CHECK(row && others);
    /* a diagonal line: antialiased (partial coverage), every lit pixel within w/2 + 1 of it */
    thx_raster_fill(img, (const unsigned char[4]){0, 0, 0, 255});
    thx_draw_line(img, 2, 3, 60, 28, 2, white);
    int partial = 0, near = 1;
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 64; i++) {
            int v = px(img, i, j)[0];
            partial += v > 0 && v < 255;
            if (v > 0 && seg_dist(i + 0.5, j + 0.5, 2, 3, 60, 28) > 2.0) near = 0;
        }
    CHECK(partial > 20 && near);
    CHECK(px(img, 31, 15)[0] > 200 || px(img, 31, 16)[0] > 200); /* on the line's middle */
    /* a wide line: its spine and round caps fully covered (coverage saturates at 1), nothing
       beyond its half-width; a cap pixel is judged from the end point, not from the segment */
    thx_raster_fill(img, (const unsigned char[4]){0, 0, 0, 255});
    thx_draw_line(img, 10.5, 16.5, 40.5, 16.5, 5, white);
    int spine = 1;
    for (int i = 10; i <= 40; i++) spine &= px(img, i, 16)[0] == 255 && px(img, i, 15)[0] == 255 && px(img, i, 17)[0] == 255;
    CHECK(spine);
    CHECK(px(img, 42, 16)[0] == 255 && px(img, 8, 16)[0] == 255);   /* 2 px past the ends, radius 2.5 */
    CHECK(px(img, 44, 16)[0] == 0 && px(img, 6, 16)[0] == 0);       /* 4 px past */
    CHECK(px(img, 25, 13)[0] == 0 && px(img, 25, 19)[0] == 0);      /* 3 px beside */
    /* half-transparent rectangle over black: half grey; over a transparent image: the colour itself */
    thx_raster_fill(img, (const unsigned char[4]){0, 0, 0, 255});
    thx_draw_rect(img, -5, -5, 10, 10, half); /* clipped */
    CHECK(abs(px(img, 0, 0)[0] - 128) <= 1 && px(img, 0, 0)[3] == 255 && px(img, 4, 4)[0] > 0 && px(img, 5, 5)[0] == 0);
    thx_raster_fill(img, (const unsigned char[4]){0, 0, 0, 0});
    thx_draw_rect(img, 60, 30, 100, 100, half);
    CHECK(px(img, 63, 31)[0] == 255 && px(img, 63, 31)[3] == 128 && px(img, 59, 31)[3] == 0);
    thx_draw_line(img, NAN, 0, 10, 10, 1, white); /* nothing, no crash */
    thx_draw_line(img, -1e300, -1e300, 1e300, 1e300, 1, white);
    thx_raster_destroy(&img);
}

/* ------------------------------------------------------------- colour bar */

static void test_colorbar(void)
{
    thx_font *f = NULL;
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 14, &f));
    thx_scale s = {THX_SCALE_LINEAR, -2, 2, 0, THX_MAPPING_TRUE};
    const int bx = 20, by = 30, bw = 16, bh = 200;

    /* vertical, continuous: the strip's column shows the map from the bottom up */
    thx_raster *img = new_image(160, 260, 255, 255, 255);
    thx_draw_colorbar(img, f, bx, by, bw, bh, THX_CMAP_ECG, &s, 0, 5, "potential", "mV");
    int exact = 1;
    for (int p = 0; p < bh; p++) {
        unsigned char rgb[3];
        thx_colormap_eval(THX_CMAP_ECG, (p + 0.5) / bh, rgb);
        if (memcmp(px(img, bx + bw / 2, by + bh - 1 - p), rgb, 3)) exact = 0;
    }
    CHECK(exact);
    unsigned char *bottom = px(img, bx + 8, by + bh - 1), *top = px(img, bx + 8, by);
    unsigned char *mid = px(img, bx + 8, by + bh / 2);
    CHECK(bottom[2] > bottom[0] + 100 && top[0] > top[2] + 100 && mid[0] > 240 && mid[1] > 240 && mid[2] > 240);
    /* labels to the right (dark ink on the white page), a title above, the frame around */
    int ink_right = 0, ink_above = 0;
    for (int j = by; j < by + bh; j++)
        for (int i = bx + bw + 6; i < 160; i++) ink_right += px(img, i, j)[0] < 128;
    for (int j = 0; j < by - 1; j++)
        for (int i = 0; i < 160; i++) ink_above += px(img, i, j)[0] < 128;
    CHECK(ink_right > 50 && ink_above > 30);
    CHECK(px(img, bx - 1, by + 50)[0] == 0 && px(img, bx + bw, by + 50)[0] == 0);
    thx_raster_destroy(&img);

    /* horizontal, 4 bands: exactly 4 colours, in order from the left */
    img = new_image(300, 80, 0, 0, 0);
    thx_draw_colorbar(img, f, 20, 20, 260, 18, THX_CMAP_VIRIDIS, &s, 4, 5, NULL, "mV");
    int changes = 0, ordered = 1;
    unsigned char last[3];
    memcpy(last, px(img, 20, 28), 3);
    for (int i = 21; i < 280; i++) {
        unsigned char *c = px(img, i, 28);
        if (memcmp(c, last, 3)) {
            changes++;
            if (!(lstar(c) > lstar(last))) ordered = 0; /* viridis brightens with t */
            memcpy(last, c, 3);
        }
    }
    CHECK(changes == 3 && ordered);
    unsigned char band0[3];
    thx_colormap_eval(THX_CMAP_VIRIDIS, 0.125, band0);
    CHECK(memcmp(px(img, 22, 28), band0, 3) == 0);
    int ink_below = 0; /* white labels on the black background */
    for (int j = 40; j < 80; j++)
        for (int i = 0; i < 300; i++) ink_below += px(img, i, j)[0] > 128;
    CHECK(ink_below > 50);
    thx_raster_destroy(&img);

    /* at the right edge: the title and the unit do not fit on one line beside the strip, so they
     * stand on two lines above it, both wholly inside the image (ink rows in two separate groups,
     * none of them reaching into the top value's label) */
    img = new_image(120, 300, 255, 255, 255);
    thx_draw_colorbar(img, f, 84, 80, 16, 200, THX_CMAP_ECG, &s, 0, 5, "potential", "mV");
    int rows_ink[80] = {0}, groups = 0, in_group = 0, right_col = 0;
    for (int j = 0; j < 80 - thx_font_height(f) / 2; j++) {
        for (int i = 0; i < 120; i++) rows_ink[j] += px(img, i, j)[0] < 128;
        if (rows_ink[j] && !in_group) groups++;
        in_group = rows_ink[j] > 0;
        right_col += px(img, 119, j)[0] < 128;
    }
    CHECK(groups == 2);
    CHECK(right_col == 0); /* nothing cut at the edge */
    thx_raster_destroy(&img);

    /* labels too wide for the room beside the strip move the strip left, whole labels in the image;
       large values without an exponent ("12600") */
    {
        thx_scale big = {THX_SCALE_LINEAR, -12600, 12600, 0, THX_MAPPING_TRUE};
        img = new_image(120, 300, 255, 255, 255);
        thx_draw_colorbar(img, f, 100, 60, 12, 200, THX_CMAP_ECG, &big, 0, 5, NULL, NULL);
        int edge = 0, strip_at = -1;
        for (int j = 0; j < 300; j++) edge += px(img, 119, j)[0] < 128;
        for (int i = 0; i < 120 && strip_at < 0; i++) {
            const unsigned char *q = px(img, i, 60 + 5); /* near the top: dark red */
            if (q[0] > 150 && q[1] < 80 && q[2] < 80) strip_at = i;
        }
        CHECK(edge == 0);
        CHECK(strip_at >= 0 && strip_at < 100);
        thx_raster_destroy(&img);
    }

    /* no font: strip only; log scale, bands */
    img = new_image(60, 60, 0, 0, 0);
    thx_scale sl = {THX_SCALE_LOG, -1, 1, 10, THX_MAPPING_TRUE};
    thx_draw_colorbar(img, NULL, 10, 5, 10, 50, THX_CMAP_COOLWARM, &sl, 0, 3, "x", "y");
    CHECK(px(img, 40, 30)[0] == 0 && px(img, 15, 30)[0] > 150);
    thx_raster_destroy(&img);
    thx_font_close(&f);
}

/* ------------------------------------------------------------- signal trace */

static void test_trace(void)
{
    enum { N = 101 };
    double v[N];
    for (int i = 0; i < N; i++) v[i] = 2 * sin(2 * M_PI * i / (N - 1)) + 0.5;
    for (int i = 60; i < 70; i++) v[i] = NAN; /* a gap */
    const size_t marker = 30;
    const unsigned char red[4] = {255, 0, 0, 255}, bg[4] = {0, 0, 0, 255};
    const int bx = 10, by = 10, bw = 280, bh = 100;
    thx_raster *img = new_image(300, 120, 0, 0, 0);
    thx_draw_trace(img, NULL, bx, by, bw, bh, v, N, 0, 2, marker, "II", "mV", red);

    /* the layout documented in annotate.c, without a font: the box inset by 2 pixels */
    const double pxl = bx + 2, pyl = by + 2, pw = bw - 4, ph = bh - 4;
    double lo = -1.5, hi = 2.5; /* the data's range */
    double spare = 0.05 * (hi - lo);
    lo -= spare, hi += spare;
    double X[N], Y[N];
    for (int i = 0; i < N; i++) {
        X[i] = pxl + 0.5 + i * (pw - 1) / (N - 1);
        Y[i] = pyl + 0.5 + (hi - v[i]) / (hi - lo) * (ph - 1);
    }
    double y0 = pyl + 0.5 + hi / (hi - lo) * (ph - 1);

    /* every sample with a finite neighbour is drawn at its place */
    int drawn = 1;
    for (int i = 0; i < N; i++) {
        if (!isfinite(v[i])) continue;
        int best = 0;
        for (int dj = -1; dj <= 1; dj++)
            for (int di = -1; di <= 1; di++) {
                int c = px(img, (int)floor(X[i]) + di, (int)floor(Y[i]) + dj)[0];
                if (c > best) best = c;
            }
        if (best < 200) {
            fprintf(stderr, "sample %d not drawn at (%g, %g)\n", i, X[i], Y[i]);
            drawn = 0;
        }
    }
    CHECK(drawn);
    /* full-strength pixels only near the polyline (or the marker's dot); the axes and the marker
       line are fainter; nothing outside the box */
    int stray = 0, outside = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = 0; i < img->w; i++) {
            unsigned char *p = px(img, i, j);
            if (i < bx || j < by || i >= bx + bw || j >= by + bh) {
                outside += memcmp(p, bg, 4) != 0;
                continue;
            }
            if (p[0] < 200 || (j == (int)floor(y0) && i == (int)floor(X[marker]))) continue; /* faint lines crossing */
            double d = 1e9, cx = i + 0.5, cy = j + 0.5;
            for (int k = 0; k + 1 < N; k++)
                if (isfinite(v[k]) && isfinite(v[k + 1])) d = fmin(d, seg_dist(cx, cy, X[k], Y[k], X[k + 1], Y[k + 1]));
            d = fmin(d, hypot(cx - X[marker], cy - Y[marker]) - 2.5);
            if (d > 1.3) {
                if (stray < 5) fprintf(stderr, "stray trace pixel (%d, %d): %d from the polyline\n", i, j, (int)d);
                stray++;
            }
        }
    CHECK(stray == 0 && outside == 0);
    /* the gap: no trace between the last sample before it and the first after */
    int gap_clear = 1;
    for (int i = (int)ceil(X[59] + 2); i < (int)floor(X[70] - 2); i++)
        for (int j = (int)pyl; j < (int)(pyl + ph); j++)
            if (px(img, i, j)[0] >= 200) gap_clear = 0;
    CHECK(gap_clear);
    /* the marker: a vertical line through the whole plot at the marker's sample */
    int mcol = (int)floor(X[marker]), lit = 0;
    for (int j = (int)pyl; j < (int)(pyl + ph); j++) lit += px(img, mcol, j)[0] >= 140;
    CHECK(lit >= ph - 2);
    int dot = 1; /* a dot on the trace at the marker */
    for (int dj = -2; dj <= 2; dj++) dot &= px(img, mcol, (int)floor(Y[marker]) + dj)[0] == 255;
    CHECK(dot);
    /* the zero line: faint, across the plot */
    int zrow = (int)floor(y0), zero_line = 0;
    for (int i = (int)pxl; i < (int)(pxl + pw); i++) {
        int r = px(img, i, zrow)[0];
        zero_line += r >= 100 && r <= 160;
    }
    CHECK(zero_line > pw / 2);

    /* with a font: the label in the header row, the trace below it, still inside the box */
    thx_font *f = NULL;
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 12, &f));
    thx_raster_fill(img, bg);
    thx_draw_trace(img, f, bx, by, bw, bh, v, N, 0, 2, N, "II", "mV", red);
    int label = 0;
    for (int j = by; j < by + 2 + thx_font_height(f); j++)
        for (int i = bx; i < bx + 2 + thx_text_width(f, "II"); i++) label += px(img, i, j)[0] > 0;
    outside = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = 0; i < img->w; i++)
            if (i < bx || j < by || i >= bx + bw || j >= by + bh) outside += memcmp(px(img, i, j), bg, 4) != 0;
    CHECK(label > 10 && outside == 0);
    /* a box too narrow for its text, the marker at the first sample (its dot reaches past the plot):
       clipped to the box */
    thx_raster_fill(img, bg);
    thx_draw_trace(img, f, 100, 20, 40, 90, v, N, -250, 2, 0, "aVR", "millivolts", red);
    outside = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = 0; i < img->w; i++)
            if (i < 100 || j < 20 || i >= 140 || j >= 110) outside += memcmp(px(img, i, j), bg, 4) != 0;
    CHECK(outside == 0);
    /* degenerate inputs draw what they can */
    thx_draw_trace(img, f, bx, by, bw, bh, v, 0, 0, 1, 0, NULL, NULL, red);
    const double one = 1.0, nan1[3] = {NAN, NAN, NAN};
    thx_draw_trace(img, f, bx, by, bw, bh, &one, 1, 0, 1, 0, "I", "", red);
    thx_draw_trace(img, f, bx, by, bw, bh, nan1, 3, 0, 1, 1, "I", "mV", red);
    thx_draw_trace(img, f, bx, by, 3, 3, v, N, 0, 1, 5, "I", "mV", red);
    thx_font_close(&f);
    thx_raster_destroy(&img);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_image")) return 1;
    test_image_basic();
    test_png();
    test_colormap_names();
    test_colormaps();
    test_coolwarm_vtk();
    test_scales();
    test_text();
    test_lines();
    test_colorbar();
    test_trace();
    int rc = tl_scratch_finish("test_image");
    thx_ctx_destroy(&ctx);
    return rc;
}
