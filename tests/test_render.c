/* The 3D renderer (paper 4.2), headless: small renders whose pixels are checked against what the
 * scene must show — background, the ECG colour convention and the anatomical view, bands and
 * contour lines, the orientation check, clipping, NaN values, viewports, arrows, translucency,
 * and the geometry cache.
 *
 * THX_RENDER_PNG=dir writes the images to dir; THX_RENDER_BENCH=1 times a 100,000-triangle sphere
 * with data at 1024 x 1024 (median of 10 frames). */
#include "testlib.h"
#include "thorax/render/render.h"
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
#define N 128

static thx_ctx *ctx;
static thx_renderer *ren;

/* A UV sphere of radius rad about c: nlat rings of latitude, nlon nodes around, triangles
 * counterclockwise seen from outside (flip = 1: inward). */
static thx_surface *sphere(int nlat, int nlon, double rad, const double c[3], int flip)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "sphere", THX_ROLE_OTHER, &s) != THX_OK) return NULL;
    s->n_nodes = 2 + (size_t)nlon * (nlat - 1);
    s->n_tris = 2 * (size_t)nlon * (nlat - 1);
    s->xyz = malloc(3 * s->n_nodes * sizeof *s->xyz);
    s->tri = malloc(3 * s->n_tris * sizeof *s->tri);
    double *p = s->xyz;
    p[0] = c[0], p[1] = c[1], p[2] = c[2] + rad;             /* north pole: node 0 */
    p[3] = c[0], p[4] = c[1], p[5] = c[2] - rad;             /* south pole: node 1 */
    for (int k = 1; k < nlat; k++)
        for (int j = 0; j < nlon; j++) {
            double th = PI * k / nlat, ph = 2 * PI * j / nlon;
            double *q = p + 3 * (2 + (size_t)(k - 1) * nlon + j);
            q[0] = c[0] + rad * sin(th) * cos(ph);
            q[1] = c[1] + rad * sin(th) * sin(ph);
            q[2] = c[2] + rad * cos(th);
        }
#define NODE(k, j) ((k) == 0 ? 0 : (k) == nlat ? 1 : 2 + ((k) - 1) * nlon + ((j) % nlon))
    int32_t *t = s->tri;
    for (int k = 0; k < nlat; k++)
        for (int j = 0; j < nlon; j++) {
            int a = NODE(k, j), b = NODE(k, j + 1), cc = NODE(k + 1, j), d = NODE(k + 1, j + 1);
            /* (a, c, b) and (b, c, d): theta x phi points outward */
            if (k > 0) *t++ = a, *t++ = cc, *t++ = b;
            if (k < nlat - 1) *t++ = b, *t++ = cc, *t++ = d;
        }
#undef NODE
    if (flip)
        for (size_t i = 0; i < s->n_tris; i++) {
            int32_t x = s->tri[3 * i + 1];
            s->tri[3 * i + 1] = s->tri[3 * i + 2];
            s->tri[3 * i + 2] = x;
        }
    return s;
}

/* The square x, z in [-1, 1] at y = 0, n x n cells, facing -y. */
static thx_surface *plane(int n)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "plane", THX_ROLE_OTHER, &s) != THX_OK) return NULL;
    s->n_nodes = (size_t)(n + 1) * (n + 1);
    s->n_tris = 2 * (size_t)n * n;
    s->xyz = malloc(3 * s->n_nodes * sizeof *s->xyz);
    s->tri = malloc(3 * s->n_tris * sizeof *s->tri);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
            double *q = s->xyz + 3 * ((size_t)i * (n + 1) + j);
            q[0] = -1 + 2.0 * j / n, q[1] = 0, q[2] = -1 + 2.0 * i / n;
        }
    int32_t *t = s->tri;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
            *t++ = a, *t++ = b, *t++ = d; /* (x, z) counterclockwise seen from -y */
            *t++ = a, *t++ = d, *t++ = c;
        }
    return s;
}

static const unsigned char *px(const thx_raster *im, int x, int y) { return im->rgba + 4 * ((size_t)y * im->w + x); }

static int near_rgb(const unsigned char *p, double r, double g, double b, int tol)
{
    return abs(p[0] - (int)lround(255 * r)) <= tol && abs(p[1] - (int)lround(255 * g)) <= tol &&
           abs(p[2] - (int)lround(255 * b)) <= tol;
}

static int diff3(const unsigned char *p, const unsigned char *q)
{
    return abs(p[0] - q[0]) + abs(p[1] - q[1]) + abs(p[2] - q[2]);
}

static void save(const thx_raster *im, const char *name)
{
    const char *dir = getenv("THX_RENDER_PNG");
    if (!dir) return;
    char path[512];
    snprintf(path, sizeof path, "%s/%s_%d.png", dir, name, ren ? thx_renderer_samples(ren) : 0);
    CHECK_OK(ctx, thx_raster_write_png(ctx, im, path));
}

static thx_scene base_scene(const thx_render_surface *rs, size_t n)
{
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = n;
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    thx_camera_view(&sc.camera, THX_VIEW_ANTERIOR, lo, hi, 1.0);
    const float bg[4] = {0.1f, 0.2f, 0.3f, 1};
    memcpy(sc.background, bg, sizeof bg);
    sc.clear = 1;
    return sc;
}

/* Looking at the plane from -y, +x to the right, the plane filling the image exactly. */
static void plane_camera(thx_camera *cam)
{
    memset(cam, 0, sizeof *cam);
    cam->eye[1] = -5;
    cam->up[2] = 1;
    cam->height = 2;
}

static thx_render_surface surf_defaults(const thx_surface *s, thx_draw_mode mode)
{
    thx_render_surface rs;
    memset(&rs, 0, sizeof rs);
    rs.surf = s;
    rs.mode = mode;
    rs.color[0] = 0.8f, rs.color[1] = 0.8f, rs.color[2] = 0.8f, rs.color[3] = 1;
    rs.cmap = THX_CMAP_ECG;
    rs.scale.model = THX_SCALE_LINEAR;
    rs.scale.lo = -1, rs.scale.hi = 1;
    return rs;
}

static void test_views(void)
{
    thx_view v;
    CHECK(thx_view_parse("anterior", &v) == 0 && v == THX_VIEW_ANTERIOR);
    CHECK(thx_view_parse("inferior", &v) == 0 && v == THX_VIEW_INFERIOR);
    CHECK(thx_view_parse("front", &v) == -1);
    thx_camera cam;
    double lo[3] = {-100, -50, 0}, hi[3] = {100, 50, 400};
    thx_camera_view(&cam, THX_VIEW_ANTERIOR, lo, hi, 1.0);
    CHECK(cam.fov_deg == 0);
    CHECK(cam.eye[1] > hi[1] && cam.eye[0] == 0 && cam.eye[2] == 200);
    CHECK_NEAR(cam.height, 440, 1e-9); /* 400 mm high with 5% margins */
    thx_camera_view(&cam, THX_VIEW_ANTERIOR, lo, hi, 4.0);
    CHECK_NEAR(cam.height, 440, 1e-9);
    thx_camera_view(&cam, THX_VIEW_ANTERIOR, lo, hi, 0.25);
    CHECK_NEAR(cam.height, 880, 1e-9); /* 200 mm wide in a narrow image */
    thx_camera_view(&cam, THX_VIEW_SUPERIOR, lo, hi, 1.0);
    CHECK(cam.eye[2] > hi[2] && cam.up[1] == 1);
    thx_camera_view(&cam, THX_VIEW_LEFT, lo, hi, 1.0);
    CHECK(cam.eye[0] < lo[0]); /* the subject's left is -x */
}

