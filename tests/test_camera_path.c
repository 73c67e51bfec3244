/* The key-framed camera path (thorax/render/camera_path.h): every key reached at its frame (eye,
 * target, orientation, field of view to 1e-12), first and second derivatives continuous at the keys
 * (analytic from both sides, and one-sided finite differences within what their step allows), the
 * analytic derivatives against central differences, unit quaternions, no flips, two keys, non-uniform
 * frames, a 360-degree flight at its distance, named views, data frames, and bad key files refused
 * with file:line messages. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/render/camera_path.h"

static double qdot(const double a[4], const double b[4]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }
static double qnorm(const double a[4]) { return sqrt(qdot(a, a)); }

/* The angle (degrees) between two cameras' orientations. */
static double cam_angle(const thx_camera *a, const thx_camera *b)
{
    double qa[4], qb[4];
    if (thx_camera_quaternion(a, qa) || thx_camera_quaternion(b, qb)) return 999;
    double d = fabs(qdot(qa, qb));
    return 2 * acos(d > 1 ? 1 : d) * 180 / M_PI;
}

/* All the curves' values of order r as one vector (3 + 3 + 4 + 1 + 1 = 12). */
static void flat(const thx_camera_path_state *s, int r, double v[12])
{
    for (int e = 0; e < 3; e++) v[e] = s->eye[r][e], v[3 + e] = s->target[r][e];
    for (int e = 0; e < 4; e++) v[6 + e] = s->q[r][e];
    v[10] = s->fov[r], v[11] = s->height[r];
}

static thx_camera_path *make(thx_ctx *ctx, const char *text, thx_camera_keys *k)
{
    thx_camera_path *p = NULL;
    if (thx_camera_keys_parse(ctx, "t.keys", text, k) != THX_OK || thx_camera_keys_resolve(ctx, k, NULL) != THX_OK ||
        thx_camera_path_create(ctx, k, &p) != THX_OK) {
        fprintf(stderr, "make: %s\n", thx_ctx_message(ctx));
        return NULL;
    }
    return p;
}

