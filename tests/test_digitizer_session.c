/* A tracing session (thorax/digitizer/session.h) on a synthetic scan: a bright cylinder whose radius
 * grows along z, blurred. Points and livewire loops, closing, editing, undo and redo, the log replayed
 * into a new session byte for byte, threshold and seed, copy and snap, interpolation, crossings, the
 * contours made and loaded again, and bad lines that change nothing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/session.h"
#include "thorax/io/contours_file.h"

#define NX 96
#define NZ 12
#define CX 3.0
#define CY -2.0

/* the cylinder's radius at height z (mm) */
static double radius(double z) { return 20 + 0.75 * z; }

static void make_image(thx_ctx *ctx, thx_image *img)
{
    size_t n[3] = {NX, NX, NZ};
    CHECK_OK(ctx, thx_image_alloc(ctx, n, img));
    img->spacing[0] = img->spacing[1] = 1;
    img->spacing[2] = 2;
    img->origin[0] = img->origin[1] = -47.5;
    img->origin[2] = 0;
    for (size_t k = 0; k < NZ; k++)
        for (size_t j = 0; j < NX; j++)
            for (size_t i = 0; i < NX; i++) {
                double x = -47.5 + (double)i - CX, y = -47.5 + (double)j - CY, z = 2.0 * (double)k;
                double d = radius(z) - hypot(x, y);
                img->v[thx_image_at(img, i, j, k)] = (float)(100 * 0.5 * (1 + erf(d / (sqrt(2.0) * 1.2))));
            }
}

/* max | |p - c| - r | over a loop's points */
static double circle_err(const thx_dig_loop *l, double r)
{
    double w = 0;
    for (size_t i = 0; i < l->n; i++) w = fmax(w, fabs(hypot(l->p[i].x - CX, l->p[i].y - CY) - r));
    return w;
}

static void apply_ok(thx_ctx *ctx, thx_dig_session *s, const char *line)
{
    thx_status st = thx_dig_apply(ctx, s, line);
    if (st != THX_OK) fprintf(stderr, "line '%s': %s\n", line, thx_ctx_message(ctx));
    CHECK(st == THX_OK);
}

/* the contour file of the session's loops, as text */
static char *contours_text(thx_ctx *ctx, thx_dig_session *s, const char *name)
{
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_dig_contours(ctx, s, -1, &c, NULL));
    if (!c) return NULL;
    CHECK_OK(ctx, thx_contours_write(ctx, c, tl_path(name), NULL));
    thx_contours_destroy(&c);
    return tl_slurp(ctx, tl_path(name), NULL);
}

/* 12 clicks on the circle of plane z with the livewire between them */
static void livewire_loop(thx_ctx *ctx, thx_dig_session *s, double z)
{
    char line[128];
    snprintf(line, sizeof line, "plane z=%g", z);
    apply_ok(ctx, s, line);
    apply_ok(ctx, s, "tool livewire");
    double r = radius(z);
    for (int i = 0; i < 12; i++) {
        double t = 2 * M_PI * i / 12 + 0.1;
        snprintf(line, sizeof line, "point %.2f %.2f", CX + r * cos(t), CY + r * sin(t));
        apply_ok(ctx, s, line);
    }
    apply_ok(ctx, s, "close");
}

