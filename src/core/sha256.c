/* SHA-256 after FIPS 180-4, section 6.2 (see thorax/core/sha256.h). */
#include "thorax/core/sha256.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* The first 32 bits of the fractional parts of the cube roots of the first 64 primes (FIPS 180-4 4.2.2). */
static const uint32_t K[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

static inline uint32_t rotr(uint32_t x, int r) { return (x >> r) | (x << (32 - r)); }

/* One 64-byte block into the state. */
static void block(uint32_t h[8], const unsigned char *p)
{
    uint32_t w[64];
    for (int t = 0; t < 16; t++)
        w[t] = (uint32_t)p[4 * t] << 24 | (uint32_t)p[4 * t + 1] << 16 | (uint32_t)p[4 * t + 2] << 8 | p[4 * t + 3];
    for (int t = 16; t < 64; t++) {
        uint32_t s0 = rotr(w[t - 15], 7) ^ rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
        uint32_t s1 = rotr(w[t - 2], 17) ^ rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
        w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], k = h[7];
    for (int t = 0; t < 64; t++) {
        uint32_t t1 = k + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + K[t] + w[t];
        uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        k = g; g = f; f = e; e = d + t1;
        d = c; c = b; b = a; a = t1 + t2;
    }
    h[0] += a; h[1] += b; h[2] += c; h[3] += d; h[4] += e; h[5] += f; h[6] += g; h[7] += k;
}

/* n blocks: the processor's SHA instructions where it has them (SHA-NI: x86's sha256rnds2, sha256msg1 and
   sha256msg2 do two rounds and the message schedule; 250 MB/s -> about 1.5 GB/s), else block() after block().
   THORAX_SHA256_PORTABLE=1 takes the portable code (the tests run both). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <cpuid.h>
#include <immintrin.h>
#include <stdlib.h>

__attribute__((target("sha,sse4.1,ssse3"))) static void blocks_shani(uint32_t h[8], const unsigned char *p, size_t nb)
{
    /* the state as the instructions want it: (a b e f) and (c d g h), highest lane first */
    __m128i t = _mm_shuffle_epi32(_mm_loadu_si128((const __m128i *)h), 0xB1);      /* b a d c */
    __m128i s1 = _mm_shuffle_epi32(_mm_loadu_si128((const __m128i *)(h + 4)), 0x1B); /* h g f e */
    __m128i s0 = _mm_alignr_epi8(t, s1, 8);                                         /* f e b a */
    s1 = _mm_blend_epi16(s1, t, 0xF0);                                              /* h g d c */
    const __m128i swap = _mm_set_epi64x(0x0c0d0e0f08090a0bLL, 0x0405060700010203LL); /* big-endian words */
    for (; nb; nb--, p += 64) {
        const __m128i save0 = s0, save1 = s1;
        __m128i w[4];
        for (int g = 0; g < 16; g++) {
            __m128i wg;
            if (g < 4) wg = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(p + 16 * g)), swap);
            else {
                /* W[t] = s1(W[t-2]) + W[t-7] + s0(W[t-15]) + W[t-16], four words at a time */
                wg = _mm_sha256msg1_epu32(w[g & 3], w[(g + 1) & 3]);
                wg = _mm_add_epi32(wg, _mm_alignr_epi8(w[(g + 3) & 3], w[(g + 2) & 3], 4));
                wg = _mm_sha256msg2_epu32(wg, w[(g + 3) & 3]);
            }
            w[g & 3] = wg;
            __m128i m = _mm_add_epi32(wg, _mm_loadu_si128((const __m128i *)(K + 4 * g)));
            s1 = _mm_sha256rnds2_epu32(s1, s0, m);
            s0 = _mm_sha256rnds2_epu32(s0, s1, _mm_shuffle_epi32(m, 0x0E));
        }
        s0 = _mm_add_epi32(s0, save0);
        s1 = _mm_add_epi32(s1, save1);
    }
    t = _mm_shuffle_epi32(s0, 0x1B);          /* a b e f, lowest first: f e b a -> a b e f */
    s1 = _mm_shuffle_epi32(s1, 0xB1);         /* g h c d */
    s0 = _mm_blend_epi16(t, s1, 0xF0);        /* a b c d */
    s1 = _mm_alignr_epi8(s1, t, 8);           /* e f g h */
    _mm_storeu_si128((__m128i *)h, s0);
    _mm_storeu_si128((__m128i *)(h + 4), s1);
}

