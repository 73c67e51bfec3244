/* The livewire (thorax/digitizer/livewire.h): paths on synthetic planes follow the shapes' edges; the
 * search is Dijkstra's optimum on its own graph (checked against a plain O(n^2) Dijkstra); the
 * on-the-fly expansion gives the same paths as a fresh search; bad input is refused. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/livewire.h"

/* Deterministic standard normal numbers (xorshift + Box-Muller). */
static uint64_t rng = 88172645463325252ULL;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2 * log(unif())) * cos(2 * M_PI * unif()); }

/* A plane of w x h 1 mm pixels (axial, z = 7, origin (-3, 5)) whose value is 100 inside the shape given by
 * its signed distance sd (positive inside), blurred by a Gaussian of blur px (erf profile), plus noise. */
typedef double (*sdf)(double x, double y);
static void make_plane(thx_image_slice *s, size_t w, size_t h, sdf f, double blur, double noise)
{
    memset(s, 0, sizeof *s);
    s->w = w;
    s->h = h;
    s->v = malloc(w * h * sizeof *s->v);
    s->origin[0] = -3;
    s->origin[1] = 5;
    s->origin[2] = 7;
    s->du[0] = 1;
    s->dv[1] = 1;
    s->normal[2] = 1;
    for (size_t b = 0; b < h; b++)
        for (size_t a = 0; a < w; a++)
            s->v[a + w * b] = (float)(100 * 0.5 * (1 + erf(f((double)a, (double)b) / (sqrt(2) * blur))) + noise * gauss());
}

static double CX = 64.3, CY = 63.7, R = 40;
static double disc(double x, double y) { return R - hypot(x - CX, y - CY); }
static double EA = 50, EB = 28;
/* ellipse: signed distance approximated to first order (value / gradient), exact on the curve */
static double ellipse(double x, double y)
{
    double u = (x - CX) / EA, v = (y - CY) / EB, q = u * u + v * v;
    double gx = 2 * u / EA, gy = 2 * v / EB;
    return (1 - q) / (hypot(gx, gy) + 1e-12);
}
static double SQ = 30; /* half side */
static double square(double x, double y)
{
    double dx = fabs(x - CX) - SQ, dy = fabs(y - CY) - SQ;
    double out = hypot(fmax(dx, 0), fmax(dy, 0)), in = fmin(fmax(dx, dy), 0);
    return -(out + in);
}

/* distance of a point (plane pixel coordinates) to a shape's boundary: |sd| by a dense search along
 * the ray from the centre for the ellipse and circle; for the square the exact formula. */
static double ellipse_dist(double x, double y)
{
    /* nearest point on the ellipse by dense sampling */
    double best = 1e9;
    for (int k = 0; k < 20000; k++) {
        double t = 2 * M_PI * k / 20000, ex = CX + EA * cos(t), ey = CY + EB * sin(t);
        double d = hypot(x - ex, y - ey);
        if (d < best) best = d;
    }
    return best;
}

/* pixel coordinates of a RAS point of the plane above */
static void px(const double *p, double *a, double *b)
{
    *a = p[0] + 3;
    *b = p[1] - 5;
}
static void ras(double a, double b, double *p)
{
    p[0] = a - 3;
    p[1] = b + 5;
    p[2] = 7;
}

