/* Fuzz harness: Wavefront OBJ (thx_surface_read_file, then thx_surface_import; properties in fuzz_import.h). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_surface(data, size, "s.obj", THX_IMPORT_OBJ);
    return 0;
}
