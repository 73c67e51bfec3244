/* Vectors (thorax/core/vec.h). */
#include "thorax/core/vec.h"

#include <math.h>

double thx_v3_norm(thx_vec3 a) { return sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
