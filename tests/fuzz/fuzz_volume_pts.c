/* Fuzz harness: a volume mesh as .pts + .tet or .elem, plain or CARP (thx_volume_import;
 * properties in fuzz_import.h). The first byte chooses the element file's name ('e': m.elem,
 * else m.tet), the rest up to the first NUL byte is m.pts, what follows it the element file. */
#include "fuzz_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0;
    fuzz_volume(data + 1, size - 1, "m.pts", data[0] == 'e' ? "m.elem" : "m.tet", THX_VOLFMT_PTS);
    return 0;
}
