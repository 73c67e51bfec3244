/*
 * The phantom's heartbeat (thorax/phantom/phantom.h): one current dipole at the
 * centre of the heart tracing a vectorcardiogram, and the potentials it makes
 * on the epicardium in an unbounded homogeneous medium.
 *
 * The loop. Each wave is a sum of a few smooth "activation fronts": a raised
 * cosine in time (zero outside its support, continuous with its first
 * derivative, rising over h1 ms to its peak at c and falling over h2 ms)
 * times a fixed direction. Overlapping fronts with different directions turn
 * the sum into a loop, as the wavefront's mean direction turns while it
 * crosses the heart. Directions are in the patient's frame, RAS (+x the
 * subject's right, +y anterior, +z cranial), so "left" is -x, "posterior" -y,
 * "inferior" -z. Times in ms from the first frame (docs/decisions.md, "The
 * phantom's beat", gives the sources of every figure):
 *
 *   baseline          0 -  10
 *   P (atria)        10 - 100   right atrium (anterior-inferior) then left
 *                               atrium (leftward-posterior); peak |p| ~ 0.1
 *   PR segment      100 - 150   (PR interval 140 ms)
 *   QRS             150 - 240   90 ms: septum (right-anterior, ~0.12),
 *                               apex and anterior free wall (left-inferior-
 *                               anterior), lateral and posterior free wall
 *                               (left-inferior-posterior; the peak, |p| = 1 at
 *                               42 ms), basal terminal forces (posterior-
 *                               superior-right); counterclockwise seen from
 *                               above; mean axis +49 deg in the frontal plane,
 *                               pointing left, inferior and posterior
 *   ST segment      240 - 310
 *   T               310 - 470   broad and asymmetric (slow rise over 90 ms,
 *                               faster fall over 70 ms), peak |p| ~ 0.31 at
 *                               397 ms, mean axis +51 deg, 25 deg from the QRS
 *   baseline        470 -
 *
 * (heart rate about 90/min: QT 320 ms, Bazett QTc 390 ms), so the default
 * 500 frames at 1 ms hold the whole beat. The QRS fronts are divided by the
 * largest |sum| over the QRS (QRS_NORM, computed once at 1 us steps and
 * checked by tests/test_electrodes.c), so the loop is in relative units with
 * |p| = 1 at the QRS peak; P and T amplitudes are relative to that.
 *
 * The potentials. phi(r) = p . (r - r0) / (4 pi sigma |r - r0|^3) with r, r0
 * in metres, p in A m and sigma in S/m gives volts; times 1000 gives mV. The
 * loop (|p| = 1 at the QRS peak) is multiplied by the dipole moment at the QRS
 * peak, dipole_mam (default 0.016 mA m = 16 uA m: the human heart's equivalent
 * dipole, chosen so that the body-surface ECG has clinical amplitudes, lead II
 * peaking at about 1.5 mV on the phantom; docs/decisions.md, "The phantom's
 * ECG amplitudes"), or, when peak_mv > 0, by the one factor k that makes the
 * largest |phi| over all nodes and frames equal peak_mv. The dipole actually
 * used is reported in the series' label, in mA m. r0 is the centroid of the
 * volume the heart surface encloses (divergence theorem over the triangles),
 * or the mean of its nodes when the surface has no triangles or encloses no
 * positive volume.
 */
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct {
    double c, h1, h2; /* peak time, rise and fall (ms) */
    double amp;       /* peak magnitude (relative units) */
    double dir[3];    /* direction, RAS (normalized when used) */
} front;

/* Atria: right atrium first (anterior, inferior, a little leftward), then
 * the left atrium (leftward, posterior). */
static const front P_WAVE[] = {
    {40.0, 30.0, 30.0, 0.10, {-0.15, 0.35, -0.92}},
    {70.0, 30.0, 30.0, 0.09, {-0.75, -0.45, -0.48}},
};
/* Ventricles: septum (left to right: rightward-anterior), apex and anterior
 * free wall, lateral and posterior free wall, posterobasal region. */
static const front QRS_WAVE[] = {
    {160.0, 10.0, 10.0, 0.12, {0.55, 0.80, -0.05}},
    {182.0, 22.0, 22.0, 0.75, {-0.55, 0.30, -0.78}},
    {200.0, 24.0, 24.0, 0.85, {-0.62, -0.50, -0.60}},
    {225.0, 15.0, 15.0, 0.22, {0.30, -0.80, 0.52}},
};
/* Largest |sum of QRS_WAVE| (at 191.73 ms), so that the QRS peak is |p| = 1. */
#define QRS_NORM 0.9751222099827609
/* Repolarization: one broad, asymmetric front, and a small anterior one a
 * little earlier that opens the loop. */
