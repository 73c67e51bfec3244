/*
 * Fuzz harness: dipole files (thx_dipoles_read: OpenMEEG's .dip and thorax-dipoles). Properties of
 * an accepted input:
 *  - at least one dipole and one frame, within what the bytes can hold (a .dip line takes at least
 *    11 bytes, "0 0 0 0 0 0" less its newline; a thorax-dipoles position 5, a frame 2 + 6 per dipole);
 *  - every position, moment and time finite, times increasing, line numbers in the file;
 *  - the .dip layout: n frames for n dipoles, frame k zero but for dipole k.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/io/dipoles_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("in.dip", data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_dipoles *d = NULL;
    if (thx_dipoles_read(ctx, path, &d) == THX_OK) {
        FUZZ_ASSERT(d && d->n >= 1 && d->n_frames >= 1);
        size_t lines = 1;
        for (size_t i = 0; i < size; i++) lines += data[i] == '\n';
        if (d->separate) {
            FUZZ_ASSERT(d->n_frames == d->n && 11 * d->n <= size + 1);
        } else {
            FUZZ_ASSERT(5 * d->n + d->n_frames * (2 + 6 * d->n) <= size + 1);
        }
        for (size_t i = 0; i < 3 * d->n; i++) FUZZ_ASSERT(isfinite(d->pos[i]));
        for (size_t i = 0; i < d->n; i++) FUZZ_ASSERT(d->line[i] >= 1 && d->line[i] <= lines);
        for (size_t f = 0; f < d->n_frames; f++) {
            FUZZ_ASSERT(isfinite(d->time[f]) && (f == 0 || d->time[f] > d->time[f - 1]));
            FUZZ_ASSERT(d->frame_line[f] >= 1 && d->frame_line[f] <= lines);
            for (size_t k = 0; k < 3 * d->n; k++) {
                double q = d->moment[3 * d->n * f + k];
                FUZZ_ASSERT(isfinite(q));
                if (d->separate && k / 3 != f) FUZZ_ASSERT(q == 0);
            }
        }
    } else {
        FUZZ_ASSERT(d == NULL);
    }
    thx_dipoles_destroy(&d);
    thx_ctx_destroy(&ctx);
    return 0;
}