/* Background, the anatomical orientation of the anterior view and the ECG map: data = x, so the
 * subject's right (+x, positive, red) appears on the image's left. */
static void test_ecg_map(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(40, 60, 1, c, 0);
    double *v = malloc(s->n_nodes * sizeof *v);
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = s->xyz[3 * i];
    thx_render_surface rs = surf_defaults(s, THX_DRAW_PHONG);
    rs.values = v;
    thx_scene sc = base_scene(&rs, 1);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    size_t n_nan = 99;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, &n_nan));
    save(im, "ecg_map");
    CHECK(im->w == N && im->h == N);
    CHECK(n_nan == 0);
    int corners[4][2] = {{0, 0}, {N - 1, 0}, {0, N - 1}, {N - 1, N - 1}};
    for (int i = 0; i < 4; i++) CHECK(near_rgb(px(im, corners[i][0], corners[i][1]), 0.1, 0.2, 0.3, 1));
    CHECK(px(im, 0, 0)[3] == 255);
    const unsigned char *l = px(im, 32, 64), *r = px(im, 96, 64);
    CHECK(l[0] > l[1] + 40 && l[0] > l[2] + 40); /* red: positive, the subject's right */
    CHECK(r[2] > r[0] + 40);                     /* blue: negative */
    /* the same in Gouraud and flat shading */
    for (int m = 0; m < 2; m++) {
        rs.mode = m ? THX_DRAW_FLAT : THX_DRAW_GOURAUD;
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        l = px(im, 32, 64), r = px(im, 96, 64);
        CHECK(l[0] > l[1] + 40 && l[0] > l[2] + 40);
        CHECK(r[2] > r[0] + 40);
    }
    /* the posterior view mirrors it */
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    thx_camera_view(&sc.camera, THX_VIEW_POSTERIOR, lo, hi, 1.0);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    l = px(im, 32, 64), r = px(im, 96, 64);
    CHECK(r[0] > r[1] + 40 && r[0] > r[2] + 40);
    CHECK(l[2] > l[0] + 40);
    /* the cache: the same surface redrawn with new values only (negated) */
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = -v[i];
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    l = px(im, 32, 64), r = px(im, 96, 64);
    CHECK(l[0] > l[1] + 40 && l[0] > l[2] + 40);
    CHECK(r[2] > r[0] + 40);
    /* ... and with its coordinates changed in place: half the radius, the silhouette shrinks */
    for (size_t i = 0; i < 3 * s->n_nodes; i++) s->xyz[i] *= 0.5;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(near_rgb(px(im, 20, 64), 0.1, 0.2, 0.3, 1));
    CHECK(!near_rgb(px(im, 50, 64), 0.1, 0.2, 0.3, 10));
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
}

/* Bands and contour lines on a plane with data = x, seen flat-on so that flat shading shows the
 * colour map exactly. */
static void test_bands_contours(void)
{
    thx_surface *s = plane(16);
    double *v = malloc(s->n_nodes * sizeof *v);
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = s->xyz[3 * i];
    thx_render_surface rs = surf_defaults(s, THX_DRAW_FLAT);
    rs.values = v;
    rs.style = THX_DATA_BANDS;
    rs.n_levels = 4;
    rs.line_width = 2;
    thx_scene sc = base_scene(&rs, 1);
    plane_camera(&sc.camera);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "bands");
    /* band k covers x in [-1 + k/2, -1/2 + k/2): pixels 32 k .. 32 k + 31 */
    unsigned char band[4][3];
    for (int k = 0; k < 4; k++) {
        thx_colormap_eval(THX_CMAP_ECG, thx_scale_band((k + 0.5) / 4, 4), band[k]);
        for (int x = 32 * k + 1; x <= 32 * k + 30; x += 7) {
            const unsigned char *p = px(im, x, 64);
            CHECK(diff3(p, band[k]) <= 6);
        }
    }
    rs.style = THX_DATA_BANDS_CONTOURS;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "bands_contours");
    for (int k = 1; k < 4; k++) {
        /* a dark line at the boundary between pixels 32 k - 1 and 32 k, unlike both bands */
        int found = 0;
        for (int x = 32 * k - 2; x <= 32 * k + 1; x++) {
            const unsigned char *p = px(im, x, 64);
            if (diff3(p, band[k - 1]) > 200 && diff3(p, band[k]) > 200 && p[0] + p[1] + p[2] < 150) found = 1;
        }
        CHECK(found);
        /* and nothing else in the rows: band centres keep their colour */
        CHECK(diff3(px(im, 32 * k - 16, 64), band[k - 1]) <= 6);
        CHECK(diff3(px(im, 32 * k - 16, 10), band[k - 1]) <= 6);
    }
    /* contours over the surface colour, lines the same width everywhere */
    rs.style = THX_DATA_CONTOURS;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "contours");
    CHECK(near_rgb(px(im, 16, 64), 0.8, 0.8, 0.8, 2));
    int dark = 0;
    for (int x = 0; x < N; x++) dark += px(im, x, 40)[0] < 100;
    CHECK(dark >= 3 * 2 && dark <= 3 * 4); /* three lines, 2 pixels wide (+ antialiasing) */
    /* continuous: the colour at the centre of the plane is the map's middle (white for ECG) */
    rs.style = THX_DATA_CONTINUOUS;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    unsigned char mid[3];
    thx_colormap_eval(THX_CMAP_ECG, 0.5, mid);
    CHECK(diff3(px(im, 63, 64), mid) <= 12);
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
}

/* NaN values: the triangles touching them in nan_color, counted. */
/* A lab scale on the plane, data = 52 x (node per pixel column): 16 bands whatever n_levels says,
 * each column whose neighbourhood lies inside one band (between two lab levels) in that band's
 * colour, and (nearly) every band seen. */
