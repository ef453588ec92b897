/*
 * host_io.h -- reading a weight file and building its network, for the host programs
 * (pdg_example.c, the budget drivers, test_nn.c). Host tooling, not flight code: the flight
 * library never touches files; its user hands tscvx_nn_init the bytes, wherever they live.
 */
#ifndef TSCVX_HOST_IO_H
#define TSCVX_HOST_IO_H

#include <stdio.h>
#include <stdlib.h>

#include "tscvx_nn.h"

/* The whole file in one malloc block (8-byte aligned, as in-place weights need), or NULL. */
static inline unsigned char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0
        && (buf = malloc((size_t)n)) != NULL) {
        if (fread(buf, 1, (size_t)n, f) != (size_t)n) {
            free(buf);
            buf = NULL;
        } else {
            *len = (size_t)n;
        }
    }
    fclose(f);
    return buf;
}

/* Reads a weight file into `*blob` and builds the network in its own arena `*arena` of
 * `*bytes` (tscvx_nn_arena_size). The caller frees both. 0 = ok, else a message on stderr. */
static inline int load_net(const char *path, unsigned char **blob, size_t *len, void **arena,
                           size_t *bytes, tscvx_nn **net)
{
    tscvx_nn_status st;
    *arena = NULL;
    if (!(*blob = read_file(path, len))) {
        fprintf(stderr, "%s: cannot read\n", path);
        return 1;
    }
    st = tscvx_nn_arena_size(*blob, *len, 0u, bytes);
    if (st == TSCVX_NN_OK) {
        *arena = malloc(*bytes);
        st = *arena ? tscvx_nn_init(net, *arena, *bytes, *blob, *len, 0u)
                    : TSCVX_NN_ARENA_TOO_SMALL;
    }
    if (st != TSCVX_NN_OK) {
        char why[TSCVX_NN_MESSAGE_LEN] = "";
        if (tscvx_nn_check_blob(*blob, *len, why) == st) { /* the blob itself: say where */
            fprintf(stderr, "%s: %s (%s)\n", path, tscvx_nn_status_message(st), why);
        } else {
            fprintf(stderr, "%s: %s\n", path, tscvx_nn_status_message(st));
        }
        return 1;
    }
    return 0;
}

#endif
