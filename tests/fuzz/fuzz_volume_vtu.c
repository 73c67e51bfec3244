/* Fuzz harness: a volume mesh as VTK XML UnstructuredGrid (ascii, base64, appended raw or base64, zlib) (thx_volume_import; properties in fuzz_import.h). */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_volume(data, size, "m.vtu", NULL, THX_VOLFMT_VTU);
    return 0;
}
