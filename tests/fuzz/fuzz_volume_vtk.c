/* Fuzz harness: a volume mesh as legacy VTK UNSTRUCTURED_GRID, ASCII and BINARY (thx_volume_import; properties in fuzz_import.h). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_volume(data, size, "m.vtk", NULL, THX_VOLFMT_VTK);
    return 0;
}
