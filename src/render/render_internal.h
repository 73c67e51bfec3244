/*
 * Internal to src/render: the camera's matrices (camera.c) for the OpenGL
 * drawing (render.c).
 *
 * Matrices are 4 x 4, column-major (m[col * 4 + row]) as OpenGL takes them,
 * in double until they are handed to a shader. Eye space is OpenGL's: the
 * camera at the origin looking along -z, +y up, +x to the right of the image.
 * The model matrix is the identity: surfaces are drawn in model coordinates
 * (millimetres, RAS).
 */
#ifndef THORAX_RENDER_INTERNAL_H
#define THORAX_RENDER_INTERNAL_H

#include "thorax/render/render.h"
/* The camera's orthonormal frame: right, up and back (from the centre toward the eye). Returns -1
 * when the camera is degenerate (eye at the centre, up along the line of sight, non-finite). */
int cam_frame(const thx_camera *cam, double right[3], double up[3], double back[3]);
/* The view matrix (model to eye space); cam_frame must have succeeded. */
void cam_view_matrix(const thx_camera *cam, double m[16]);
/* The projection for a viewport of the given aspect (w / h) between the depths znear < zfar (eye
 * distances along the line of sight; znear > 0 in perspective, any sign when orthographic). */
void cam_proj_matrix(const thx_camera *cam, double aspect, double znear, double zfar, double m[16]);
/* Depths (distances in front of the eye along the line of sight) that enclose the box lo..hi with a
 * margin; in perspective znear is kept positive and at least zfar / 2000 (24-bit depth buffer). */
void cam_depth_range(const thx_camera *cam, const double lo[3], const double hi[3], double *znear, double *zfar);

#endif
