/* FNV-1a, 64 bits: the checksum the guidance workspace and the networks keep of what their
 * set-up fixed (pdg_layout_sum, nn_layout_sum). Not part of the API: shared by the two
 * layers, like tscvx_types.h. Bytewise, a few instructions per byte. */
#ifndef TSCVX_FNV1A_H
#define TSCVX_FNV1A_H

#include <stddef.h>
#include <stdint.h>

#define TSCVX_FNV1A_START 0xCBF29CE484222325ull

static inline uint64_t tscvx_fnv1a(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; ++i) {
        h = (h ^ b[i]) * 0x100000001B3ull;
    }
    return h;
}

#endif /* TSCVX_FNV1A_H */
