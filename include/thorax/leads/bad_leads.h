/*
 * thorax/leads/bad_leads.h — bad leads of a recording: flat, saturated, duplicated and outlying
 * channels found, written to and read from a bad-lead list, and filled in from their neighbours on
 * a surface by Laplacian interpolation (leads layer; `thorax series check`, `--bad-leads`;
 * docs/design/leads.md "Reliability, round 2", docs/formats.md "Bad-lead lists").
 *
 * Rows are a series' rows (0-based in memory); a list names them 1-based as "channels": the
 * recording's rows, whatever channel map (thorax/model/channels.h) later moves them onto nodes.
 *
 * The checks (thx_bad_leads_detect), each on the row's values over the frames, centred on the
 * row's mean (x_i = v_i - mean v_i; rms_i = sqrt(mean x_i^2)); a row holding a NaN or an infinite
 * value is "missing": neither checked nor used to check others.
 *   flat        peak-to-peak 0, or rms_i <= flat * the median rms of the rows
 *   saturated   at least `saturated` of the frames (a fraction), and at least
 *               THX_BAD_SATURATED_MIN frames, hold exactly the row's largest value, or exactly its
 *               smallest (an amplifier or converter at its limit; the count keeps a short series,
 *               Dalhousie's 6 dipole maps, from calling 2 equal values of 6 a plateau)
 *   duplicated  d_ij = rms(x_i - x_j) / max(rms_i, rms_j), the pair's difference against the
 *               larger of the two. Without a surface: d_ij <= duplicate_exact (a copy). With a
 *               surface: i and j are not neighbours, d_ij <= duplicate and d_ij <= duplicate_contrast
 *               * min(c_i, c_j), c_i = the smallest d_ik over i's neighbours k: two distant leads
 *               alike while each is unlike the leads around it; of such a pair, a row whose neighbours'
 *               mean predicts it (the unlike score below <= 1) is taken for the original and kept
 *               (without a surface both rows of a pair are flagged). (Adjacent leads on a smooth body
 *               surface field are near copies of each other: the Utah tank's 146 and 147 have
 *               d = 0.031; hence no looser test without a surface.)
 * With a surface (rows = its nodes; neighbours = the nodes sharing a triangle edge, missing and
 * already flagged rows left out), for a row with at least 2 neighbours, m_i = their mean:
 *   unlike      rms(x_i - (m_i - mean m_i)) / rms_i > unlike: the neighbours' mean predicts the
 *               row worse than zero would by that factor (a dead lead among live ones)
 *   small/large rms_i / median over the neighbours of rms_k < small, or > large
 * The neighbour checks are repeated, flagging the one row of largest excess (the largest of
 * unlike score / unlike, small / ratio, ratio / large) at a time and leaving it out of its
 * neighbours' means, until no row exceeds a threshold: one dead lead does not pull a live
 * neighbour over a threshold.
 * The correlation of x_i with its neighbours' centred mean is reported but is not a criterion:
 * on the epicardium the field changes sign over a few millimetres (the Utah sock's channel 194,
 * 1.6 times its neighbours' RMS, correlates -0.67 with their mean).
 */
#ifndef THORAX_LEADS_BAD_LEADS_H
#define THORAX_LEADS_BAD_LEADS_H

#include <stdint.h>

