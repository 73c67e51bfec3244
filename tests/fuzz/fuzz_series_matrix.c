/*
 * Fuzz harness: a plain numeric matrix or CSV in text (thx_series_read, THX_SERIES_MATRIX).
 * Properties of an accepted series: series_fuzz.h (every value takes at least 2 bytes: a digit
 * and a separator; a finite increasing time axis; round trips through text, raw and .mat).
 */
#include "series_fuzz.h"

static size_t max_values(size_t size) { return size / 2 + 1; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    series_fuzz_one(data, size, "s.csv", THX_SERIES_MATRIX, max_values);
    return 0;
}
