/* Forced include (-include) of test_arena_limit's build of the SOCP runtime: the arena
 * arithmetic of a host whose size_t ends at 2^26 - 1, a scale model of the RAD750's 32-bit
 * size_t. The runtime's only use of SIZE_MAX is its arena's limit, SIZE_MAX / 2: 32 MiB here,
 * 2 GiB on the 32-bit PowerPC, so that problems of a few MB reach the limit as problems of a
 * few hundred MB reach it there. */
#include <stdint.h>
#undef SIZE_MAX
#define SIZE_MAX (((size_t)1 << 26) - 1)
