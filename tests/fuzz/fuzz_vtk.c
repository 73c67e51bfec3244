/* Fuzz harness: legacy VTK POLYDATA, ASCII and BINARY, classic cells and 5.1 OFFSETS/CONNECTIVITY (thx_surface_read_file, then thx_surface_import; properties in fuzz_import.h). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_surface(data, size, "s.vtk", THX_IMPORT_VTK);
    return 0;
}
