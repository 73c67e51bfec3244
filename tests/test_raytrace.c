/* RaySpray (thorax/raytrace/raytrace.h) against known answers:
 *  - a sphere over a plane lit by a point light straight above: the shadow's edge at the radius the
 *    tangent cone gives, L R / sqrt((L - h)^2 - R^2), to a pixel;
 *  - a mirror at 45 degrees reflecting a checkerboard: each pixel's light or dark square is the one
 *    the reflected ray reaches;
 *  - a glass slab (n = 1.5) tilted in front of a dark line: the line seen shifted by the slab's lateral
 *    displacement T sin(i - r) / cos r, Snell's law;
 *  - the same picture for 1 and 2 threads; a frame step (new values only) builds no geometry;
 *  - motion blur: a square seen by a camera that moves sideways by a known offset between two frames,
 *    with the shutter open the whole interval: the blurred edge as wide as the move projected to the
 *    screen (to a pixel), on the side the square moves to; shutter 0 the unblurred picture byte for
 *    byte; values going from 0 to 1 between the frames: the mean colour the colour map's mean over
 *    [0, 1] (to a few levels); the same bytes on 1 and 2 threads; no geometry built.
 *  - an image plane with a checker texture seen face-on: every pixel its texel (nearest), what is
 *    behind where alpha < 128, the mean of two texels midway between them (bilinear);
 *  - an arrow of known length: its pixels' extent, its shaft's and head's widths in pixels, and its
 *    shadow on a floor under a directional light;
 *  - a coarse smooth-shaded sphere alone under a side light: a convex body casts no shadow on itself,
 *    so its picture with shadows is the one without (the shadow terminator's bands absent).
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shapes.h"
#include "testlib.h"
#include "thorax/geom/predicates.h"
#include "thorax/raytrace/raytrace.h"

static thx_ctx *ctx;

/* THX_TEST_PNG=DIR: the pictures written there, to look at */
static void keep(const thx_raster *img, const char *name)
{
    const char *dir = getenv("THX_TEST_PNG");
    if (!dir) return;
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    thx_raster_write_png(ctx, img, p);
}

/* a surface from arrays (copied) */
static thx_surface *mesh(const char *name, const double *xyz, size_t nn, const int32_t *tri, size_t nt)
{
    thx_surface *s = NULL;
    CHECK_OK(ctx, thx_surface_create(ctx, name, THX_ROLE_OTHER, &s));
    s->xyz = malloc(3 * nn * sizeof *s->xyz);
    s->tri = malloc(3 * nt * sizeof *s->tri);
    memcpy(s->xyz, xyz, 3 * nn * sizeof *s->xyz);
    memcpy(s->tri, tri, 3 * nt * sizeof *s->tri);
    s->n_nodes = nn;
    s->n_tris = nt;
    return s;
}

/* a UV sphere (outward), nlon x nlat (tests/shapes.h) */
static thx_surface *sphere(double cx, double cy, double cz, double r, int nlon, int nlat)
{
    thx_surface *s = shape_sphere(ctx, "sphere", (const double[3]){cx, cy, cz}, r, nlon, nlat);
    CHECK(s != NULL);
    return s;
}

/* a rectangle: corner o, edges u and v (two triangles, normal u x v) */
static thx_surface *rect(const char *name, const double o[3], const double u[3], const double v[3])
{
    double x[12];
    for (int k = 0; k < 3; k++) {
        x[k] = o[k];
        x[3 + k] = o[k] + u[k];
        x[6 + k] = o[k] + u[k] + v[k];
        x[9 + k] = o[k] + v[k];
    }
    int32_t t[6] = {0, 1, 2, 0, 2, 3};
    return mesh(name, x, 4, t, 2);
}

/* a box lo..hi (outward) */
static thx_surface *box(const char *name, const double lo[3], const double hi[3])
{
    double x[24];
    for (int c = 0; c < 8; c++) {
        x[3 * c] = c & 1 ? hi[0] : lo[0];
        x[3 * c + 1] = c & 2 ? hi[1] : lo[1];
        x[3 * c + 2] = c & 4 ? hi[2] : lo[2];
    }
    int32_t t[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                     2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    return mesh(name, x, 8, t, 12);
}

static double lum(const thx_raster *img, int x, int y)
{
    const unsigned char *p = img->rgba + 4 * ((size_t)y * (size_t)img->w + (size_t)x);
    return (p[0] + p[1] + p[2]) / 3.0;
}

static void camera_down(thx_scene *sc, double height)
{
    sc->camera = (thx_camera){{0, 0, 500}, {0, 0, 0}, {0, 1, 0}, 0, height};
}

static void test_shadow(thx_tracer *tr)
{
    const double R = 20, H = 40, L = 160; /* sphere radius and centre height, light height */
    thx_surface *sph = sphere(0, 0, H, R, 256, 128);
    double o[3] = {-100, -100, 0}, u[3] = {200, 0, 0}, v[3] = {0, 200, 0};
    thx_surface *pl = rect("plane", o, u, v);
    thx_render_surface rs[2];
    memset(rs, 0, sizeof rs);
    rs[0].surf = pl;
    rs[0].mode = THX_DRAW_FLAT;
    rs[1].surf = sph;
    rs[1].mode = THX_DRAW_PHONG;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = 2;
    camera_down(&sc, 200);
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.n_lights = 1;
    to.lights[0] = (thx_light){.kind = THX_LIGHT_POINT, .pos = {0, 0, L}, .intensity = 1, .shadows = 1};
    const int N = 400; /* 0.5 mm a pixel */
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &img));
    thx_raytrace_stats st;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, &st));
    keep(img, "shadow.png");
    /* along the row through the centre, right of the sphere: where the plane turns from dark to lit */
    double rs_exact = L * R / sqrt((L - H) * (L - H) - R * R), mm = 200.0 / N, edge = -1;
    int yc = N / 2;
    for (int x = N / 2 + (int)(R / mm) + 2; x < N - 1; x++)
        if (lum(img, x, yc) < 100 && lum(img, x + 1, yc) >= 100) edge = (x + 1 - N / 2.0) * mm;
    printf("sphere R %g at height %g, point light at %g: shadow edge %.2f mm, the tangent cone's %.2f mm (pixel %.2f mm); "
           "%zu rays in %.3f s\n", R, H, L, edge, rs_exact, mm, st.rays, st.seconds);
    CHECK(fabs(edge - rs_exact) <= mm);
    /* the same picture on 1 and 2 threads */
    thx_raster *img1 = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &img1));
    to.samples = 2;
    to.ao_samples = 4;
    omp_set_num_threads(2);
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
    omp_set_num_threads(1);
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img1, &st));
    omp_set_num_threads(2);
    CHECK(!memcmp(img->rgba, img1->rgba, 4 * (size_t)N * N));
    CHECK(st.builds == 0); /* the surfaces' geometry kept from the first call */
    thx_raster_destroy(&img);
    thx_raster_destroy(&img1);
    thx_surface_destroy(&sph);
    thx_surface_destroy(&pl);
}

