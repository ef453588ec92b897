/* Proof that the library claims no heap memory: malloc/calloc/realloc/free are interposed
 * by this executable (the dynamic linker binds every shared object's calls, libamd/libldl
 * included, to these definitions) and counted around setup, update and solve, which must
 * all count zero; the last check proves the binding on a shared object's calls
 * (libsuitesparseconfig's). Run natively (valgrind replaces malloc itself). */
#include <stddef.h>
#include <string.h>

#include <SuiteSparse_config.h>

#include "ctest_util.h"
#include "tscvx_socp.h"

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);

static volatile int counting = 0;
static volatile long heap_calls = 0;

void *malloc(size_t n) {
    heap_calls += counting;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    heap_calls += counting;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    heap_calls += counting;
    return __libc_realloc(p, n);
}
void free(void *p) {
    heap_calls += counting && p != NULL;
    __libc_free(p);
}

#define N 40
#define P_ 5
#define NSOC 8
#define L 20
static tscvx_int q[NSOC] = {3, 4, 3, 20, 2, 3, 4, 5}; /* one cone gets the sparse expansion */
#define M (L + 44)

static unsigned char arena[1 << 21];
static unsigned char scratch[1 << 21];

int main(void) {
    /* a random feasible SOCP: G, A dense-ish, h = G x0 + s0 with s0 in int K, c = -G'z0 */
    static tscvx_int Ap[N + 1], Ai[N * P_], Gp[N + 1], Gi[N * M];
    static tscvx_float Ax[N * P_], Gx[N * M], b[P_], h[M], c[N], x0[N], s0[M], z0[M];
    int nz = 0;
    for (int j = 0; j < N; j++) {
        Ap[j] = nz;
        for (int i = 0; i < P_; i++)
            if (ct_rand() < 0.3 || i == j % P_) Ai[nz] = i, Ax[nz++] = ct_randn();
    }
    Ap[N] = nz;
    nz = 0;
    for (int j = 0; j < N; j++) {
        Gp[j] = nz;
        for (int i = 0; i < M; i++)
            if (ct_rand() < 0.2 || i == j % M) Gi[nz] = i, Gx[nz++] = ct_randn();
    }
    Gp[N] = nz;
    for (int j = 0; j < N; j++) x0[j] = ct_randn();
    for (int i = 0; i < M; i++) s0[i] = ct_randn(), z0[i] = ct_randn();
    for (int i = 0; i < L; i++) s0[i] = 1.0 + ct_rand(), z0[i] = 1.0 + ct_rand();
    for (int k = 0, o = L; k < NSOC; o += q[k++]) s0[o] = z0[o] = 2.0 * sqrt((double)q[k]) + 1.0;
    for (int i = 0; i < P_; i++) b[i] = 0.0;
    for (int i = 0; i < M; i++) h[i] = s0[i];
    memset(c, 0, sizeof c);
    for (int j = 0; j < N; j++) {
        for (int k = Ap[j]; k < Ap[j + 1]; k++) b[Ai[k]] += Ax[k] * x0[j];
        for (int k = Gp[j]; k < Gp[j + 1]; k++) h[Gi[k]] += Gx[k] * x0[j], c[j] -= Gx[k] * z0[Gi[k]];
    }
    tscvx_data d = {N, P_, M, NULL, NULL, NULL, c, Ap, Ai, Ax, b, Gp, Gi, Gx, h, L, NSOC, q};
    tscvx_settings st;
    tscvx_default_settings(&st);

    counting = 1;
    size_t ns = 0, na = 0;
    CHECK(tscvx_scratch_size(&d, &st, &ns) == TSCVX_SETUP_OK && ns <= sizeof scratch, "scratch");
    CHECK(tscvx_workspace_size(&d, &st, scratch, ns, &na) == TSCVX_SETUP_OK, "size");
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, arena, na, &d, &st) == TSCVX_SETUP_OK, "setup");
    const long after_setup = heap_calls;
    const tscvx_solve_status s1 = tscvx_solve(ws);
    const long in_solve = heap_calls - after_setup;
    for (int i = 0; i < M; i++) h[i] *= 1.5;
    CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, NULL, h) == TSCVX_SETUP_OK, "update");
    const tscvx_solve_status s2 = tscvx_solve(ws);
    counting = 0;

    tscvx_info info;
    tscvx_get_info(ws, &info);
    CHECK(s1 == TSCVX_SOLVED && s2 == TSCVX_SOLVED, "statuses %d %d", (int)s1, (int)s2);
    CHECK(after_setup == 0, "%ld heap calls during size queries and setup", after_setup);
    CHECK(in_solve == 0, "%ld heap calls during solve", in_solve);
    CHECK(heap_calls == 0, "%ld heap calls in total", heap_calls);
    printf("test_noalloc: heap calls setup %ld, solve %ld, update+solve %ld; arena %zu bytes "
           "(high-water %zu), %d iterations\n",
           after_setup, in_solve, heap_calls - after_setup - in_solve, na, info.arena_high_water,
           (int)info.iterations);
    /* the counter sees a shared library's calls: SuiteSparse_malloc and SuiteSparse_free
     * call malloc and free from libsuitesparseconfig, what libamd allocates through (libldl
     * calls neither). A malloc called here would bind to this file's definition whether or
     * not the dynamic linker interposes it, and prove nothing. */
    counting = 1;
    void *p = SuiteSparse_malloc(1, 16);
    SuiteSparse_free(p);
    counting = 0;
    CHECK(p != NULL && heap_calls == 2, "shared objects' calls not counted (%ld)", heap_calls);
    return ct_report("test_noalloc");
}
