/* src/raytrace/rt_impl.h — what the ray tracer's files share (private to src/raytrace). */
#ifndef THORAX_RT_IMPL_H
#define THORAX_RT_IMPL_H

#include <embree3/rtcore.h>
#include <stdint.h>

#include "thorax/raytrace/raytrace.h"

/* A surface's geometry as Embree holds it, kept across calls while the surface is the same. */
typedef struct {
    const thx_surface *surf;        /* the key: the surface, */
    const double *xyz;              /* its arrays and sizes as they were at the build */
    const int32_t *tri;
    size_t n_nodes, n_tris;
    RTCGeometry geom;
    float *nrm;                     /* per-node normals (area-weighted), 3 n_nodes */
    unsigned long used;             /* the call that last used it */
} rt_geom;

/* One scene surface during a call: its cache entry, its colours' inputs, its material. */
typedef struct {
    const thx_render_surface *rs;
    const rt_geom *g;
    float *t;                       /* per-node t = scale(value) (NULL: no data) */
    float *t_next;                  /* motion blur: the next frame's t (NULL: the values do not move) */
    float color[4];
    thx_raytrace_material mat;
    double transmit;                /* mat.transmit, or 1 - alpha */
    int no_clip;
} rt_surf;

/* A volume mesh as the volume renderer walks it (rt_volume.c): kept across calls while (xyz, tet)
 * stay the same. */
typedef struct {
    const double *xyz;
    const int32_t *tet;
    size_t n_nodes, n_tets;
    int32_t *nbr;                   /* 4 n_tets: the tetrahedron across face k (opposite vertex k), -1 none */
    int32_t *nbr_face;              /* ... and that face's number in it */
    int32_t *bface;                 /* boundary face (Embree primitive) -> tet * 4 + k */
    double *plane;                  /* 16 n_tets: per tetrahedron the 4 barycentric coordinates as a . p + b */
    size_t n_bface;
    RTCScene scene;                 /* the boundary faces */
    size_t builds;
} rt_vmesh;

/* The transfer function: 256 entries over t in [0, 1]. */
typedef struct {
    double c[256][3];
    double tau[256];                /* extinction per mm */
} rt_tf;

/* A call's frame: what the shading reads. */
typedef struct {
    const thx_scene *sc;
    const thx_raytrace_opts *o;
    RTCScene scene;
    rt_surf *s;                     /* by Embree geometry ID (= the scene surface's index) */
    size_t n_s;
    double eye[3], view[3], right[3], up[3]; /* camera frame; view: the line of sight */
    int ortho;
    double back;                    /* orthographic: eye rays start this far behind the eye's plane */
    double pixel_mm;                /* orthographic: a pixel's size; perspective: per mm of distance */
    float bg[4], nan_color[4];
    int any_clip;
    thx_light lights[THX_RAYTRACE_MAX_LIGHTS]; /* the options' lights, camera-relative ones turned into the model's axes */
    const rt_vmesh *vm;             /* the volume rendered (NULL none), its transfer function, its t per node */
    const rt_tf *tf;
    const double *tnode;
    /* motion blur (o->next and o->shutter > 0; else next is NULL): the camera of the sample being
       traced (cam; without blur the scene's), the scene's box (where orthographic eye rays start),
       the samples a pixel and the stride of their times' strata */
    thx_camera cam;
    const thx_scene *next;
    double shutter;
    int n_samples, tau_stride;
    double box_lo[3], box_hi[3];
} rt_frame;

thx_status rt_vmesh_build(thx_ctx *ctx, RTCDevice dev, const thx_raytrace_volume *v, rt_vmesh *m);
void rt_vmesh_free(rt_vmesh *m);
void rt_tf_build(const thx_raytrace_volume *v, rt_tf *tf);
/* The volume integral from tnear to tfar: rgb (premultiplied) and the transmittance *T left. */
void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const double *tnode, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays);
/* Point data: the scale applied to each node's value (malloc'd; NULL for cell data or no memory). */
double *rt_volume_tnode(thx_ctx *ctx, const thx_raytrace_volume *v);
/* The tracer's volume mesh for v, built when new (raytrace.c). */
thx_status rt_tracer_vmesh(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v);
const rt_vmesh *rt_tracer_vmesh_get(const thx_tracer *t);

/* A random number in [0, 1) from a hash of the four keys (deterministic). */
double rt_rand(uint32_t a, uint32_t b, uint32_t c, uint32_t d);

/* A sample's time in the shutter interval [0, shutter) (0 without motion blur): the pixel's n
 * samples take the n strata of the interval, sample k stratum (k stride + offset) mod n (the offset a
 * hash of the pixel, the stride coprime with n so that time and place in the pixel do not go
 * together), jittered within it by a hash of (pixel, sample). */
static inline double rt_tau(const rt_frame *f, uint32_t px, uint32_t sample)
{
    if (!f->next) return 0;
    uint32_t n = (uint32_t)f->n_samples, off = (uint32_t)(rt_rand(px, 0, 0, 4) * n);
    uint32_t k = (sample * (uint32_t)f->tau_stride + off) % n;
    return f->shutter * (k + rt_rand(px, sample, 0, 3)) / n;
}

/* The colour along a ray (rt_shade.c): rgb, and *alpha the coverage (0 where the ray meets only the
 * background). weight: what the ray's colour counts for in the pixel (1 for an eye ray; branches
 * below 1/256 are not traced). px, sample: the random keys. *rays counts the rays traced. */
void rt_shade(const rt_frame *f, const double org[3], const double dir[3], int depth, double weight, uint32_t px,
              uint32_t sample, double rgb[3], double *alpha, double *thit, size_t *rays);

/* What a ray that leaves the scene sees along dir: the environment image, the sky, or the
 * background colour. */
void rt_environment(const rt_frame *f, const double dir[3], double rgb[3]);

/* The nearest hit along the ray beyond tnear that the clip planes keep: 1 and the hit in *rh; 0
 * none. */
int rt_intersect(const rt_frame *f, const double org[3], const double dir[3], double tnear, double tfar,
                 struct RTCRayHit *rh, size_t *rays);
#endif
