/*
 * fuzz.h -- shared by the fuzz harnesses of c_runtime/fuzz/ (libFuzzer entry point, the byte
 * reader that turns a fuzz input into numbers, and the oracle's failure report).
 *
 * Each harness defines LLVMFuzzerTestOneInput. Built two ways (c_runtime/fuzz/fuzz.mk):
 *   - clang -fsanitize=fuzzer,address,undefined: `make fuzz` (libFuzzer drives it);
 *   - gcc -fsanitize=address,undefined with fuzz_replay.c's main(): `make ctest-asan` runs
 *     every harness over its checked-in corpus (c_runtime/fuzz/corpus/<harness>/).
 * An oracle failure prints what failed and aborts: a crash to libFuzzer, a failed test to
 * the replay driver.
 */
#ifndef TSCVX_FUZZ_H
#define TSCVX_FUZZ_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The fuzz input read front to back; past its end every read gives 0. */
typedef struct {
    const uint8_t *p;
    size_t n, at;
} fz_reader;

static inline unsigned fz_u8(fz_reader *r)
{
    return r->at < r->n ? r->p[r->at++] : 0u;
}

static inline unsigned fz_u16(fz_reader *r)
{
    const unsigned lo = fz_u8(r);
    return lo | (fz_u8(r) << 8);
}

/* A double chosen to reach the edges: one byte picks a special value (NaN, +-inf, the
 * largest and smallest normal and subnormal numbers, +-0, large and tiny magnitudes), a
 * small value on a grid, or the next 8 bytes as raw IEEE bits. */
static inline double fz_double(fz_reader *r)
{
    static const double special[16] = {
        0.0, -0.0, 1.0, -1.0, 1e300, -1e300, 1e-300, 2.2250738585072014e-308,
        4.9406564584124654e-324, 1.7976931348623157e308, 1e8, -1e8, 1e-8, 1e20, -1e-20, 0.5};
    const unsigned b = fz_u8(r);
    if (b < 0x80u) {
        return ((double)b - 64.0) / 16.0; /* -4 .. 3.9375 */
    }
    if (b < 0xF0u) {
        return special[b & 15u];
    }
    if (b < 0xF8u) {
        return b & 1u ? -(double)INFINITY : (b & 2u ? (double)INFINITY : (double)NAN);
    }
    {
        uint64_t u = 0;
        double d;
        unsigned i;
        for (i = 0; i < 8; ++i) {
            u |= (uint64_t)fz_u8(r) << (8 * i);
        }
        memcpy(&d, &u, sizeof d);
        return d;
    }
}

#define FZ_FAIL(...)                                                                           \
    do {                                                                                       \
        fprintf(stderr, "fuzz oracle: " __VA_ARGS__);                                          \
        fprintf(stderr, "\n");                                                                 \
        abort();                                                                               \
    } while (0)

#endif /* TSCVX_FUZZ_H */