static void test_terminator(thx_tracer *tr)
{
    thx_surface *sph = sphere(0, 0, 0, 40, 10, 4); /* 36 x 45 degrees a facet: the bands would be wide */
    thx_render_surface rs;
    memset(&rs, 0, sizeof rs);
    rs.surf = sph;
    rs.mode = THX_DRAW_PHONG;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = &rs;
    sc.n_surfaces = 1;
    sc.camera = (thx_camera){{0, -500, 0}, {0, 0, 0}, {0, 0, 1}, 0, 100}; /* from the front */
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.n_lights = 1;
    /* from above and a little in front: the terminator runs along the facets' bands */
    to.lights[0] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .dir = {0, 0.4, -1}, .intensity = 1, .shadows = 1};
    const int N = 300;
    thx_raster *on = NULL, *off = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &on));
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &off));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, on, NULL));
    to.lights[0].shadows = 0;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, off, NULL));
    keep(on, "terminator.png");
    size_t differ = 0, lit = 0;
    for (size_t i = 0; i < (size_t)N * N; i++) {
        int d = 0;
        for (int k = 0; k < 3; k++) d += abs(on->rgba[4 * i + k] - off->rgba[4 * i + k]);
        differ += d > 3;
        lit += off->rgba[4 * i] > 40;
    }
    printf("a 10 x 4 facet sphere under a light from above: %zu of %zu lit pixels differ with shadows on\n", differ, lit);
    CHECK(lit > 10000 && differ <= lit / 100); /* (without the lift: 5,937 of 40,724, bands across the lower facets) */
    thx_raster_destroy(&on);
    thx_raster_destroy(&off);
    thx_surface_destroy(&sph);
}

static void test_mirror(thx_tracer *tr)
{
    /* camera looking down -z; the mirror z = x (normal (-1, 0, 1)/sqrt 2) sends the rays along -x to
       a checkerboard on the plane x = -60 (facing +x) */
    const double q = 10, D = 60;
    double mo[3] = {-40, -40, -40}, mu[3] = {80, 0, 80}, mv[3] = {0, 80, 0};
    thx_surface *mir = rect("mirror", mo, mv, mu); /* normal mv x mu = (80 * 80, 0, -80 * 80)?: see below */
    double co[3] = {-D, -100, -100}, cu[3] = {0, 200, 0}, cv[3] = {0, 0, 200};
    thx_surface *chk = rect("checker", co, cu, cv);
    thx_render_surface rs[2];
    memset(rs, 0, sizeof rs);
    rs[0].surf = mir;
    rs[0].mode = THX_DRAW_FLAT;
    rs[0].color[0] = rs[0].color[1] = rs[0].color[2] = 0.1f;
    rs[0].color[3] = 1;
    rs[1].surf = chk;
    rs[1].mode = THX_DRAW_FLAT;
    rs[1].color[0] = rs[1].color[1] = rs[1].color[2] = 1;
    rs[1].color[3] = 1;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = 2;
    camera_down(&sc, 60);
    sc.camera.eye[2] = 300;
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.ambient = 1; /* unlit: the colours as they are */
    to.n_lights = 1;
    to.lights[0] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .dir = {0, 0, -1}, .intensity = 1e-9};
    to.material[0].reflect = 1;
    to.material[1].texture = 2;
    to.material[1].texture_mm = q;
    const int N = 240;
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &img));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
    keep(img, "mirror.png");
    size_t agree = 0, counted = 0;
    double mm = 60.0 / N;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            /* the pixel's ray: x to the right is -x in the model (the camera's right is view x up =
               (0,0,-1) x (0,1,0) = (1, 0, 0)); compute from the camera frame */
            double px = (x + 0.5 - N / 2.0) * mm, py = (N / 2.0 - y - 0.5) * mm; /* camera right = +x, up = +y */
            /* the mirror at z = x: the reflected ray reaches (-D, py, px) */
            double yy = py, zz = px;
            double fy = yy / q - floor(yy / q), fz = zz / q - floor(zz / q);
            if (fmin(fy, 1 - fy) * q < 1.5 * mm || fmin(fz, 1 - fz) * q < 1.5 * mm) continue; /* near a square's edge */
            long par = (long)floor(-D / q) + (long)floor(yy / q) + (long)floor(zz / q);
            int dark = (int)(par & 1);
            double l = lum(img, x, y);
            counted++;
            agree += dark ? l < 128 : l >= 128;
        }
    printf("mirror at 45 degrees over a checkerboard: %zu of %zu pixels show the square the reflected ray reaches\n", agree, counted);
    CHECK(counted > (size_t)(N * N / 2) && agree == counted);
    thx_raster_destroy(&img);
    thx_surface_destroy(&mir);
    thx_surface_destroy(&chk);
}

