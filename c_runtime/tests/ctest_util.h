/* Tiny test helpers shared by the C unit tests. */
#ifndef CTEST_UTIL_H
#define CTEST_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int ct_failures = 0;

#define CHECK(cond, ...)                                                        \
    do {                                                                        \
        if (!(cond)) {                                                          \
            ct_failures++;                                                      \
            fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                       \
            fprintf(stderr, "\n");                                              \
        }                                                                       \
    } while (0)

/* deterministic LCG in [0, 1) */
static unsigned long long ct_seed = 12345u;
static inline double ct_rand(void) {
    ct_seed = ct_seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(ct_seed >> 11) / 9007199254740992.0;
}
static inline double ct_randn(void) { return 2.0 * ct_rand() - 1.0; }

static inline int ct_report(const char *name) {
    if (ct_failures) fprintf(stderr, "%s: %d failure(s)\n", name, ct_failures);
    else printf("%s: ok\n", name);
    return ct_failures ? 1 : 0;
}

#endif
