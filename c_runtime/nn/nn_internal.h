/*
 * nn_internal.h -- the model blob layout and the net's arena layout (private to c_runtime/nn).
 *
 * Blob (".tnn", format version 2; every field little-endian; guidance/nn/flight.py writes it):
 *
 *   offset  type      field
 *   0       char[8]   magic "TSCVXNN\0"
 *   8       u32       format version (2)
 *   12      u32       header bytes (128)
 *   16      u32       kind (1 constraint, 2 solution)
 *   20      u32       tokens (0 single, 1 scalar)
 *   24      u32 x 8   d_in, d_out, d_model, n_heads, n_layers, d_ff, seq_len, N
 *   56      u32       n_probes
 *   60      u32       n_params: trained-for problem parameters (at the end of the values)
 *   64      f64       LayerNorm epsilon
 *   72      f64       threshold (probability of a tight bit; 0.5 for a solution network)
 *   80      u64       n_values: float64 values after the header (weights, probes, params)
 *   88      u64       n_weights: of which network values (normalization included)
 *   96      u8 x 28   reserved (0; a blob with other bytes there is refused as a format
 *                     this library does not know)
 *   124     u32       CRC-32 (IEEE 802.3, zlib's crc32) of bytes [0, 124) and [128, end)
 *   128     f64 x n_values, in this order (matrices row-major, [out][in] as torch.nn.Linear):
 *           in_mean [d_in], in_scale [d_in] (= 1 / in_std), out_mean [d_out], out_std [d_out]
 *           encoder   single: W_e [d_model][d_in], b_e [d_model]
 *                     scalar: w [L][d_model], b [L][d_model]
 *           pos [L][d_model]
 *           per layer: W_qkv [3 d_model][d_model], b_qkv [3 d_model],
 *                      W_o [d_model][d_model], b_o [d_model], ln1 gamma, beta [d_model],
 *                      W_1 [d_ff][d_model], b_1 [d_ff], W_2 [d_model][d_ff], b_2 [d_model],
 *                      ln2 gamma, beta [d_model]
 *           decoder W_d [d_out][L d_model], b_d [d_out]
 *           probes: inputs [n_probes][d_in], recorded outputs [n_probes][d_out]
 *           params [n_params]: the problem parameters the network was trained for
 */
#ifndef TSCVX_NN_INTERNAL_H
#define TSCVX_NN_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "tscvx_nn.h"

#define NN_MAGIC "TSCVXNN"     /* 7 characters + NUL = 8 bytes */
#define NN_CRC_OFFSET 124u
#define NN_COOKIE 0x544E4E31u  /* "TNN1": set by init, checked by every call */
#define NN_SELF_TEST_TOL 1e-4
/* Sizes the kind fixes (tscvx_nn_kind; guidance.nn.infer.expected_sizes): theta (16 numbers)
 * in, with the iteration k for a constraint network; out 7 tight-constraint logits per node,
 * or per node x (14) and u (3), then t_f. */
#define NN_THETA_LEN 16u
#define NN_TIGHT_PER_NODE 7u
#define NN_SOLUTION_PER_NODE 17u

/* Header fields, decoded. */
typedef struct {
    uint32_t version, header_bytes, kind, tokens;
    uint32_t d_in, d_out, d_model, n_heads, n_layers, d_ff, seq_len, N, n_probes, n_params;
    double ln_eps, threshold;
    uint64_t n_values, n_weights;
} nn_header;

/* Weights of one encoder layer (pointers into the weights). */
typedef struct {
    const double *W_qkv, *b_qkv; /* 3d x d, 3d */
    const double *W_o, *b_o;     /* d x d, d */
    const double *ln1_g, *ln1_b; /* d, d */
    const double *W_1, *b_1;     /* ff x d, ff */
    const double *W_2, *b_2;     /* d x ff, d */
    const double *ln2_g, *ln2_b; /* d, d */
} nn_layer;

struct tscvx_nn {
    uint32_t cookie;
    nn_header hdr;
    int d_in, d_out, d, heads, n_layers, ff, L;
    size_t arena_bytes;
    uintptr_t arena_at; /* the caller's arena [arena_at, arena_at + arena_len): the buffers of */
    size_t arena_len;   /* tscvx_nn_run must lie outside it (integers: no pointer comparison) */
    int weights_in_arena;
    /* weights (in the blob or in the arena) */
    const double *in_mean, *in_scale, *out_mean, *out_std; /* d_in, d_in, d_out, d_out */
    const double *enc_w, *enc_b; /* single: d x d_in, d; scalar: L x d, L x d */
    const double *pos;           /* L x d */
    nn_layer *layers;           /* n_layers entries, in the arena */
    const double *W_d, *b_d;     /* d_out x (L d), d_out */
    const double *probe_in, *probe_out; /* n_probes x d_in, n_probes x d_out */
    const double *params;               /* n_params: trained-for problem parameters */
    /* activations (double, in the arena) */
    double *z;   /* d_in: standardized input */
    double *h;   /* L x d: token states */
    double *qkv; /* L x 3d */
    double *o;   /* L x d: attention output (concatenated heads) */
    double *t;   /* d: pre-LayerNorm sum of one token */
    double *f;   /* ff: feed-forward hidden of one token */
    double *sc;  /* L: attention scores of one query */
    double *xb;  /* d_in: self-test input */
    double *yb;  /* d_out: self-test output */
    uint64_t layout_sum; /* FNV-1a of everything above (nn_live) */
    uint64_t table_sum;  /* FNV-1a of the layer table (its pointers), read once layout_sum
                            has vouched for n_layers */
};

/* The net is initialized (cookie) and nothing init fixed has changed since (the checksums):
 * every field of the net is set by init and read-only after it, so a bit flipped in a
 * dimension or a pointer is refused instead of followed. */
int nn_live(const tscvx_nn *net);
uint64_t nn_layout_sum(const tscvx_nn *net);
uint64_t nn_table_sum(const tscvx_nn *net);

/* nn_blob.c: decodes and validates a blob (magic, version, sizes, CRC-32, input and output
 * sizes against the kind and N, finite weights, positive scales); `why` (NULL, or
 * TSCVX_NN_MESSAGE_LEN bytes) receives what is wrong, naming the field and its value. */
tscvx_nn_status nn_parse(const void *blob, size_t len, nn_header *hdr, char *why);
/* Float32 values of the network (normalization included) for the given dimensions, or 0
 * when a size overflows. */
size_t nn_count_weights(const nn_header *hdr);
int nn_host_is_little_endian(void);
uint32_t nn_crc32(const unsigned char *p, size_t n, uint32_t crc);

/* nn_infer.c: one inference of a live net whose sizes and buffers were checked (by
 * tscvx_nn_run, or the self-test's own buffers in the arena): the input's and the output's
 * values checked, BAD_INPUT or NUMERICAL_ERROR. */
tscvx_nn_status nn_run(tscvx_nn *net, const double *input, double *output);
/* [a, a + na) and [b, b + nb) share a byte (no sum formed: none can wrap). */
int nn_overlap(uintptr_t a, size_t na, uintptr_t b, size_t nb);
/* The caller's buffers of one call (n_in, n_out bytes) lie apart: input and output outside the
 * arena (the net, its activations, copied weights: written while the input is read), the
 * output apart from the input and from a blob whose weights are read in place (it must stay
 * unchanged while the net is used). The input may lie in the blob: both are only read. */
int nn_buffers_apart(const tscvx_nn *net, const void *input, size_t n_in, const void *output,
                     size_t n_out);

#endif /* TSCVX_NN_INTERNAL_H */