static void test_refraction(thx_tracer *tr)
{
    /* a white plane z = 0 with a dark line x in [-0.5, 0.5] (a thin box on it); camera straight down;
       a glass slab of thickness T between, tilted by i about the y axis: a ray through it is shifted
       sideways by T sin(i - r) / cos r, r = asin(sin i / n) */
    const double T = 20, deg = 30, n = 1.5, i = deg * M_PI / 180, r = asin(sin(i) / n);
    const double shift = T * sin(i - r) / cos(r); /* perpendicular to the ray, i.e. along x here */
    double po[3] = {-100, -100, 0}, pu[3] = {200, 0, 0}, pv[3] = {0, 200, 0};
    thx_surface *pl = rect("plane", po, pu, pv);
    double llo[3] = {-0.5, -100, 0}, lhi[3] = {0.5, 100, 0.5};
    thx_surface *line = box("line", llo, lhi);
    double slo[3] = {-60, -60, -T / 2}, shi[3] = {60, 60, T / 2};
    thx_surface *slab = box("slab", slo, shi);
    /* tilt the slab by i about y and lift it to z = 50 */
    for (size_t k = 0; k < slab->n_nodes; k++) {
        double *p = slab->xyz + 3 * k, x = p[0], z = p[2];
        p[0] = cos(i) * x + sin(i) * z;
        p[2] = -sin(i) * x + cos(i) * z + 50;
    }
    thx_render_surface rs[3];
    memset(rs, 0, sizeof rs);
    for (int k = 0; k < 3; k++) { rs[k].mode = THX_DRAW_FLAT; rs[k].color[3] = 1; }
    rs[0].surf = pl;
    rs[0].color[0] = rs[0].color[1] = rs[0].color[2] = 1;
    rs[1].surf = line;
    rs[2].surf = slab;
    rs[2].color[0] = rs[2].color[1] = rs[2].color[2] = 1;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = 3;
    camera_down(&sc, 40);
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.ambient = 1;
    to.n_lights = 1;
    to.lights[0] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .dir = {0, 0, -1}, .intensity = 1e-9};
    to.material[2].transmit = 1;
    to.material[2].ior = n;
    const int N = 400; /* 0.1 mm a pixel */
    double mm = 40.0 / N, seen[2];
    for (int with = 0; with < 2; with++) {
        sc.n_surfaces = with ? 3 : 2;
        thx_raster *img = NULL;
        CHECK_OK(ctx, thx_raster_create(ctx, N, N, &img));
        CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
        keep(img, with ? "slab.png" : "noslab.png");
        /* the line's centre along the middle row: the mean x of the dark pixels */
        double sx = 0;
        int cnt = 0;
        for (int x = 0; x < N; x++)
            if (lum(img, x, N / 2) < 100) { sx += (x + 0.5 - N / 2.0) * mm; cnt++; }
        seen[with] = cnt ? sx / cnt : NAN;
        thx_raster_destroy(&img);
    }
    printf("glass slab (n = %.1f, %g mm, tilted %g degrees): the line seen %.3f mm aside, Snell's law %.3f mm (pixel %.2f mm)\n",
           n, T, deg, fabs(seen[1] - seen[0]), shift, mm);
    CHECK(fabs(seen[0]) <= mm);
    CHECK(fabs(fabs(seen[1] - seen[0]) - shift) <= mm);
    thx_surface_destroy(&pl);
    thx_surface_destroy(&line);
    thx_surface_destroy(&slab);
}

/* One tetrahedron, corners at the origin and 10 mm along each axis, a constant field 0.5 on the grey
 * map over [0, 1] with a flat opacity 1, extinction tau per mm (the closed form's case). */
static void const_tet_volume(thx_raytrace_volume *v, double tau)
{
    static const double tx[12] = {0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10}, cv = 0.5;
    static const int32_t tt[4] = {0, 1, 2, 3};
    memset(v, 0, sizeof *v);
    v->xyz = tx;
    v->n_nodes = 4;
    v->tet = tt;
    v->n_tets = 1;
    v->cell_values = &cv;
    v->cmap = THX_CMAP_GRAY;
    thx_scale_from_range(&v->scale, THX_SCALE_LINEAR, 0, 1, 0);
    v->opacity[0][0] = 0, v->opacity[0][1] = 1, v->opacity[1][0] = 1, v->opacity[1][1] = 1;
    v->n_opacity = 2;
    v->density = tau;
}

/* The volume integral against closed forms: a constant field in one tetrahedron (colour C and
 * extinction tau constant: C (1 - e^(-tau L)), transmittance e^(-tau L)), and a field linear in z
 * through a cube of six tetrahedra with the grey map (C(t) = t) and a flat opacity: emission
 * int_0^L (z / 10) tau e^(-tau z) dz = (1 - e^(-tau L) (1 + tau L)) / (10 tau); then a frame step (new
 * values, same mesh) that builds nothing. */
