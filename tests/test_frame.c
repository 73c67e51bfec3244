/* The anatomical frame (thorax/model/frame.h): axis names, the frame from two names, its vectors and
 * left axis, the map to RAS and back (a rotation: det +1, inverse of each other), the message of
 * a missing frame. */
#include "testlib.h"
#include "thorax/model/frame.h"
#include <math.h>
#include <string.h>

static thx_ctx *ctx;

static double det3(const double a[3], const double b[3], const double c[3])
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_axis a;
    char buf[3];
    CHECK(thx_axis_parse("+z", &a) == 0 && a.axis == 2 && a.sign == 1);
    CHECK(thx_axis_parse("-y", &a) == 0 && a.axis == 1 && a.sign == -1);
    CHECK(thx_axis_parse("x", &a) == 0 && a.axis == 0 && a.sign == 1);
    CHECK(thx_axis_parse("+w", &a) != 0 && thx_axis_parse("", &a) != 0 && thx_axis_parse("+zz", &a) != 0 &&
          thx_axis_parse("--z", &a) != 0);
    a.axis = 1, a.sign = -1;
    CHECK(strcmp(thx_axis_name(a, buf), "-y") == 0);

    thx_frame f;
    CHECK(thx_frame_from_names(ctx, "+z", "-z", "--up/--front", &f) == THX_EINPUT && tl_msg_has(ctx, "different axes"));
    CHECK(thx_frame_from_names(ctx, "+q", "+y", "c.txt:3", &f) == THX_EINPUT && tl_msg_has(ctx, "c.txt:3: superior axis"));
    CHECK(thx_frame_from_names(ctx, "+z", NULL, "x", &f) == THX_EINPUT && tl_msg_has(ctx, "anterior axis"));

    /* RAS: left -x, the identity map */
    thx_frame r = thx_frame_ras();
    CHECK(thx_frame_valid(&r));
    thx_axis l = thx_frame_left(&r);
    CHECK(l.axis == 0 && l.sign == -1);
    const double p[3] = {1.5, -2.25, 7};
    double q[3], back[3];
    thx_frame_to_ras(&r, p, q);
    CHECK(q[0] == p[0] && q[1] == p[1] && q[2] == p[2]);

    /* every frame of the 24: a rotation taking up to +z, front to +y, left to -x; from_ras inverts to_ras */
    static const char *const names[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
    int n = 0, ok = 1;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) {
            if (thx_frame_from_names(ctx, names[i], names[j], "t", &f) != THX_OK) continue;
            n++;
            double u[3], fr[3], lf[3], e[3][3];
            thx_frame_vectors(&f, u, fr, lf);
            thx_frame_to_ras(&f, u, q);
            ok &= q[0] == 0 && q[1] == 0 && q[2] == 1;
            thx_frame_to_ras(&f, fr, q);
            ok &= q[0] == 0 && q[1] == 1 && q[2] == 0;
            thx_frame_to_ras(&f, lf, q);
            ok &= q[0] == -1 && q[1] == 0 && q[2] == 0;
            for (int k = 0; k < 3; k++) {
                double x[3] = {k == 0, k == 1, k == 2};
                thx_frame_to_ras(&f, x, e[k]);
            }
            ok &= det3(e[0], e[1], e[2]) == 1; /* a rotation, never a reflection */
            thx_frame_to_ras(&f, p, q);
            thx_frame_from_ras(&f, q, back);
            ok &= back[0] == p[0] && back[1] == p[1] && back[2] == p[2];
            thx_axis la = thx_frame_left(&f);
            ok &= lf[la.axis] == la.sign;
        }
    CHECK(n == 24 && ok);

    /* the Dalhousie torso: superior -y, anterior -z, so left +x */
    CHECK_OK(ctx, thx_frame_from_names(ctx, "-y", "-z", "t", &f));
    l = thx_frame_left(&f);
    CHECK(l.axis == 0 && l.sign == 1);

    thx_frame none = {0};
    CHECK(!thx_frame_valid(&none));
    CHECK(thx_frame_require(ctx, &none, "model dal", "the electrode landmarks") == THX_EINPUT &&
          tl_msg_has(ctx, "model dal has no anatomical frame") && tl_msg_has(ctx, "--up and --front to thorax import") &&
          tl_msg_has(ctx, "the electrode landmarks"));
    CHECK(thx_frame_require(ctx, &f, "m", "x") == THX_OK);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
