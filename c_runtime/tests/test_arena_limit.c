/* The size queries and set-up against the arena's limit, SIZE_MAX / 2 bytes: 2 GiB on a host
 * with a 32-bit size_t (the RAD750's PowerPC), 32 MiB in the x86 build of this test, whose
 * runtime is compiled with small_size_t.h. A size past the limit is never reported: every
 * call says TSCVX_SETUP_TOO_LARGE. (The arena used to drop the request it could not count and
 * report the rest: tscvx_scratch_size said OK with a fraction of the size, tscvx_workspace_size
 * a size that tscvx_setup then found too small, and setup ARENA_TOO_SMALL for any arena.) */
#include <stdint.h>
#include <stdlib.h>

#include "ctest_util.h"
#include "tscvx_socp.h"

/* An LP of n variables with no constraints (min c'x: only c given), sized by the queries:
 * the scratch size, then the arena size in a scratch of that size. */
static tscvx_setup_status sizes(int n, size_t *scratch_bytes, size_t *arena_bytes)
{
    tscvx_data d = {0};
    tscvx_settings st;
    tscvx_setup_status s;
    double *c = calloc((size_t)n, sizeof(double));
    void *scratch;
    tscvx_default_settings(&st);
    d.n = n;
    d.c = c;
    CHECK(c != NULL, "calloc of c");
    if (!c) return TSCVX_SETUP_NULL_ARGUMENT;
    *scratch_bytes = *arena_bytes = 0;
    s = tscvx_scratch_size(&d, &st, scratch_bytes);
    if (s == TSCVX_SETUP_OK) {
        scratch = malloc(*scratch_bytes);
        CHECK(scratch != NULL, "malloc of %zu scratch bytes", *scratch_bytes);
        s = scratch ? tscvx_workspace_size(&d, &st, scratch, *scratch_bytes, arena_bytes)
                    : TSCVX_SETUP_NULL_ARGUMENT;
        free(scratch);
    }
    free(c);
    return s;
}

/* Set-up of that LP in an arena of `bytes` */
static tscvx_setup_status set_up(int n, size_t bytes)
{
    tscvx_data d = {0};
    tscvx_settings st;
    tscvx_workspace *ws = NULL;
    tscvx_setup_status s;
    double *c = calloc((size_t)n, sizeof(double));
    void *arena = malloc(bytes);
    tscvx_default_settings(&st);
    d.n = n;
    d.c = c;
    CHECK(arena != NULL && c != NULL, "malloc of %zu arena bytes", bytes);
    s = arena && c ? tscvx_setup(&ws, arena, bytes, &d, &st) : TSCVX_SETUP_NULL_ARGUMENT;
    free(arena);
    free(c);
    return s;
}

int main(void)
{
    const size_t limit = SIZE_MAX / 2; /* this build's: 2 GiB on ppc, 32 MiB on x86 */
    /* this LP's sizes: about 119 bytes of scratch and 149 of arena per variable */
    const int fits = 1000, arena_past = (int)(limit / 130), both_past = (int)(limit / 100);
    size_t scratch = 1, arena = 1;
    tscvx_setup_status s;

    printf("arena limit %zu bytes\n", limit);
    /* well inside: sized, and set up in the size reported */
    s = sizes(fits, &scratch, &arena);
    CHECK(s == TSCVX_SETUP_OK && arena > 0 && arena < limit, "n = %d: status %d, %zu bytes",
          fits, (int)s, arena);
    CHECK(set_up(fits, arena) == TSCVX_SETUP_OK, "set-up in %zu bytes", arena);

    /* the scratch fits, the arena would not: the arena query refuses */
    s = sizes(arena_past, &scratch, &arena);
    CHECK(s == TSCVX_SETUP_TOO_LARGE, "n = %d: status %d (%s), scratch %zu, arena %zu bytes",
          arena_past, (int)s, tscvx_setup_status_message(s), scratch, arena);
    CHECK(scratch > 0 && scratch < limit, "n = %d: scratch %zu bytes", arena_past, scratch);
    CHECK(arena == 0, "n = %d: an arena size %zu reported with the refusal", arena_past, arena);
    /* ... and so does set-up, in an arena of the limit (not "arena too small") */
    s = set_up(arena_past, limit);
    CHECK(s == TSCVX_SETUP_TOO_LARGE, "n = %d: set-up in %zu bytes: status %d (%s)",
          arena_past, limit, (int)s, tscvx_setup_status_message(s));

    /* even the scratch would not fit: the scratch query refuses */
    s = sizes(both_past, &scratch, &arena);
    CHECK(s == TSCVX_SETUP_TOO_LARGE, "n = %d: status %d (%s), scratch %zu bytes", both_past,
          (int)s, tscvx_setup_status_message(s), scratch);
    return ct_report("test_arena_limit");
}