static void test_volume(thx_tracer *tr)
{
    const double tau = 0.1;
    thx_raytrace_volume v;
    const_tet_volume(&v, tau);
    double o[3] = {2, 2, -5}, d[3] = {0, 0, 1}, rgb[3], T;
    CHECK_OK(ctx, thx_raytrace_volume_ray(ctx, tr, &v, o, d, 0, INFINITY, rgb, &T));
    double L = 6, eT = exp(-tau * L), eC = 0.5 * (1 - eT); /* from z = 0 to the face x + y + z = 10 */
    printf("constant field in a tetrahedron, a ray of %g mm in it: transmittance %.12f (exact %.12f), colour %.12f (exact %.12f)\n",
           L, T, eT, rgb[0], eC);
    CHECK_NEAR(T, eT, 1e-6);
    CHECK_NEAR(rgb[0], eC, 1e-6);
    /* the cube [0, 10]^3 as six tetrahedra round its diagonal (0,0,0)-(10,10,10), each positive */
    double cx[24];
    int32_t ct[24];
    shape_cube_grid(1, 10, cx, ct);
    double pv[8];
    for (int c = 0; c < 8; c++) pv[c] = cx[3 * c + 2]; /* the field z */
    memset(&v, 0, sizeof v);
    v.xyz = cx;
    v.n_nodes = 8;
    v.tet = ct;
    v.n_tets = 6;
    v.point_values = pv;
    v.cmap = THX_CMAP_GRAY;
    thx_scale_from_range(&v.scale, THX_SCALE_LINEAR, 0, 10, 0);
    v.opacity[0][0] = 0;
    v.opacity[0][1] = 1;
    v.opacity[1][0] = 1;
    v.opacity[1][1] = 1;
    v.n_opacity = 2;
    v.density = tau;
    double o2[3] = {3, 7.5, -2};
    CHECK_OK(ctx, thx_raytrace_volume_ray(ctx, tr, &v, o2, d, 0, INFINITY, rgb, &T));
    L = 10;
    double exact = (1 - exp(-tau * L) * (1 + tau * L)) / (10 * tau);
    printf("a field linear in z through a cube of 6 tetrahedra: colour %.12f (exact %.12f), transmittance %.12f (exact %.12f)\n",
           rgb[0], exact, T, exp(-tau * L));
    CHECK_NEAR(rgb[0], exact, 1e-6);
    CHECK_NEAR(T, exp(-tau * L), 1e-6);
    /* thin pieces (the series' branch) with the extinction varying along each: the field z over a
       scale of 0 to 1000, so t = z / 1000 spans 2.55 of the table's entries over the ray and the
       pieces are millimetres long; the opacity a ramp (0 at t = 0, 1 at t = 1) and 2 per mm at
       opacity 1, so tau = 2 z / 1000 and C = z / 1000; the emission int_0^10 C tau e^(-D) dz with D
       = z^2 / 1000, against Simpson's rule on 100,000 intervals; the transmittance e^(-0.1); one
       ray, and eight through the lanes */
    thx_scale_from_range(&v.scale, THX_SCALE_LINEAR, 0, 1000, 0);
    v.opacity[0][1] = 0;
    v.density = 2;
    double ref = 0, hz = 10.0 / 100000;
    for (int i = 0; i <= 100000; i++) {
        double z = i * hz, f = (z / 1000) * (2 * z / 1000) * exp(-z * z / 1000);
        ref += f * (i == 0 || i == 100000 ? 1 : i % 2 ? 4 : 2);
    }
    ref *= hz / 3;
    CHECK_OK(ctx, thx_raytrace_volume_ray(ctx, tr, &v, o2, d, 0, INFINITY, rgb, &T));
    double o8[8][3], d8[8][3], f8[8], rgb8[8][3], T8[8];
    for (int r = 0; r < 8; r++) {
        memcpy(o8[r], o2, sizeof o2);
        memcpy(d8[r], d, sizeof d8[r]);
        f8[r] = INFINITY;
    }
    CHECK_OK(ctx, thx_raytrace_volume_rays(ctx, tr, &v, 8, (const double(*)[3])o8, (const double(*)[3])d8, f8, rgb8, T8));
    printf("thin pieces, extinction ramping along each: colour %.12g one ray, %.12g in the lanes (quadrature %.12g), "
           "transmittance %.12f (exact %.12f)\n", rgb[0], rgb8[0][0], ref, T, exp(-0.1));
    CHECK(fabs(rgb[0] - ref) <= 1e-6 * ref);
    CHECK_NEAR(T, exp(-0.1), 1e-7);
    for (int r = 0; r < 8; r++) {
        CHECK(fabs(rgb8[r][0] - ref) <= 1e-6 * ref);
        CHECK_NEAR(T8[r], exp(-0.1), 1e-7);
    }
    thx_scale_from_range(&v.scale, THX_SCALE_LINEAR, 0, 10, 0);
    v.opacity[0][1] = 1;
    v.density = tau;
    /* in a picture: the first frame builds the mesh's faces, a frame step (other values) builds nothing */
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.camera = (thx_camera){{5, 5, 100}, {5, 5, 0}, {0, 1, 0}, 0, 20};
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.volume = &v;
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 40, 40, &img));
    thx_tracer *t2 = NULL;
    CHECK_OK(ctx, thx_tracer_create(ctx, &t2));
    thx_raytrace_stats st1, st2;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, t2, &sc, &to, img, &st1));
    double pv2[8];
    for (int c = 0; c < 8; c++) pv2[c] = 10 - pv[c];
    v.point_values = pv2;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, t2, &sc, &to, img, &st2));
    printf("volume in a picture: first frame %zu build(s), the next frame %zu\n", st1.builds, st2.builds);
    CHECK(st1.builds == 1 && st2.builds == 0);
    /* the cube seen from above: grey, lighter where the field is higher near the eye */
    const unsigned char *mid = img->rgba + 4 * (20 * 40 + 20);
    CHECK(mid[0] > 10 && mid[0] == mid[1] && mid[1] == mid[2]);
    thx_raster_destroy(&img);
    thx_tracer_destroy(&t2);
}

/* The walk in eight lanes (thx_raytrace_volume_rays, what a picture's eye rays take) against the
 * one-ray walk (thx_raytrace_volume_ray), ray by ray: a cube of 6^3 cells (1,296 tetrahedra), a
 * field that varies across it (point data, and constant per tetrahedron), a colour map and an
 * opacity with several points, extinctions from thin (most pieces within one table entry or
 * crossing a few) to thick, 256 rays from a perspective eye, a third of them ending inside the mesh
 * (a surface hit). The closed forms above through the lanes too (eight copies of the ray). */
