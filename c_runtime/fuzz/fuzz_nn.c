/*
 * fuzz_nn.c -- fuzz harness of the network blob loader and inference (tscvx_nn.h).
 *
 * The input is a model blob (".tnn"). It is tried as it is and "sealed": with n_values set
 * to what its length holds and the CRC-32 recomputed, so that mutations get past the length
 * and checksum checks to the dimensions, counts and values. Each in both modes (weights read
 * in place, weights copied into the arena). Oracle:
 *   - tscvx_nn_check_blob, tscvx_nn_arena_size and tscvx_nn_init agree on the status (the
 *     header's promise), a documented one, with a non-empty message;
 *   - a refused blob leaves *bytes 0; an accepted one builds in an arena of exactly the size
 *     asked (heap block of that size: ASan sees any byte beyond) and is refused one byte
 *     smaller (TSCVX_NN_ARENA_TOO_SMALL);
 *   - an inference on the zero input and on each probe returns OK with finite outputs, or
 *     NUMERICAL_ERROR with every output NaN; the tight mask of a constraint network is 0/1;
 *     the self-test returns OK or SELF_TEST_FAILED (max_rel_err infinite or NaN then).
 * Seeds: the shipped networks (build/models/, the .tnn files) and tiny ones (nn_seeds.py).
 */
#include "fuzz.h"

#include "tscvx_nn.h"

#define HEADER 128u
#define CRC_AT 124u

