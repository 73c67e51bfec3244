/* Fuzz harness: an image read by its metaimage reader (thx_image_read on a file named s.mha); properties in
 * image_fuzz.h (within what the file can hold, valid, the same back through thorax's .mha writer). */
#include "image_fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    image_fuzz_one(data, size, "s.mha", ".mha");
    return 0;
}
