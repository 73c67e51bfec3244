/*
 * thorax/core/hash.h — a number from an integer alone (splitmix64's finalizer, Steele, Lea and Flood
 * 2014): the same in every run, every thread and every order of visit, for checks that need fixed
 * "random" vectors (the kept stiffness matrix's symmetry test, the combinations that check a block of
 * solves).
 */
#ifndef THORAX_CORE_HASH_H
#define THORAX_CORE_HASH_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* i's 64 mixed bits. */
static inline uint64_t thx_hash64(uint64_t i)
{
    uint64_t z = i + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* A double in [-1, 1) from i: the top 53 bits of thx_hash64(i), scaled. */
static inline double thx_hash_signed_unit(uint64_t i) { return (double)(thx_hash64(i) >> 11) * 0x1.0p-52 - 1.0; }

#ifdef __cplusplus
}
#endif

#endif