/* The checks every path must pass: keys reached, C2 at the keys, derivatives right, unit, no flips. */
static void check_path(thx_ctx *ctx, const char *text, double max_step_deg)
{
    thx_camera_keys k;
    thx_camera_path *p = make(ctx, text, &k);
    CHECK(p != NULL);
    if (!p) return;
    /* every key reached at its frame */
    for (size_t j = 0; j < k.n; j++) {
        thx_camera c;
        const thx_camera *kc = &k.keys[j].cam;
        thx_camera_path_camera(p, k.keys[j].frame, &c);
        double scale = 1;
        for (int e = 0; e < 3; e++) scale = fmax(scale, fmax(fabs(kc->eye[e]), fabs(kc->center[e])));
        for (int e = 0; e < 3; e++) {
            CHECK_NEAR(c.eye[e], kc->eye[e], 1e-12 * scale);
            CHECK_NEAR(c.center[e], kc->center[e], 1e-12 * scale);
        }
        CHECK_NEAR(c.fov_deg, kc->fov_deg, 1e-12 * fmax(1, kc->fov_deg));
        double qa[4], qb[4];
        CHECK(thx_camera_quaternion(&c, qa) == 0 && thx_camera_quaternion(kc, qb) == 0);
        CHECK_NEAR(fabs(qdot(qa, qb)), 1, 1e-12);
        /* the curve's own quaternion, from either side */
        thx_camera_path_state sl, sr;
        thx_camera_path_state_at(p, k.keys[j].frame, -1, &sl);
        thx_camera_path_state_at(p, k.keys[j].frame, 1, &sr);
        CHECK_NEAR(fabs(qdot(sl.q[0], qb)), 1, 1e-12);
        CHECK_NEAR(fabs(qdot(sr.q[0], qb)), 1, 1e-12);
        if (j == 0 || j + 1 == k.n) continue;
        /* C2: the pieces before and after the key agree in value, first and second derivative */
        for (int r = 0; r < 3; r++) {
            double a[12], b[12], mag = 0;
            flat(&sl, r, a), flat(&sr, r, b);
            for (int e = 0; e < 12; e++) mag = fmax(mag, fabs(a[e]));
            for (int e = 0; e < 12; e++) CHECK_NEAR(a[e], b[e], 1e-9 * fmax(1, mag));
        }
        /* one-sided finite differences agree within h times the next derivative */
        double t = k.keys[j].frame, h = 1e-3;
        thx_camera_path_state sm1, sm2, sp1, sp2;
        thx_camera_path_state_at(p, t - h, 1, &sm1);
        thx_camera_path_state_at(p, t - 2 * h, 1, &sm2);
        thx_camera_path_state_at(p, t + h, 1, &sp1);
        thx_camera_path_state_at(p, t + 2 * h, 1, &sp2);
        double f0[12], fm1[12], fm2[12], fp1[12], fp2[12], d2[12], d2l[12], d2r[12];
        flat(&sr, 0, f0), flat(&sm1, 0, fm1), flat(&sm2, 0, fm2), flat(&sp1, 0, fp1), flat(&sp2, 0, fp2);
        flat(&sr, 2, d2), flat(&sm1, 2, d2l), flat(&sp1, 2, d2r);
        for (int e = 0; e < 12; e++) {
            double dl = (f0[e] - fm1[e]) / h, dr = (fp1[e] - f0[e]) / h;
            double m3 = fmax(fabs(d2r[e] - d2[e]), fabs(d2[e] - d2l[e])) / h; /* |third derivative| */
            CHECK(fabs(dl - dr) <= h * (fabs(d2[e]) + 2 * h * m3) * 1.01 + 1e-9 * fmax(1, fabs(f0[e])));
            double sl2 = (f0[e] - 2 * fm1[e] + fm2[e]) / (h * h), sr2 = (fp2[e] - 2 * fp1[e] + f0[e]) / (h * h);
            CHECK(fabs(sl2 - sr2) <= 2.5 * h * m3 + 2e-9 * fmax(1, fabs(f0[e])) / (h * h));
        }
    }
    /* the analytic derivatives against central differences inside the pieces; unit quaternions; no flips */
    double t0 = k.keys[0].frame, t1 = k.keys[k.n - 1].frame, worst_unit = 0, worst_step = 0, worst_d1 = 0;
    thx_camera prev;
    thx_camera_path_camera(p, t0, &prev);
    for (int i = 1; t0 + 0.1 * i < t1 - 0.05; i++) {
        double t = t0 + 0.1 * i;
        thx_camera_path_state s, sp, sm;
        double h = 1e-4;
        thx_camera_path_state_at(p, t, 1, &s);
        thx_camera_path_state_at(p, t + h, 1, &sp);
        thx_camera_path_state_at(p, t - h, 1, &sm);
        worst_unit = fmax(worst_unit, fabs(qnorm(s.q[0]) - 1));
        double f[12], fp[12], fm[12], d1[12], d2[12];
        flat(&s, 0, f), flat(&sp, 0, fp), flat(&sm, 0, fm), flat(&s, 1, d1), flat(&s, 2, d2);
        for (int e = 0; e < 12; e++) {
            double mag = fmax(1, fabs(f[e]));
            worst_d1 = fmax(worst_d1, fabs((fp[e] - fm[e]) / (2 * h) - d1[e]) / mag);
            CHECK(fabs((fp[e] - 2 * f[e] + fm[e]) / (h * h) - d2[e]) <= 1e-3 * mag + 1e-3 * fabs(d2[e]));
        }
        thx_camera c;
        thx_camera_path_camera(p, t, &c);
        worst_step = fmax(worst_step, cam_angle(&prev, &c) / 0.1);
        double du = prev.up[0] * c.up[0] + prev.up[1] * c.up[1] + prev.up[2] * c.up[2];
        CHECK(du > 0.9);
        prev = c;
    }
    CHECK(worst_unit < 1e-12);
    CHECK(worst_d1 < 1e-6);
    CHECK(worst_step <= max_step_deg);
    printf("path: %zu keys, |q|-1 %.1e, d/dt vs differences %.1e, the largest turn %.2f deg/frame (bound %.1f)\n", k.n,
           worst_unit, worst_d1, worst_step, max_step_deg);
    thx_camera_path_destroy(&p);
    thx_camera_keys_free(&k);
}