static void test_livewire_undo_replay(thx_ctx *ctx, const thx_image *img)
{
    thx_dig_session *s = NULL;
    CHECK_OK(ctx, thx_dig_session_create(ctx, img, &s));
    CHECK(thx_dig_n_planes(s) == NZ);
    CHECK_NEAR(thx_dig_plane_z(s, 3), 6.0, 1e-12);
    apply_ok(ctx, s, "surface torso");
    CHECK(thx_dig_surface_role(s, 0) == THX_ROLE_OUTER);
    livewire_loop(ctx, s, 6);
    const thx_dig_loop *l;
    CHECK(thx_dig_loops(s, 0, 3, &l) == 1);
    double err = circle_err(&l[0], radius(6));
    printf("livewire through 12 clicks at z = 6: %zu points, max |r - %.2f| = %.3f mm\n", l[0].n, radius(6), err);
    CHECK(l[0].closed && l[0].n > 60);
    CHECK(err < 0.5);
    livewire_loop(ctx, s, 14);
    char *base = contours_text(ctx, s, "base.txt");
    /* edits, then undone: the contours come back byte for byte */
    size_t nu = thx_dig_n_undo(s);
    apply_ok(ctx, s, "plane z=6");
    apply_ok(ctx, s, "move 1 3 0 0");
    apply_ok(ctx, s, "insert 1 5 1 1");
    apply_ok(ctx, s, "delete 1 7");
    apply_ok(ctx, s, "surface lungs");
    apply_ok(ctx, s, "tool points");
    apply_ok(ctx, s, "point -5 -5");
    apply_ok(ctx, s, "point 5 -5");
    apply_ok(ctx, s, "point 0 5");
    apply_ok(ctx, s, "close");
    CHECK(thx_dig_n_surfaces(s) == 2);
    CHECK(thx_dig_n_undo(s) == nu + 8); /* surface lungs made is a step; plane, tool are not */
    char *edited = contours_text(ctx, s, "edited.txt");
    CHECK(edited && base && strcmp(edited, base) != 0);
    for (int i = 0; i < 8; i++) apply_ok(ctx, s, "undo");
    CHECK(thx_dig_n_surfaces(s) == 1);
    char *undone = contours_text(ctx, s, "undone.txt");
    CHECK(undone && base && !strcmp(undone, base));
    apply_ok(ctx, s, "plane z=20"); /* redo acts where the line was first applied, not on the plane shown */
    for (int i = 0; i < 8; i++) apply_ok(ctx, s, "redo");
    char *redone = contours_text(ctx, s, "redone.txt");
    CHECK(redone && edited && !strcmp(redone, edited));
    CHECK(thx_dig_apply(ctx, s, "redo") == THX_EINPUT && tl_msg_has(ctx, "nothing to redo"));
    /* the log replayed into a new session gives the same file */
    const char *const *lines;
    size_t nl = thx_dig_log(s, &lines);
    thx_dig_session *t = NULL;
    CHECK_OK(ctx, thx_dig_session_create(ctx, img, &t));
    for (size_t i = 0; i < nl; i++) apply_ok(ctx, t, lines[i]);
    char *replayed = contours_text(ctx, t, "replayed.txt");
    CHECK(replayed && edited && !strcmp(replayed, edited));
    printf("undo x8 gives the file before the edits, redo x8 the edited one, the log of %zu lines replays it\n", nl);
    /* a bad line changes nothing and names the object */
    unsigned long g = thx_dig_surface_gen(s, 0);
    size_t n_log = thx_dig_log(s, &lines);
    apply_ok(ctx, s, "surface torso");
    CHECK(thx_dig_apply(ctx, s, "move 4 1 0 0") == THX_EINPUT && tl_msg_has(ctx, "torso has 1 loop on plane z=6"));
    CHECK(thx_dig_apply(ctx, s, "move 1 9999 0 0") == THX_EINPUT && tl_msg_has(ctx, "loop 1 of torso has"));
    CHECK(thx_dig_apply(ctx, s, "point 500 0") == THX_EINPUT && tl_msg_has(ctx, "outside the image"));
    CHECK(thx_dig_apply(ctx, s, "plane z=900") == THX_EINPUT && tl_msg_has(ctx, "outside the image's planes"));
    CHECK(thx_dig_apply(ctx, s, "surface torso:heart") == THX_EINPUT && tl_msg_has(ctx, "traced already as outer"));
    CHECK(thx_dig_apply(ctx, s, "frobnicate") == THX_EINPUT && tl_msg_has(ctx, "no such line"));
    CHECK(thx_dig_apply(ctx, s, "copy 4") == THX_EINPUT && tl_msg_has(ctx, "already"));
    /* a close that fails (one point) leaves the point there, and the state as it was */
    apply_ok(ctx, s, "plane z=20");
    apply_ok(ctx, s, "point 1 1");
    unsigned long g2 = thx_dig_surface_gen(s, 0);
    CHECK(thx_dig_apply(ctx, s, "close") == THX_EINPUT && tl_msg_has(ctx, "needs 3 points"));
    const thx_dig_loop *one;
    CHECK(thx_dig_loops(s, 0, 10, &one) == 1 && one[0].n == 1 && !one[0].closed);
    CHECK(thx_dig_surface_gen(s, 0) != g); /* the point changed it */
    (void)g2;
    CHECK(thx_dig_log(s, &lines) == n_log + 3);
    /* an open loop is left out of the contours, and counted */
    thx_contours *c = NULL;
    size_t skipped = 0;
    CHECK_OK(ctx, thx_dig_contours(ctx, s, 0, &c, &skipped));
    CHECK(skipped == 1 && c && c->n_surfaces == 1 && c->surf[0].n_layers == 2);
    thx_contours_destroy(&c);
    free(base);
    free(edited);
    free(undone);
    free(redone);
    free(replayed);
    thx_dig_session_destroy(&t);
    thx_dig_session_destroy(&s);
}