static void test_lab_bands(void)
{
    thx_surface *s = plane(N);
    double *v = malloc(s->n_nodes * sizeof *v);
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = 52 * s->xyz[3 * i];
    thx_render_surface rs = surf_defaults(s, THX_DRAW_FLAT);
    rs.values = v;
    rs.style = THX_DATA_BANDS;
    rs.n_levels = 4; /* ignored: the lab scale has 16 bands */
    thx_scale_from_range_mapped(&rs.scale, THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -37, 52);
    CHECK(thx_scale_bands(&rs.scale, rs.n_levels) == 16);
    thx_scene sc = base_scene(&rs, 1);
    plane_camera(&sc.camera);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "lab_bands");
    int seen[16] = {0}, exact = 1, distinct = 0;
    for (int x = 1; x + 2 <= N; x++) {
        /* nodes x - 1 .. x + 2 (columns x - 1 .. x + 1) in one band */
        int b = -1, one = 1;
        for (int k = x - 1; k <= x + 2; k++) {
            int bk = (int)floor(thx_scale_apply(&rs.scale, 52 * (-1 + 2.0 * k / N)) * 16);
            if (bk > 15) bk = 15;
            if (b >= 0 && bk != b) one = 0;
            b = bk;
        }
        if (!one) continue;
        unsigned char want[3];
        thx_colormap_eval(THX_CMAP_ECG, (b + 0.5) / 16, want);
        if (diff3(px(im, x, 64), want) > 6) exact = 0;
        seen[b] = 1;
    }
    for (int b = 0; b < 16; b++) distinct += seen[b];
    CHECK(exact);
    CHECK(distinct >= 13);
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
}

static void test_nan(void)
{
    thx_surface *s = plane(16);
    double *v = malloc(s->n_nodes * sizeof *v);
    size_t expect = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        double x = s->xyz[3 * i];
        v[i] = x > 0.6 ? NAN : x;
        expect += x > 0.6;
    }
    thx_render_surface rs = surf_defaults(s, THX_DRAW_FLAT);
    rs.values = v;
    thx_scene sc = base_scene(&rs, 1);
    plane_camera(&sc.camera);
    const float nanc[4] = {0.5f, 0.9f, 0.1f, 1};
    memcpy(sc.nan_color, nanc, sizeof nanc);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    size_t n_nan = 0;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, &n_nan));
    save(im, "nan");
    CHECK(expect > 0 && n_nan == expect);
    /* x > 0.6 is NaN-only; the cells touching x = 0.625 from below too (x > 0.5) */
    CHECK(near_rgb(px(im, 120, 64), 0.5, 0.9, 0.1, 2));
    CHECK(near_rgb(px(im, 100, 30), 0.5, 0.9, 0.1, 2));
    CHECK(!near_rgb(px(im, 90, 64), 0.5, 0.9, 0.1, 30));
    const unsigned char *p = px(im, 20, 64);
    CHECK(p[2] > p[0] + 40); /* data still drawn (negative, blue) */
    /* the default NaN colour when nan_color is zero */
    memset(sc.nan_color, 0, sizeof sc.nan_color);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, &n_nan));
    p = px(im, 120, 64);
    CHECK(p[0] > p[1] + 20 && p[2] > p[1] + 20);
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
}

static int count_color(const thx_raster *im, int r, int g, int b, int tol)
{
    int n = 0;
    for (int y = 0; y < im->h; y++)
        for (int x = 0; x < im->w; x++) {
            const unsigned char *p = px(im, x, y);
            n += abs(p[0] - r) <= tol && abs(p[1] - g) <= tol && abs(p[2] - b) <= tol;
        }
    return n;
}

/* The paper's orientation check: a sphere seen from outside draws its triangles and no points; with
 * its triangles flipped, the near side's nodes show as points in the back colour over the far
 * side's inside. */
static void test_orientation(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *good = sphere(24, 36, 1, c, 0), *bad = sphere(24, 36, 1, c, 1);
    CHECK(thx_surface_volume(good) > 0 && thx_surface_volume(bad) < 0);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    for (int f = 0; f < 2; f++) {
        thx_render_surface rs = surf_defaults(f ? bad : good, THX_DRAW_ORIENTATION);
        rs.color[0] = 0.2f, rs.color[1] = 0.7f, rs.color[2] = 0.2f;
        rs.back_color[0] = 1, rs.back_color[1] = 0, rs.back_color[2] = 1, rs.back_color[3] = 1;
        rs.point_size = 4;
        thx_scene sc = base_scene(&rs, 1);
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        save(im, f ? "orientation_flipped" : "orientation");
        int back = count_color(im, 255, 0, 255, 60);
        const unsigned char *p = px(im, 64, 64);
        if (!f) {
            CHECK(back == 0);
            CHECK(p[1] > p[0] + 40 && p[1] > p[2] + 40); /* the front colour, lit */
        } else {
            CHECK(back > 300); /* 24 x 36 nodes, about half of them in front, 4 px wide */
        }
        CHECK(near_rgb(px(im, 0, 0), 0.1, 0.2, 0.3, 1));
    }
    thx_raster_destroy(&im);
    thx_surface_destroy(&good);
    thx_surface_destroy(&bad);
}

/* Clip planes: data = y (front red, back blue); cutting off the front cap shows the inside of the
 * back; cutting off x > 0 shows the background there. */
static void test_clip(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(40, 60, 1, c, 0);
    double *v = malloc(s->n_nodes * sizeof *v);
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = s->xyz[3 * i + 1];
    thx_render_surface rs = surf_defaults(s, THX_DRAW_PHONG);
    rs.values = v;
    thx_scene sc = base_scene(&rs, 1);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    const unsigned char *p = px(im, 64, 64);
    CHECK(p[0] > p[2] + 40); /* the front: red */
    sc.n_clip = 1;
    sc.clip[0].n[1] = -1, sc.clip[0].d = 0.3; /* keeps y <= 0.3 */
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "clip_front");
    p = px(im, 64, 64);
    CHECK(p[2] > p[0] + 40); /* the inside of the back: blue */
    p = px(im, 64, 2);      /* beyond the sphere: still background */
    CHECK(near_rgb(p, 0.1, 0.2, 0.3, 1));
    memset(&sc.clip[0], 0, sizeof sc.clip[0]);
    sc.clip[0].n[0] = -1; /* keeps x <= 0: the image's right half in the anterior view */
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "clip_x");
    CHECK(near_rgb(px(im, 32, 64), 0.1, 0.2, 0.3, 1));
    CHECK(!near_rgb(px(im, 96, 64), 0.1, 0.2, 0.3, 10));
    /* two planes: x <= 0 and z <= 0 leave the lower right quadrant */
    sc.n_clip = 2;
    sc.clip[1].n[2] = -1;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(near_rgb(px(im, 96, 32), 0.1, 0.2, 0.3, 1));
    CHECK(!near_rgb(px(im, 96, 96), 0.1, 0.2, 0.3, 10));
    /* a surface exempt from the planes (no_clip) is drawn whole beside one that is cut: a small
       sphere inside a big one, both cut by y <= 0.3 in front; the inner sphere shows its red
       front at the centre, while the outer one, cut, shows only its inside at the edges */
    {
        double c2[3] = {0, 0, 0};
        thx_surface *in = sphere(30, 40, 0.5, c2, 0);
        double *v2 = malloc(in->n_nodes * sizeof *v2);
        for (size_t i = 0; i < in->n_nodes; i++) v2[i] = in->xyz[3 * i + 1];
        thx_render_surface two[2] = {rs, surf_defaults(in, THX_DRAW_PHONG)};
        two[1].values = v2;
        two[1].scale = rs.scale;
        two[1].cmap = rs.cmap;
        thx_scene s2 = base_scene(two, 2);
        s2.n_clip = 1;
        s2.clip[0].n[1] = -1, s2.clip[0].d = 0.3;
        CHECK_OK(ctx, thx_render(ctx, ren, &s2, im, NULL));
        p = px(im, 64, 64);
        unsigned char cut[3] = {p[0], p[1], p[2]}; /* the inner sphere cut at y = 0.3 too: its inside */
        CHECK(cut[2] > cut[0] + 40);
        two[1].no_clip = 1;
        CHECK_OK(ctx, thx_render(ctx, ren, &s2, im, NULL));
        save(im, "clip_noclip");
        p = px(im, 64, 64);
        CHECK(p[0] > p[2] + 40); /* whole: its red front */
        p = px(im, 64, 10);      /* the outer sphere still cut: its inside (blue back) where the inner one is not */
        CHECK(p[2] > p[0] + 20);
        free(v2);
        thx_surface_destroy(&in);
    }
    sc.n_clip = 5;
    CHECK(thx_render(ctx, ren, &sc, im, NULL) == THX_EINPUT);
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
}

