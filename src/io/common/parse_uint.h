/*
 * The one integer parser of the time series and electrode readers
 * (src/io/series*.c, electrodes.c): a count, a size or a node number in a
 * file. Decimal digits only (no sign, no blank, no "0x", no exponent), the
 * whole token; overflow-safe: every digit is checked against `max` before it
 * is added, so a value of any length is refused, never wrapped, and strtol's
 * errno and LONG_MAX cases do not arise.
 */
#ifndef THORAX_IO_PARSE_UINT_H
#define THORAX_IO_PARSE_UINT_H

#include <stddef.h>
#include <stdint.h>

/* Parses t[0..n-1] (n = 0: up to the NUL) as an unsigned decimal <= max.
 * Returns 0 and sets *out, or -1 (empty, a non-digit, or above max). */
static inline int thx_parse_uint(const char *t, size_t n, uint64_t max, uint64_t *out)
{
    if (!t) return -1;
    if (n == 0)
        while (t[n]) n++;
    if (n == 0) return -1;
    uint64_t v = 0;
    for (size_t i = 0; i < n; i++) {
        if (t[i] < '0' || t[i] > '9') return -1;
        unsigned d = (unsigned)(t[i] - '0');
        if (v > (max - d) / 10) return -1;
        v = 10 * v + d;
    }
    *out = v;
    return 0;
}

#endif
