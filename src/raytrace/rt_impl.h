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

/* Four floats as one SSE register (GCC's and Clang's vector extension): a transfer function's
 * colour and extinction (r, g, b, tau) travel together, and a tetrahedron's four faces are tested
 * at once. */
typedef float rt_v4f __attribute__((vector_size(16)));
typedef int32_t rt_v4i __attribute__((vector_size(16)));

/* A tetrahedron as the volume renderer walks it, in one 64-byte cache line: three of its four
 * barycentric coordinates as affine functions (lambda_k(p) = a_k . p + b_k, 1 at vertex k, 0 on the
 * face opposite it; lambda_3 = 1 - lambda_0 - lambda_1 - lambda_2) stored lane by lane, q[0] = (a_0x,
 * a_1x, a_2x, .), q[1] the y components, q[2] the z, q[3] = (b_0, b_1, b_2, .), so that one vector
 * operation serves the four faces; the fourth lanes hold the neighbours across faces 0..3 (each as
 * its tetrahedron * 4 + its number of that face; -1 the mesh's boundary): RT_TET_NB(T, k). */
typedef union {
    rt_v4f q[4];
    float f[16];
    int32_t i[16];
} rt_tet;
#define RT_TET_NB(T, k) ((T)->i[4 * (k) + 3])

/* An image plane during a call (rt_glyphs.c): the inverse of its edges' Gram matrix (g11 g12; g12
 * g22)^-1 as (a, b, c) = ((a b; b c)), which takes a point's dot products with u and v to its place
 * (s, t) in [0, 1]^2 on the rectangle. */
typedef struct {
    const thx_render_plane *pl;
    double gi[3];
} rt_plane;

/* One thx_render_arrows during a call (rt_glyphs.c): the glyphs of the arrows drawn, RT_ARROW_TRIS
 * triangles each, in order; per arrow its colour and its index in the input. */
#define RT_ARROW_TRIS 60
typedef struct {
    const thx_render_arrows *a;
    size_t n;                       /* arrows drawn */
    int32_t *index;                 /* n: the arrow's index in a->pos */
    float (*color)[4];              /* n: rgba */
    float *nrm;                     /* per vertex normals */
    const unsigned *ib;             /* the triangles (Embree's buffer) */
} rt_arrows;

/* A volume mesh as the volume renderer walks it (rt_volume.c): kept across calls while (xyz, tet)
 * stay the same. */
typedef struct {
    const double *xyz;
    const int32_t *tet;
    size_t n_nodes, n_tets;
    rt_tet *tets;                   /* n_tets, in the walk's order (64-byte aligned) */
    int32_t *order;                 /* the walk's tetrahedron i is the mesh's order[i] (a Morton order of
                                       their centres: a ray's next tetrahedra, and its neighbour rays',
                                       near in memory) */
    int32_t *bface;                 /* boundary face (Embree primitive) -> tet * 4 + k */
    size_t n_bface;
    RTCScene scene;                 /* the boundary faces */
    float *fld;                     /* the call's field (rt_volume_field): 4 floats a tetrahedron, kept
                                       with the mesh so that a frame step allocates nothing */
    size_t builds;
} rt_vmesh;

/* The transfer function: 256 entries over t in [0, 1], each (r, g, b, tau) with tau the extinction
 * per mm, and each entry's step to the next (d[255] zero), so that its value between entries is one
 * vector multiply-add. */
typedef struct {
    rt_v4f v[256];
    rt_v4f d[256];
} rt_tf;

/* A call's frame: what the shading reads. */
typedef struct {
    const thx_scene *sc;
    const thx_raytrace_opts *o;
    RTCScene scene;
    rt_surf *s;                     /* Embree geometry IDs: 0 .. n_s - 1 the scene's surfaces, */
    size_t n_s;
    RTCScene planes;                /* n_s .. n_s + n_pl - 1 its image planes (a scene of their own), */
    rt_plane *pl;
    size_t n_pl;
    rt_arrows *ar;                  /* then its arrow sets (in scene, with the surfaces) */
    size_t n_ar;
    double eye[3], view[3], right[3], up[3]; /* camera frame; view: the line of sight */
    int ortho;
    double back;                    /* orthographic: eye rays start this far behind the eye's plane */
    int vp_h;                       /* the viewport's rows */
    double aspect;                  /* the viewport's width over its height */
    double half_w, half_h;          /* the view's half extents: perspective tan(fov/2) times the aspect
                                       and tan(fov/2); orthographic in mm (eye rays, primary_ray) */
    double pixel_mm;                /* orthographic: a pixel's size; perspective: per mm of distance */
    float bg[4], nan_color[4];
    int any_clip;
    thx_light lights[THX_RAYTRACE_MAX_LIGHTS]; /* the options' lights, camera-relative ones turned into the model's axes */
    const rt_vmesh *vm;             /* the volume rendered (NULL none), its transfer function, its t per node */
    const rt_tf *tf;
    const float *fld;               /* the frame's field per tetrahedron (rt_volume_field) */
    /* motion blur (o->next and o->shutter > 0; else next is NULL): the camera of the sample being
       traced (cam; without blur the scene's), the scene's box (where orthographic eye rays start),
       the samples a pixel and the stride of their times' strata */
    thx_camera cam;
    const thx_scene *next;
    double shutter;
    int n_samples, tau_stride;
    double box_lo[3], box_hi[3];
} rt_frame;

