/*
 * Shared pieces of the fuzz harnesses (tests/fuzz/fuzz_*.c).
 *
 * Each harness defines LLVMFuzzerTestOneInput(data, size): it hands the bytes
 * to one reader and, when the reader accepts them, checks a property of what
 * it built (counts within what the file can hold, indices in range, a
 * round trip). A reader may refuse any input; it must never crash, leak,
 * hang, read out of bounds or allocate far beyond the file's size.
 *
 * Built two ways (CMakeLists.txt):
 *  - THORAX_FUZZ=ON with clang: linked with -fsanitize=fuzzer,address,undefined
 *    and run by `make fuzz` (scripts/fuzz.sh) and bench/fuzz.sh;
 *  - every build: linked with tests/fuzz/replay.c into fuzz_replay_NAME, and
 *    ctest replays tests/fuzz/corpus/NAME/ (the seeds and every finding kept
 *    as a regression input) through it.
 *
 * Readers take paths, so the bytes are written to a file in a private
 * temporary directory (fuzz_file), named with the extension the reader
 * dispatches on.
 */
#ifndef THORAX_TESTS_FUZZ_H
#define THORAX_TESTS_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/core.h"
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The process's scratch directory (created on first use, removed at exit). */
const char *fuzz_dir(void);

/* Writes data to fuzz_dir()/name and returns that path (static storage,
 * valid until the next call); aborts on an I/O failure (the harness, not
 * the reader, is broken then). */
const char *fuzz_file(const char *name, const uint8_t *data, size_t size);

/* A context for one input (destroy it after); messages are dropped. */
thx_ctx *fuzz_ctx(void);

/* Stops the run with a message: a property of an accepted input failed. */
#define FUZZ_ASSERT(cond)                                                                                    \
    do {                                                                                                     \
        if (!(cond)) {                                                                                       \
            fprintf(stderr, "%s:%d: fuzz property failed: %s\n", __FILE__, __LINE__, #cond);                 \
            abort();                                                                                         \
        }                                                                                                    \
    } while (0)

#endif