/* Two scenes side by side in one image, each clearing its own viewport, and a third drawn over the
 * first without clearing. */
static void test_viewports(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(20, 30, 1, c, 0);
    thx_render_surface rs = surf_defaults(s, THX_DRAW_PHONG);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    const unsigned char grey[4] = {128, 128, 128, 255};
    thx_raster_fill(im, grey);
    thx_scene a = base_scene(&rs, 1), b = base_scene(&rs, 1);
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    thx_camera_view(&a.camera, THX_VIEW_ANTERIOR, lo, hi, 64.0 / 128);
    b.camera = a.camera;
    int va[4] = {0, 0, 64, 128}, vb[4] = {64, 32, 64, 64};
    memcpy(a.viewport, va, sizeof va);
    memcpy(b.viewport, vb, sizeof vb);
    a.background[0] = 1, a.background[1] = 0, a.background[2] = 0;
    b.background[0] = 0, b.background[1] = 0, b.background[2] = 1;
    thx_camera_view(&b.camera, THX_VIEW_ANTERIOR, lo, hi, 1.0);
    CHECK_OK(ctx, thx_render(ctx, ren, &a, im, NULL));
    CHECK_OK(ctx, thx_render(ctx, ren, &b, im, NULL));
    save(im, "viewports");
    CHECK(near_rgb(px(im, 1, 1), 1, 0, 0, 1));       /* a's background */
    CHECK(near_rgb(px(im, 65, 33), 0, 0, 1, 1));     /* b's */
    CHECK(near_rgb(px(im, 100, 10), 0.5, 0.5, 0.5, 1)); /* outside both: untouched */
    CHECK(near_rgb(px(im, 100, 120), 0.5, 0.5, 0.5, 1));
    const unsigned char *p = px(im, 32, 64), *q = px(im, 96, 64); /* spheres at both centres */
    CHECK(abs(p[0] - p[1]) < 30 && p[1] > 100);
    CHECK(abs(q[0] - q[1]) < 30 && q[1] > 100);
    /* a small green sphere drawn over viewport a without clearing it: the red and the grey sphere stay */
    thx_render_surface small = rs;
    double c2[3] = {0, 0, 0};
    thx_surface *s2 = sphere(12, 16, 0.3, c2, 0);
    small.surf = s2;
    small.color[0] = 0, small.color[1] = 1, small.color[2] = 0;
    a.surfaces = &small;
    a.clear = 0;
    CHECK_OK(ctx, thx_render(ctx, ren, &a, im, NULL));
    save(im, "viewports_overlay");
    CHECK(near_rgb(px(im, 1, 1), 1, 0, 0, 1));
    p = px(im, 32, 64);
    CHECK(p[1] > p[0] + 60); /* the green sphere over the grey one */
    p = px(im, 32, 40);      /* the grey sphere still there, drawn before */
    CHECK(abs(p[0] - p[1]) < 30 && p[1] > 80);
    int bad[4] = {100, 0, 64, 64};
    memcpy(a.viewport, bad, sizeof bad);
    CHECK(thx_render(ctx, ren, &a, im, NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "viewport") != NULL);
    thx_raster_destroy(&im);
    thx_surface_destroy(&s);
    thx_surface_destroy(&s2);
}

/* Points, wire, translucency, arrows. */
static void test_modes(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(16, 24, 1, c, 0);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    thx_render_surface rs = surf_defaults(s, THX_DRAW_POINTS);
    rs.color[0] = 1, rs.color[1] = 1, rs.color[2] = 0;
    rs.point_size = 5;
    thx_scene sc = base_scene(&rs, 1);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "points");
    int n_pts = count_color(im, 255, 255, 0, 10), n_bg = count_color(im, 26, 51, 77, 1);
    CHECK(n_pts > 200 && n_bg > N * N / 3);
    CHECK(n_pts + n_bg < N * N); /* antialiased edges in between, and nothing else */
    rs.mode = THX_DRAW_WIRE;
    rs.line_width = 1.5f;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "wire");
    int n_wire = count_color(im, 255, 255, 0, 10);
    CHECK(n_wire > 500);
    CHECK(near_rgb(px(im, 0, 0), 0.1, 0.2, 0.3, 1));
    /* a translucent red sphere around an opaque blue one: purple in the middle, red at the rim */
    double c0[3] = {0, 0, 0};
    thx_surface *inner = sphere(16, 24, 0.5, c0, 0);
    thx_render_surface two[2] = {surf_defaults(s, THX_DRAW_PHONG), surf_defaults(inner, THX_DRAW_PHONG)};
    two[0].color[0] = 1, two[0].color[1] = 0, two[0].color[2] = 0, two[0].color[3] = 0.4f;
    two[1].color[0] = 0, two[1].color[1] = 0, two[1].color[2] = 1;
    sc = base_scene(two, 2);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "translucent");
    const unsigned char *p = px(im, 64, 64), *q = px(im, 64, 12);
    CHECK(p[0] > 60 && p[2] > 60 && p[1] < 60);
    CHECK(q[0] > q[2] + 20);
    /* translucent over a transparent background: un-premultiplied on the way out */
    memset(sc.background, 0, sizeof sc.background);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(px(im, 0, 0)[3] == 0);
    q = px(im, 64, 12);
    CHECK(q[3] > 60 && q[3] < 200 && q[0] > 150 && q[2] < 40);
    /* arrows along +x seen from -y (+x to the right): a solid one and a unit-length one coloured by
     * magnitude */
    double pos[6] = {-0.8, 0, 0.5, -0.8, 0, -0.5}, vec[6] = {1.6, 0, 0, 4, 0, 0};
    thx_render_arrows ar[2];
    memset(ar, 0, sizeof ar);
    ar[0].pos = pos, ar[0].vec = vec, ar[0].n = 1, ar[0].scale = 1, ar[0].width = 3;
    ar[0].color[0] = 1, ar[0].color[1] = 1, ar[0].color[3] = 1;
    ar[1].pos = pos + 3, ar[1].vec = vec + 3, ar[1].n = 1, ar[1].scale = 1.6, ar[1].unit_length = 1, ar[1].width = 3;
    ar[1].cmap = THX_CMAP_ECG, ar[1].mag_scale.lo = -4, ar[1].mag_scale.hi = 4;
    sc = base_scene(NULL, 0);
    plane_camera(&sc.camera);
    sc.arrows = ar;
    sc.n_arrows = 2;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    save(im, "arrows");
    /* z = 0.5 is row 32 from the top; x = -0.8 .. 0.8 are columns 13 .. 115 */
    CHECK(near_rgb(px(im, 40, 32), 1, 1, 0, 2));
    CHECK(near_rgb(px(im, 40, 28), 0.1, 0.2, 0.3, 1));
    int head = 0;
    for (int y = 24; y <= 40; y++) head += near_rgb(px(im, 105, y), 1, 1, 0, 2);
    CHECK(head >= 6); /* the head is wider than the 3-pixel shaft */
    CHECK(near_rgb(px(im, 5, 32), 0.1, 0.2, 0.3, 1));
    CHECK(near_rgb(px(im, 122, 32), 0.1, 0.2, 0.3, 1));
    unsigned char red[3];
    thx_colormap_eval(THX_CMAP_ECG, 1.0, red);
    CHECK(diff3(px(im, 40, 96), red) <= 6); /* |v| = 4 at the top of the scale */
    thx_raster_destroy(&im);
    thx_surface_destroy(&s);
    thx_surface_destroy(&inner);
}