static void test_volume_lanes(thx_tracer *tr)
{
    enum { N = 6, NN = (N + 1) * (N + 1) * (N + 1), NT = 6 * N * N * N, NR = 256 };
    printf("the volume walk takes %d ray(s) at once on this processor%s\n", thx_raytrace_volume_lanes(),
           thx_raytrace_volume_lanes() == 1 ? " (no AVX2: both walks below are the one-ray walk)" : "");
    static double xyz[3 * NN], pv[NN], cv[NT];
    static int32_t tet[4 * NT];
    shape_cube_grid(N, 5, xyz, tet);
    for (int i = 0; i < NN; i++) {
        const double *p = xyz + 3 * i;
        pv[i] = sin(p[0] / 7) + cos(p[1] / 5) * p[2] / 30;
    }
    for (int t = 0; t < NT; t++) {
        cv[t] = 0;
        for (int k = 0; k < 4; k++) cv[t] += pv[tet[4 * t + k]] / 4;
    }
    static double org[NR][3], dir[NR][3], tfar[NR], rgb[NR][3], T[NR];
    for (int r = 0; r < NR; r++) {
        double eye[3] = {15, -40, 60}, at[3] = {-5 + 40.0 * (r % 16) / 15, -5 + 40.0 * (r / 16) / 15, -5}, len = 0;
        for (int k = 0; k < 3; k++) {
            org[r][k] = eye[k];
            dir[r][k] = at[k] - eye[k];
            len += dir[r][k] * dir[r][k];
        }
        for (int k = 0; k < 3; k++) dir[r][k] /= sqrt(len);
        tfar[r] = r % 3 == 0 ? 60 + 0.17 * r : INFINITY;
    }
    thx_raytrace_volume v;
    memset(&v, 0, sizeof v);
    v.xyz = xyz;
    v.n_nodes = NN;
    v.tet = tet;
    v.n_tets = NT;
    v.cmap = THX_CMAP_JET;
    thx_scale_from_range(&v.scale, THX_SCALE_LINEAR, -1.5, 1.5, 0);
    double op[3][2] = {{0, 0.2}, {0.5, 1}, {1, 0.3}};
    memcpy(v.opacity, op, sizeof op);
    v.n_opacity = 3;
    static const double density[3] = {0.02, 0.3, 5};
    for (int data = 0; data < 2; data++)
        for (int di = 0; di < 3; di++) {
            v.point_values = data == 0 ? pv : NULL;
            v.cell_values = data == 1 ? cv : NULL;
            v.density = density[di];
            CHECK_OK(ctx, thx_raytrace_volume_rays(ctx, tr, &v, NR, (const double(*)[3])org, (const double(*)[3])dir, tfar, rgb, T));
            double worst = 0, Tmin = 1, cmax = 0;
            for (int r = 0; r < NR; r++) {
                double rgb1[3], T1;
                CHECK_OK(ctx, thx_raytrace_volume_ray(ctx, tr, &v, org[r], dir[r], 0, tfar[r], rgb1, &T1));
                for (int k = 0; k < 3; k++) {
                    worst = fmax(worst, fabs(rgb[r][k] - rgb1[k]));
                    cmax = fmax(cmax, rgb1[k]);
                }
                worst = fmax(worst, fabs(T[r] - T1));
                Tmin = fmin(Tmin, T1);
            }
            printf("lanes against one ray, %s data, density %g per mm (transmittance down to %.3g, colour up to %.3f): "
                   "largest difference %.2g\n", data ? "cell" : "point", v.density, Tmin, cmax, worst);
            CHECK(cmax > 0.05 && worst <= 1e-5); /* float rounding over a ray: 400 times below a grey level */
        }
    /* the closed forms through the lanes: the constant field in one tetrahedron */
    double o8[8][3], d8[8][3], f8[8];
    const_tet_volume(&v, 0.1);
    for (int r = 0; r < 8; r++) {
        o8[r][0] = 2, o8[r][1] = 2, o8[r][2] = -5;
        d8[r][0] = 0, d8[r][1] = 0, d8[r][2] = 1;
        f8[r] = INFINITY;
    }
    double rgb8[8][3], T8[8];
    CHECK_OK(ctx, thx_raytrace_volume_rays(ctx, tr, &v, 8, (const double(*)[3])o8, (const double(*)[3])d8, f8, rgb8, T8));
    double eT = exp(-0.1 * 6), eC = 0.5 * (1 - eT);
    printf("constant field in a tetrahedron through the lanes: transmittance %.12f (exact %.12f), colour %.12f (exact %.12f)\n",
           T8[7], eT, rgb8[7][0], eC);
    for (int r = 0; r < 8; r++) {
        CHECK_NEAR(T8[r], eT, 1e-6);
        CHECK_NEAR(rgb8[r][0], eC, 1e-6);
    }
}

/* The environment: rays leaving the scene upward see its top row, downward its bottom row. */
static void test_environment(thx_tracer *tr)
{
    thx_raster *env = NULL, *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 8, 4, &env));
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 8; x++) {
            unsigned char *p = env->rgba + 4 * (y * 8 + x);
            p[0] = y < 2 ? 200 : 10;
            p[1] = 20;
            p[2] = y < 2 ? 10 : 220;
            p[3] = 255;
        }
    CHECK_OK(ctx, thx_raster_create(ctx, 16, 16, &img));
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.environment = env;
    for (int up = 0; up < 2; up++) {
        sc.camera = (thx_camera){{0, 0, up ? -100 : 100}, {0, 0, 0}, {0, 1, 0}, 0, 10};
        CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
        const unsigned char *p = img->rgba + 4 * (8 * 16 + 8);
        printf("environment, looking %s: %d %d %d\n", up ? "up" : "down", p[0], p[1], p[2]);
        CHECK(up ? p[0] == 200 && p[2] == 10 : p[0] == 10 && p[2] == 220);
    }
    thx_raster_destroy(&env);
    thx_raster_destroy(&img);
}

/* The position along row y where lum crosses level going from x0 towards x1 (linear between pixel
 * centres; -1 none). */
static double crossing(const thx_raster *img, int y, int x0, int x1, double level)
{
    int step = x1 > x0 ? 1 : -1;
    for (int x = x0; x != x1; x += step) {
        double a = lum(img, x, y), b = lum(img, x + step, y);
        if ((a - level) * (b - level) <= 0 && a != b) return x + 0.5 + step * (level - a) / (b - a);
    }
    return -1;
}

