/* Fuzz harness: map3d graphicsio .geom (thx_surface_read_file, then thx_surface_import; properties in
 * fuzz_import.h: no more nodes or triangles than the file has bytes, indices in range). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_surface(data, size, "s.geom", THX_IMPORT_GEOM);
    return 0;
}