/* A flight round the z axis at radius R, keys every `step` degrees, at frames 1, 1 + df, ... */
static void circle(char *buf, size_t cap, double R, int step, int df, const char *extra)
{
    size_t len = snprintf(buf, cap, "%s\n", extra);
    for (int a = 0, f = 1; a <= 360; a += step, f += df)
        len += snprintf(buf + len, cap - len, "%d eye %.17g,%.17g,50 target 0,0,50 up 0,0,1 fov 30\n", f,
                        R * sin(a * M_PI / 180), -R * cos(a * M_PI / 180));
}

static double circle_error(thx_ctx *ctx, const char *text, double R, double *look_err)
{
    thx_camera_keys k;
    thx_camera_path *p = make(ctx, text, &k);
    if (!p) return INFINITY;
    double worst = 0, wl = 0;
    for (double t = k.keys[0].frame; t <= k.keys[k.n - 1].frame; t += 0.05) {
        thx_camera c;
        thx_camera_path_camera(p, t, &c);
        double d = hypot(c.eye[0], c.eye[1]);
        worst = fmax(worst, fabs(d - R) / R);
        CHECK_NEAR(c.eye[2], 50, 1e-9);
        /* the view's direction against the direction to the axis (look orientation) */
        double b[3] = {c.eye[0] - c.center[0], c.eye[1] - c.center[1], c.eye[2] - c.center[2]};
        double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double cosang = (b[0] * c.eye[0] + b[1] * c.eye[1]) / (lb * d);
        wl = fmax(wl, acos(fmin(1, cosang)) * 180 / M_PI);
    }
    *look_err = wl;
    thx_camera_path_destroy(&p);
    thx_camera_keys_free(&k);
    return worst;
}