static void test_disc(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    make_plane(&s, 128, 128, disc, 1.5, 3.0);
    for (int sub = 0; sub <= 1; sub++) {
        thx_livewire_opts o;
        thx_livewire_opts_default(&o);
        o.subvoxel = sub;
        thx_livewire *lw = NULL;
        CHECK_OK(ctx, thx_livewire_create(ctx, &s, &o, &lw));
        double A[3], B[3];
        ras(CX + R, CY, A);
        ras(CX + R * cos(1.9), CY + R * sin(1.9), B);
        CHECK_OK(ctx, thx_livewire_seed(ctx, lw, A));
        double *xyz = NULL;
        size_t n = 0;
        CHECK_OK(ctx, thx_livewire_path(ctx, lw, B, &xyz, &n));
        double worst = 0, mean = 0, arc_ok = 1;
        for (size_t i = 0; i < n; i++) {
            double a, b;
            px(xyz + 3 * i, &a, &b);
            double e = fabs(hypot(a - CX, b - CY) - R), th = atan2(b - CY, a - CX);
            worst = fmax(worst, e);
            if (getenv("DBG") && e > 1) printf("  %zu (%.2f %.2f) e %.2f\n", i, a, b, e);
            mean += e / (double)n;
            if (th < -0.05 || th > 1.95) arc_ok = 0; /* on the short arc between the two points */
            CHECK(xyz[3 * i + 2] == 7);
        }
        printf("disc r=40 (blur 1.5, noise 3), subvoxel %d: %zu points, |r - 40| max %.3f mean %.3f px\n", sub, n,
               worst, mean);
        CHECK(n > 60);
        CHECK(worst <= 1.0);
        CHECK(arc_ok);
        if (sub) CHECK(mean <= 0.15);
        free(xyz);
        thx_livewire_destroy(&lw);
        CHECK(lw == NULL);
    }
    free(s.v);
    thx_ctx_destroy(&ctx);
}

static void test_shapes(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    for (int shape = 0; shape < 2; shape++) {
        thx_image_slice s;
        make_plane(&s, 128, 128, shape ? square : ellipse, 1.5, 3.0);
        thx_livewire *lw = NULL;
        CHECK_OK(ctx, thx_livewire_create(ctx, &s, NULL, &lw));
        /* four clicks round the shape (the square's on its sides' middles, so the path turns its corners) */
        double clicks[12];
        for (int k = 0; k < 4; k++) {
            double t = k * M_PI / 2 + 0.3, a, b;
            if (shape) {
                double c = cos(t), sn = sin(t), m = fmax(fabs(c), fabs(sn));
                a = CX + SQ * c / m;
                b = CY + SQ * sn / m;
            } else {
                a = CX + EA * cos(t);
                b = CY + EB * sin(t);
            }
            ras(a, b, clicks + 3 * k);
        }
        double *xyz = NULL;
        size_t n = 0;
        CHECK_OK(ctx, thx_livewire_loop(ctx, lw, clicks, 4, &xyz, &n));
        double worst = 0, area = 0;
        for (size_t i = 0; i < n; i++) {
            double a, b, a1, b1;
            px(xyz + 3 * i, &a, &b);
            px(xyz + 3 * ((i + 1) % n), &a1, &b1);
            area += 0.5 * (a * b1 - a1 * b);
            double e = shape ? fabs(square(a, b)) : ellipse_dist(a, b);
            /* the blurred square's corners are rounded by the blur: measured away from them */
            if (shape && fabs(fabs(a - CX) - SQ) < 3 && fabs(fabs(b - CY) - SQ) < 3) continue;
            worst = fmax(worst, e);
        }
        double area0 = shape ? 4 * SQ * SQ : M_PI * EA * EB;
        printf("%s: loop of %zu points through 4 clicks, distance to the outline max %.3f px, area %.1f (%.1f)\n",
               shape ? "square 60 px" : "ellipse 50 x 28 px", n, worst, area, area0);
        CHECK(worst <= 1.0);
        CHECK(fabs(area - area0) <= 0.02 * area0);
        free(xyz);
        thx_livewire_destroy(&lw);
        free(s.v);
    }
    thx_ctx_destroy(&ctx);
}

/* Dijkstra by the book: O(n^2), the cheapest unfinished node found by a linear scan each time. */
static void brute_dijkstra(const thx_livewire *lw, size_t n, size_t seed, long *dist)
{
    char *done = calloc(n, 1);
    for (size_t i = 0; i < n; i++) dist[i] = LONG_MAX;
    dist[seed] = 0;
    for (;;) {
        size_t p = n;
        for (size_t i = 0; i < n; i++)
            if (!done[i] && dist[i] != LONG_MAX && (p == n || dist[i] < dist[p])) p = i;
        if (p == n) break;
        done[p] = 1;
        for (size_t q = 0; q < n; q++) {
            long c = thx_livewire_link_cost(lw, p, q);
            if (c >= 0 && dist[p] + c < dist[q]) dist[q] = dist[p] + c;
        }
    }
    free(done);
}