/* The processor's SHA, SSE4.1 and SSSE3 (CPUID: leaf 7 EBX bit 29, leaf 1 ECX bits 19 and 9), asked of CPUID
   itself: clang 14's __builtin_cpu_supports knows no "sha". */
static int use_shani(void)
{
    const char *e = getenv("THORAX_SHA256_PORTABLE");
    if (e && !strcmp(e, "1")) return 0;
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & (1u << 19)) || !(c & (1u << 9))) return 0;
    if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return 0;
    return (b >> 29) & 1;
}
#endif

static void blocks(uint32_t h[8], const unsigned char *p, size_t nb)
{
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (use_shani()) {
        blocks_shani(h, p, nb);
        return;
    }
#endif
    for (; nb; nb--, p += 64) block(h, p);
}

void thx_sha256_init(thx_sha256_ctx *s)
{
    static const uint32_t H0[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                   0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    memcpy(s->h, H0, sizeof H0);
    s->n = 0;
}

void thx_sha256_update(thx_sha256_ctx *s, const void *data, size_t n)
{
    const unsigned char *p = data;
    size_t have = (size_t)(s->n % 64);
    s->n += n;
    if (have) {
        size_t take = 64 - have < n ? 64 - have : n;
        memcpy(s->buf + have, p, take);
        p += take;
        n -= take;
        if (have + take < 64) return;
        blocks(s->h, s->buf, 1);
    }
    blocks(s->h, p, n / 64);
    p += n / 64 * 64;
    n %= 64;
    if (n) memcpy(s->buf, p, n);
}

void thx_sha256_final(thx_sha256_ctx *s, unsigned char digest[32])
{
    uint64_t bits = s->n * 8;
    size_t have = (size_t)(s->n % 64);
    s->buf[have++] = 0x80; /* a one bit, then zeros, then the length in bits, big-endian (5.1.1) */
    if (have > 56) {
        memset(s->buf + have, 0, 64 - have);
        blocks(s->h, s->buf, 1);
        have = 0;
    }
    memset(s->buf + have, 0, 56 - have);
    for (int i = 0; i < 8; i++) s->buf[56 + i] = (unsigned char)(bits >> (56 - 8 * i));
    blocks(s->h, s->buf, 1);
    for (int i = 0; i < 8; i++) {
        digest[4 * i] = (unsigned char)(s->h[i] >> 24);
        digest[4 * i + 1] = (unsigned char)(s->h[i] >> 16);
        digest[4 * i + 2] = (unsigned char)(s->h[i] >> 8);
        digest[4 * i + 3] = (unsigned char)s->h[i];
    }
}

static void to_hex(const unsigned char d[32], char hex[65])
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 0; i < 32; i++) {
        hex[2 * i] = digits[d[i] >> 4];
        hex[2 * i + 1] = digits[d[i] & 15];
    }
    hex[64] = '\0';
}

void thx_sha256_hex(const void *data, size_t n, char hex[65])
{
    thx_sha256_ctx s;
    unsigned char d[32];
    thx_sha256_init(&s);
    thx_sha256_update(&s, data, n);
    thx_sha256_final(&s, d);
    to_hex(d, hex);
}

thx_status thx_sha256_file(thx_ctx *ctx, const char *path, char hex[65])
{
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    thx_sha256_ctx s;
    unsigned char buf[1 << 15], d[32];
    thx_sha256_init(&s);
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, f)) > 0) thx_sha256_update(&s, buf, got);
    int err = ferror(f);
    fclose(f);
    if (err) return thx_error(ctx, THX_EIO, "%s: read error", path);
    thx_sha256_final(&s, d);
    to_hex(d, hex);
    return THX_OK;
}
