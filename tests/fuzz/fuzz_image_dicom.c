/* Fuzz harness: DICOM (thx_image_read on one .dcm file: the folder scan, GDCM in the helper program
 * thorax-dicom, the series logic of src/image/dicom.c). An accepted file is one slice whose image
 * passes the invariants; a refused one leaves nothing allocated. GDCM runs in the helper, started by
 * posix_spawn + exec (Debian's build aborts on truncated input): a crash inside GDCM is a refusal
 * here, not a finding, and none of libFuzzer's handlers follow the helper. What is fuzzed is our
 * side: the requests and the checked replies through the socket, the checks, the assembly. In the
 * default campaign of scripts/fuzz.sh. */
#include "fuzz.h"

#include "thorax/image/image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    thx_ctx *ctx = fuzz_ctx();
    const char *p = fuzz_file("s.dcm", data, size);
    thx_image img;
    if (thx_image_read(ctx, p, NULL, &img) == THX_OK) {
        if (img.n[2] != 1 || strcmp(img.format, "dicom") != 0 || strlen(img.sha256) != 64) abort();
        if (thx_image_validate(ctx, &img, p) != THX_OK) abort();
        thx_image_free(&img);
    } else if (img.v) {
        abort();
    }
    thx_ctx_destroy(&ctx);
    return 0;
}
