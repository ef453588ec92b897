/*
 * tscvx_nn.h -- flight inference of the T-SCvx transformer networks (the constraint network:
 * theta (16) + iteration k -> 7N tight-constraint logits; the solution network: theta (16) ->
 * warm start (x (N x 14), u (N x 3), t_f)). The one public header of the network layer.
 *
 * The architecture is guidance/nn/model.py's, in general (any d_model, layers, heads,
 * feed-forward width, token mode, sequence length):
 *
 *   z   = (x - in_mean) * in_scale                               standardization (folded in)
 *   h_0 = E(z) + P            E: "single" token  h = W_e z + b_e   (L = 1 token of d_model)
 *                                "scalar" tokens h_i = z_i w_i + b_i (L = d_in tokens)
 *   for each layer (post-norm, torch.nn.TransformerEncoderLayer order):
 *       [q k v] = h W_qkv^T + b_qkv,  per head: a = softmax(q k^T / sqrt(d_model / heads))
 *       h = LN1(h + (a v) W_o^T + b_o)
 *       h = LN2(h + relu(h W_1^T + b_1) W_2^T + b_2)
 *   y   = (W_d vec(h) + b_d) * out_std + out_mean                 decoder, de-standardization
 *
 * With one token (L = 1) the attention weights are exactly 1 (softmax of one finite score), so
 * the attention output is v and q, k are not computed: the same numbers for a quarter fewer
 * multiply-adds. The weights are the exported float32 values stored as float64 (exactly; see
 * guidance/nn/flight.py for why), read in place from the model blob; every sum is in double.
 *
 * Model blob (".tnn", written by guidance/nn/flight.py from the shipped ONNX file; all fields
 * little-endian): a 128-byte header -- magic "TSCVXNN\0", format version, kind, token mode,
 * dimensions, LayerNorm epsilon, decision threshold, number of values, CRC-32 -- then float64
 * arrays: normalization (in_mean, in_scale, out_mean, out_std), encoder, positional encoding,
 * layers, decoder, self-test probes (inputs and the exporter's outputs), and the problem
 * parameters the network was trained for (tscvx_nn_info.params). The exact layout
 * is in c_runtime/nn/nn_internal.h and guidance/nn/flight.py.
 *
 * Lifecycle (memory is claimed in exactly one place, from ONE caller-provided arena):
 *
 *   1. tscvx_nn_arena_size(blob, len, flags, &bytes)   validates the blob (magic, version,
 *        sizes, CRC-32, input and output sizes against the kind and N, every weight finite,
 *        normalization scales positive) and sizes the arena
 *   2. tscvx_nn_init(&net, arena, bytes, blob, len, flags)   validates again, lays out the net
 *        and its activation buffers in the arena. Without TSCVX_NN_COPY_WEIGHTS the weights are
 *        read from the blob in place: the blob must stay valid and unchanged while the net is
 *        used, and be 8-byte aligned. With it (or on a host whose double byte order is not
 *        little-endian, e.g. a big-endian PowerPC) the weights are copied (byte-swapped if
 *        needed) into the arena.
 *   3. tscvx_nn_self_test(net, &max_err)   optional built-in test: runs the recorded probes
 *   4. tscvx_nn_run(net, input, n_in, output, n_out)   any number of times: no allocation, no
 *        recursion, every loop bounded by the dimensions checked at init. Inputs are checked
 *        (sizes, overlapping buffers, finite values); a non-finite result is reported, not
 *        returned as an answer.
 *   5. cleanup is trivial: the caller owns the arena (and the blob).
 *
 * Every function returns a tscvx_nn_status; tscvx_nn_status_message() says what it means.
 */
#ifndef TSCVX_NN_H
#define TSCVX_NN_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TSCVX_NN_FORMAT_VERSION 2u /* 2: the trained-for problem parameters recorded */
#define TSCVX_NN_HEADER_BYTES 128u
/* Limits checked at init (they bound every loop of tscvx_nn_run). */
#define TSCVX_NN_MAX_DIM 65536      /* d_in, d_out, d_model, d_ff */
#define TSCVX_NN_MAX_LAYERS 64
#define TSCVX_NN_MAX_HEADS 64
#define TSCVX_NN_MAX_PROBES 64
#define TSCVX_NN_MAX_PARAMS 256   /* trained-for problem parameters recorded */

/* Flags of tscvx_nn_arena_size / tscvx_nn_init. */
#define TSCVX_NN_COPY_WEIGHTS 1u /* copy the weights into the arena; the blob may be released */

