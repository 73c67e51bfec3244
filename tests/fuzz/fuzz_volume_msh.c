/* Fuzz harness: a volume mesh as Gmsh MSH (4.1 read, 2.x and others refused) (thx_volume_import; properties in fuzz_import.h). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_volume(data, size, "m.msh", NULL, THX_VOLFMT_MSH);
    return 0;
}