static double small_disc(double x, double y) { return 8.5 - hypot(x - 11.2, y - 12.6); }

static void test_optimum(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    const size_t W = 24, H = 22, N = W * H;
    make_plane(&s, W, H, small_disc, 1.0, 8.0);
    s.v[5 + W * 20] = NAN; /* a hole in the image: walled off */
    thx_livewire *lw = NULL;
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, NULL, &lw));
    long *dist = malloc(N * sizeof *dist);
    size_t seeds[3] = {3 + W * 12, 19 + W * 12, 0};
    int all_equal = 1, sums_ok = 1;
    for (int k = 0; k < 3; k++) {
        brute_dijkstra(lw, N, seeds[k], dist);
        CHECK_OK(ctx, thx_livewire_seed_pixel(ctx, lw, seeds[k] % W, seeds[k] / W));
        for (size_t t = 0; t < N; t++) {
            size_t *idx = NULL, m = 0;
            long cost = -1;
            thx_status st = thx_livewire_path_pixels(ctx, lw, t % W, t / W, &idx, &m, &cost);
            if (t == 5 + W * 20) {
                CHECK(st == THX_EINPUT && dist[t] == LONG_MAX);
                continue;
            }
            if (st != THX_OK || cost != dist[t]) all_equal = 0;
            /* the path is a chain of links from the seed to t whose costs add up to the total */
            long sum = 0;
            if (m == 0 || idx[0] != seeds[k] || idx[m - 1] != t) sums_ok = 0;
            for (size_t i = 0; i + 1 < m; i++) sum += thx_livewire_link_cost(lw, idx[i], idx[i + 1]);
            if (sum != cost) sums_ok = 0;
            free(idx);
        }
    }
    CHECK(all_equal);
    CHECK(sums_ok);
    /* every link cost in 1..MAX_LINK, none into the NaN pixel */
    int links_ok = 1;
    for (size_t p = 0; p < N; p++)
        for (size_t q = 0; q < N; q++) {
            long c = thx_livewire_link_cost(lw, p, q);
            if (c >= 0 && (c < 1 || c > THX_LIVEWIRE_MAX_LINK || q == 5 + W * 20 || p == 5 + W * 20)) links_ok = 0;
        }
    CHECK(links_ok);
    free(dist);
    thx_livewire_destroy(&lw);
    free(s.v);
    thx_ctx_destroy(&ctx);
}

/* On the fly: a near target finishes few pixels; a far one asked afterwards gets the same path as
 * from a fresh search. */
