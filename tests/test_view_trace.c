/* Tracing a scan in the viewer (issue 26 item 7), under Xvfb: the phantom's simulated MR as `thorax
 * phantom --image --modality mr` writes it (2 mm voxels, Rician noise 20), traced by scripted
 * sessions of `thorax view --image` whose clicks lie on the phantom's analytic outlines:
 *  - the torso, 12 clicks on each of 20 axial planes with the livewire between them: every loop
 *    within 1 mm of the analytic outline both ways, and the model passes thorax check;
 *  - the torso's first loop copied from plane to plane and snapped: within 1.5 mm;
 *  - threshold and seed on each lung: within a voxel (2 mm);
 *  - the same session with edits undone and redone, and the saved session replayed: the contour
 *    file byte for byte;
 *  - a loop that crosses itself: drawn red in the pane, and the surface's verdict says so;
 *  - two surfaces that cross each other: drawn red, and the model (it would fail the check) not
 *    written.
 * The viewer is the program (../bin/thorax view, run through xvfb-run); the distances are measured
 * here against thx_phantom_section. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/geom/inside.h"
#include "thorax/image/image.h"
#include "thorax/io/contours_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/phantom/phantom.h"
#include "thorax/render/image.h"

#define NPLANES 20

static thx_ctx *ctx;
static thx_phantom_field *fld;
static double planes[NPLANES];

static double wall(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Runs a viewer script under Xvfb; its standard output kept in OUT. */
static int run_view(const char *script, const char *out)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "cd '%s' && timeout 300 xvfb-run -a -s '-screen 0 1600x1000x24' ../../bin/thorax view --script '%s' > '%s' 2> '%s.err'",
             tl_scratch, script, out, out);
    double t0 = wall();
    int rc = system(cmd);
    printf("  (%s: %.1f s)\n", script, wall() - t0);
    if (rc != 0) {
        char *err = tl_slurp(ctx, tl_path(out), NULL);
        fprintf(stderr, "thorax view --script %s: exit %d\n%s\n", script, rc, err ? err : "");
        free(err);
        snprintf(cmd, sizeof cmd, "grep -v 'dbus\\|session bus\\|allocation\\|^$' '%s/%s.err' >&2", tl_scratch, out);
        if (system(cmd)) {}
    }
    return rc;
}

/* both ways between a loop and the analytic outline of a phantom surface at z (mm) */
static void distances(const thx_loop *l, int surface, double z, double *to_outline, double *to_loop)
{
    thx_vec2 *pts = NULL;
    size_t m = 0;
    *to_outline = *to_loop = INFINITY;
    if (thx_phantom_section(ctx, fld, surface, z, &pts, &m) != THX_OK || m < 3) return;
    *to_outline = *to_loop = 0;
    for (size_t i = 0; i < l->n; i++) *to_outline = fmax(*to_outline, thx_loop_distance(pts, m, l->p[i]));
    for (size_t i = 0; i < m; i++) *to_loop = fmax(*to_loop, thx_loop_distance(l->p, l->n, pts[i]));
    free(pts);
}

/* 12 clicks on the analytic outline at z, as script lines, placed as a user places them: the first on
 * the outline's sharpest corner (the spinal groove: the livewire follows the image's blurred edge,
 * which cuts a corner sharper than the blur, so a user clicks there), then every twelfth of the
 * perimeter from it. */
