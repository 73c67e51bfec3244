/*
 * thorax/inverse/inverse.h — regularized inverse solutions: heart-surface potentials from
 * body-surface potentials through a transfer matrix (paper 4.1: the inverse problem, "ill-posed").
 *
 * The problem: find x (heart nodes) with A x ≈ b (A: the transfer matrix, rows the body-surface
 * nodes or electrodes, columns the heart nodes; b: one frame of the data), for every frame.
 *
 * Methods (docs/decisions.md, "The inverse problem"):
 *   Tikhonov order 0, 1, 2   min ||A x - b||² + λ² ||L x||², L = I, the surface gradient or the
 *                            surface Laplacian on the heart mesh (thx_inverse_operator). Orders 1
 *                            and 2 are brought to standard form (Eldén's A-weighted pseudo-inverse of
 *                            L, L's null space: the constants), so one SVD of the transformed matrix
 *                            gives every λ at once: the GSVD's filter factors without dggsvd3.
 *   TSVD                     the first k singular components; the rules pick k.
 *   Greensite                the data's temporal SVD: the leading temporal components solved with
 *                            Tikhonov order 0 as if they were frames, recombined with their time
 *                            courses.
 *   total variation          min ||A x - b||² + λ² Σ_t area_t |∇x|_t, iteratively reweighted least
 *                            squares on the gradient-Tikhonov system, λ from the order-1 rule.
 * λ rules: the L-curve's corner (maximum curvature of (log ||Ax-b||, log ||Lx||)), CRESO (the first
 * local maximum of C(λ) = ||Lx||² + 2λ² d||Lx||²/dλ² met coming down from λ = s_1), GCV (minimum of
 * ||Ax-b||² / (m - p0 - Σ f_i)², p0 the dimension of L's null space: the trace of I minus the
 * influence matrix, docs/design/inverse.md), the discrepancy principle (||Ax-b|| = sqrt(m) σ, σ the noise's
 * standard deviation per row), or a fixed value; per frame or one λ for the whole series (the
 * curves summed over frames: the series as one long vector).
 *
 * Invariants: matrices column-major; the solution's rows are A's columns in order; nothing here
 * prints or writes but thx_inverse_write_svg.
 */
#ifndef THORAX_INVERSE_INVERSE_H
#define THORAX_INVERSE_INVERSE_H

#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/model/series.h"
#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_INVERSE_TIKHONOV0 = 0,
    THX_INVERSE_TIKHONOV1,
    THX_INVERSE_TIKHONOV2,
    THX_INVERSE_TSVD,
    THX_INVERSE_GREENSITE,
    THX_INVERSE_TV
} thx_inverse_method;

typedef enum {
    THX_LAMBDA_LCURVE = 0,
    THX_LAMBDA_CRESO,
    THX_LAMBDA_GCV,
    THX_LAMBDA_DISCREPANCY,
    THX_LAMBDA_FIXED
} thx_lambda_rule;

const char *thx_inverse_method_name(thx_inverse_method m);
const char *thx_lambda_rule_name(thx_lambda_rule r);

/* What a rule says of the λ it picked (thx_inverse_report.flags, per frame; bits) */
enum {
    THX_LAMBDA_AT_LOW = 1,     /* at the small end of the search range (s_min of the nonzero singular values;
                                  TSVD: every nonzero component kept; discrepancy: the target out of reach below) */
    THX_LAMBDA_AT_HIGH = 2,    /* at the large end (s_1; TSVD: one component; discrepancy: out of reach above) */
    THX_LAMBDA_NO_CORNER = 4,  /* the rule's feature is not there: an L-curve with no positive curvature, CRESO
                                  with no local maximum */
    THX_LAMBDA_BELOW_NOISE = 8 /* λ per frame: the frame's data below the noise level (||b||² < 2 m σ²); the
                                  series' λ used instead of the frame's own (unless opts.no_fallback) */
};