typedef enum {
    TSCVX_NN_OK = 0,
    TSCVX_NN_NULL_ARGUMENT,    /* a required pointer is NULL */
    TSCVX_NN_BAD_MAGIC,        /* the blob is not a T-SCvx network (magic) */
    TSCVX_NN_BAD_VERSION,      /* unsupported format version or header size */
    TSCVX_NN_TRUNCATED,        /* the blob is shorter (or longer) than its header says, or
                                  shorter than the header (its bytes begin the magic) */
    TSCVX_NN_BAD_CHECKSUM,     /* CRC-32 mismatch: the blob is corrupt */
    TSCVX_NN_BAD_DIMENSIONS,   /* dimensions out of range or inconsistent with each other (the
                                  input and output sizes with the kind and N) */
    TSCVX_NN_BAD_WEIGHTS,      /* a weight or normalization value is NaN/inf or beyond the
                                  float32 range, a scale <= 0, or the threshold or LayerNorm
                                  epsilon is outside (0, 1) */
    TSCVX_NN_BAD_ALIGNMENT,    /* in-place weights need an 8-byte aligned blob */
    TSCVX_NN_ARENA_TOO_SMALL,  /* arena smaller than tscvx_nn_arena_size() */
    TSCVX_NN_NOT_READY,        /* the net was not initialized, or a field init fixed (a
                                  dimension, a weight pointer, the layer table) changed since:
                                  every call checks checksums of them. The weight values
                                  themselves (in the blob, or copied into the arena) only
                                  tscvx_nn_self_test checks */
    TSCVX_NN_BAD_SIZE,         /* n_in / n_out differ from the network's input / output size */
    TSCVX_NN_BAD_INPUT,        /* an input value is NaN or infinite */
    TSCVX_NN_NUMERICAL_ERROR,  /* the output is not finite (overflow inside the network) */
    TSCVX_NN_SELF_TEST_FAILED, /* the recorded probe outputs are not reproduced */
    TSCVX_NN_BAD_FLAGS,        /* unknown flag bits */
    TSCVX_NN_BAD_BUFFER,       /* buffers overlap: an input or output (of tscvx_nn_run,
                                  tscvx_nn_tight_mask) with the net's arena, an output with the
                                  input or the in-place blob, or (init) the blob with the arena */
    TSCVX_NN_NSTATUS
} tscvx_nn_status;

typedef enum {
    TSCVX_NN_KIND_CONSTRAINT = 1, /* theta + k -> 7N tight logits; tight when p >= threshold */
    TSCVX_NN_KIND_SOLUTION = 2    /* theta -> (x (N x 14), u (N x 3), t_f) */
} tscvx_nn_kind;

typedef enum {
    TSCVX_NN_TOKENS_SINGLE = 0, /* the whole input is one token (L = 1) */
    TSCVX_NN_TOKENS_SCALAR = 1  /* every input component is a token (L = d_in) */
} tscvx_nn_tokens;

/* What a network is (from its header). */
typedef struct {
    int kind;         /* tscvx_nn_kind */
    int tokens;       /* tscvx_nn_tokens */
    int d_in, d_out;  /* input and output sizes */
    int d_model, n_heads, n_layers, d_ff;
    int seq_len;      /* L: 1 (single) or d_in (scalar) */
    int N;            /* trajectory nodes the network was trained for */
    int n_probes;     /* self-test probes in the blob */
    double threshold; /* probability threshold of a tight bit (constraint network) */
    double ln_eps;    /* LayerNorm epsilon */
    size_t n_weights; /* values of the network (normalization included, probes not) */
    int n_params;     /* problem parameters the network was trained for, as recorded by the
                         exporter (guidance/nn/flight.py: every parameter that is not a
                         network input, in its order); the caller compares them */
    const double *params; /* n_params values, valid while the net is */
    size_t arena_bytes; /* the arena this net was sized for */
    int weights_in_arena; /* 1 when the weights were copied into the arena */
} tscvx_nn_info;

typedef struct tscvx_nn tscvx_nn; /* opaque, lives in the arena */

const char *tscvx_nn_status_message(tscvx_nn_status status);

