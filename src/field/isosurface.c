/* Equipotential surfaces (paper 4.3; thorax/field/field.h): marching tetrahedra on one frame's
 * volume potentials, several values in one pass over the tetrahedra (cut.c). */
#include <math.h>

#include "field_impl.h"

thx_status thx_field_isosurface(thx_ctx *ctx, const thx_volume *v, const double *phi, const double *values,
                                size_t n_values, const unsigned char *use_region, thx_field_mesh *out)
{
    if (!v || !phi || !out || (n_values && !values))
        return thx_error(ctx, THX_EINTERNAL, "thx_field_isosurface: missing volume, potentials, values or output");
    return field_cut(ctx, v, phi, values, n_values, 0, phi, 1, use_region, "potential", out);
}