static void test_region_copy_interp(thx_ctx *ctx, const thx_image *img)
{
    thx_dig_session *s = NULL;
    CHECK_OK(ctx, thx_dig_session_create(ctx, img, &s));
    apply_ok(ctx, s, "surface body:other");
    apply_ok(ctx, s, "plane z=4");
    char line[128];
    snprintf(line, sizeof line, "region 50 1000 %g %g", CX, CY);
    apply_ok(ctx, s, line);
    const thx_dig_loop *l;
    CHECK(thx_dig_loops(s, 0, 2, &l) == 1);
    double er = circle_err(&l[0], radius(4));
    printf("threshold 50 + seed at z = 4: %zu points, max |r - %.2f| = %.3f mm\n", l[0].n, radius(4), er);
    CHECK(er < 0.3);
    /* copied 3 planes up (6 mm: the radius grows 4.5 mm) and snapped there */
    apply_ok(ctx, s, "copy 3");
    CHECK(thx_dig_current_plane(s) == 5);
    CHECK(thx_dig_loops(s, 0, 5, &l) == 1);
    double es = circle_err(&l[0], radius(10));
    printf("copied to z = 10 and snapped: max |r - %.2f| = %.3f mm (%.2f before)\n", radius(10), es, radius(10) - radius(4));
    CHECK(es < 0.6);
    apply_ok(ctx, s, "copy 4 raw");
    CHECK(thx_dig_loops(s, 0, 9, &l) == 1 && circle_err(&l[0], radius(10)) < 0.6);
    apply_ok(ctx, s, "undo");
    CHECK(thx_dig_loops(s, 0, 9, &l) == 0);
    CHECK(thx_dig_current_plane(s) == 5);
    /* interpolation fills planes 3 and 4 between the traced 2 and 5 */
    apply_ok(ctx, s, "interpolate");
    long ks[16];
    size_t nk = thx_dig_planes_traced(s, 0, ks, 16);
    CHECK(nk == 4 && ks[0] == 2 && ks[1] == 3 && ks[2] == 4 && ks[3] == 5);
    for (long k = 3; k <= 4; k++) {
        CHECK(thx_dig_loops(s, 0, k, &l) == 1);
        double ei = circle_err(&l[0], radius(thx_dig_plane_z(s, k)));
        printf("interpolated at z = %g: max |r - %.2f| = %.3f mm\n", thx_dig_plane_z(s, k), radius(thx_dig_plane_z(s, k)), ei);
        CHECK(ei < 0.8);
    }
    CHECK(thx_dig_apply(ctx, s, "interpolate") == THX_EINPUT && tl_msg_has(ctx, "no gap"));
    /* crossings: a second surface's square across the circle at z = 4 */
    apply_ok(ctx, s, "plane z=4");
    apply_ok(ctx, s, "surface other:other");
    apply_ok(ctx, s, "point 0 -5");
    apply_ok(ctx, s, "point 40 -5");
    apply_ok(ctx, s, "point 40 5");
    apply_ok(ctx, s, "point 0 5");
    thx_dig_crossing *x = NULL;
    size_t nx = 0;
    CHECK_OK(ctx, thx_dig_crossings(ctx, s, 2, &x, &nx));
    CHECK(nx == 0); /* the square is open yet */
    apply_ok(ctx, s, "close");
    CHECK_OK(ctx, thx_dig_crossings(ctx, s, 2, &x, &nx));
    CHECK(nx == 1 && x && x[0].sa == 0 && x[0].sb == 1);
    if (nx) {
        /* on the circle, where the square's edge meets it */
        printf("crossing at (%.2f, %.2f)\n", x[0].x, x[0].y);
        CHECK(fabs(hypot(x[0].x - CX, x[0].y - CY) - radius(4)) < 1.0);
    }
    free(x);
    /* a loop crossing itself (a bow tie) */
    apply_ok(ctx, s, "plane z=0");
    apply_ok(ctx, s, "point -30 -30");
    apply_ok(ctx, s, "point -20 -20");
    apply_ok(ctx, s, "point -30 -20");
    apply_ok(ctx, s, "point -20 -30");
    apply_ok(ctx, s, "close");
    CHECK_OK(ctx, thx_dig_crossings(ctx, s, 0, &x, &nx));
    CHECK(nx == 1 && x && x[0].sa == 1 && x[0].sb == 1 && x[0].la == x[0].lb);
    if (nx) CHECK(fabs(x[0].x + 25) < 1e-9 && fabs(x[0].y + 25) < 1e-9);
    free(x);
    /* contours out and in: the same file */
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_dig_contours(ctx, s, -1, &c, NULL));
    CHECK(c && c->n_surfaces == 2 && c->frame.set);
    CHECK_OK(ctx, thx_contours_write(ctx, c, tl_path("out.txt"), NULL));
    thx_contours *back = NULL;
    CHECK_OK(ctx, thx_contours_read_raw(ctx, tl_path("out.txt"), &back));
    thx_dig_session *t = NULL;
    CHECK_OK(ctx, thx_dig_session_create(ctx, img, &t));
    CHECK_OK(ctx, thx_dig_load(ctx, t, back));
    thx_contours *again = NULL;
    CHECK_OK(ctx, thx_dig_contours(ctx, t, -1, &again, NULL));
    CHECK_OK(ctx, thx_contours_write(ctx, again, tl_path("again.txt"), NULL));
    char *a = tl_slurp(ctx, tl_path("out.txt"), NULL), *b = tl_slurp(ctx, tl_path("again.txt"), NULL);
    CHECK(a && b && !strcmp(a, b));
    /* a layer off the image's planes is refused by name */
    back->surf[0].layers[0].z += 0.9;
    thx_dig_session *u = NULL;
    CHECK_OK(ctx, thx_dig_session_create(ctx, img, &u));
    CHECK(thx_dig_load(ctx, u, back) == THX_EINPUT && tl_msg_has(ctx, "not on one of"));
    free(a);
    free(b);
    thx_contours_destroy(&c);
    thx_contours_destroy(&back);
    thx_contours_destroy(&again);
    thx_dig_session_destroy(&t);
    thx_dig_session_destroy(&u);
    thx_dig_session_destroy(&s);
}

int main(void)
{
    if (tl_scratch_make("test_digitizer_session")) return 1;
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image img;
    make_image(ctx, &img);
    test_livewire_undo_replay(ctx, &img);
    test_region_copy_interp(ctx, &img);
    thx_image_free(&img);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_digitizer_session");
}