static void test_on_the_fly(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    make_plane(&s, 128, 128, disc, 1.5, 3.0);
    thx_livewire *lw = NULL;
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, NULL, &lw));
    size_t a0 = 104, b0 = 64, *p1 = NULL, *p2 = NULL, n1 = 0, n2 = 0, done = 0;
    long c1 = 0, c2 = 0;
    CHECK_OK(ctx, thx_livewire_seed_pixel(ctx, lw, a0, b0));
    CHECK_OK(ctx, thx_livewire_path_pixels(ctx, lw, 103, 70, &p1, &n1, &c1));
    thx_livewire_size(lw, NULL, NULL, &done);
    printf("near target: %zu of %d pixels finished\n", done, 128 * 128);
    CHECK(done < 128 * 128 / 10);
    free(p1);
    CHECK_OK(ctx, thx_livewire_path_pixels(ctx, lw, 25, 60, &p1, &n1, &c1));
    CHECK_OK(ctx, thx_livewire_seed_pixel(ctx, lw, a0, b0));
    CHECK_OK(ctx, thx_livewire_path_pixels(ctx, lw, 25, 60, &p2, &n2, &c2));
    CHECK(c1 == c2 && n1 == n2 && n1 && memcmp(p1, p2, n1 * sizeof *p1) == 0);
    free(p1);
    free(p2);
    /* bad input */
    double out[3] = {500, 0, 7};
    double *xyz = NULL;
    size_t n = 0;
    CHECK(thx_livewire_seed(ctx, lw, out) == THX_EINPUT && tl_msg_has(ctx, "outside the plane"));
    CHECK(thx_livewire_path(ctx, lw, out, &xyz, &n) == THX_EINPUT && xyz == NULL && n == 0);
    thx_livewire_destroy(&lw);
    thx_livewire_destroy(&lw); /* NULL accepted */
    thx_livewire_opts o;
    thx_livewire_opts_default(&o);
    o.wz = o.wg = o.wd = 0;
    CHECK(thx_livewire_create(ctx, &s, &o, &lw) == THX_EINPUT && lw == NULL && tl_msg_has(ctx, "weights"));
    thx_livewire_opts_default(&o);
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, &o, &lw));
    CHECK(thx_livewire_path(ctx, lw, out, &xyz, &n) == THX_EINPUT);
    double in[3] = {30, 40, 7};
    CHECK(thx_livewire_path(ctx, lw, in, &xyz, &n) == THX_EINPUT && tl_msg_has(ctx, "before a seed"));
    thx_livewire_destroy(&lw);
    for (size_t p = 0; p < 128 * 128; p++) s.v[p] = NAN;
    CHECK(thx_livewire_create(ctx, &s, &o, &lw) == THX_EINPUT && tl_msg_has(ctx, "no sample"));
    free(s.v);
    thx_ctx_destroy(&ctx);
}

/* The link costs against the paper's formulas on planes where they are known exactly (no smoothing). */
static double ramp(double x, double y)
{
    (void)y;
    return x;
}
static void test_costs(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    const size_t W = 24, H = 20;
    thx_image_slice s;
    make_plane(&s, W, H, ramp, 1, 0); /* replaced below */
    thx_livewire_opts o;
    thx_livewire_opts_default(&o);
    o.sigma = 0;
    thx_livewire *lw = NULL;
    /* 1. I = x: G constant (fG = 0), no zero crossing (fZ = 1), D = (0, -1): fD = 2/(3 pi) 2 acos|dy| for a
     * link of unit direction (dx, dy): horizontal 2/3, vertical 0, diagonal 1/3 */
    for (size_t p = 0; p < W * H; p++) s.v[p] = (float)(p % W);
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, &o, &lw));
    int ok1 = 1;
    for (size_t b = 2; b + 2 < H; b++)
        for (size_t a = 2; a + 3 < W; a++) /* (the mirrored border makes column W - 2 a zero crossing) */
            for (int db = -1; db <= 1; db++)
                for (int da = -1; da <= 1; da++) {
                    if (!da && !db) continue;
                    double dy = db / hypot(da, db), fd = 2 / (3 * M_PI) * 2 * acos(fabs(dy));
                    long want = lround(255 * (0.43 + 0.14 * fd));
                    long got = thx_livewire_link_cost(lw, a + W * b, (a + da) + W * (b + db));
                    if (got != want) ok1 = 0;
                }
    CHECK(ok1);
    CHECK(thx_livewire_link_cost(lw, 5, 7) == -1); /* not neighbours */
    thx_livewire_destroy(&lw);
    /* 2. gradient term alone, I = x^2 / 2: G = |x| (central differences exact), max G = W - 1.5 (one-sided
     * at the last column); fG(q) scaled by the link's length over the diagonal's */
    o.wz = 0, o.wg = 1, o.wd = 0;
    for (size_t p = 0; p < W * H; p++) s.v[p] = (float)(0.5 * (double)(p % W) * (double)(p % W));
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, &o, &lw));
    int ok2 = 1;
    for (size_t b = 1; b + 1 < H; b++)
        for (size_t a = 1; a + 2 < W; a++)
            for (int k = 0; k < 2; k++) {
                size_t q = (a + 1) + W * (b + (size_t)k);
                double fg = 1 - (double)(a + 1) / (W - 1.5), len = k ? 1 : 1 / sqrt(2);
                long want = lround(255 * fg * len), got = thx_livewire_link_cost(lw, a + W * b, q);
                if (want < 1) want = 1;
                if (got != want) ok2 = 0;
            }
    CHECK(ok2);
    thx_livewire_destroy(&lw);
    /* 3. zero crossings alone, I = tanh((x - 10.3) / 3): the Laplacian changes sign between columns 10 and
     * 11, column 10 nearer zero: links into column 10 cost the minimum 1, elsewhere 255 */
    o.wz = 1, o.wg = 0, o.wd = 0;
    for (size_t p = 0; p < W * H; p++) s.v[p] = (float)tanh(((double)(p % W) - 10.3) / 3);
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, &o, &lw));
    int ok3 = 1;
    for (size_t b = 1; b + 1 < H; b++)
        for (size_t a = 3; a + 3 < W; a++) {
            long got = thx_livewire_link_cost(lw, (a - 1) + W * b, a + W * b);
            if (got != (a == 10 ? 1 : 255)) ok3 = 0;
        }
    CHECK(ok3);
    thx_livewire_destroy(&lw);
    free(s.v);
    thx_ctx_destroy(&ctx);
}