static void test_errors(void)
{
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 64, 64, &im));
    thx_scene sc = base_scene(NULL, 0);
    CHECK(thx_render(ctx, ren, &sc, im, NULL) == THX_EINPUT); /* wrong image size */
    CHECK(strstr(thx_ctx_message(ctx), "64 x 64") != NULL);
    thx_raster_destroy(&im);
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    sc.camera.center[0] = sc.camera.eye[0], sc.camera.center[1] = sc.camera.eye[1];
    sc.camera.center[2] = sc.camera.eye[2];
    CHECK(thx_render(ctx, ren, &sc, im, NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "camera") != NULL);
    thx_surface *s = plane(2);
    thx_render_surface rs = surf_defaults(s, THX_DRAW_FLAT);
    s->tri[4] = 99; /* out of range */
    sc = base_scene(&rs, 1);
    CHECK(thx_render(ctx, ren, &sc, im, NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "triangle") != NULL);
    s->tri[4] = 1;
    double v[9] = {0};
    rs.values = v;
    rs.style = THX_DATA_BANDS;
    rs.n_levels = 0;
    CHECK(thx_render(ctx, ren, &sc, im, NULL) == THX_EINPUT);
    rs.n_levels = 3;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    thx_renderer *bad = NULL;
    CHECK(thx_renderer_create(ctx, -3, 10, &bad) == THX_EINPUT && bad == NULL);
    /* a renderer for the caller's context cannot read back */
    CHECK_OK(ctx, thx_renderer_create(ctx, 0, 0, &bad));
    CHECK(thx_render(ctx, bad, &sc, im, NULL) == THX_EINPUT);
    thx_renderer_destroy(&bad);
    CHECK(bad == NULL);
    thx_renderer_destroy(&bad);
    thx_raster_destroy(&im);
    thx_surface_destroy(&s);
}

/* Culling and two-sided lighting: a closed sphere drawn only from outside is the same picture; from
 * inside (perspective, eye at the centre) its inside shows; so does the back of an open surface and
 * a closed sphere whose triangles all face inward. */
static void test_sides(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *good = sphere(24, 36, 1, c, 0), *bad = sphere(24, 36, 1, c, 1), *pl = plane(4);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    for (int f = 0; f < 2; f++) {
        thx_render_surface rs = surf_defaults(f ? bad : good, THX_DRAW_PHONG);
        thx_scene sc = base_scene(&rs, 1);
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        const unsigned char *p = px(im, 64, 64);
        CHECK(p[0] > 150 && abs(p[0] - p[2]) < 10); /* lit grey, facing the light */
        CHECK(near_rgb(px(im, 2, 2), 0.1, 0.2, 0.3, 1));
        /* inside, looking along -y (perspective): the sphere's inside fills the view */
        memset(&sc.camera, 0, sizeof sc.camera);
        sc.camera.center[1] = -1;
        sc.camera.up[2] = 1;
        sc.camera.fov_deg = 60;
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        save(im, f ? "inside_flipped" : "inside");
        CHECK(!near_rgb(px(im, 64, 64), 0.1, 0.2, 0.3, 20));
        CHECK(!near_rgb(px(im, 2, 2), 0.1, 0.2, 0.3, 20));
    }
    /* the plane faces -y; seen from +y its back is lit the same */
    thx_render_surface rs = surf_defaults(pl, THX_DRAW_FLAT);
    thx_scene sc = base_scene(&rs, 1);
    plane_camera(&sc.camera);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(near_rgb(px(im, 64, 64), 0.8, 0.8, 0.8, 2));
    sc.camera.eye[1] = 5;
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(near_rgb(px(im, 64, 64), 0.8, 0.8, 0.8, 2));
    thx_raster_destroy(&im);
    thx_surface_destroy(&good);
    thx_surface_destroy(&bad);
    thx_surface_destroy(&pl);
}

/* Perspective: a square of half-width 1 at distance d under a vertical field of view fov has its
 * edge at 1 / (d tan(fov / 2)) of the half-image. With d = 2 / tan(fov / 2) the square fills the
 * middle half of the image (pixels 32..96 of 128), at 60 and at 30 degrees; a field of view taken
 * as the half angle would show it at a third (60) or under half (30) of that size. */
static void test_perspective(void)
{
    thx_surface *pl = plane(4);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    const double fovs[2] = {60, 30};
    for (int k = 0; k < 2; k++) {
        thx_render_surface rs = surf_defaults(pl, THX_DRAW_FLAT);
        thx_scene sc = base_scene(&rs, 1);
        memset(&sc.camera, 0, sizeof sc.camera);
        double d = 2 / tan(0.5 * fovs[k] * PI / 180); /* the edge at half the half-image */
        sc.camera.eye[1] = -d;
        sc.camera.up[2] = 1;
        sc.camera.fov_deg = fovs[k];
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        save(im, k ? "perspective30" : "perspective60");
        int row = 0, col = 0;
        for (int i = 0; i < N; i++) {
            row += !near_rgb(px(im, i, N / 2), 0.1, 0.2, 0.3, 40); /* lit by a headlight: not one grey */
            col += !near_rgb(px(im, N / 2, i), 0.1, 0.2, 0.3, 40);
        }
        printf("perspective %g deg: the square spans %d x %d pixels of %d (expected %d)\n", fovs[k], row, col, N, N / 2);
        CHECK(abs(row - N / 2) <= 2 && abs(col - N / 2) <= 2);
        CHECK(!near_rgb(px(im, N / 4 + 2, N / 2), 0.1, 0.2, 0.3, 40) && near_rgb(px(im, N / 4 - 2, N / 2), 0.1, 0.2, 0.3, 3));
    }
    thx_raster_destroy(&im);
    thx_surface_destroy(&pl);
}