static void bad(thx_ctx *ctx, const char *text, const char *needle, int stage)
{
    thx_camera_keys k;
    thx_camera_path *p = NULL;
    thx_status st = thx_camera_keys_parse(ctx, "bad.keys", text, &k);
    if (st == THX_OK) st = thx_camera_keys_resolve(ctx, &k, NULL);
    if (st == THX_OK) st = thx_camera_path_create(ctx, &k, &p);
    CHECK(st != THX_OK);
    CHECK(p == NULL);
    if (st != THX_OK) CHECK(tl_msg_has(ctx, needle));
    (void)stage;
    thx_camera_keys_free(&k);
    thx_camera_path_destroy(&p);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    char buf[8192];

    /* non-uniform frames, turns about changing axes, roll, a changing field of view */
    check_path(ctx,
               "# a wandering camera\n"
               "1  eye 0,-800,100 target 0,0,0 up 0,0,1 fov 30\n"
               "7  eye 500,-500,300 target 10,0,20 up 0.2,0,1 fov 25   # rolled\n"
               "20 eye 700,200,-100 target 0,20,0 fov 40\n"
               "24 eye 100,600,0 target 0,0,0 up 0,0.3,1\n"
               "40 eye -600,100,500 up 0,0,1 fov 20\n"
               "41 eye -620,80,480\n",
               40);
    /* rest ends, orthographic with a changing height, looking by orientation */
    check_path(ctx,
               "ends rest\nlook orientation\n"
               "1 eye 0,-800,0 target 0,0,0 up 0,0,1 fov 0 height 400\n"
               "10 eye 800,0,0 height 300\n"
               "30 eye 0,0,800 up 0,1,0 height 500\n",
               40);
    /* two keys only */
    check_path(ctx, "1 eye 0,-500,0 target 0,0,0 up 0,0,1 fov 30\n11 eye 500,0,0 up 0,0,1 fov 30\n", 20);
    /* the 360-degree flight, keys every 90 degrees */
    circle(buf, sizeof buf, 800, 90, 12, "");
    check_path(ctx, buf, 15);
    circle(buf, sizeof buf, 800, 90, 12, "ends closed");
    check_path(ctx, buf, 15);

    /* two keys, one axis: the turn is linear in the frame (the natural ends' straight line), the eye too */
    {
        thx_camera_keys k;
        thx_camera_path *p = make(ctx, "1 eye 0,-500,0 target 0,0,0 up 0,0,1 fov 30\n11 eye 500,0,0 fov 50\n", &k);
        CHECK(p != NULL);
        for (int f = 1; p && f <= 11; f++) {
            thx_camera c;
            thx_camera_path_state s0, s;
            thx_camera_path_state_at(p, 1, 1, &s0);
            thx_camera_path_state_at(p, f, 1, &s);
            thx_camera_path_camera(p, f, &c);
            double d = fabs(qdot(s0.q[0], s.q[0]));
            CHECK_NEAR(2 * acos(fmin(1, d)) * 180 / M_PI, 9.0 * (f - 1), 1e-6);
            CHECK_NEAR(c.eye[0], 50.0 * (f - 1), 1e-9);
            CHECK_NEAR(c.fov_deg, 30 + 2.0 * (f - 1), 1e-9);
        }
        /* held before the first key and after the last */
        thx_camera a, b;
        if (p) {
            thx_camera_path_camera(p, 0, &a);
            thx_camera_path_camera(p, 1, &b);
            CHECK(!memcmp(&a, &b, sizeof a));
            CHECK(thx_camera_path_first(p) == 1 && thx_camera_path_last(p) == 11);
        }
        thx_camera_path_destroy(&p);
        thx_camera_keys_free(&k);
    }

    /* the 360-degree flight stays near its radius; more keys, nearer */
    {
        double look;
        circle(buf, sizeof buf, 800, 90, 12, "");
        double e90 = circle_error(ctx, buf, 800, &look);
        circle(buf, sizeof buf, 800, 45, 6, "");
        double e45 = circle_error(ctx, buf, 800, &look);
        circle(buf, sizeof buf, 800, 90, 12, "ends closed");
        double c90 = circle_error(ctx, buf, 800, &look);
        circle(buf, sizeof buf, 800, 45, 6, "ends closed");
        double c45 = circle_error(ctx, buf, 800, &look);
        circle(buf, sizeof buf, 800, 45, 6, "look orientation");
        double e45o = circle_error(ctx, buf, 800, &look);
        printf("360-degree flight at 800 mm: distance off by %.2f%% (keys every 90 degrees), %.3f%% (every 45); "
               "closed: %.2f%%, %.3f%%; look orientation: the view %.2f degrees off the axis at worst\n",
               100 * e90, 100 * e45, 100 * c90, 100 * c45, look);
        CHECK(e90 < 0.15);
        CHECK(e45 < 0.035);
        CHECK(c90 < 0.05);
        CHECK(c45 < 0.005);
        CHECK(e45o == e45);
        CHECK(look < 3);
    }

    /* a closed flight joins C2 at its seam: the velocity and acceleration at the first key equal those at the
       last (the quaternion is -1 times itself after a full turn) */
    {
        thx_camera_keys k;
        circle(buf, sizeof buf, 800, 90, 12, "ends closed");
        thx_camera_path *p = make(ctx, buf, &k);
        CHECK(p != NULL);
        if (p) {
            thx_camera_path_state a, b;
            thx_camera_path_state_at(p, thx_camera_path_first(p), 1, &a);
            thx_camera_path_state_at(p, thx_camera_path_last(p), -1, &b);
            double sg = qdot(a.q[0], b.q[0]) < 0 ? -1 : 1;
            for (int r = 0; r < 3; r++) {
                for (int e = 0; e < 3; e++) CHECK_NEAR(a.eye[r][e], b.eye[r][e], 1e-9 * 800);
                for (int e = 0; e < 4; e++) CHECK_NEAR(a.q[r][e], sg * b.q[r][e], 1e-9);
            }
            CHECK(sg < 0);
        }
        thx_camera_path_destroy(&p);
        thx_camera_keys_free(&k);
        circle(buf, sizeof buf, 800, 90, 12, "ends closed");
        strcat(buf, "60 eye 0,-700,50\n");
        bad(ctx, buf, "ends closed: the last key must repeat the first key's camera (line 2)", 2);
    }

    /* named views on the standard cameras of a box */
    {
        thx_camera views[6];
        double lo[3] = {-150, -100, 0}, hi[3] = {150, 100, 300};
        for (int v = 0; v < 6; v++) thx_camera_view(&views[v], (thx_view)v, lo, hi, 1);
        thx_camera_keys k;
        CHECK_OK(ctx, thx_camera_keys_parse(ctx, "v.keys", "1 view anterior distance 900 fov 30\n13 view left\n"
                                                           "25 view posterior target 0,0,100 distance 700 data 3\n", &k));
        CHECK_OK(ctx, thx_camera_keys_resolve(ctx, &k, views));
        CHECK_NEAR(k.keys[0].cam.eye[1], 900, 1e-9); /* anterior: +y */
        CHECK_NEAR(k.keys[0].cam.eye[2], 150, 1e-9);
        CHECK_NEAR(k.keys[1].cam.eye[0], -900, 1e-9); /* left: -x, the distance carried on */
        CHECK_NEAR(k.keys[1].cam.fov_deg, 30, 0);
        CHECK_NEAR(k.keys[2].cam.eye[1], -700, 1e-9);
        CHECK_NEAR(k.keys[2].cam.eye[2], 100, 1e-9);
        CHECK_NEAR(k.keys[2].cam.up[2], 1, 0);
        thx_camera_path *p = NULL;
        CHECK_OK(ctx, thx_camera_path_create(ctx, &k, &p));
        if (p) {
            CHECK(thx_camera_path_data_frame(p, 1) == 3 && thx_camera_path_data_frame(p, 30) == 3);
            thx_camera c;
            thx_camera_path_camera(p, 7, &c); /* halfway from anterior to left: the up stays cranial */
            CHECK(c.up[2] > 0.999);
        }
        thx_camera_path_destroy(&p);
        thx_camera_keys_free(&k);
        CHECK(thx_camera_keys_parse(ctx, "v.keys", "1 view sideways fov 30\n2 view left\n", &k) != THX_OK);
        CHECK(tl_msg_has(ctx, "v.keys:1: view 'sideways'"));
    }

    /* data frames: linear in the movie frame between the keys that give one, rounded, held outside */
    {
        thx_camera_keys k;
        thx_camera_path *p = make(ctx, "3 eye 0,-500,0 target 0,0,0 up 0,0,1 fov 30 data 1\n"
                                       "10 eye 500,0,0\n13 eye 0,500,0 data 11\n30 eye -500,0,0 data 2\n", &k);
        CHECK(p != NULL);
        if (p) {
            CHECK(thx_camera_path_data_frame(p, 1) == 1);
            CHECK(thx_camera_path_data_frame(p, 3) == 1);
            CHECK(thx_camera_path_data_frame(p, 8) == 6);  /* 1 + 10 * 5/10 */
            CHECK(thx_camera_path_data_frame(p, 4) == 2);  /* 2.0 */
            CHECK(thx_camera_path_data_frame(p, 13) == 11);
            CHECK(thx_camera_path_data_frame(p, 20) == 7); /* 11 - 9 * 7/17 = 7.29 */
            CHECK(thx_camera_path_data_frame(p, 40) == 2);
        }
        thx_camera_path_destroy(&p);
        thx_camera_keys_free(&k);
        p = make(ctx, "1 eye 0,-500,0 target 0,0,0 up 0,0,1 fov 30\n5 eye 1,-500,0\n", &k);
        CHECK(p && thx_camera_path_data_frame(p, 3) == 0);
        thx_camera_path_destroy(&p);
        thx_camera_keys_free(&k);
    }

    /* bad key files: file:line and the field */
    const char *A = "1 eye 0,-500,0 target 0,0,0 up 0,0,1 fov 30\n";
    snprintf(buf, sizeof buf, "%s5 eye 1,2,3\n5 eye 3,2,1\n", A);
    bad(ctx, buf, "bad.keys:3: frame 5: not after the previous key's frame 5 (line 2)", 0);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 up 1,0,0\n", A);
    bad(ctx, buf, "bad.keys:2: up 1,0,0 is along the view direction", 1);
    bad(ctx, A, "bad.keys: 1 key: a camera flight needs at least 2", 0);
    bad(ctx, "# nothing\n", "bad.keys: 0 keys", 0);
    snprintf(buf, sizeof buf, "%s2 eye nan,0,0\n", A);
    bad(ctx, buf, "bad.keys:2: eye 'nan,0,0': three finite numbers", 0);
    snprintf(buf, sizeof buf, "%s2 eye 1,0\n", A);
    bad(ctx, buf, "bad.keys:2: eye '1,0'", 0);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 fov 200\n", A);
    bad(ctx, buf, "bad.keys:2: fov '200'", 0);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 zoom 2\n", A);
    bad(ctx, buf, "bad.keys:2: 'zoom': expected data, eye", 0);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 fov\n", A);
    bad(ctx, buf, "bad.keys:2: fov: no value", 0);
    snprintf(buf, sizeof buf, "%s2 target 1,1,1\n", A);
    bad(ctx, buf, "bad.keys:2: frame 2: no eye X,Y,Z or view NAME", 0);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 view left\n", A);
    bad(ctx, buf, "bad.keys:2: eye and view both given", 0);
    snprintf(buf, sizeof buf, "%s2 view left\n", A);
    bad(ctx, buf, "bad.keys:2: view left: no model", 1);
    snprintf(buf, sizeof buf, "%s2 eye 500,0,0 fov 0 height 300\n", A);
    bad(ctx, buf, "bad.keys:2: fov 0: perspective and orthographic keys cannot be mixed", 1);
    bad(ctx, "1 eye 0,-500,0 up 0,0,1 fov 30\n2 eye 1,1,1\n", "bad.keys:1: the first key gives no target", 1);
    bad(ctx, "1 eye 0,-500,0 target 0,0,0 up 0,0,1\n2 eye 1,1,1\n", "bad.keys:1: the first key gives no fov", 1);
    snprintf(buf, sizeof buf, "%s2 eye 0,0,0\n", A);
    bad(ctx, buf, "bad.keys:2: the eye 0,0,0 is on the target", 1);
    snprintf(buf, sizeof buf, "%s0 eye 1,1,1\n", A);
    bad(ctx, buf, "bad.keys:2: frame '0'", 0);
    snprintf(buf, sizeof buf, "%s2 eye 1,1,1 data 0\n", A);
    bad(ctx, buf, "bad.keys:2: data '0'", 0);
    snprintf(buf, sizeof buf, "%s2 eye 0,500,0\n", A);
    bad(ctx, buf, "bad.keys:2: the camera turns 180.0 degrees from the key at line 1", 2);
    snprintf(buf, sizeof buf, "%sends sudden\n", A);
    bad(ctx, buf, "bad.keys:2: ends: settings come before the first key", 0);
    bad(ctx, "ends sudden\n", "bad.keys:1: ends 'sudden': natural, rest or closed", 0);
    snprintf(buf, sizeof buf, "%s3 eye 500,0,0 fov 170\n4 eye 0,500,0 fov 1\n", A);
    bad(ctx, buf, "the field of view leaves 0..180 degrees", 2);
    CHECK(thx_camera_keys_read(ctx, "/nonexistent/k.keys", &(thx_camera_keys){0}) != THX_OK);

    thx_ctx_destroy(&ctx);
    return tl_finish();
}
