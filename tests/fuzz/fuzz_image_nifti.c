/* Fuzz harness: an image read by its nifti reader (thx_image_read on a file named s.nii); properties in
 * image_fuzz.h (within what the file can hold, valid, the same back through thorax's .nii writer). */
#include "image_fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    image_fuzz_one(data, size, "s.nii", ".nii");
    return 0;
}
