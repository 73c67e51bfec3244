/*
 * thorax/check/verdict.h — a volume check's verdict kept in the model (docs/design/parallel.md,
 * "The volume read once, its check verdict kept"). The volume check of a 1.8-million-tetrahedron
 * mesh takes 3 s, and every solver runs it before it solves. `thorax mesh` checks the mesh it makes
 * before writing it; it then records the verdict in model.json:
 *
 *   "volume": { ..., "check": {"passed": true, "rules": R, "options": "default", "sha256": HEX} }
 *
 * HEX is the SHA-256 of what a solver reads of the model: model.json without this "check" member
 * (as cJSON prints it unformatted) and the bytes of every file model.json names for the surfaces
 * and the volume (NAME.pts, NAME.fac, NAME.vmap, volume.pts, volume.tet, volume.steiner), in that
 * order. R is THX_VOLUME_CHECK_RULES. A solver trusts the verdict, and skips the check, only when
 * all of it holds: passed, these rules, the default options, the same digest. Any change of a
 * byte in those files, of model.json, or of the checker's rules means a check as before. A model
 * read and written again carries the member over as it was (thx_model.volume_check_json): when the
 * files are the same it is still trusted, when anything changed its digest no longer matches and the
 * model is checked again until `mesh` writes a new verdict. `thorax check` never writes into a model.
 */
#ifndef THORAX_CHECK_VERDICT_H
#define THORAX_CHECK_VERDICT_H

#include <stddef.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The version of thx_volume_check's rules: raised whenever a check is added or changed, so that a
 * verdict an older thorax kept is not trusted. */
#define THX_VOLUME_CHECK_RULES 1

/* 1 when dir's model.json holds a verdict a solver may trust (above), 0 when not, with the reason in
 * why ("no verdict", "the files changed since", ...). Reading errors count as "no" with their
 * message in why: the check that follows reports them in its own words. */
int thx_volume_verdict_trusted(thx_ctx *ctx, const char *dir, char *why, size_t why_n);

/* Records a passed verdict in dir's model.json (rewritten atomically, the rest unchanged). Call only
 * after the model written there passed thx_volume_check with the default options. */
thx_status thx_volume_verdict_record(thx_ctx *ctx, const char *dir);

#ifdef __cplusplus
}
#endif
#endif
