/*
 * thorax/model/model.h — a model: the surfaces of one subject, their interior points, its
 * anatomical frame and (once meshed) its tetrahedral volume (model layer; the model directory
 * that holds one on disk is thorax/io/model_dir.h).
 */
#ifndef THORAX_MODEL_MODEL_H
#define THORAX_MODEL_MODEL_H

#include "thorax/model/frame.h"
#include "thorax/model/surface.h"
#include "thorax/model/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_model {
    size_t n_surfaces;
    thx_surface **surf;      /* owned */
    int *has_interior;       /* per surface: 1 if interior[s] is a known interior point */
    thx_vec3 *interior;      /* per surface: a point inside it (for the 4 pi check) */
    char *provenance_json;   /* owned JSON text of the "provenance" object, or NULL */
    struct thx_volume *volume; /* owned tetrahedral mesh with regions (thorax/model/volume.h), or NULL */
    thx_frame frame;         /* which model axes point superior and anterior (thorax/model/frame.h);
                                .set = 0: unknown (a command that needs anatomy refuses the model) */
    char *edit_log;          /* owned text of the edit log the surfaces went through (thorax/edit/edit.h;
                                the model directory's edits.txt, named in the provenance), or NULL: the
                                surfaces are as built or imported. Opaque text to the model and io layers. */
    char *volume_check_json; /* owned JSON text of model.json's "volume"."check" (the volume check's verdict,
                                thorax/check/verdict.h) as read, written back as it was; NULL: none. The verdict
                                names the SHA-256 of the files it covers, so one carried over to a changed model
                                is simply not trusted. */
} thx_model;

thx_status thx_model_create(thx_ctx *ctx, thx_model **out);
/* Frees the model and its surfaces; accepts NULL; nulls *m. */
void thx_model_destroy(thx_model **m);
/* Appends a surface; the model takes ownership of *s (and nulls *s) even on failure. */
thx_status thx_model_add_surface(thx_ctx *ctx, thx_model *m, thx_surface **s);

/* Checks m->volume (must be non-NULL) against the model before anything is written or exported:
 * arrays present, finite coordinates, node numbers in range and distinct per tetrahedron, region
 * numbers in range, region table valid (names, symmetric positive definite tensors), node tables
 * consistent with the surfaces, Steiner records in range. Geometry (orientation, quality) is the
 * volume checker's (thorax/check/check_volume.h). `where` prefixes the messages (a path or
 * "volume"). */
thx_status thx_model_volume_validate(thx_ctx *ctx, const thx_model *m, const char *where);

#ifdef __cplusplus
}
#endif
#endif