typedef struct {
    thx_inverse_method method;
    thx_lambda_rule rule;
    double lambda;        /* THX_LAMBDA_FIXED: λ (TSVD: components with s_i > λ are kept) */
    int per_series;       /* 1: one λ for the whole series; 0: λ per frame */
    double noise;         /* discrepancy: noise standard deviation per row, data units (0: use snr_db) */
    double snr_db;        /* when noise == 0: signal-to-noise ratio in dB against the whole series' RMS
                             (σ = rms(B) 10^(-snr/20), the same σ for every frame) */
    int greensite_rank;   /* temporal components kept (0: by the noise level if given, else 99.99% energy) */
    int tv_iterations;    /* IRLS iterations (default 10) */
    int n_grid;           /* λ grid points for the rules (default 100, log-spaced; then golden section) */
    int no_fallback;      /* λ per frame: keep each frame's own λ on frames below the noise level */
    const char *matrix_name, *data_name, *heart_name; /* names for messages (file names) */
} thx_inverse_opts;

void thx_inverse_opts_default(thx_inverse_opts *o);

/* Per-frame figures and the series' L-curve, filled by thx_inverse_solve (all arrays owned;
 * thx_inverse_report_free releases them). */
#define THX_INVERSE_FRAME_CURVES 48

typedef struct {
    size_t n_frames;
    double *lambda;        /* λ used per frame (TSVD: the truncation threshold s_k; Greensite: NaN) */
    int *k;                /* TSVD: components kept per frame (else 0) */
    double *residual;      /* ||A x - b|| per frame */
    double *seminorm;      /* ||L x|| per frame (order 0, TSVD, Greensite: ||x||; TV: Σ area |∇x|) */
    size_t n_components;   /* Greensite: temporal components kept, with their λ */
    double *component_lambda;
    size_t n_curve;        /* the series' L-curve (summed over frames, as a series λ rule sees it) */
    double *curve_lambda, *curve_residual, *curve_seminorm;
    double corner_lambda;  /* the curve's maximum-curvature λ */
    double chosen_lambda;  /* the series' λ, or the median of the frames' λ */
    /* What the L-curve picture marks (thorax/picture/lcurve_plot.h). One λ for the series
     * (mark_frame = -1): the summed curve above, the series' λ on it. A λ per frame: the curve of
     * the representative frame mark_frame (0-based), the frame whose data has the largest norm
     * ||b|| (the peak of the beat; Greensite: the first temporal component), and that frame's own
     * λ on it. The point is the solution's own (||A x - b||, ||L x||) at that λ (TV: the order-1
     * solution it starts from, on the order-1 curve); the corner is that curve's maximum-curvature
     * λ and its point. */
    long mark_frame;
    double mark_lambda, mark_residual, mark_seminorm;
    double mark_corner_lambda, mark_corner_residual, mark_corner_seminorm;
    /* A λ per frame: the L-curves of up to THX_INVERSE_FRAME_CURVES frames spread evenly over the
     * series (the first and the last among them) and of mark_frame when it is not one of those
     * (so at most THX_INVERSE_FRAME_CURVES + 1; ascending), each at curve_lambda's n_curve points:
     * curve j at frame_curve_residual[j * n_curve ..]. None for one λ per series. */
    size_t n_frame_curves;
    size_t *frame_curve_frame;
    double *frame_curve_residual, *frame_curve_seminorm;
    size_t rank;           /* singular values of the (transformed) matrix, largest first */
    double *sv;
    double noise_sigma;    /* σ used by the discrepancy rule (first frame's, per frame) */
    int *flags;            /* per frame: THX_LAMBDA_AT_LOW | ... of the λ used (the frame's own rule's, or with
                              THX_LAMBDA_BELOW_NOISE and the fallback the series'; Greensite: 0) */
    int series_flags;      /* the same of the series' λ (one λ per series, or the fallback's) */
    double series_lambda;  /* λ per frame: the series' λ by the same rule (the fallback), else NaN */
    double frame_noise;    /* λ per frame: the σ that tells the frames below the noise (given, or the series'
                              GCV estimate ||Ax-b||²/trace(I-H) per row); 0: none */
    int frame_noise_estimated; /* 1: frame_noise estimated by GCV, 0: from --noise */
    size_t n_fallback;     /* frames whose λ is the series' (THX_LAMBDA_BELOW_NOISE and the fallback on) */
    size_t null_dim;       /* dimension of the regularization operator's null space (orders 1, 2, TV: 1) */
    double t_svd, t_frames; /* seconds: standard form + SVD; everything per frame */
    char note[256];        /* a remark for the report (e.g. discrepancy target out of reach) */
} thx_inverse_report;