/* Path cooling: the free point moving along the circle; the part of the path near the seed freezes. */
static void test_cooling(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    make_plane(&s, 128, 128, disc, 1.5, 3.0);
    thx_livewire *lw = NULL;
    CHECK_OK(ctx, thx_livewire_create(ctx, &s, NULL, &lw));
    double A[3], T[3], *xyz = NULL, *last = NULL, *fr = NULL;
    size_t n = 0, nl = 0, nf = 0;
    ras(CX + R, CY, A);
    CHECK_OK(ctx, thx_livewire_seed(ctx, lw, A));
    CHECK_OK(ctx, thx_livewire_cool(ctx, lw, 3, 10, &fr, &nf));
    CHECK(nf == 0 && fr == NULL); /* nothing asked yet */
    for (int i = 0; i < 5; i++) {
        double th = 1.2 + 0.06 * i;
        ras(CX + R * cos(th), CY + R * sin(th), T);
        free(last);
        CHECK_OK(ctx, thx_livewire_path(ctx, lw, T, &last, &nl));
    }
    CHECK_OK(ctx, thx_livewire_cool(ctx, lw, 3, 10, &fr, &nf));
    printf("cooling: %zu of the last path's %zu points frozen\n", nf, nl);
    CHECK(nf >= 10 && nf < nl);
    int prefix = 1, on = 1;
    for (size_t i = 0; i < 3 * nf && i < 3 * nl; i++) prefix &= fr[i] == last[i];
    for (size_t i = 0; i < nf; i++) {
        double a, b;
        px(fr + 3 * i, &a, &b);
        on &= fabs(hypot(a - CX, b - CY) - R) <= 1.0;
    }
    CHECK(prefix && on);
    /* the seed is now the frozen part's end: the next path starts there and ends at the target */
    CHECK_OK(ctx, thx_livewire_path(ctx, lw, T, &xyz, &n));
    CHECK(n >= 2 && memcmp(xyz, fr + 3 * (nf - 1), 3 * sizeof *xyz) == 0 &&
          memcmp(xyz + 3 * (n - 1), last + 3 * (nl - 1), 3 * sizeof *xyz) == 0);
    free(xyz);
    free(fr);
    CHECK_OK(ctx, thx_livewire_cool(ctx, lw, 3, 10, &fr, &nf));
    CHECK(nf == 0); /* one query since: nothing cooled */
    CHECK(thx_livewire_cool(ctx, lw, 0, 10, &fr, &nf) == THX_EINPUT);
    free(last);
    thx_livewire_destroy(&lw);
    free(s.v);
    thx_ctx_destroy(&ctx);
}

int main(void)
{
    test_cooling();
    test_costs();
    test_disc();
    test_shapes();
    test_optimum();
    test_on_the_fly();
    return tl_finish();
}