static void clicks(FILE *f, int surface, double z)
{
    thx_vec2 *pts = NULL;
    size_t m = 0;
    CHECK_OK(ctx, thx_phantom_section(ctx, fld, surface, z, &pts, &m));
    if (m < 24) { free(pts); return; }
    double *arc = malloc((m + 1) * sizeof *arc), sharp = -1;
    size_t corner = 0, w = m / 60 + 1;
    arc[0] = 0;
    for (size_t i = 0; i < m; i++) {
        thx_vec2 a = pts[(i + m - w) % m], b = pts[i], c = pts[(i + w) % m];
        double t = fabs(atan2((b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x), (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y)));
        if (t > sharp) { sharp = t; corner = i; }
        arc[i + 1] = arc[i] + hypot(pts[(i + 1) % m].x - b.x, pts[(i + 1) % m].y - b.y);
    }
    for (size_t k = 0, i = corner; k < 12; k++) {
        double want = arc[corner] + arc[m] * (double)k / 12;
        while ((arc[i % m] + (i >= m ? arc[m] : 0)) < want) i++;
        fprintf(f, "action trace point %.2f %.2f\n", pts[i % m].x, pts[i % m].y);
    }
    free(arc);
    free(pts);
}

static void head(FILE *f)
{
    fprintf(f, "--image ph.nii.gz\n--size 360x300\n--trace-surface torso:outer\n--trace-surface lungs:lung\n");
}

/* The torso on the 20 planes by livewire; with `edits`, edits undone and redone on the way. */
static void script_livewire(const char *path, const char *save, int edits)
{
    FILE *f = fopen(tl_path(path), "w");
    head(f);
    fprintf(f, "action trace surface torso\naction trace tool livewire\n");
    for (int p = 0; p < NPLANES; p++) {
        fprintf(f, "action trace plane z=%g\n", planes[p]);
        clicks(f, 0, planes[p]);
        fprintf(f, "action trace close\n");
        if (edits && p == 5) { /* three edits, two undone, one redone and undone again */
            fprintf(f, "action trace move 1 3 0 0\naction trace delete 1 5\naction trace insert 1 2 10 10\n");
            fprintf(f, "action trace undo\naction trace undo\naction trace redo\naction trace undo\naction trace undo\n");
        }
        if (edits && p == 9) { /* a loop on another surface, then undone whole (the surface too) */
            fprintf(f, "action trace surface heart\naction trace tool points\naction trace point 0 0\naction trace point 10 0\n"
                       "action trace point 0 10\naction trace close\naction trace undo\naction trace undo\naction trace undo\n"
                       "action trace undo\naction trace undo\naction trace surface torso\naction trace tool livewire\n");
        }
    }
    fprintf(f, "action trace-screenshot %s.png\naction screenshot %s-3d.png\naction trace-save %s\nquit\n", save, save, save);
    fclose(f);
}

static thx_contours *read_contours(const char *dir)
{
    char p[1200];
    snprintf(p, sizeof p, "%s/contours.txt", tl_path(dir));
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_contours_read_raw(ctx, p, &c));
    return c;
}

/* the largest distances over every loop of surface `name`, against phantom surface `ps` (or the
 * lung nearest each loop when ps < 0) */
static void worst(const thx_contours *c, const char *name, int ps, double *w1, double *w2, size_t *n_loops)
{
    *w1 = *w2 = 0;
    *n_loops = 0;
    int s = c ? thx_contours_find_surface(c, name) : -1;
    if (s < 0) { *w1 = *w2 = INFINITY; return; }
    for (size_t j = 0; j < c->surf[s].n_layers; j++) {
        const thx_contour_layer *L = &c->surf[s].layers[j];
        for (size_t l = 0; l < L->n_loops; l++) {
            double a, b;
            if (ps >= 0) {
                distances(&L->loops[l], ps, L->z, &a, &b);
            } else { /* a lung loop: the lung whose outline it is nearest */
                double a3, b3, a4, b4;
                distances(&L->loops[l], 3, L->z, &a3, &b3);
                distances(&L->loops[l], 4, L->z, &a4, &b4);
                a = a3 < a4 ? a3 : a4;
                b = a3 < a4 ? b3 : b4;
            }
            if (a > *w1 || b > *w2) printf("  %s z = %g: loop -> outline %.3f mm, outline -> loop %.3f mm\n", name, L->z, a, b);
            *w1 = fmax(*w1, a);
            *w2 = fmax(*w2, b);
            (*n_loops)++;
        }
    }
}

