/*
 * thorax/core/sha256.h — SHA-256 (FIPS 180-4) of bytes in memory or of a file: the content hash
 * that ties a model and an edit log to the contour file they came from (docs/formats.md, "Edit
 * logs"). The hex form is what `sha256sum` prints, so a user can check it by hand.
 */
#ifndef THORAX_CORE_SHA256_H
#define THORAX_CORE_SHA256_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Incremental hashing: init, update any number of times, final. Plain data, no allocation. */
typedef struct {
    uint32_t h[8];
    uint64_t n;            /* bytes hashed so far */
    unsigned char buf[64]; /* the block being filled (n % 64 bytes of it) */
} thx_sha256_ctx;

void thx_sha256_init(thx_sha256_ctx *s);
void thx_sha256_update(thx_sha256_ctx *s, const void *data, size_t n);
/* Writes the 32-byte digest; s must be initialised again before reuse. */
void thx_sha256_final(thx_sha256_ctx *s, unsigned char digest[32]);

/* The digest of n bytes as 64 lowercase hex digits and a NUL. */
void thx_sha256_hex(const void *data, size_t n, char hex[65]);
/* The digest of a file's bytes (read in blocks, any size) as hex; THX_EIO naming the file if it
 * cannot be read. */
thx_status thx_sha256_file(thx_ctx *ctx, const char *path, char hex[65]);

#ifdef __cplusplus
}
#endif
#endif