/* Validates `blob` (len bytes) as tscvx_nn_init does and, when `message` is not NULL, writes
 * into it (TSCVX_NN_MESSAGE_LEN bytes) what is wrong, naming the field and its value
 * ("d_model = 300 is not a multiple of n_heads = 7"), or "ok". For a refused blob's report;
 * the status is the one tscvx_nn_arena_size and tscvx_nn_init return for the blob's content
 * (where the blob lies is theirs to check: an in-place blob not 8-byte aligned is
 * TSCVX_NN_BAD_ALIGNMENT from both). */
#define TSCVX_NN_MESSAGE_LEN 160
tscvx_nn_status tscvx_nn_check_blob(const void *blob, size_t len, char *message);

/* Validates `blob` (len bytes) as tscvx_nn_init does, but for the arena, and writes the arena
 * size it needs into *bytes (0 when refused). */
tscvx_nn_status tscvx_nn_arena_size(const void *blob, size_t len, unsigned flags, size_t *bytes);

/* Validates `blob` and builds the net in `arena` (any alignment; `arena_bytes` at least
 * tscvx_nn_arena_size()). On success *net points into the arena; on any refusal *net is NULL
 * (net itself NULL: TSCVX_NN_NULL_ARGUMENT, nothing written), as tscvx_setup and pdg_setup
 * leave their workspace pointer. The arena, all
 * `arena_bytes` of it, is the net's until the caller drops the net: a blob within it is
 * TSCVX_NN_BAD_BUFFER (init would write over the weights it reads). */
tscvx_nn_status tscvx_nn_init(tscvx_nn **net, void *arena, size_t arena_bytes, const void *blob,
                              size_t len, unsigned flags);

/* One inference: raw inputs (n_in = d_in values; theta (16) [+ k]) -> raw outputs (n_out =
 * d_out values: logits, or the physical warm start). A refused call leaves `output` untouched;
 * TSCVX_NN_NUMERICAL_ERROR (an entry not finite) sets every entry of it NaN: no part of it is
 * an answer. TSCVX_NN_BAD_INPUT for a non-finite input. TSCVX_NN_BAD_BUFFER when `input` or
 * `output` overlaps the arena given to tscvx_nn_init, `output` overlaps `input`, or `output`
 * overlaps the blob whose weights are read in place (writing there would change the
 * activations, the net or its weights; the input may lie in the blob, e.g. its probes). */
tscvx_nn_status tscvx_nn_run(tscvx_nn *net, const double *input, int n_in, double *output,
                             int n_out);

/* Mask of the tight bits from constraint-network logits: mask[i] = 1 when the probability
 * 1 / (1 + exp(-logit[i])) >= threshold, else 0 (the tscvx_guidance.h mask convention:
 * nonzero = keep). n = d_out. Rejects a solution network (TSCVX_NN_BAD_SIZE), NaN logits, and
 * buffers as tscvx_nn_run does (logits its input, mask its output: TSCVX_NN_BAD_BUFFER). */
tscvx_nn_status tscvx_nn_tight_mask(const tscvx_nn *net, const double *logits, int n,
                                    unsigned char *mask);

tscvx_nn_status tscvx_nn_get_info(const tscvx_nn *net, tscvx_nn_info *info);

/* The buffer rule of tscvx_nn_run and tscvx_nn_tight_mask alone, in bytes: TSCVX_NN_OK when
 * an inference reading `input` and writing `output` would take them, TSCVX_NN_BAD_BUFFER when
 * they overlap as those calls refuse. For a caller that fixes its buffers once and wants the
 * refusal before it starts (pdg_solve_tscvx checks its own this way). */
tscvx_nn_status tscvx_nn_check_buffers(const tscvx_nn *net, const void *input,
                                       size_t input_bytes, const void *output,
                                       size_t output_bytes);

/* Runs the probes recorded in the blob; *max_rel_err (may be NULL) = max |y - y_rec| /
 * max(1, |y_rec|). TSCVX_NN_SELF_TEST_FAILED above 1e-4 (the exporter's probe tolerance); for
 * a probe whose input, output or recorded output is not finite (a weight or probe value
 * damaged since init: max_rel_err infinite; it used to return NUMERICAL_ERROR or BAD_INPUT,
 * or pass a NaN recorded output); and for a blob that records no probe (max_rel_err NaN):
 * nothing tested is not a pass. Otherwise only TSCVX_NN_NULL_ARGUMENT and _NOT_READY. */
tscvx_nn_status tscvx_nn_self_test(tscvx_nn *net, double *max_rel_err);

#ifdef __cplusplus
}
#endif

#endif /* TSCVX_NN_H */
