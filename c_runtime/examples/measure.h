/*
 * measure.h -- what the budget drivers measure around one call (pdg_budget_driver.c,
 * c_runtime/nn/tests/nn_budget_driver.c): heap allocations inside it (glibc malloc
 * interposition: set `counting` around the call), its stack high-water (paint_stack() before,
 * painted_depth() after: the deepest byte below the caller's frame that lost the pattern) and
 * wall time. Host tooling, not flight code; include once, after #define _GNU_SOURCE.
 */
#ifndef TSCVX_MEASURE_H
#define TSCVX_MEASURE_H

#include <stddef.h>
#include <string.h>
#include <time.h>

/* ---- heap allocations inside the measured call (glibc interposition) --------------------- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
static volatile int counting = 0;
static volatile long n_alloc = 0;
void *malloc(size_t n)
{
    if (counting) n_alloc++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b)
{
    if (counting) n_alloc++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n)
{
    if (counting) n_alloc++;
    return __libc_realloc(p, n);
}

/* ---- stack painting ---------------------------------------------------------------------- */
#define PAINT_BYTES (4u << 20) /* 4 MB below the caller's frame (default stack limit 8 MB) */
#define PAINT 0xA5u

static __attribute__((noinline)) void paint_stack(void)
{
    unsigned char buf[PAINT_BYTES];
    unsigned char *p = buf;
    __asm__ volatile("" : "+r"(p) : : "memory"); /* the compiler cannot drop the writes */
    memset(p, PAINT, PAINT_BYTES);
    __asm__ volatile("" : : "r"(p) : "memory");
}

/* Bytes used below this frame's buffer top: the deepest non-pattern byte. */
static __attribute__((noinline)) size_t painted_depth(void)
{
    unsigned char buf[PAINT_BYTES];
    const volatile unsigned char *p = buf;
    size_t i;
    __asm__ volatile("" : "+r"(p) : : "memory"); /* contents unknown to the compiler */
    for (i = 0; i < PAINT_BYTES; ++i) { /* p[0] is the deepest address */
        if (p[i] != PAINT) {
            return PAINT_BYTES - i;
        }
    }
    return 0;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