static void test_motion_blur(thx_tracer *tr)
{
    /* a 40 mm square facing an orthographic camera looking down, 0.5 mm pixels; the next frame's
       camera 10 mm further along +x (the screen's right): the square moves 20 pixels left */
    const int N = 200;
    const double H = 100, MOVE = 10, mm = H / N, move_px = MOVE / mm;
    double o[3] = {-20, -20, 0}, u[3] = {40, 0, 0}, v[3] = {0, 40, 0};
    thx_surface *sq = rect("square", o, u, v);
    double val0[4] = {0, 0, 0, 0}, val1[4] = {1, 1, 1, 1};
    thx_render_surface rs[1], rn[1];
    memset(rs, 0, sizeof rs);
    rs[0].surf = sq;
    rs[0].mode = THX_DRAW_FLAT;
    rs[0].color[0] = rs[0].color[1] = rs[0].color[2] = rs[0].color[3] = 1;
    thx_scene sc, nx;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = 1;
    camera_down(&sc, H);
    sc.clear = 1;
    sc.background[3] = 1;
    nx = sc;
    rn[0] = rs[0];
    nx.surfaces = rn;
    nx.camera.eye[0] += MOVE;
    nx.camera.center[0] += MOVE;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 16; /* 256 samples a pixel, 256 strata of the shutter */
    thx_raster *still = NULL, *blur = NULL, *zero = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &still));
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &blur));
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &zero));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, still, NULL));
    to.next = &nx;
    to.shutter = 0;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, zero, NULL));
    CHECK(!memcmp(still->rgba, zero->rgba, 4 * (size_t)N * N)); /* shutter 0: the picture of this frame */
    to.shutter = 1;
    thx_raytrace_stats st;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, blur, &st));
    keep(still, "blur_still.png");
    keep(blur, "blur_square.png");
    CHECK(st.builds == 0);
    /* the centre row: the still square's edges, the blurred left edge's 10 % and 90 % crossings (a
       linear ramp over the move: the width is their distance / 0.8), and the right edge likewise */
    int yc = N / 2;
    double top = lum(still, N / 2, yc), bg = lum(still, 2, yc);
    double lo = bg + 0.1 * (top - bg), hi = bg + 0.9 * (top - bg), mid = 0.5 * (top + bg);
    double still_l = crossing(still, yc, N / 2, 0, mid), still_r = crossing(still, yc, N / 2, N - 1, mid);
    double l10 = crossing(blur, yc, 0, N / 2, lo), l90 = crossing(blur, yc, 0, N / 2, hi);
    double r90 = crossing(blur, yc, N - 1, N / 2, hi), r10 = crossing(blur, yc, N - 1, N / 2, lo);
    double wl = (l90 - l10) / 0.8, wr = (r90 - r10) / -0.8;
    printf("motion blur: camera moved %g mm = %g pixels; still edges at %.2f and %.2f px, blurred edges %.2f and %.2f px "
           "wide (10-90 %%: %.2f..%.2f, %.2f..%.2f)\n", MOVE, move_px, still_l, still_r, wl, wr, l10, l90, r90, r10);
    CHECK(fabs(wl - move_px) <= 1 && fabs(wr - move_px) <= 1);
    /* the ramps run from the still edges towards the left, where the square goes */
    CHECK(fabs(0.5 * (l10 + l90) - (still_l - move_px / 2)) <= 1);
    CHECK(fabs(0.5 * (r10 + r90) - (still_r - move_px / 2)) <= 1);
    CHECK(fabs(lum(blur, N / 2, yc) - top) < 1); /* the middle covered all the time */
    /* the same bytes on 1 and 2 threads */
    to.samples = 3;
    omp_set_num_threads(1);
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, blur, NULL));
    omp_set_num_threads(2);
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, zero, NULL));
    CHECK(!memcmp(blur->rgba, zero->rgba, 4 * (size_t)N * N));

    /* values 0 at this frame, 1 at the next, the camera still: the square's colour is the colour
       map's mean over [0, 1]. Lit by the ambient term alone (1; a light from behind), so a pixel's
       colour is the map's. */
    rs[0].values = val0;
    rn[0].values = val1;
    rs[0].cmap = rn[0].cmap = THX_CMAP_VIRIDIS;
    thx_scale_from_range_mapped(&rs[0].scale, THX_SCALE_LINEAR, THX_MAPPING_TRUE, 0, 1);
    rn[0].scale = rs[0].scale;
    nx.camera = sc.camera;
    to.samples = 16;
    to.ambient = 1;
    to.n_lights = 1;
    to.lights[0] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .dir = {0, 0, 1}, .intensity = 1};
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, blur, NULL));
    keep(blur, "blur_values.png");
    double ref[3] = {0, 0, 0}, got[3] = {0, 0, 0};
    const int M = 100000;
    for (int i = 0; i < M; i++) {
        unsigned char c[3];
        thx_colormap_eval(THX_CMAP_VIRIDIS, (i + 0.5) / M, c);
        for (int k = 0; k < 3; k++) ref[k] += c[k] / (double)M;
    }
    size_t n = 0;
    for (int y = N / 2 - 30; y < N / 2 + 30; y++) /* inside the square */
        for (int x = N / 2 - 30; x < N / 2 + 30; x++, n++)
            for (int k = 0; k < 3; k++) got[k] += blur->rgba[4 * ((size_t)y * N + x) + k];
    double worst = 0;
    for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(got[k] / n - ref[k]));
    unsigned char c0[3];
    thx_colormap_eval(THX_CMAP_VIRIDIS, 0, c0);
    printf("motion blur of values 0 -> 1: mean colour %.2f %.2f %.2f, viridis' mean over [0, 1] %.2f %.2f %.2f (%.2f levels "
           "apart; the still frame's %d %d %d)\n", got[0] / n, got[1] / n, got[2] / n, ref[0], ref[1], ref[2], worst, c0[0],
           c0[1], c0[2]);
    CHECK(worst <= 2);
    to.shutter = 0;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, zero, NULL));
    const unsigned char *p = zero->rgba + 4 * ((size_t)(N / 2) * N + N / 2);
    CHECK(p[0] == c0[0] && p[1] == c0[1] && p[2] == c0[2]);
    /* refused: a next frame with other surfaces, a shutter outside 0..1 */
    to.shutter = 1.5;
    CHECK(thx_raytrace_scene(ctx, tr, &sc, &to, zero, NULL) == THX_EINPUT);
    to.shutter = 1;
    nx.n_surfaces = 0;
    CHECK(thx_raytrace_scene(ctx, tr, &sc, &to, zero, NULL) == THX_EINPUT);
    printf("refused: %s\n", thx_ctx_message(ctx));
    thx_raster_destroy(&still);
    thx_raster_destroy(&blur);
    thx_raster_destroy(&zero);
    thx_surface_destroy(&sq);
}

/* An image plane seen face-on, nearest texels: each pixel shows the texel the geometry puts under its
 * centre (texel (a, b) covers origin + [a, a + 1] / w u + [b, b + 1] / h v), unlit, exactly; a texel of
 * alpha below 128 shows what is behind it (the same pixel as the picture without the plane); the id
 * image names the plane where it is drawn. */
