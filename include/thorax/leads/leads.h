/*
 * thorax/leads/leads.h — signals at electrodes and the 12-lead ECG from potentials on a surface
 * (paper 4.1: potentials on the body).
 */
#ifndef THORAX_LEADS_LEADS_H
#define THORAX_LEADS_LEADS_H

#include "thorax/model/electrodes.h"
#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Signals at the electrodes: rows = electrodes, from a series on their surface (rows = its nodes).
 * An electrode between nodes (placed, thx_electrodes_place) takes the weighted sum of its
 * triangle's node rows; NaN in a row it reads gives NaN. */
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