static const front T_WAVE[] = {
    {400.0, 90.0, 70.0, 0.30, {-0.62, 0.15, -0.77}},
    {385.0, 45.0, 45.0, 0.04, {-0.20, 0.90, -0.10}},
};

/* Raised cosine: 0 outside [c - h1, c + h2], 1 at c, C^1 everywhere. */
static double bump(double t, double c, double h1, double h2)
{
    if (t <= c - h1 || t >= c + h2) return 0.0;
    double h = t < c ? h1 : h2;
    return 0.5 * (1.0 + cos(M_PI * (t - c) / h));
}

static void add_fronts(const front *w, size_t n, double scale, double t, double p[3])
{
    for (size_t i = 0; i < n; i++) {
        double b = bump(t, w[i].c, w[i].h1, w[i].h2);
        if (b == 0.0) continue;
        const double *d = w[i].dir;
        double nd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double a = scale * w[i].amp * b / nd;
        for (int k = 0; k < 3; k++) p[k] += a * d[k];
    }
}

void thx_beat_opts_default(thx_beat_opts *o)
{
    memset(o, 0, sizeof *o);
    o->n_frames = 500;
    o->dt_ms = 1.0;
    o->sigma = 0.2;
    o->peak_mv = 0.0;      /* not given: the dipole moment sets the scale */
    o->dipole_mam = 0.016; /* mA m at the QRS peak (docs/decisions.md) */
}

void thx_beat_dipole(const thx_beat_opts *o, size_t f, double p[3])
{
    double dt = o ? o->dt_ms : 1.0;
    double t = (double)f * dt;
    p[0] = p[1] = p[2] = 0.0;
    add_fronts(P_WAVE, sizeof P_WAVE / sizeof P_WAVE[0], 1.0, t, p);
    add_fronts(QRS_WAVE, sizeof QRS_WAVE / sizeof QRS_WAVE[0], 1.0 / QRS_NORM, t, p);
    add_fronts(T_WAVE, sizeof T_WAVE / sizeof T_WAVE[0], 1.0, t, p);
}

/* The centroid of the enclosed volume (tetrahedra from the bounding-box
 * centre to each triangle), or the mean of the nodes if that volume is not
 * positive. */
static void heart_centre(const thx_surface *s, double r0[3])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            double v = s->xyz[3 * i + k];
            lo[k] = fmin(lo[k], v);
            hi[k] = fmax(hi[k], v);
            mean[k] += v;
        }
    double o[3], vol = 0, m[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        o[k] = 0.5 * (lo[k] + hi[k]);
        mean[k] /= (double)s->n_nodes;
    }
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *tri = s->tri + 3 * t;
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; k++) {
            a[k] = s->xyz[3 * (size_t)tri[0] + k] - o[k];
            b[k] = s->xyz[3 * (size_t)tri[1] + k] - o[k];
            c[k] = s->xyz[3 * (size_t)tri[2] + k] - o[k];
        }
        double v = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                    a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        vol += v;
        for (int k = 0; k < 3; k++) m[k] += v * (a[k] + b[k] + c[k]) / 4.0;
    }
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (s->n_tris && vol > 1e-9 * ext * ext * ext) {
        for (int k = 0; k < 3; k++) r0[k] = o[k] + m[k] / vol;
    } else {
        for (int k = 0; k < 3; k++) r0[k] = mean[k];
    }
}

static thx_status epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_frame *frame, const thx_beat_opts *o,
                             thx_series **out);

thx_status thx_phantom_epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_beat_opts *o, thx_series **out)
{
    thx_frame ras = thx_frame_ras();
    return epicardial(ctx, heart, &ras, o, out);
}

thx_status thx_torso_epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_frame *frame, const thx_beat_opts *o,
                                thx_series **out)
{
    *out = NULL;
    THX_CHECK(thx_frame_require(ctx, frame, "the model", "the dipole's directions"));
    if (!thx_frame_valid(frame)) return thx_error(ctx, THX_EINPUT, "beat: the model's frame is not valid");
    return epicardial(ctx, heart, frame, o, out);
}