/* thx_camera_project lands a point where the renderer draws it, and thx_camera_ray is its inverse:
 * a small square of the plane drawn around a point off the axis, under an orthographic and a
 * perspective camera turned off the axes, has its pixels' centre where the projection says; and
 * every pixel's ray projects back to that pixel. */
static void test_project(void)
{
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    for (int persp = 0; persp < 2; persp++) {
        thx_camera cam;
        memset(&cam, 0, sizeof cam);
        cam.eye[0] = 3; cam.eye[1] = -9; cam.eye[2] = 2;
        cam.center[0] = 0.2; cam.center[1] = 0; cam.center[2] = 0.1;
        cam.up[2] = 1; cam.up[0] = 0.2;
        if (persp) cam.fov_deg = 40;
        else cam.height = 5;
        /* round trips: pixel -> ray -> a point along it -> pixel */
        double worst = 0;
        for (int i = 0; i < 50; i++) {
            double x = (i * 37 % 101) * N / 100.0, y = (i * 53 % 97) * N / 96.0, o[3], d[3], p[3], px2, py2, dep;
            CHECK(thx_camera_ray(&cam, N, N, x, y, o, d) == 0);
            for (int k = 0; k < 3; k++) p[k] = o[k] + (3 + i % 7) * d[k];
            CHECK(thx_camera_project(&cam, N, N, p, &px2, &py2, &dep) == 0);
            worst = fmax(worst, fmax(fabs(px2 - x), fabs(py2 - y)));
        }
        CHECK(worst < 1e-9);
        /* a square of side 0.2 around (0.7, 0, 0.5) in the plane y = 0 */
        thx_surface *sq = NULL;
        CHECK_OK(ctx, thx_surface_create(ctx, "sq", THX_ROLE_OTHER, &sq));
        double c[3] = {0.7, 0, 0.5}, h = 0.1;
        double xyz[12] = {c[0] - h, 0, c[2] - h, c[0] + h, 0, c[2] - h, c[0] + h, 0, c[2] + h, c[0] - h, 0, c[2] + h};
        int32_t tri[6] = {0, 1, 2, 0, 2, 3};
        sq->xyz = malloc(sizeof xyz);
        sq->tri = malloc(sizeof tri);
        memcpy(sq->xyz, xyz, sizeof xyz);
        memcpy(sq->tri, tri, sizeof tri);
        sq->n_nodes = 4;
        sq->n_tris = 2;
        thx_render_surface rs = surf_defaults(sq, THX_DRAW_FLAT);
        thx_scene sc = base_scene(&rs, 1);
        sc.camera = cam;
        CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
        double sx = 0, sy = 0, n = 0;
        for (int y = 0; y < N; y++)
            for (int x = 0; x < N; x++)
                if (!near_rgb(px(im, x, y), 0.1, 0.2, 0.3, 40)) { sx += x + 0.5; sy += y + 0.5; n++; }
        double ex, ey, dep;
        CHECK(thx_camera_project(&cam, N, N, c, &ex, &ey, &dep) == 0);
        printf("project (%s): square drawn at (%.2f, %.2f) over %.0f pixels, projected (%.2f, %.2f), depth %.3f\n",
               persp ? "perspective" : "orthographic", sx / n, sy / n, n, ex, ey, dep);
        CHECK(n > 4);
        CHECK(fabs(sx / n - ex) < 1.0 && fabs(sy / n - ey) < 1.0);
        double bv[3], bl = 0, de = 0;
        for (int k = 0; k < 3; k++) { bv[k] = cam.eye[k] - cam.center[k]; bl += bv[k] * bv[k]; }
        for (int k = 0; k < 3; k++) de -= (c[k] - cam.eye[k]) * bv[k] / sqrt(bl);
        CHECK_NEAR(dep, de, 1e-12); /* the distance in front of the eye along the line of sight */
        double q[3] = {cam.eye[0], cam.eye[1], cam.eye[2]}, a, b2, d2;
        if (persp) CHECK(thx_camera_project(&cam, N, N, q, &a, &b2, &d2) == -1); /* the eye itself is not in front */
        thx_surface_destroy(&sq);
    }
    thx_raster_destroy(&im);
}

/* A renderer without a context of its own (the viewer's case) drawing with thx_render_scene_gl into
 * a framebuffer of the caller's: here the first renderer's context, which thx_render leaves current
 * when no other was. */
static void test_callers_context(void)
{
    if (eglGetCurrentContext() == EGL_NO_CONTEXT) {
        fprintf(stderr, "test_callers_context: no current context, skipped\n");
        return;
    }
    GLuint fbo, rb[2];
    glGenFramebuffers(1, &fbo);
    glGenRenderbuffers(2, rb);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 64, 32);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, 64, 32);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    thx_renderer *att = NULL;
    CHECK_OK(ctx, thx_renderer_create(ctx, 0, 0, &att));
    CHECK(thx_renderer_samples(att) == 0);
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(16, 24, 1, c, 0);
    double *v = malloc(s->n_nodes * sizeof *v);
    for (size_t i = 0; i < s->n_nodes; i++) v[i] = s->xyz[3 * i];
    thx_render_surface rs = surf_defaults(s, THX_DRAW_FLAT);
    rs.values = v;
    thx_scene sc = base_scene(&rs, 1);
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    thx_camera_view(&sc.camera, THX_VIEW_ANTERIOR, lo, hi, 2.0);
    size_t n_nan = 7;
    CHECK_OK(ctx, thx_render_scene_gl(ctx, att, &sc, 64, 32, &n_nan));
    CHECK(n_nan == 0);
    CHECK(strstr(thx_renderer_info(att), "OpenGL") != NULL);
    unsigned char pix[64 * 32 * 4];
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, 64, 32, GL_RGBA, GL_UNSIGNED_BYTE, pix);
    const unsigned char *bg = pix, *l = pix + 4 * (16 * 64 + 24), *r = pix + 4 * (16 * 64 + 40);
    CHECK(abs(bg[0] - 26) <= 1 && abs(bg[1] - 51) <= 1 && abs(bg[2] - 77) <= 1);
    CHECK(l[0] > l[2] + 30); /* the subject's right, positive, on the left */
    CHECK(r[2] > r[0] + 30);
    CHECK(glGetError() == GL_NO_ERROR);
    thx_renderer_destroy(&att);
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(2, rb);
    free(v);
    thx_surface_destroy(&s);
}

