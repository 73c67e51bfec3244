/*
 * thorax/core/vec.h — 2D and 3D points and vectors (millimetres), with inline helpers.
 */
#ifndef THORAX_CORE_VEC_H
#define THORAX_CORE_VEC_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct { double x, y; } thx_vec2;
typedef struct { double x, y, z; } thx_vec3;

/* Vector helpers (inline, no context). */
static inline thx_vec3 thx_v3(double x, double y, double z) { thx_vec3 v = {x, y, z}; return v; }
static inline thx_vec3 thx_v3_sub(thx_vec3 a, thx_vec3 b) { return thx_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline thx_vec3 thx_v3_add(thx_vec3 a, thx_vec3 b) { return thx_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline thx_vec3 thx_v3_scale(thx_vec3 a, double s) { return thx_v3(a.x * s, a.y * s, a.z * s); }
static inline double thx_v3_dot(thx_vec3 a, thx_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline thx_vec3 thx_v3_cross(thx_vec3 a, thx_vec3 b)
{
    return thx_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
double thx_v3_norm(thx_vec3 a);

#ifdef __cplusplus
}
#endif
#endif