static void test_plane(thx_tracer *tr)
{
    enum { TW = 8, TH = 6, W = 240, H = 180 }; /* 10 mm texels, 0.5 mm pixels */
    unsigned char tex[4 * TW * TH];
    for (int b = 0; b < TH; b++)
        for (int a = 0; a < TW; a++) {
            unsigned char *q = tex + 4 * (b * TW + a);
            q[0] = (unsigned char)(20 + 30 * a);
            q[1] = (unsigned char)(15 + 40 * b);
            q[2] = (a + b) & 1 ? 230 : 40;
            q[3] = a == b ? 100 : (a + 2 == b ? 127 : (a == b + 3 ? 128 : 255)); /* 100 and 127: not drawn */
        }
    thx_render_plane pl = {.w = TW, .h = TH, .rgba = tex, .origin = {-40, -30, 5}, .u = {80, 0, 0}, .v = {0, 60, 0}, .nearest = 1};
    double o[3] = {-100, -100, -10}, u[3] = {200, 0, 0}, v[3] = {0, 200, 0};
    thx_surface *floor_ = rect("floor", o, u, v);
    thx_render_surface rs;
    memset(&rs, 0, sizeof rs);
    rs.surf = floor_;
    rs.mode = THX_DRAW_FLAT;
    rs.color[0] = 0.2f;
    rs.color[1] = 0.5f;
    rs.color[2] = 0.3f;
    rs.color[3] = 1;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = &rs;
    sc.n_surfaces = 1;
    camera_down(&sc, 90);
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    thx_raster *img = NULL, *under = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, W, H, &img));
    CHECK_OK(ctx, thx_raster_create(ctx, W, H, &under));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, under, NULL));
    sc.planes = &pl;
    sc.n_planes = 1;
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
    keep(img, "plane.png");
    int32_t *sid = malloc((size_t)W * H * sizeof *sid), *tid = malloc((size_t)W * H * sizeof *tid);
    CHECK_OK(ctx, thx_raytrace_ids(ctx, tr, &sc, W, H, sid, tid));
    size_t texel_ok = 0, texel_n = 0, behind_ok = 0, behind_n = 0, ids_ok = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double mx = -60 + (x + 0.5) * 0.5, my = 45 - (y + 0.5) * 0.5; /* the pixel centre in the model */
            int a = (int)floor((mx + 40) / 10), b = (int)floor((my + 30) / 10);
            int in = a >= 0 && a < TW && b >= 0 && b < TH, drawn = in && tex[4 * (b * TW + a) + 3] >= 128;
            size_t i = (size_t)y * W + (size_t)x;
            const unsigned char *p = img->rgba + 4 * i, *q = under->rgba + 4 * i;
            if (drawn) {
                const unsigned char *t = tex + 4 * (b * TW + a);
                texel_n++;
                texel_ok += p[0] == t[0] && p[1] == t[1] && p[2] == t[2];
                ids_ok += sid[i] == THX_RAYTRACE_ID_PLANE && tid[i] == 0;
            } else {
                behind_n++;
                behind_ok += !memcmp(p, q, 4);
                ids_ok += sid[i] == 0;
            }
        }
    printf("image plane, %d x %d texels of 10 mm face-on, 0.5 mm pixels: %zu of %zu pixels show their texel exactly, "
           "%zu of %zu (transparent texels and around) what is behind; ids %zu of %d\n",
           TW, TH, texel_ok, texel_n, behind_ok, behind_n, ids_ok, W * H);
    CHECK(texel_n > 0 && texel_ok == texel_n);
    CHECK(behind_n > 0 && behind_ok == behind_n);
    CHECK(ids_ok == (size_t)W * H);
    /* bilinear: at the middle between two texel centres along u, the mean of the two */
    pl.nearest = 0;
    camera_down(&sc, 2);
    sc.camera.eye[0] = sc.camera.center[0] = -20; /* texels (1, 4) and (2, 4): centres x = -25 and -15 */
    sc.camera.eye[1] = sc.camera.center[1] = 15;
    thx_raster *one = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 1, 1, &one));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, one, NULL));
    const unsigned char *t1 = tex + 4 * (4 * TW + 1), *t2 = tex + 4 * (4 * TW + 2);
    printf("bilinear between texels (1, 4) and (2, 4): %d %d %d, their mean %.1f %.1f %.1f\n", one->rgba[0], one->rgba[1],
           one->rgba[2], (t1[0] + t2[0]) / 2.0, (t1[1] + t2[1]) / 2.0, (t1[2] + t2[2]) / 2.0);
    for (int k = 0; k < 3; k++) CHECK(fabs(one->rgba[k] - (t1[k] + t2[k]) / 2.0) <= 0.51);
    free(sid);
    free(tid);
    thx_raster_destroy(&one);
    thx_raster_destroy(&img);
    thx_raster_destroy(&under);
    thx_surface_destroy(&floor_);
}

/* An arrow along +x, 60 mm long, 20 mm over a floor, seen from above (orthographic, 0.25 mm pixels): its
 * pixels span the projected length to a pixel, its shaft is the width asked in pixels and its head
 * the OpenGL renderer's (2 max(0.4 hl, w), hl = min(0.4 length, 4 w + 6)); a directional light down
 * and towards +y casts its shadow on the floor 20 mm along +y, as long as the arrow. */