/* A second renderer of another size alongside the first, then destroyed: the first still works. */
static void test_second_renderer(void)
{
    thx_renderer *r2 = NULL;
    CHECK_OK(ctx, thx_renderer_create(ctx, 200, 100, &r2));
    if (!r2) return;
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(16, 24, 1, c, 0);
    thx_render_surface rs = surf_defaults(s, THX_DRAW_GOURAUD);
    thx_scene sc = base_scene(&rs, 1);
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    thx_camera_view(&sc.camera, THX_VIEW_LEFT, lo, hi, 2.0);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 200, 100, &im));
    CHECK_OK(ctx, thx_render(ctx, r2, &sc, im, NULL));
    CHECK(near_rgb(px(im, 10, 50), 0.1, 0.2, 0.3, 1));
    CHECK(!near_rgb(px(im, 100, 50), 0.1, 0.2, 0.3, 10));
    thx_renderer_destroy(&r2);
    thx_raster_destroy(&im);
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &im));
    sc = base_scene(&rs, 1);
    CHECK_OK(ctx, thx_render(ctx, ren, &sc, im, NULL));
    CHECK(!near_rgb(px(im, 64, 64), 0.1, 0.2, 0.3, 10));
    thx_raster_destroy(&im);
    thx_surface_destroy(&s);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* 100,000 triangles with data at 1024 x 1024: the values change every frame (an animation). */
static void bench(void)
{
    thx_renderer *big = NULL;
    CHECK_OK(ctx, thx_renderer_create(ctx, 1024, 1024, &big));
    if (!big) return;
    double c[3] = {0, 0, 0};
    thx_surface *s = sphere(201, 250, 100, c, 0);
    double *v = malloc(s->n_nodes * sizeof *v);
    thx_render_surface rs = surf_defaults(s, THX_DRAW_PHONG);
    rs.values = v;
    rs.style = THX_DATA_BANDS_CONTOURS;
    rs.n_levels = 12;
    rs.scale.lo = -100, rs.scale.hi = 100;
    thx_scene sc = base_scene(&rs, 1);
    double lo[3] = {-100, -100, -100}, hi[3] = {100, 100, 100};
    thx_camera_view(&sc.camera, THX_VIEW_ANTERIOR, lo, hi, 1.0);
    thx_raster *im = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 1024, 1024, &im));
    for (int pass = 0; pass < 3; pass++) {
        /* automatic samples; 4x multisampling; automatic with a clip plane (both sides drawn) */
        CHECK_OK(ctx, thx_renderer_set_samples(ctx, big, pass == 1 ? 4 : 0));
        sc.n_clip = pass == 2;
        sc.clip[0].n[1] = -1, sc.clip[0].d = 150; /* cuts nothing, but disables culling */
        double t[11];
        for (int f = 0; f < 11; f++) {
            for (size_t i = 0; i < s->n_nodes; i++)
                v[i] = s->xyz[3 * i] * cos(0.3 * f) + s->xyz[3 * i + 2] * sin(0.3 * f);
            double t0 = thx_wtime();
            CHECK_OK(ctx, thx_render(ctx, big, &sc, im, NULL));
            t[f] = thx_wtime() - t0;
        }
        save(im, pass == 1 ? "bench_msaa" : "bench");
        qsort(t + 1, 10, sizeof *t, cmp_double);
        printf("bench: %zu triangles, %zu nodes, 1024 x 1024, %d sample%s%s: first frame %.1f ms, median of 10 %.1f ms "
               "(min %.1f, max %.1f)\n", s->n_tris, s->n_nodes, thx_renderer_samples(big),
               thx_renderer_samples(big) > 1 ? "s" : " + FXAA", pass == 2 ? ", clip plane" : "", 1e3 * t[0],
               1e3 * 0.5 * (t[5] + t[6]), 1e3 * t[1], 1e3 * t[10]);
    }
    thx_raster_destroy(&im);
    free(v);
    thx_surface_destroy(&s);
    thx_renderer_destroy(&big);
}

/* ------------------------------------------------------------- arrow selection (no GL) */

static double urand(unsigned *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (*state >> 8) / 16777216.0;
}

