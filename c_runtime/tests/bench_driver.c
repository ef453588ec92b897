/* clock_gettime */
#define _POSIX_C_SOURCE 199309L
/* Benchmark driver: loads a problem dumped by guidance.bench_socp (binary, little endian),
 * sets it up in one malloc'ed arena and solves it `reps` times. Used with callgrind:
 *   valgrind --tool=callgrind --toggle-collect=tscvx_solve build/ctest/bench_driver FILE 1
 * (optional third argument: kkt_backend, 0 automatic (default: banded when the problem has the
 * structure), 1 SuiteSparse LDL, 2 static-pattern LDL', 3 banded; optional fourth: a file
 * f64 x[n] y[p] z[m] s[m], given to tscvx_warm_start before each solve)
 * File: int32 n p m l nsoc nnzP nnzA nnzG (nnzP = -1: no P), then int32 q[nsoc],
 * [int32 Pp[n+1] Pi[nnzP] f64 Px[nnzP]], f64 c[n], int32 Ap[n+1] Ai[nnzA] f64 Ax[nnzA] b[p],
 * int32 Gp[n+1] Gi[nnzG] f64 Gx[nnzG] h[m]. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "tscvx_socp.h"

/* Every buffer read, to free at the end (the problem's arrays are const in tscvx_data). */
static void *owned[32];
static size_t n_owned;

static void *rd(FILE *f, size_t count, size_t size) {
    void *p = malloc(count * size + 8);
    if (p == NULL || fread(p, size, count, f) != count ||
        n_owned == sizeof owned / sizeof owned[0]) {
        fprintf(stderr, "bench_driver: short file\n");
        exit(2);
    }
    owned[n_owned++] = p;
    return p;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_driver FILE [reps [kkt_backend [WARM_FILE]]]\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (f == NULL) return 2;
    int hdr[8];
    if (fread(hdr, sizeof(int), 8, f) != 8) return 2;
    tscvx_data d = {0};
    d.n = hdr[0], d.p = hdr[1], d.m = hdr[2], d.l = hdr[3], d.nsoc = hdr[4];
    d.q = rd(f, (size_t)d.nsoc, sizeof(int));
    if (hdr[5] >= 0) {
        d.Pp = rd(f, (size_t)d.n + 1, sizeof(int));
        d.Pi = rd(f, (size_t)hdr[5], sizeof(int));
        d.Px = rd(f, (size_t)hdr[5], sizeof(double));
    }
    d.c = rd(f, (size_t)d.n, sizeof(double));
    d.Ap = rd(f, (size_t)d.n + 1, sizeof(int));
    d.Ai = rd(f, (size_t)hdr[6], sizeof(int));
    d.Ax = rd(f, (size_t)hdr[6], sizeof(double));
    d.b = rd(f, (size_t)d.p, sizeof(double));
    d.Gp = rd(f, (size_t)d.n + 1, sizeof(int));
    d.Gi = rd(f, (size_t)hdr[7], sizeof(int));
    d.Gx = rd(f, (size_t)hdr[7], sizeof(double));
    d.h = rd(f, (size_t)d.m, sizeof(double));
    fclose(f);
    double *wx = NULL, *wy = NULL, *wz = NULL, *ws_ = NULL; /* warm start */
    if (argc > 4) {
        FILE *fw = fopen(argv[4], "rb");
        if (fw == NULL) return 2;
        wx = rd(fw, (size_t)d.n, sizeof(double));
        wy = rd(fw, (size_t)d.p, sizeof(double));
        wz = rd(fw, (size_t)d.m, sizeof(double));
        ws_ = rd(fw, (size_t)d.m, sizeof(double));
        fclose(fw);
    }
    const int reps = argc > 2 ? atoi(argv[2]) : 1;
    tscvx_settings st;
    tscvx_default_settings(&st);
    if (argc > 3) st.kkt_backend = atoi(argv[3]);
    size_t nscratch = 0, narena = 0;
    if (tscvx_scratch_size(&d, &st, &nscratch) != TSCVX_SETUP_OK) return 3;
    void *scratch = malloc(nscratch);
    if (tscvx_workspace_size(&d, &st, scratch, nscratch, &narena) != TSCVX_SETUP_OK) return 3;
    free(scratch);
    void *arena = malloc(narena);
    tscvx_workspace *ws = NULL;
    if (tscvx_setup(&ws, arena, narena, &d, &st) != TSCVX_SETUP_OK) return 3;
    struct timespec t0, t1;
    double best = 1e30;
    tscvx_solve_status s = TSCVX_UNSOLVED;
    for (int r = 0; r < reps; r++) {
        if (wx && tscvx_warm_start(ws, wx, wy, wz, ws_) != TSCVX_SETUP_OK) return 3;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        s = tscvx_solve(ws);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        const double dt = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (dt < best) best = dt;
    }
    tscvx_info info;
    tscvx_get_info(ws, &info);
    printf("status %d (%s) iter %d factorizations %d pcost %.12e time %.3f ms arena %zu kkt %d nnz %d lnz %d warm %d\n",
           (int)s, tscvx_solve_status_message(s), (int)info.iterations, (int)info.factorizations, info.pcost, 1e3 * best,
           narena, (int)info.kkt_dim, (int)info.kkt_nnz, (int)info.factor_nnz, (int)info.warm_started);
    free(arena);
    for (size_t i = 0; i < n_owned; i++) free(owned[i]);
    return 0;
}
