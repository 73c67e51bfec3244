/*
 * Fuzz harness: a time series read as mat (thx_series_read, THX_SERIES_MAT).
 * Properties of an accepted series: series_fuzz.h (at most size + (1032 size + 4096) / 8 values
 * for a file of `size` bytes, a finite increasing time axis, round trips).
 */
#include "series_fuzz.h"

/* uncompressed: one value per stored byte at most; zlib-compressed: 8 bytes of doubles per value within
 * 1032 times the compressed bytes (series_mat.c) */
static size_t max_values(size_t size) { return size + (1032 * size + 4096) / 8; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    series_fuzz_one(data, size, "s.mat", THX_SERIES_MAT, max_values);
    return 0;
}