static int count_red(const char *png)
{
    thx_raster *r = NULL;
    if (thx_raster_read_png(ctx, tl_path(png), &r) != THX_OK) return -1;
    int n = 0;
    for (int i = 0; i < r->w * r->h; i++) {
        const unsigned char *p = r->rgba + 4 * i;
        n += p[0] >= 250 && p[1] <= 40 && p[2] <= 40;
    }
    thx_raster_destroy(&r);
    return n;
}

int main(void)
{
    if (tl_scratch_make("test_view_trace")) return 1;
    thx_ctx_create(&ctx);
    CHECK_OK(ctx, thx_phantom_field_create(ctx, &fld));
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "cd '%s' && ../../bin/thorax phantom --image ph.nii.gz --modality mr --voxel 2 --noise 20 "
             "--noise-kind rician > phantom.out 2>&1", tl_scratch);
    CHECK(system(cmd) == 0);
    thx_image img;
    memset(&img, 0, sizeof img);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("ph.nii.gz"), NULL, &img));
    /* 20 planes of voxel centres through the torso's slab, its ends left out by 6 mm */
    double z0, z1;
    thx_phantom_slab(fld, 0, &z0, &z1);
    for (int p = 0; p < NPLANES; p++) {
        double z = z0 + 6 + (z1 - z0 - 12) * p / (NPLANES - 1);
        planes[p] = img.origin[2] + 2 * floor((z - img.origin[2]) / 2 + 0.5);
    }
    printf("torso slab z %.1f .. %.1f mm; planes %.0f .. %.0f mm\n", z0, z1, planes[0], planes[NPLANES - 1]);

    /* 1. livewire through 12 clicks a plane */
    script_livewire("a.txt", "A", 0);
    CHECK(run_view("a.txt", "a.out") == 0);
    thx_contours *A = read_contours("A");
    double w1, w2;
    size_t nl;
    worst(A, "torso", 0, &w1, &w2, &nl);
    printf("livewire, 12 clicks on each of %zu planes: loop -> outline max %.3f mm, outline -> loop max %.3f mm\n", nl, w1, w2);
    CHECK(nl == NPLANES);
    CHECK(w1 <= 1.0 && w2 <= 1.0);
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("A/model"), &m));
    thx_model_report *rep = NULL;
    if (m) CHECK_OK(ctx, thx_model_check(ctx, m, NULL, &rep));
    thx_model_report_destroy(&rep);
    thx_model_destroy(&m);
    char *out = tl_slurp(ctx, tl_path("a.out"), NULL);
    CHECK(out && strstr(out, "trace: torso: passes thorax check: 20 planes"));
    CHECK(out && strstr(out, "trace-save A: contours.txt, model/, labels.nii.gz, session.txt"));
    free(out);
    CHECK(tl_exists(tl_path("A/labels.nii.gz")));
    CHECK(count_red("A.png") == 0);

    /* 2. copy and snap: the first plane's loop copied up plane by plane */
    FILE *f = fopen(tl_path("b.txt"), "w");
    head(f);
    fprintf(f, "action trace surface torso\naction trace tool livewire\naction trace plane z=%g\n", planes[0]);
    clicks(f, 0, planes[0]);
    fprintf(f, "action trace close\n");
    for (int p = 1; p < NPLANES; p++) fprintf(f, "action trace copy %d\n", (int)lround((planes[p] - planes[p - 1]) / 2));
    fprintf(f, "action trace-save B\nquit\n");
    fclose(f);
    CHECK(run_view("b.txt", "b.out") == 0);
    thx_contours *B = read_contours("B");
    worst(B, "torso", 0, &w1, &w2, &nl);
    printf("copy and snap from plane to plane (%zu planes): loop -> outline max %.3f mm, outline -> loop max %.3f mm\n", nl, w1, w2);
    CHECK(nl == NPLANES);
    CHECK(w1 <= 1.5 && w2 <= 1.5);

    /* 3. threshold and seed in each lung, on the planes through the lungs' middle */
    double l0, l1, r0, r1;
    thx_phantom_slab(fld, 3, &r0, &r1);
    thx_phantom_slab(fld, 4, &l0, &l1);
    double lz0 = fmax(r0, l0) + 0.3 * (fmin(r1, l1) - fmax(r0, l0)), lz1 = fmax(r0, l0) + 0.9 * (fmin(r1, l1) - fmax(r0, l0));
    f = fopen(tl_path("c.txt"), "w");
    head(f);
    fprintf(f, "action trace surface lungs\n");
    int n_lung_planes = 0;
    for (int p = 0; p < 8; p++) {
        double z = lz0 + (lz1 - lz0) * p / 7;
        z = img.origin[2] + 2 * floor((z - img.origin[2]) / 2 + 0.5);
        fprintf(f, "action trace plane z=%g\n", z);
        for (int lung = 3; lung <= 4; lung++) {
            thx_vec2 *pts = NULL;
            size_t mm = 0;
            CHECK_OK(ctx, thx_phantom_section(ctx, fld, lung, z, &pts, &mm));
            /* the seed: the point inside the lung farthest from its outline (a crescent's centroid lies outside) */
            double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY, cx = 0, cy = 0, best = -1;
            for (size_t i = 0; i < mm; i++) {
                bx0 = fmin(bx0, pts[i].x); bx1 = fmax(bx1, pts[i].x);
                by0 = fmin(by0, pts[i].y); by1 = fmax(by1, pts[i].y);
            }
            for (double x = bx0; x <= bx1; x += 1)
                for (double y = by0; y <= by1; y += 1) {
                    int in = 0;
                    for (size_t i = 0, j = mm - 1; i < mm; j = i++)
                        if ((pts[i].y > y) != (pts[j].y > y) &&
                            x < pts[j].x + (y - pts[j].y) * (pts[i].x - pts[j].x) / (pts[i].y - pts[j].y))
                            in = !in;
                    thx_vec2 q = {x, y};
                    double d = in ? thx_loop_distance(pts, mm, q) : -1;
                    if (d > best) { best = d; cx = x; cy = y; }
                }
            fprintf(f, "action trace region -1000 170 %.2f %.2f\n", cx, cy);
            free(pts);
        }
        n_lung_planes++;
    }
    fprintf(f, "action trace-save C\nquit\n");
    fclose(f);
    CHECK(run_view("c.txt", "c.out") == 0);
    thx_contours *C = read_contours("C");
    worst(C, "lungs", -1, &w1, &w2, &nl);
    printf("threshold [-1000, 170] + seed in each lung on %d planes (%zu loops): loop -> outline max %.3f mm, outline -> loop "
           "max %.3f mm\n", n_lung_planes, nl, w1, w2);
    CHECK(nl == 2 * (size_t)n_lung_planes);
    CHECK(w1 <= 2.0 && w2 <= 2.0);

    /* 4. undo and redo, and the saved session replayed: the same file, byte for byte */
    script_livewire("d.txt", "D", 1);
    CHECK(run_view("d.txt", "d.out") == 0);
    char *fa = tl_slurp(ctx, tl_path("A/contours.txt"), NULL), *fd = tl_slurp(ctx, tl_path("D/contours.txt"), NULL);
    CHECK(fa && fd && !strcmp(fa, fd));
    char *sess = tl_slurp(ctx, tl_path("A/session.txt"), NULL);
    CHECK(sess && strstr(sess, "action trace close"));
    f = fopen(tl_path("e.txt"), "w");
    fprintf(f, "%saction trace-screenshot E.png\naction trace-save E\nquit\n", sess ? sess : "");
    fclose(f);
    CHECK(run_view("e.txt", "e.out") == 0);
    char *fe = tl_slurp(ctx, tl_path("E/contours.txt"), NULL);
    CHECK(fa && fe && !strcmp(fa, fe));
    /* ... and the same picture in the pane, pixel for pixel */
    thx_raster *pa = NULL, *pe = NULL;
    CHECK_OK(ctx, thx_raster_read_png(ctx, tl_path("A.png"), &pa));
    CHECK_OK(ctx, thx_raster_read_png(ctx, tl_path("E.png"), &pe));
    CHECK(pa && pe && pa->w == pe->w && pa->h == pe->h && !memcmp(pa->rgba, pe->rgba, 4 * (size_t)pa->w * (size_t)pa->h));
    thx_raster_destroy(&pa);
    thx_raster_destroy(&pe);
    printf("undo/redo (%s) and the session replayed (%s): the contour file byte for byte\n", fa && fd && !strcmp(fa, fd) ? "same" : "DIFFERENT",
           fa && fe && !strcmp(fa, fe) ? "same" : "DIFFERENT");
    free(fa);
    free(fd);
    free(fe);
    free(sess);

    /* 5. a loop that crosses itself is drawn red, and the surface's verdict names the crossing */
    f = fopen(tl_path("f.txt"), "w");
    head(f);
    fprintf(f, "action trace surface torso\naction trace plane z=%g\n", planes[3]);
    fprintf(f, "action trace point -60 -40\naction trace point 60 40\naction trace point 60 -40\naction trace point -60 40\n"
               "action trace close\naction trace plane z=%g\n", planes[4]);
    clicks(f, 0, planes[4]);
    fprintf(f, "action trace close\naction trace plane z=%g\naction trace-screenshot F.png\naction trace-save F\nquit\n", planes[3]);
    fclose(f);
    CHECK(run_view("f.txt", "f.out") == 0);
    int red = count_red("F.png");
    out = tl_slurp(ctx, tl_path("f.out"), NULL);
    printf("a bow tie: %d red pixels in the pane; verdict: %s\n", red, out && strstr(out, "intersects itself") ? "crossing named" : "?");
    CHECK(red > 50);
    CHECK(out && strstr(out, "trace: torso: not built:") && strstr(out, "intersects itself"));
    CHECK(out && strstr(out, "model not written"));
    CHECK(!tl_exists(tl_path("F/model")));
    free(out);

    /* 6. two surfaces that each pass but cross each other: marked, and the model (which would fail
     *    thorax check) not written, the contours and session are */
    f = fopen(tl_path("g.txt"), "w");
    head(f);
    fprintf(f, "action trace surface torso\naction trace tool livewire\n");
    for (int p = 3; p <= 4; p++) {
        fprintf(f, "action trace plane z=%g\n", planes[p]);
        clicks(f, 0, planes[p]);
        fprintf(f, "action trace close\n");
    }
    fprintf(f, "action trace surface heart\naction trace tool points\n");
    for (int p = 3; p <= 4; p++)
        fprintf(f, "action trace plane z=%g\naction trace point 100 -20\naction trace point 178 -20\naction trace point 178 20\n"
                   "action trace point 100 20\naction trace close\n", planes[p]);
    fprintf(f, "action trace-screenshot G.png\naction trace-save G\nquit\n");
    fclose(f);
    CHECK(run_view("g.txt", "g.out") == 0);
    out = tl_slurp(ctx, tl_path("g.out"), NULL);
    red = count_red("G.png");
    printf("torso and a surface across it: %d red pixels; %s\n", red, out && strstr(out, "model not written") ? "the model not written" : "?");
    CHECK(out && strstr(out, "trace: torso: passes thorax check: 2 planes") && strstr(out, "trace: heart: passes thorax check: 2 planes"));
    CHECK(out && strstr(out, "model not written"));
    CHECK(red > 50);
    CHECK(tl_exists(tl_path("G/contours.txt")) && tl_exists(tl_path("G/session.txt")));
    CHECK(!tl_exists(tl_path("G/model")) && !tl_exists(tl_path("G/labels.nii.gz")));
    free(out);

    thx_contours_destroy(&A);
    thx_contours_destroy(&B);
    thx_contours_destroy(&C);
    thx_image_free(&img);
    thx_phantom_field_destroy(&fld);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_view_trace");
}