/* What an Embree geometry ID names (rt_frame): RT_SURFACE, RT_PLANE or RT_ARROWS, and *k its index
 * among them. */
enum { RT_SURFACE, RT_PLANE, RT_ARROWS };
static inline int rt_kind(const rt_frame *f, unsigned id, size_t *k)
{
    if (id < f->n_s) { *k = id; return RT_SURFACE; }
    if (id < f->n_s + f->n_pl) { *k = id - f->n_s; return RT_PLANE; }
    *k = id - f->n_s - f->n_pl;
    return RT_ARROWS;
}

/* rt_glyphs.c: the scene's image planes into f->planes, its arrows' glyphs into f->scene (before
 * its commit; f's camera frame and pixel size set; the scene's arrays checked by frame_build); freed by
 * rt_glyphs_free. */
thx_status rt_planes_build(thx_ctx *ctx, RTCDevice dev, rt_frame *f);
thx_status rt_arrows_build(thx_ctx *ctx, RTCDevice dev, rt_frame *f);
void rt_glyphs_free(rt_frame *f);
/* The plane's colour at point pt on it (rgb may be NULL): 1 where its texel is drawn (alpha at least
 * 1/2), 0 where it is transparent. */
int rt_plane_texel(const rt_plane *p, const double pt[3], double rgb[3]);
/* At a hit (prim, u, v) on an arrow set: the shading normal, the colour (rgba), *index the arrow's
 * index in its input (may be NULL). */
void rt_arrow_hit(const rt_arrows *r, unsigned prim, double u, double v, double n[3], double color[4], int32_t *index);

thx_status rt_vmesh_build(thx_ctx *ctx, RTCDevice dev, const thx_raytrace_volume *v, rt_vmesh *m);
void rt_vmesh_free(rt_vmesh *m);
void rt_tf_build(const thx_raytrace_volume *v, rt_tf *tf);
/* The volume integral from tnear to tfar: rgb (premultiplied) and the transmittance *T left. */
void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays);
/* The same for n rays from tnear 0 (o, d, tfar, rgb and T: n each), eight at a time in AVX2's lanes
 * where the processor has them (rt_volume_lanes.c). */
void rt_volume_march_n(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, int n,
                       const double (*o)[3], const double (*d)[3], const double *tfar, double (*rgb)[3], double *T, size_t *rays);
/* The frame's field as the walk reads it, into m->fld (returned; NULL when out of memory): per
 * tetrahedron t = scale(value) as g . p + c (4 floats: g, c; point data: the linear interpolant of
 * the corners' scaled values, as the OpenGL renderer interpolates a surface's; cell data: g = 0). */
float *rt_volume_field(thx_ctx *ctx, rt_vmesh *m, const thx_raytrace_volume *v);
/* The tracer's volume mesh for v, built when new (raytrace.c). */
thx_status rt_tracer_vmesh(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v);
rt_vmesh *rt_tracer_vmesh_get(thx_tracer *t);

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
/* The same for an eye ray whose first Embree hit in f->scene (from 0 to infinity) is already known
 * (a packet of eye rays traced together): first, counted in *rays here. Only for a frame without
 * image planes; a hit the clip planes may cut is looked for again. */
void rt_shade_first(const rt_frame *f, const double org[3], const double dir[3], const struct RTCRayHit *first, uint32_t px,
                    uint32_t sample, double rgb[3], double *alpha, double *thit, size_t *rays);

/* What a ray that leaves the scene sees along dir: the environment image, the sky, or the
 * background colour. */
void rt_environment(const rt_frame *f, const double dir[3], double rgb[3]);

/* One Embree ray through scene sc from tnear to tfar (float, all geometry, robust as the scene is). */
void rt_ray_once(RTCScene sc, const double org[3], const double dir[3], double tnear, double tfar, struct RTCRayHit *rh);

/* The nearest hit along the ray beyond tnear that the clip planes keep: 1 and the hit in *rh; 0
 * none. */
int rt_intersect(const rt_frame *f, const double org[3], const double dir[3], double tnear, double tfar,
                 struct RTCRayHit *rh, size_t *rays);
#endif
