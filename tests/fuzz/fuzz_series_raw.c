/*
 * Fuzz harness: a time series read as raw (thx_series_read, THX_SERIES_RAW).
 * Properties of an accepted series: series_fuzz.h (at most size / 8 values
 * for a file of `size` bytes, a finite increasing time axis, round trips).
 */
#include "series_fuzz.h"

static size_t max_values(size_t size) { return size / 8; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    series_fuzz_one(data, size, "s.raw", THX_SERIES_RAW, max_values);
    return 0;
}
