/*
 * test_libm_hypot.c -- the landing does not depend on the host's hypot.
 *
 * libm's hypot is not the same function everywhere: Debian's 32-bit PowerPC glibc rounds
 * about a third of the default landing's calls differently from x86-64 glibc, and the
 * RAD750's own libm is another again. The guidance used it in the trust-region step and the
 * penalty, so the same landing gave another trajectory and another IPM iteration count on the
 * RAD750's kind of CPU than on the ground (`make check-ppc`). Linked with -Wl,--wrap=hypot,
 * this program solves the default landing with the host's hypot, then with one that rounds
 * every result one ulp up (a libm within glibc's documented 1 ulp), and requires the two
 * answers to be the same to the last bit: iterations, subproblems, IPM iterations, x and u.
 */
#include <math.h>
#include <string.h>

#include "gnc_test.h"

static int odd_hypot; /* 1: __wrap_hypot rounds one ulp up */
static long hypot_calls;

double __real_hypot(double a, double b);
double __wrap_hypot(double a, double b);
double __wrap_hypot(double a, double b)
{
    const double h = __real_hypot(a, b);
    ++hypot_calls;
    return odd_hypot && h > 0.0 && isfinite(h) ? nextafter(h, INFINITY) : h;
}

static double x2[PDG_N_MAX * PDG_NSTATE], u2[PDG_N_MAX * PDG_NCTRL];

int main(void)
{
    pdg_settings st;
    pdg_scenario s;
    pdg_workspace *ws = NULL;
    pdg_result r, r2;
    void *arena = NULL;
    size_t need = 0;
    int tries, N;
    pdg_default_settings(&st);
    pdg_default_scenario(&s);
    N = s.params.N;
    CHECK(arena_size(N, s.params.final_roll_free, &st, &need, &tries) == PDG_SETUP_OK);
    CHECK((arena = malloc(need)) != NULL);
    if (!arena) return 1;
    CHECK(pdg_setup(&ws, arena, need, &s.params, &st) == PDG_SETUP_OK);
    memset(&r, 0, sizeof r);
    memset(&r2, 0, sizeof r2);
    r.x = x, r.u = u, r2.x = x2, r2.u = u2;

    odd_hypot = 0;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    odd_hypot = 1;
    CHECK(pdg_solve(ws, &s, NULL, &r2) == PDG_SOLVED);
    printf("host hypot: %d iterations, %d subproblems, %d IPM iterations, m_f %.17g\n",
           r.iterations, r.subproblems_solved, r.socp_iterations, x[PDG_NSTATE * (N - 1) + 13]);
    printf("hypot one ulp up: %d iterations, %d subproblems, %d IPM iterations, m_f %.17g "
           "(%ld hypot calls from the library)\n", r2.iterations, r2.subproblems_solved,
           r2.socp_iterations, x2[PDG_NSTATE * (N - 1) + 13], hypot_calls);
    CHECK(r2.iterations == r.iterations && r2.subproblems_solved == r.subproblems_solved);
    CHECK(r2.socp_iterations == r.socp_iterations);
    CHECK(memcmp(x, x2, sizeof(double) * (size_t)N * PDG_NSTATE) == 0);
    CHECK(memcmp(u, u2, sizeof(double) * (size_t)N * PDG_NCTRL) == 0);
    free(arena);
    return gnc_report("test_libm_hypot");
}
