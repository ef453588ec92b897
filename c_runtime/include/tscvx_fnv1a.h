/* The checksums the flight library keeps of what its set-up fixed. Not part of the API:
 * shared by the layers, like tscvx_types.h.
 *   tscvx_fnv1a: FNV-1a, 64 bits, bytewise, about 4 host instructions per byte (the
 *     networks' nn_layout_sum);
 *   tscvx_wordsum: 8 bytes at a time, h = rotl(h ^ w, 29) * FNV's prime, a shorter final word
 *     zero-padded and the length mixed in; about 4 host instructions per 8 bytes (the SOCP
 *     workspace's head and body sums, wssum.c, and the guidance workspace's pdg_layout_sum).
 *     Each step is a bijection of h for a given word and of the word for a given h, so any
 *     change confined to one word (any single bit flip, any burst within 8 bytes) changes
 *     the sum for certain, as any change within one byte does FNV-1a's; the rotation carries
 *     a change in a word's high bits down, where the product spreads it (plain word-wise
 *     FNV-1a would let two flips of bit 63 cancel). Other damage goes unseen with
 *     probability about 2^-64 by either. */
#ifndef TSCVX_FNV1A_H
#define TSCVX_FNV1A_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define TSCVX_FNV1A_START 0xCBF29CE484222325ull
#define TSCVX_FNV_PRIME 0x100000001B3ull

static inline uint64_t tscvx_fnv1a(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; ++i) {
        h = (h ^ b[i]) * TSCVX_FNV_PRIME;
    }
    return h;
}

/* One word into the word-wise sum. */
static inline uint64_t tscvx_wordmix(uint64_t h, uint64_t w)
{
    h ^= w;
    h = (h << 29) | (h >> 35);
    return h * TSCVX_FNV_PRIME;
}

/* `bytes` bytes at p into the word-wise sum (nothing beyond them is read; p may be NULL when
 * bytes is 0). */
static inline uint64_t tscvx_wordsum(uint64_t h, const void *p, size_t bytes)
{
    const unsigned char *b = (const unsigned char *)p;
    const size_t words = bytes / 8, rest = bytes % 8;
    uint64_t w;
    size_t k;
    for (k = 0; k < words; ++k) {
        memcpy(&w, b + 8 * k, sizeof w);
        h = tscvx_wordmix(h, w);
    }
    if (rest > 0) {
        w = 0;
        for (k = 0; k < rest; ++k) {
            w |= (uint64_t)b[8 * words + k] << (8 * k);
        }
        h = tscvx_wordmix(h, w);
    }
    return tscvx_wordmix(h, (uint64_t)bytes); /* the length: a shorter array is another sum */
}

#endif /* TSCVX_FNV1A_H */
