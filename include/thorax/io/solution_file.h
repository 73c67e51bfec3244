/*
 * thorax/io/solution_file.h — what the volume tools (slices, equipotential surfaces, current
 * streamlines: thorax/field) read of a forward solution (docs/formats.md, "Solutions"): the model
 * solution.json names, with its volume mesh, and the volume potentials (`files.volume`, written by
 * `thorax forward ... --volume`), one row per volume node, one column per frame.
 */
#ifndef THORAX_IO_SOLUTION_FILE_H
#define THORAX_IO_SOLUTION_FILE_H

#include "thorax/core/core.h"
#include "thorax/model/model.h"
#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Reads DIR/solution.json, the model it names (which must have a volume mesh) and the volume
 * potentials. *model and *volume are the caller's (thx_model_destroy, thx_series_destroy); on
 * failure both are NULL and the message names the file: not a thorax solution, no model, a model
 * without a volume mesh, no volume potentials ("run thorax forward ... --volume"), or a series
 * whose rows are not the volume's nodes. model_dir (may be NULL, size model_dir_size) gets the
 * model's directory as solution.json gives it.
 */
thx_status thx_solution_read_volume(thx_ctx *ctx, const char *dir, thx_model **model, thx_series **volume,
                                    char *model_dir, size_t model_dir_size);

/*
 * The regions of v where the solution in DIR holds potentials: use[r] = 1 or 0 for each of the
 * v->n_regions regions. The heart-surface problems ("epicardial", "transfer matrix (epicardial)")
 * prescribe the heart's surface and leave its interior (a region named "heart") out of the solve:
 * its nodes carry no solution; dipoles and defibrillation solve the whole conductor. An unknown
 * problem is THX_EINPUT naming the file. (The same rule as thx_forward_* use, src/fem/forward.c.)
 */
thx_status thx_solution_domain(thx_ctx *ctx, const char *dir, const struct thx_volume *v, unsigned char *use);

#ifdef __cplusplus
}
#endif
#endif