#include "thorax/model/series.h"
#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The fewest frames a series must have to be checked: over the six frames of the Dalhousie torso's
 * dipole maps (map3d's dipole2), unrelated nodes 11 and 139 differ by d = 0.005 and nodes near a
 * nodal line look dead; over its 96-frame record (p2_3200_77) nothing is flagged. */
#define THX_BAD_MIN_FRAMES 20

/* The fewest frames at an extreme that make a plateau. */
#define THX_BAD_SATURATED_MIN 5

/* Why a row is bad (bits of thx_bad_leads.flags). */
enum {
    THX_BAD_FLAT = 1u << 0,
    THX_BAD_SATURATED = 1u << 1,
    THX_BAD_DUPLICATE = 1u << 2,
    THX_BAD_UNLIKE = 1u << 3, /* unlike its neighbours */
    THX_BAD_SMALL = 1u << 4,  /* much smaller than its neighbours */
    THX_BAD_LARGE = 1u << 5,  /* much larger than its neighbours */
    THX_BAD_LISTED = 1u << 6  /* named by a bad-lead list (thx_bad_list_read) */
};

typedef struct {
    double flat;               /* 0.01: rms <= this * the median rms */
    double saturated;          /* 0.10: fraction of the frames at the row's extreme value */
    double duplicate_exact;    /* 0.01: d without a surface */
    double duplicate;          /* 0.20: d with a surface ... */
    double duplicate_contrast; /* 0.25: ... and d <= this * the pair's closeness to their neighbours */
    double unlike;             /* 2.5: residual against the neighbours' mean / rms */
    double small, large;       /* 0.2, 5: rms / the neighbours' median rms */
} thx_bad_leads_opts;

/* Fills the defaults listed above. */
void thx_bad_leads_opts_default(thx_bad_leads_opts *o);

/* What the checks found, per row (arrays of n; NaN or -1 where a score was not computed). */
typedef struct {
    size_t n;
    unsigned *flags;     /* THX_BAD_* bits; 0 = good */
    int *missing;        /* 1: the row holds a NaN or infinite value (not checked) */
    double *rms;         /* rms_i, the series' unit */
    double *extreme;     /* the larger fraction of frames at the row's largest or smallest value */
    int32_t *nearest;    /* the row most alike (smallest d), -1 */
    double *d;           /* d to it */
    double *contrast;    /* d / min(c_i, c_j) (with a surface) */
    int32_t *twin;       /* the row it duplicates (flag THX_BAD_DUPLICATE), else -1 */
    double *unlike;      /* the unlike score (with a surface) */
    double *ratio;       /* rms_i / the neighbours' median rms (with a surface) */
    double *corr;        /* correlation with the neighbours' mean (with a surface; reported only) */
    int32_t *n_nb;       /* neighbours used (with a surface) */
    double median_rms;   /* over the rows that are not missing */
    size_t n_bad, n_missing;
} thx_bad_leads;

/*
 * Checks every row of s (at least THX_BAD_MIN_FRAMES frames). surf: NULL, or the surface whose nodes the rows are
 * (n_nodes == n_rows; the neighbour checks). o: NULL for the defaults. Deterministic; the
 * duplicate search compares only rows whose rms are within the tolerance of each other.
 * Errors: THX_EINPUT for fewer than THX_BAD_MIN_FRAMES frames, a row count that is not the surface's node count,
 * thresholds out of range. Caller destroys *out.
 */
thx_status thx_bad_leads_detect(thx_ctx *ctx, const thx_series *s, const thx_surface *surf,
                                const thx_bad_leads_opts *o, thx_bad_leads **out);
void thx_bad_leads_destroy(thx_bad_leads **b);

/* Why row i is bad, in words, with its scores ("duplicate of channel 308 (d 0.046); unlike its
 * neighbours (7.8)"), rows named as channel[row] (1-based; NULL: row + 1). "" for a good row. */
void thx_bad_leads_reason(const thx_bad_leads *b, size_t i, const int *channel, char *buf, size_t cap);

/*
 * Bad-lead list (docs/formats.md): text; '#' starts a comment; blank lines skipped; every other
 * line is a channel number (1-based, the recording's row) and, after blanks, optional free text
 * (the reason). A channel twice, a number < 1, more than max_channel (0: no limit) or a word that
 * is not a number is an error naming file:line. *channels: the n channels, 0-based, increasing
 * (caller frees); n may be 0.
 */
thx_status thx_bad_list_read(thx_ctx *ctx, const char *path, size_t max_channel, int32_t **channels, size_t *n);
/*
 * Writes the bad rows of b as a list (atomically; the file starts "# thorax bad-lead list"):
 * a comment line `note` (may be NULL), then "CHANNEL  REASON" per bad row, in channel order,
 * channels channel[row] (1-based; NULL: row + 1).
 */
thx_status thx_bad_list_write(thx_ctx *ctx, const char *path, const thx_bad_leads *b, const int *channel,
                              const char *note);

/*
 * The rows of s that spec names bad (bad[i] = 1, n_rows of them; *n_bad counted): spec "auto" runs
 * thx_bad_leads_detect (on surf when not NULL), else spec is a bad-lead list's path. channel: the
 * 1-based channel of each row (0 = none; NULL: row + 1): a list names channels. A listed channel
 * no row has is logged and ignored. Logs the bad channels (INFO) and each reason (DEBUG).
 */
thx_status thx_bad_leads_mark(thx_ctx *ctx, const char *spec, const thx_series *s, const thx_surface *surf,
                              const int *channel, unsigned char *bad, size_t *n_bad);
/* thx_bad_leads_mark, then thx_bad_leads_interpolate of those rows on surf (rows = its nodes). */
thx_status thx_bad_leads_fill(thx_ctx *ctx, const char *spec, const thx_surface *surf, const int *channel, thx_series *s);

/*
 * Laplacian interpolation on a triangulated surface (Oostendorp, van Oosterom and Huiskamp 1989,
 * as map3d fills its bad leads): the values of the rows with fill[i] != 0 are replaced, frame by
 * frame, by those minimising || L u ||^2 over all nodes with the other rows fixed, L the discrete
 * surface Laplacian (Huiskamp 1991): (L u)_i = 4 / (hbar_i n_i) sum_j (u_j - u_i) / h_ij over
 * the n_i neighbours j of node i (edge lengths h_ij, their mean hbar_i). The minimiser solves
 * (L_B^T L_B) u_B = -L_B^T L_G u_G (B the filled nodes, G the others), a small dense SPD system
 * factored once for all frames. A NaN in a known row of a frame gives NaN to the rows it reaches
 * in that frame.
 * Rows = surf's nodes. Errors: THX_EINPUT for a row count that is not the node count, or a
 * filled node whose connected group of filled nodes touches no kept node (nothing to fill it
 * from: the message names it, 1-based); THX_EGEOM for an edge of zero length.
 */
thx_status thx_bad_leads_interpolate(thx_ctx *ctx, const thx_surface *surf, thx_series *s, const unsigned char *fill);

#ifdef __cplusplus
}
#endif
#endif