static uint32_t crc32_ieee(const uint8_t *p, size_t n, uint32_t crc)
{
    size_t i;
    crc = ~crc;
    for (i = 0; i < n; ++i) {
        unsigned k;
        crc ^= p[i];
        for (k = 0; k < 8; ++k) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    unsigned i;
    for (i = 0; i < 4; ++i) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

/* n_values from the length, then the CRC over [0, 124) and [128, len). */
static void seal(uint8_t *b, size_t len)
{
    uint32_t crc;
    if (len < HEADER) {
        return;
    }
    if ((len - HEADER) % 8u == 0) {
        const uint64_t nv = (len - HEADER) / 8u;
        unsigned i;
        for (i = 0; i < 8; ++i) {
            b[80 + i] = (uint8_t)(nv >> (8 * i));
        }
    }
    crc = crc32_ieee(b, CRC_AT, 0);
    crc = crc32_ieee(b + HEADER, len - HEADER, crc);
    put_u32(b + CRC_AT, crc);
}

static void check_message(tscvx_nn_status st)
{
    const char *m;
    if ((unsigned)st >= (unsigned)TSCVX_NN_NSTATUS) {
        FZ_FAIL("undocumented status %d", (int)st);
    }
    m = tscvx_nn_status_message(st);
    if (!m || !m[0]) {
        FZ_FAIL("status %d has no message", (int)st);
    }
}

/* One inference from `in`; OK (finite outputs) or NUMERICAL_ERROR (every output NaN). */
static void run_once(tscvx_nn *net, const tscvx_nn_info *info, const double *in, double *out,
                     unsigned char *mask)
{
    const tscvx_nn_status st = tscvx_nn_run(net, in, info->d_in, out, info->d_out);
    int i;
    check_message(st);
    if (st == TSCVX_NN_NUMERICAL_ERROR) {
        for (i = 0; i < info->d_out; ++i) {
            if (!isnan(out[i])) {
                FZ_FAIL("tscvx_nn_run said NUMERICAL_ERROR with output %d = %g", i, out[i]);
            }
        }
        return;
    }
    if (st != TSCVX_NN_OK) {
        FZ_FAIL("tscvx_nn_run on a finite input: status %d", (int)st);
    }
    for (i = 0; i < info->d_out; ++i) {
        if (!isfinite(out[i])) {
            FZ_FAIL("tscvx_nn_run said OK with output %d = %g", i, out[i]);
        }
    }
    if (info->kind == TSCVX_NN_KIND_CONSTRAINT) {
        const tscvx_nn_status sm = tscvx_nn_tight_mask(net, out, info->d_out, mask);
        if (sm != TSCVX_NN_OK) {
            FZ_FAIL("tscvx_nn_tight_mask on finite logits: status %d", (int)sm);
        }
        for (i = 0; i < info->d_out; ++i) {
            if (mask[i] > 1u) {
                FZ_FAIL("mask[%d] = %u", i, (unsigned)mask[i]);
            }
        }
    }
}

static void exercise(tscvx_nn *net, const void *blob, size_t len, unsigned flags, size_t need)
{
    tscvx_nn_info info;
    double *in, *out, err = 0.0;
    unsigned char *mask;
    tscvx_nn_status st = tscvx_nn_get_info(net, &info);
    int k;
    if (st != TSCVX_NN_OK) {
        FZ_FAIL("tscvx_nn_get_info after init: status %d", (int)st);
    }
    if (info.d_in < 1 || info.d_out < 1 || info.arena_bytes != need
        || info.weights_in_arena != (int)(flags & TSCVX_NN_COPY_WEIGHTS)) {
        FZ_FAIL("info: d_in %d d_out %d arena %zu (asked %zu) in_arena %d", info.d_in,
                info.d_out, info.arena_bytes, need, info.weights_in_arena);
    }
    in = (double *)calloc((size_t)info.d_in, sizeof *in);
    out = (double *)calloc((size_t)info.d_out, sizeof *out);
    mask = (unsigned char *)calloc((size_t)info.d_out, 1);
    if (!in || !out || !mask) {
        abort();
    }
    run_once(net, &info, in, out, mask);
    /* the probes, read from the blob (each within its n_values) */
    for (k = 0; k < info.n_probes && k < 4; ++k) {
        const size_t at = HEADER + 8u * (info.n_weights + (size_t)k * (size_t)info.d_in);
        if (at + 8u * (size_t)info.d_in <= len) {
            memcpy(in, (const uint8_t *)blob + at, 8u * (size_t)info.d_in);
            run_once(net, &info, in, out, mask);
        }
    }
    st = tscvx_nn_self_test(net, &err);
    check_message(st);
    if (st != TSCVX_NN_OK && st != TSCVX_NN_SELF_TEST_FAILED) {
        FZ_FAIL("tscvx_nn_self_test: status %d", (int)st);
    }
    if (st == TSCVX_NN_OK && !(err <= 1e-4)) {
        FZ_FAIL("self-test passed with error %g", err);
    }
    free(in);
    free(out);
    free(mask);
}

static void try_blob(const uint8_t *blob, size_t len)
{
    char why[TSCVX_NN_MESSAGE_LEN];
    const tscvx_nn_status st_check = tscvx_nn_check_blob(blob, len, why);
    unsigned flags;
    check_message(st_check);
    if (!why[0] || !memchr(why, 0, sizeof why)) {
        FZ_FAIL("tscvx_nn_check_blob: status %d with an empty message", (int)st_check);
    }
    for (flags = 0; flags <= TSCVX_NN_COPY_WEIGHTS; ++flags) {
        size_t need = 12345;
        tscvx_nn *net = NULL;
        unsigned char *arena;
        tscvx_nn_status st = tscvx_nn_arena_size(blob, len, flags, &need);
        check_message(st);
        if (st != st_check) {
            FZ_FAIL("arena_size status %d, check_blob %d (%s)", (int)st, (int)st_check, why);
        }
        if (st != TSCVX_NN_OK) {
            if (need != 0) {
                FZ_FAIL("refused blob (status %d) sized %zu", (int)st, need);
            }
            continue;
        }
        if (need == 0 || need > ((size_t)1 << 30)) {
            FZ_FAIL("arena size %zu", need);
        }
        arena = (unsigned char *)malloc(need);
        if (!arena) {
            abort();
        }
        st = tscvx_nn_init(&net, arena, need - 1, blob, len, flags);
        if (st != TSCVX_NN_ARENA_TOO_SMALL || net) {
            FZ_FAIL("init in an arena a byte short: status %d", (int)st);
        }
        st = tscvx_nn_init(&net, arena, need, blob, len, flags);
        if (st != TSCVX_NN_OK || !net) {
            FZ_FAIL("init of a blob arena_size accepted: status %d", (int)st);
        }
        exercise(net, blob, len, flags, need);
        free(arena);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* heap copies: 8-byte aligned for the in-place mode, and ASan sees reads past the end */
    uint8_t *b = (uint8_t *)calloc(size ? size : 1, 1);
    if (!b) {
        abort();
    }
    if (size) {
        memcpy(b, data, size);
    }
    try_blob(b, size);
    if (size >= HEADER) {
        seal(b, size);
        try_blob(b, size);
    }
    free(b);
    return 0;
}
