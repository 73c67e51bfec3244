/*
 * SHA-256 (thorax/core/sha256.h) against the FIPS 180-4 / NIST example vectors, fed whole and in
 * pieces that cross the 64-byte blocks every way, and a file against the same bytes in memory.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/core/sha256.h"

static const struct {
    const char *msg;
    size_t repeat;
    const char *hex;
} VEC[] = {
    {"", 1, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"},
    {"abc", 1, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"},
    {"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq", 1,
     "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"},
    {"abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu",
     1, "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1"},
    {"a", 1000000, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"},
};

static char *expand(const char *msg, size_t repeat, size_t *n)
{
    size_t m = strlen(msg);
    *n = m * repeat;
    char *b = malloc(*n + 1);
    for (size_t i = 0; i < repeat; i++) memcpy(b + i * m, msg, m);
    b[*n] = '\0';
    return b;
}

/* The vectors, the pieces, a file, the padding's edges: once with the processor's SHA instructions where it
   has them, once with the portable code (THORAX_SHA256_PORTABLE=1), and a long random buffer the same both
   ways. */
static void vectors(thx_ctx *ctx)
{
    for (size_t v = 0; v < sizeof VEC / sizeof *VEC; v++) {
        size_t n;
        char *b = expand(VEC[v].msg, VEC[v].repeat, &n);
        char hex[65];
        thx_sha256_hex(b, n, hex);
        CHECK(strcmp(hex, VEC[v].hex) == 0);
        /* in pieces of every size 1..130: the same digest */
        int pieces_ok = 1;
        for (size_t step = 1; step <= 130 && n <= 200; step++) {
            thx_sha256_ctx s;
            unsigned char d[32];
            thx_sha256_init(&s);
            for (size_t at = 0; at < n; at += step) thx_sha256_update(&s, b + at, n - at < step ? n - at : step);
            thx_sha256_final(&s, d);
            char h2[65];
            for (int i = 0; i < 32; i++) snprintf(h2 + 2 * i, 3, "%02x", d[i]);
            pieces_ok &= strcmp(h2, VEC[v].hex) == 0;
        }
        CHECK(pieces_ok);
        /* the file's hash is the bytes' hash */
        tl_write_bytes(tl_path("f.bin"), b, n);
        CHECK_OK(ctx, thx_sha256_file(ctx, tl_path("f.bin"), hex));
        CHECK(strcmp(hex, VEC[v].hex) == 0);
        free(b);
    }
    /* 55, 56 and 64 bytes: the padding's edge cases (the length in the same block or the next);
     * the digests are sha256sum's */
    char a55[56], a56[57], a64[65], hex[65];
    memset(a55, 'a', 55);
    memset(a56, 'a', 56);
    memset(a64, 'a', 64);
    thx_sha256_hex(a55, 55, hex);
    CHECK(strcmp(hex, "9f4390f8d30c2dd92ec9f095b65e2b9ae9b0a925a5258e241c9f1e910f734318") == 0);
    thx_sha256_hex(a56, 56, hex);
    CHECK(strcmp(hex, "b35439a4ac6f0948b6d6f9e3c6af0f5f590ce20f1bde7090ef7970686ec6738a") == 0);
    thx_sha256_hex(a64, 64, hex);
    CHECK(strcmp(hex, "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb") == 0);
    CHECK(thx_sha256_file(ctx, tl_path("missing"), hex) == THX_EIO && tl_msg_has(ctx, "missing: cannot open"));
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK || tl_scratch_make("test_sha256")) return 1;
    size_t n = (3 << 20) + 37;
    unsigned char *r = malloc(n);
    srand(11);
    for (size_t i = 0; i < n; i++) r[i] = (unsigned char)(rand() >> 7);
    char h1[65], h2[65];
    unsetenv("THORAX_SHA256_PORTABLE");
    vectors(ctx);
    thx_sha256_hex(r, n, h1);
    setenv("THORAX_SHA256_PORTABLE", "1", 1);
    vectors(ctx);
    thx_sha256_hex(r, n, h2);
    unsetenv("THORAX_SHA256_PORTABLE");
    CHECK(strcmp(h1, h2) == 0);
    printf("3 MB of random bytes: %s both ways\n", h1);
    free(r);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_sha256");
}