static void test_arrow(thx_tracer *tr)
{
    enum { N = 401 };
    const double px = 0.25, L = 60, Z = 20, x0 = -30.1, wpx = 6;
    double o[3] = {-100, -100, 0}, u[3] = {200, 0, 0}, v[3] = {0, 200, 0};
    thx_surface *floor_ = rect("floor", o, u, v);
    thx_render_surface rs;
    memset(&rs, 0, sizeof rs);
    rs.surf = floor_;
    rs.mode = THX_DRAW_FLAT;
    double tail[3] = {x0, 0, Z}, vec[3] = {2, 0, 0};
    thx_render_arrows ar;
    memset(&ar, 0, sizeof ar);
    ar.pos = tail;
    ar.vec = vec;
    ar.n = 1;
    ar.scale = L / 2; /* length |v| scale */
    ar.color[0] = 1;
    ar.color[3] = 1;
    ar.width = (float)wpx;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = &rs;
    sc.n_surfaces = 1;
    sc.arrows = &ar;
    sc.n_arrows = 1;
    camera_down(&sc, N * px); /* the middle row and column through the model's axes */
    sc.clear = 1;
    sc.background[3] = 1;
    thx_raytrace_opts to;
    thx_raytrace_opts_default(&to);
    to.samples = 1;
    to.n_lights = 1;
    to.lights[0] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .dir = {0, 1, -1}, .intensity = 1, .shadows = 1};
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, N, N, &img));
    CHECK_OK(ctx, thx_raytrace_scene(ctx, tr, &sc, &to, img, NULL));
    keep(img, "arrow.png");
    int xmin = N, xmax = -1, shaft = 0, head = 0;
    double hl = fmin(0.4 * L, (4 * wpx + 6) * px), r_head = fmax(0.4 * hl, wpx * px);
    /* columns: the shaft's middle (x = 0), and 0.5 mm into the head (its width there 2 r_head (1 - 0.5 / hl)) */
    int xs = N / 2, xh = (int)lround((x0 + L - hl + 0.5 + N * px / 2) / px - 0.5);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            const unsigned char *p = img->rgba + 4 * ((size_t)y * N + (size_t)x);
            if (!(p[0] > p[1] + 40 && p[0] > p[2] + 40)) continue; /* red: the arrow */
            xmin = x < xmin ? x : xmin;
            xmax = x > xmax ? x : xmax;
            shaft += x == xs;
            head += x == xh;
        }
    double ext = (xmax - xmin + 1) * px, head_exp = 2 * r_head * (1 - 0.5 / hl) / px;
    printf("arrow of %.0f mm along +x, %g px wide: its pixels span %.2f mm (pixel %.2f mm); shaft %d px wide, head %d px "
           "0.5 mm from its back (%.1f expected)\n", L, wpx, ext, px, shaft, head, head_exp);
    CHECK(fabs(ext - L) <= px);
    CHECK(abs(shaft - (int)wpx) <= 1);
    CHECK(fabs(head - head_exp) <= 1.5);
    /* the shadow: light along (0, 1, -1) moves it Z along +y; along that row, dark from the tail to the tip */
    int ys = (int)lround((N * px / 2 - Z) / px - 0.5), dmin = N, dmax = -1;
    for (int x = 0; x < N; x++)
        if (lum(img, x, ys) < 80) {
            dmin = x < dmin ? x : dmin;
            dmax = x > dmax ? x : dmax;
        }
    double sh = (dmax - dmin + 1) * px;
    int lit_beside = lum(img, N / 2, ys - 20) > 120 && lum(img, N / 2, ys + 20) > 120;
    printf("its shadow %.0f mm along +y: dark over %.2f mm of the row (x %.2f..%.2f mm), lit 5 mm either side: %s\n", Z, sh,
           (dmin + 0.5) * px - N * px / 2, (dmax + 0.5) * px - N * px / 2, lit_beside ? "yes" : "no");
    CHECK(fabs(sh - L) <= 2 * px);
    CHECK(lit_beside);
    /* the id image: the arrow's index */
    int32_t sid[1], tid[1];
    sc.camera.eye[0] = sc.camera.center[0] = 0;
    sc.camera.height = 0.1;
    CHECK_OK(ctx, thx_raytrace_ids(ctx, tr, &sc, 1, 1, sid, tid));
    CHECK(sid[0] == THX_RAYTRACE_ID_ARROW && tid[0] == 0);
    thx_raster_destroy(&img);
    thx_surface_destroy(&floor_);
}

/* The id image's eye rays in packets of 16 (rtcIntersect16) against one at a time (a clip plane
 * that cuts nothing sends them one by one): the same surface and triangle at every pixel, a sphere
 * before a box from a perspective camera, 203 x 117 pixels (rows not a multiple of 16). */
static void test_ids_packets(thx_tracer *tr)
{
    enum { W = 203, H = 117 };
    thx_surface *ball = sphere(0, 0, 0, 20, 48, 24), *back = box("back", (double[3]){-60, -60, -90}, (double[3]){60, 60, -70});
    thx_render_surface rs[2];
    memset(rs, 0, sizeof rs);
    rs[0].surf = ball;
    rs[1].surf = back;
    rs[0].mode = rs[1].mode = THX_DRAW_PHONG;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.surfaces = rs;
    sc.n_surfaces = 2;
    sc.camera = (thx_camera){{30, 20, 120}, {0, 0, -20}, {0, 1, 0}, 40, 0};
    static int32_t s1[W * H], t1[W * H], s2[W * H], t2[W * H];
    CHECK_OK(ctx, thx_raytrace_ids(ctx, tr, &sc, W, H, s1, t1));
    sc.clip[0] = (thx_clip_plane){{0, 0, 1}, 1000}; /* keeps z >= -1000: everything */
    sc.n_clip = 1;
    CHECK_OK(ctx, thx_raytrace_ids(ctx, tr, &sc, W, H, s2, t2));
    size_t same = 0, ball_px = 0, back_px = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        same += s1[i] == s2[i] && t1[i] == t2[i];
        ball_px += s1[i] == 0;
        back_px += s1[i] == 1;
    }
    printf("id image in packets against one ray at a time: %zu of %d pixels the same (sphere %zu, box %zu)\n", same, W * H, ball_px,
           back_px);
    CHECK(same == (size_t)W * H && ball_px > 1000 && back_px > 1000);
    thx_surface_destroy(&ball);
    thx_surface_destroy(&back);
}

int main(void)
{
    thx_ctx_create(&ctx);
    thx_tracer *tr = NULL;
    CHECK_OK(ctx, thx_tracer_create(ctx, &tr));
    if (tr) {
        printf("%s\n", thx_tracer_info(tr));
        /* THX_TEST_ONLY=NAME: that test alone (e.g. motion_blur under valgrind) */
        const char *only = getenv("THX_TEST_ONLY");
#define RUN(name) if (!only || !strcmp(only, #name)) test_##name(tr)
        RUN(shadow);
        RUN(terminator);
        RUN(mirror);
        RUN(refraction);
        RUN(volume);
        RUN(volume_lanes);
        RUN(environment);
        RUN(motion_blur);
        RUN(plane);
        RUN(arrow);
        RUN(ids_packets);
#undef RUN
    }
    thx_tracer_destroy(&tr);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