static void test_arrows_select(void)
{
    enum { NP = 3000 };
    double *xyz = malloc(3 * NP * sizeof *xyz), *v = malloc(3 * NP * sizeof *v);
    unsigned char *in = malloc(NP);
    unsigned seed = 7;
    for (int i = 0; i < NP; i++) {
        for (int k = 0; k < 3; k++) { xyz[3 * i + k] = 100 * urand(&seed); v[3 * i + k] = urand(&seed) - 0.5; }
        in[i] = (i % 5) != 0;
    }
    v[3 * 4] = NAN;          /* non-finite: dropped */
    v[3 * 8] = v[3 * 8 + 1] = v[3 * 8 + 2] = 0; /* zero: dropped */
    double *P = NULL, *V = NULL, vmax = 0;
    size_t n = 0;

    /* one per point, no limits: every finite nonzero vector inside, strongest first */
    CHECK_OK(ctx, thx_arrows_select(ctx, xyz, v, NP, in, 0, 0, (size_t)NP, &P, &V, &n, &vmax));
    size_t expect = 0;
    double best = 0;
    for (int i = 0; i < NP; i++)
        if (in[i] && i != 4 && i != 8) { expect++; best = fmax(best, sqrt(v[3*i]*v[3*i] + v[3*i+1]*v[3*i+1] + v[3*i+2]*v[3*i+2])); }
    CHECK(n == expect);
    CHECK(fabs(vmax - best) < 1e-15);
    int sorted = 1, inside = 1;
    for (size_t a = 0; a < n; a++) {
        double m = sqrt(V[3*a]*V[3*a] + V[3*a+1]*V[3*a+1] + V[3*a+2]*V[3*a+2]);
        if (a && m > sqrt(V[3*a-3]*V[3*a-3] + V[3*a-2]*V[3*a-2] + V[3*a-1]*V[3*a-1]) + 1e-15) sorted = 0;
        int found = 0; /* the tail is one of the points inside, with its own vector */
        for (int i = 0; i < NP && !found; i++)
            found = in[i] && xyz[3*i] == P[3*a] && xyz[3*i+1] == P[3*a+1] && xyz[3*i+2] == P[3*a+2] && v[3*i] == V[3*a];
        inside &= found;
    }
    CHECK(sorted && inside);
    free(P); free(V);

    /* at most max_n, and those the strongest */
    CHECK_OK(ctx, thx_arrows_select(ctx, xyz, v, NP, in, 0, 0, 50, &P, &V, &n, &vmax));
    CHECK(n == 50);
    double weakest = INFINITY;
    for (size_t a = 0; a < n; a++) weakest = fmin(weakest, V[3*a]*V[3*a] + V[3*a+1]*V[3*a+1] + V[3*a+2]*V[3*a+2]);
    int stronger_left_out = 0;
    for (int i = 0; i < NP; i++) {
        if (!in[i] || !isfinite(v[3*i])) continue;
        double m = v[3*i]*v[3*i] + v[3*i+1]*v[3*i+1] + v[3*i+2]*v[3*i+2];
        int kept = 0;
        for (size_t a = 0; a < n; a++) kept |= xyz[3*i] == P[3*a] && xyz[3*i+1] == P[3*a+1];
        if (!kept && m > weakest) stronger_left_out++;
    }
    CHECK(stronger_left_out == 0);
    free(P); free(V);

    /* minimum gap: kept tails at least gap apart, and every point left out lies within gap of a
       kept arrow at least as strong (the greedy rule, nothing dropped without cause) */
    const double gap = 12;
    CHECK_OK(ctx, thx_arrows_select(ctx, xyz, v, NP, in, 0, gap, (size_t)NP, &P, &V, &n, &vmax));
    CHECK(n > 30 && n < 1000);
    double dmin = INFINITY;
    for (size_t a = 0; a < n; a++)
        for (size_t b = a + 1; b < n; b++) {
            double d0 = P[3*a] - P[3*b], d1 = P[3*a+1] - P[3*b+1], d2 = P[3*a+2] - P[3*b+2];
            dmin = fmin(dmin, sqrt(d0*d0 + d1*d1 + d2*d2));
        }
    CHECK(dmin >= gap);
    int unexplained = 0;
    for (int i = 0; i < NP; i++) {
        if (!in[i] || i == 4 || i == 8) continue;
        double m = sqrt(v[3*i]*v[3*i] + v[3*i+1]*v[3*i+1] + v[3*i+2]*v[3*i+2]);
        int ok = 0;
        for (size_t a = 0; a < n && !ok; a++) {
            double d0 = xyz[3*i] - P[3*a], d1 = xyz[3*i+1] - P[3*a+1], d2 = xyz[3*i+2] - P[3*a+2];
            double ma = sqrt(V[3*a]*V[3*a] + V[3*a+1]*V[3*a+1] + V[3*a+2]*V[3*a+2]);
            ok = (d0 == 0 && d1 == 0 && d2 == 0) || (d0*d0 + d1*d1 + d2*d2 < gap * gap && ma >= m);
        }
        unexplained += !ok;
    }
    CHECK(unexplained == 0);
    printf("arrows: %zu of %d points kept %g mm apart (closest pair %.2f mm)\n", n, NP, gap, dmin);
    free(P); free(V);

    /* grid averaging: each arrow is the mean position and mean vector of the points of its cell */
    const double h = 25;
    CHECK_OK(ctx, thx_arrows_select(ctx, xyz, v, NP, NULL, h, 0, (size_t)NP, &P, &V, &n, &vmax));
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    for (int i = 0; i < NP; i++) for (int k = 0; k < 3; k++) lo[k] = fmin(lo[k], xyz[3*i+k]);
    CHECK(n >= 60 && n <= 125); /* 5^3 cells at most over the 100 mm cube, nearly all filled */
    double err = 0;
    for (size_t a = 0; a < n; a++) {
        int c[3];
        for (int k = 0; k < 3; k++) c[k] = (int)((P[3*a+k] - lo[k]) / h);
        double sp[3] = {0, 0, 0}, sv[3] = {0, 0, 0}, cnt = 0;
        for (int i = 0; i < NP; i++) {
            if (i == 4) continue;
            int same = 1;
            for (int k = 0; k < 3; k++) same &= (int)((xyz[3*i+k] - lo[k]) / h) == c[k];
            if (!same) continue;
            for (int k = 0; k < 3; k++) { sp[k] += xyz[3*i+k]; sv[k] += v[3*i+k]; }
            cnt++;
        }
        for (int k = 0; k < 3; k++) err = fmax(err, fmax(fabs(sp[k] / cnt - P[3*a+k]), fabs(sv[k] / cnt - V[3*a+k])));
    }
    CHECK(err < 1e-12);
    free(P); free(V);

    /* bad parameters */
    CHECK(thx_arrows_select(ctx, xyz, v, NP, NULL, -1, 0, 10, &P, &V, &n, &vmax) == THX_EINPUT);
    CHECK(P == NULL && V == NULL && n == 0);
    free(xyz); free(v); free(in);
}

/* The symmetric colour range is the largest magnitude, on whichever side: data -5..2 gives -5..5
 * (the range `thorax render` uses: thx_scale_from_range over the values its --scope covers; a
 * range from the largest value would give -2..2). */
static void test_symmetric_range(void)
{
    thx_scale s;
    thx_scale_from_range(&s, THX_SCALE_LINEAR, -5, 2, 1);
    CHECK(s.lo == -5 && s.hi == 5);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, -2, 5, 1);
    CHECK(s.lo == -5 && s.hi == 5);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, -5, 2, 0);
    CHECK(s.lo == -5 && s.hi == 2);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, -7, -3, 1); /* all negative */
    CHECK(s.lo == -7 && s.hi == 7);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, 0, 0, 1);
    CHECK(s.lo == -1 && s.hi == 1);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, 3, 3, 0);
    CHECK(s.lo == 2 && s.hi == 4);
    thx_scale_from_range(&s, THX_SCALE_LINEAR, INFINITY, -INFINITY, 1); /* no finite value */
    CHECK(s.lo == -1 && s.hi == 1);
    const double v[] = {2, -5, 1, NAN, 0.5};
    thx_scale_from_data(&s, THX_SCALE_LINEAR, v, 5, 1); /* the same rule over an array */
    CHECK(s.lo == -5 && s.hi == 5);
    CHECK(fabs(thx_scale_apply(&s, 2) - 0.7) < 1e-12 && thx_scale_apply(&s, -5) == 0);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_symmetric_range();
    test_views();
    test_arrows_select();
    thx_status st = thx_renderer_create(ctx, N, N, &ren);
    if (st != THX_OK) {
        fprintf(stderr, "test_render: no renderer: %s\n", thx_ctx_message(ctx));
        CHECK(st == THX_OK);
        thx_ctx_destroy(&ctx);
        return tl_finish();
    }
    CHECK(strstr(thx_renderer_info(ren), "OpenGL") != NULL);
    /* every picture with the automatic antialiasing, then with 4x multisampling */
    for (int pass = 0; pass < 2; pass++) {
        if (pass) CHECK_OK(ctx, thx_renderer_set_samples(ctx, ren, 4));
        int ns = thx_renderer_samples(ren);
        CHECK(ns == 1 || ns == 4);
        CHECK(!pass || ns == 4);
        printf("renderer: %s, %d sample%s\n", thx_renderer_info(ren), ns, ns > 1 ? "s" : " + FXAA");
        test_ecg_map();
        test_bands_contours();
        test_lab_bands();
        test_nan();
        test_orientation();
        test_clip();
        test_viewports();
        test_modes();
        test_sides();
        test_perspective();
        test_project();
        test_errors();
    }
    CHECK(thx_renderer_set_samples(ctx, ren, 2) == THX_EINPUT);
    test_callers_context();
    test_second_renderer();
    if (getenv("THX_RENDER_BENCH")) bench();
    thx_renderer_destroy(&ren);
    CHECK(ren == NULL);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
