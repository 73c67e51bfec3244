/*
 * thorax/electrodes.h — electrodes on the torso surface, ECG leads, and the
 * phantom's sources (paper 4.1: sources in the heart, potentials on the body).
 *
 * An electrode set names nodes of one surface of a model (normally the outer
 * one): each electrode is a surface node, so its signal is that node's row
 * of a surface series. File (docs/formats.md, "Electrodes"): a first line
 * `thorax-electrodes 1`, `surface NAME`, `count N`, then N lines
 * `NAME NODE X Y Z` (NODE 1-based on that surface; X Y Z, mm, its position,
 * checked against the model when one is given), then `end`.
 */
#ifndef THORAX_ELECTRODES_H
#define THORAX_ELECTRODES_H

#include "thorax/model.h"
#include "thorax/series.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char surface[64];   /* the surface the nodes belong to */
    size_t n;
    char (*name)[32];   /* electrode names: "RA", "LA", "LL", "V1".."V6", "A001".. */
    int32_t *node;      /* node on that surface, 0-based */
    double *xyz;        /* 3 n: the node's position, mm */
    char path[512];     /* the file it was read from (thx_electrodes_read; "" otherwise): checks name it */
} thx_electrodes;

thx_status thx_electrodes_create(thx_ctx *ctx, size_t n, thx_electrodes **out);
void thx_electrodes_destroy(thx_electrodes **e);
thx_status thx_electrodes_read(thx_ctx *ctx, const char *path, thx_electrodes **out);
/* Atomic; nothing half-written on failure. */
thx_status thx_electrodes_write(thx_ctx *ctx, const thx_electrodes *e, const char *path);
/* Checks the set against the model: the surface exists, every node is on it, positions agree within
 * 1e-3 mm; errors name the electrode. */
thx_status thx_electrodes_check(thx_ctx *ctx, const thx_electrodes *e, const thx_model *m);

/*
 * The phantom's electrodes on its outer surface (the model built from
 * `thorax phantom` contours): the standard 12-lead positions (RA, LA, LL at
 * the shoulders and the left hip end of the torso as limb-lead proxies, the
 * Mason-Likar convention; V1-V6 at the precordial landmarks: 4th intercostal
 * space either side of the sternum, V4 5th space mid-clavicular, V5 anterior
 * axillary, V6 mid-axillary, all at the height of V4 for V5/V6), each the
 * surface node nearest its landmark; and a body-surface-mapping array of
 * n_array electrodes (default 192: 16 columns evenly around the torso at 12
 * heights over the thorax), named A001...
 */
thx_status thx_phantom_electrodes(thx_ctx *ctx, const thx_model *m, thx_electrodes **leads12, size_t n_array,
                                  thx_electrodes **array);

/*
 * The phantom's epicardial potentials: a current dipole at the centre of
 * the heart, in an unbounded homogeneous medium of conductivity sigma,
 * tracing a vectorcardiographic loop (P, QRS and T loops with physiological
 * timing and amplitudes) sampled every dt ms; potentials in mV at the nodes
 * of the heart surface (rows: the heart surface's nodes in order).
 */
typedef struct {
    size_t n_frames;  /* default 500 (500 ms at 1 ms) */
    double dt_ms;     /* default 1 */
    double sigma;     /* S/m, default 0.2 */
    double peak_mv;   /* largest |potential| on the heart surface over the beat, mV (default 40): sets the
                         dipole's scale */
} thx_beat_opts;

void thx_beat_opts_default(thx_beat_opts *o);
/* The dipole moment at frame f (time f * o->dt_ms; 3 values, RAS) for the default loop shape, in units
 * where |p| = 1 at the QRS peak (o may be NULL: dt 1 ms). thx_phantom_epicardial places it at the centroid
 * of the heart's enclosed volume and multiplies it by the factor (A m) that gives peak_mv; the series'
 * label reports both. */
void thx_beat_dipole(const thx_beat_opts *o, size_t f, double p[3]);
thx_status thx_phantom_epicardial(thx_ctx *ctx, const thx_surface *heart, const thx_beat_opts *o, thx_series **out);

/* Signals at the electrodes: rows = electrodes, from a series on their surface (rows = its nodes). */
thx_status thx_electrodes_sample(thx_ctx *ctx, const thx_electrodes *e, const thx_series *surface, thx_series **out);

/*
 * The 12-lead ECG from a series on the electrodes' surface: rows I, II, III,
 * aVR, aVL, aVF, V1..V6 (the precordial leads against Wilson's central
 * terminal (RA + LA + LL) / 3, the augmented limb leads after Goldberger).
 * The set must hold RA, LA, LL, V1..V6 (by name); an error names what is
 * missing.
 */
thx_status thx_ecg12(thx_ctx *ctx, const thx_electrodes *e, const thx_series *surface, thx_series **out);

#ifdef __cplusplus
}
#endif
#endif
