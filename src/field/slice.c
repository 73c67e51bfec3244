/* Slices (paper 4.3, "arbitrary slicing"; thorax/field/field.h): the volume cut exactly by planes.
 * A plane n.x = d is the level set s = d of the node scalar s = n.x, cut by the same marching
 * tetrahedra as an equipotential surface (cut.c), with the potential interpolated along each cut
 * edge. For a plane normal to an axis s is that coordinate itself, so a plane through a layer of
 * nodes is met exactly (and the rule "a node at the value is above it" applies to it). */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "field_impl.h"

double thx_field_slice_scale(const thx_volume *v)
{
    double scale = 0;
    for (size_t i = 0; i < 3 * v->n_nodes; i++) scale = fmax(scale, fabs(v->xyz[i]));
    return scale;
}

thx_status thx_field_slice(thx_ctx *ctx, const thx_volume *v, const double *phi, const thx_field_plane *planes,
                           size_t n_planes, const unsigned char *use_region, thx_field_mesh *out)
{
    if (!v) return thx_error(ctx, THX_EINTERNAL, "thx_field_slice: missing volume");
    return thx_field_slice_scaled(ctx, v, phi, planes, n_planes, use_region, thx_field_slice_scale(v), out);
}

thx_status thx_field_slice_scaled(thx_ctx *ctx, const thx_volume *v, const double *phi, const thx_field_plane *planes,
                                  size_t n_planes, const unsigned char *use_region, double scale, thx_field_mesh *out)
{
    if (!v || !out || (n_planes && !planes))
        return thx_error(ctx, THX_EINTERNAL, "thx_field_slice: missing volume, planes or output");
    double *s = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *s);
    if (!s) return THX_ENOMEM;
    thx_status st = THX_OK;
    for (size_t k = 0; k < n_planes && st == THX_OK; k++) {
        const double *n = planes[k].n;
        int axis = -1;
        for (int i = 0; i < 3; i++)
            if (n[i] == 1 && n[(i + 1) % 3] == 0 && n[(i + 2) % 3] == 0) axis = i;
        for (size_t i = 0; i < v->n_nodes; i++) {
            const double *x = v->xyz + 3 * i;
            s[i] = axis >= 0 ? x[axis] : n[0] * x[0] + n[1] * x[1] + n[2] * x[2];
        }
        if (axis < 0) {
            double tol = 16 * DBL_EPSILON * fmax(scale, fabs(planes[k].d));
            for (size_t i = 0; i < v->n_nodes; i++)
                if (fabs(s[i] - planes[k].d) <= tol) s[i] = planes[k].d;
        }
        st = field_cut(ctx, v, s, &planes[k].d, 1, (int32_t)k, phi, 0, use_region, "coordinate", out);
    }
    free(s);
    return st;
}
