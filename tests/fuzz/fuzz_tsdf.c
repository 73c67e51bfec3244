/*
 * Fuzz harness: a time series read as map3d graphicsio .tsdf (thx_series_read, THX_SERIES_TSDF).
 * Properties of an accepted series: series_fuzz.h (every value takes at least 2 bytes of the file,
 * 16-bit integers; a finite increasing time axis; round trips through text, raw and .mat).
 */
#include "series_fuzz.h"

static size_t max_values(size_t size) { return size / 2; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    series_fuzz_one(data, size, "s.tsdf", THX_SERIES_TSDF, max_values);
    return 0;
}