/* The dipole's RAS directions (thx_beat_dipole) are carried into the model's axes by the frame (a rotation). */
static thx_status epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_frame *frame, const thx_beat_opts *o,
                             thx_series **out)
{
    *out = NULL;
    thx_beat_opts def;
    if (!o) {
        thx_beat_opts_default(&def);
        o = &def;
    }
    if (!heart || heart->n_nodes == 0)
        return thx_error(ctx, THX_EINPUT, "heart surface \"%s\" has no nodes", heart ? heart->name : "(none)");
    if (o->n_frames == 0) return thx_error(ctx, THX_EINPUT, "beat: n_frames is 0 (at least one frame is needed)");
    if (!(o->dt_ms > 0) || !isfinite(o->dt_ms))
        return thx_error(ctx, THX_EINPUT, "beat: dt %g ms is not a positive time step", o->dt_ms);
    if (!(o->sigma > 0) || !isfinite(o->sigma))
        return thx_error(ctx, THX_EINPUT, "beat: conductivity %g S/m is not positive", o->sigma);
    if (o->peak_mv != 0 && (!(o->peak_mv > 0) || !isfinite(o->peak_mv)))
        return thx_error(ctx, THX_EINPUT, "beat: peak %g mV is not positive", o->peak_mv);
    if (o->peak_mv == 0 && (!(o->dipole_mam > 0) || !isfinite(o->dipole_mam)))
        return thx_error(ctx, THX_EINPUT, "beat: dipole moment %g mA m is not positive", o->dipole_mam);
    for (size_t i = 0; i < 3 * heart->n_tris; i++)
        if (heart->tri[i] < 0 || (size_t)heart->tri[i] >= heart->n_nodes)
            return thx_error(ctx, THX_EINPUT, "heart surface \"%s\": triangle %zu has node %d, out of range 1..%zu",
                             heart->name, i / 3 + 1, (int)heart->tri[i] + 1, heart->n_nodes);
    for (size_t i = 0; i < 3 * heart->n_nodes; i++)
        if (!isfinite(heart->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "heart surface \"%s\": node %zu has a non-finite coordinate", heart->name,
                             i / 3 + 1);
    double r0[3];
    heart_centre(heart, r0);

    size_t N = heart->n_nodes, M = o->n_frames;
    /* per node: the lead field g = (r - r0) / (4 pi sigma |r - r0|^3), so phi = 1000 p . g (mV) */
    thx_series *s = NULL;
    THX_CHECK(thx_series_create(ctx, N, M, &s));
    double *g = thx_malloc(ctx, 3 * N * sizeof *g);
    if (!g) {
        thx_series_destroy(&s);
        return THX_ENOMEM;
    }
    for (size_t r = 0; r < N; r++) {
        double d[3], d2 = 0;
        for (int k = 0; k < 3; k++) {
            d[k] = (heart->xyz[3 * r + k] - r0[k]) * 1e-3; /* mm -> m */
            d2 += d[k] * d[k];
        }
        double dist = sqrt(d2);
        if (!(dist > 1e-9)) { /* within 1 um of the dipole */
            thx_status st = thx_error(ctx, THX_EGEOM,
                                      "heart surface \"%s\": node %zu at (%.6f, %.6f, %.6f) lies on the dipole "
                                      "(the surface's centre), where the potential is infinite",
                                      heart->name, r + 1, heart->xyz[3 * r], heart->xyz[3 * r + 1],
                                      heart->xyz[3 * r + 2]);
            free(g);
            thx_series_destroy(&s);
            return st;
        }
        double c = 1.0 / (4.0 * M_PI * o->sigma * d2 * dist);
        for (int k = 0; k < 3; k++) g[3 * r + k] = d[k] * c;
    }
    double vmax = 0;
    for (size_t f = 0; f < M; f++) {
        double q[3], p[3];
        thx_beat_dipole(o, f, q);
        thx_frame_from_ras(frame, q, p);
        double *v = s->v + f * N;
        for (size_t r = 0; r < N; r++) {
            v[r] = 1000.0 * (p[0] * g[3 * r] + p[1] * g[3 * r + 1] + p[2] * g[3 * r + 2]);
            vmax = fmax(vmax, fabs(v[r]));
        }
        s->time[f] = (double)f * o->dt_ms;
    }
    free(g);
    if (!(vmax > 0)) {
        thx_series_destroy(&s);
        return thx_error(ctx, THX_EINPUT,
                         "beat: the dipole is zero in all %zu frames (0 .. %g ms; the P wave starts at 10 ms, the "
                         "beat ends at 470 ms)",
                         M, (double)(M - 1) * o->dt_ms);
    }
    /* k: the dipole moment in A m at |p| = 1 */
    double k = o->peak_mv > 0 ? o->peak_mv / vmax : o->dipole_mam * 1e-3;
    for (size_t i = 0; i < N * M; i++) s->v[i] *= k;
    /* the time axis must increase strictly: f * dt can stall only for absurd sizes */
    for (size_t f = 1; f < M; f++)
        if (!(s->time[f] > s->time[f - 1])) {
            thx_series_destroy(&s);
            return thx_error(ctx, THX_EINPUT, "beat: %zu frames of %g ms do not give increasing times", M, o->dt_ms);
        }
    snprintf(s->unit, sizeof s->unit, "mV");
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    snprintf(s->label, sizeof s->label,
             "phantom beat: dipole %.4g mA m at QRS peak, at (%.1f, %.1f, %.1f) mm, sigma %g S/m, unbounded", k * 1e3,
             r0[0], r0[1], r0[2], o->sigma);
    *out = s;
    return THX_OK;
}