void thx_inverse_report_free(thx_inverse_report *r);

/*
 * The Tikhonov matrix M = L^T L (n x n, column-major, new array the caller frees) of the heart
 * surface (n = heart->n_nodes): order 1: the gradient of the piecewise-linear potential,
 * ∫ |∇x|² = x^T M x (the cotangent stiffness matrix); order 2: the Laplacian D^-1 K (D the lumped
 * mass, area/3 per corner), weighted by the mass: M = K D^-1 K. Both vanish on constants.
 * Errors: a degenerate triangle (zero area), named.
 */
thx_status thx_inverse_operator(thx_ctx *ctx, const thx_surface *heart, int order, double **M);

/*
 * Solves A X ≈ B for every frame. A: the transfer matrix (rows x heart nodes), B: the data
 * (rows x frames); heart: the surface whose nodes are A's columns (needed for orders 1, 2 and TV;
 * NULL otherwise). *X: a new series (A's columns x B's frames, B's time axis and unit).
 * Errors, each naming the file (o->matrix_name, o->data_name): sizes that disagree, NaN or Inf in
 * A (row, column) or B (row, frame), a heart surface whose node count is not A's columns, a rule
 * a method cannot use (CRESO with TSVD), LAPACK failing.
 */
thx_status thx_inverse_solve(thx_ctx *ctx, const thx_series *A, const thx_series *B, const thx_surface *heart,
                             const thx_inverse_opts *o, thx_series **X, thx_inverse_report *r);

/*
 * Building blocks (the tests check them against independent computations).
 * Filter factors of singular values s[0..k-1] at λ: Tikhonov s²/(s²+λ²), TSVD 1 if s > λ else 0.
 */
void thx_inverse_filter(const double *s, size_t k, double lambda, int tsvd, double *f);

/* The λ a rule picks from the spectral data of one right-hand side (or a series summed):
 * s[k] the nonzero singular values (decreasing; the numerically zero ones left out, their β² in
 * perp2), beta2[k] = (u_i^T b)² summed over the frames concerned, perp2 = the part of ||b||² outside
 * the span of those u_i, dof = GCV's degrees of freedom at λ → ∞: rows minus the dimension of the
 * regularization operator's null space (trace(I - H) = dof - Σ f_i), target = the discrepancy's
 * residual norm. Tikhonov (tsvd = 0) or TSVD (tsvd = 1, λ = s_k, *kept = k). Returns the λ (and
 * *kept for TSVD); *flags (may be NULL) the THX_LAMBDA_AT_LOW ... bits. */
double thx_inverse_pick(const double *s, const double *beta2, size_t k, double perp2, double dof, thx_lambda_rule rule,
                        double fixed, double target, int tsvd, int n_grid, int *kept, int *flags);

/* Correlation coefficient and relative error ||x - t|| / ||t|| of two vectors of n values. */
void thx_inverse_compare(const double *x, const double *t, size_t n, double *cc, double *re);

/* Writes the report's L-curve as an SVG picture (log-log axes, the corner and the chosen λ
 * marked), atomically. */
thx_status thx_inverse_write_svg(thx_ctx *ctx, const thx_inverse_report *r, const char *title, const char *path);

#ifdef __cplusplus
}
#endif
#endif
