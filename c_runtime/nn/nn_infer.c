/*
 * nn_infer.c -- one forward pass of the transformer (tscvx_nn.h has the equations).
 *
 * Plain scalar C in double. All loops run over dimensions fixed and bounded at init; no
 * allocation, no recursion. The matrix-vector product is the hot spot (about 97 % of the
 * instructions): each output row is a dot product of a contiguous weight row with the input,
 * unrolled by eight into four partial sums so that the loop overhead stays small on a scalar
 * FPU (load, multiply, add per weight, and 4 loop instructions per 8 weights).
 */
#include <math.h>

#include "nn_internal.h"

/* sum_j w[j] x[j] */
static double dot_wx(const double *w, const double *x, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int j = 0;
    for (; j + 8 <= n; j += 8) {
        s0 += w[j] * x[j];
        s1 += w[j + 1] * x[j + 1];
        s2 += w[j + 2] * x[j + 2];
        s3 += w[j + 3] * x[j + 3];
        s0 += w[j + 4] * x[j + 4];
        s1 += w[j + 5] * x[j + 5];
        s2 += w[j + 6] * x[j + 6];
        s3 += w[j + 7] * x[j + 7];
    }
    for (; j < n; ++j) {
        s0 += w[j] * x[j];
    }
    return (s0 + s1) + (s2 + s3);
}

/* y = W x + b, W [n_out][n_in] row-major (torch.nn.Linear's weight). */
static void linear(const double *W, const double *b, const double *x, int n_out, int n_in,
                   double *y)
{
    int r;
    for (r = 0; r < n_out; ++r) {
        y[r] = b[r] + dot_wx(W + (size_t)r * n_in, x, n_in);
    }
}

/* sum_j a[j] b[j] (attention scores) */
static double dot_dd(const double *a, const double *b, int n)
{
    double s = 0.0;
    int j;
    for (j = 0; j < n; ++j) {
        s += a[j] * b[j];
    }
    return s;
}

/* y = (x - mean(x)) / sqrt(var(x) + eps) * g + b   (biased variance, as torch.nn.LayerNorm) */
static void layer_norm(const double *x, const double *g, const double *b, int n, double eps,
                       double *y)
{
    double mean = 0.0, var = 0.0, inv;
    int i;
    for (i = 0; i < n; ++i) {
        mean += x[i];
    }
    mean /= n;
    for (i = 0; i < n; ++i) {
        var += (x[i] - mean) * (x[i] - mean);
    }
    /* a variance past the double range (inputs near 1e154) would give inv = 0 and the bias
     * alone, whatever the input: NaN instead, which tscvx_nn_run reports */
    inv = isfinite(var) ? 1.0 / sqrt(var / n + eps) : (double)NAN;
    for (i = 0; i < n; ++i) {
        y[i] = (x[i] - mean) * inv * g[i] + b[i];
    }
}

/* o = concat_heads softmax(q k^T / sqrt(dh)) v for all L tokens (qkv: L x 3d). */
static void attention(tscvx_nn *net)
{
    const int L = net->L, d = net->d, dh = d / net->heads;
    const double scale = sqrt((double)dh);
    int hh, i, j, c;
    for (hh = 0; hh < net->heads; ++hh) {
        for (i = 0; i < L; ++i) {
            const double *q = net->qkv + (size_t)i * 3 * d + hh * dh;
            double *o = net->o + (size_t)i * d + hh * dh;
            double mx, sum = 0.0;
            for (j = 0; j < L; ++j) {
                net->sc[j] = dot_dd(q, net->qkv + (size_t)j * 3 * d + d + hh * dh, dh) / scale;
            }
            mx = net->sc[0];
            for (j = 1; j < L; ++j) {
                mx = net->sc[j] > mx ? net->sc[j] : mx;
            }
            for (j = 0; j < L; ++j) {
                net->sc[j] = exp(net->sc[j] - mx);
                sum += net->sc[j];
            }
            for (c = 0; c < dh; ++c) {
                o[c] = 0.0;
            }
            for (j = 0; j < L; ++j) {
                const double a = net->sc[j] / sum;
                const double *v = net->qkv + (size_t)j * 3 * d + 2 * d + hh * dh;
                for (c = 0; c < dh; ++c) {
                    o[c] += a * v[c];
                }
            }
        }
    }
}

/* One post-norm encoder layer on the token states net->h (L x d). */
static void encoder_layer(tscvx_nn *net, const nn_layer *ly)
{
    const int L = net->L, d = net->d;
    const double eps = net->hdr.ln_eps;
    int i, c;
    if (L == 1) {
        /* softmax over one (finite) score is exactly 1: the attention output is v */
        linear(ly->W_qkv + (size_t)2 * d * d, ly->b_qkv + 2 * d, net->h, d, d, net->o);
    } else {
        for (i = 0; i < L; ++i) {
            linear(ly->W_qkv, ly->b_qkv, net->h + (size_t)i * d, 3 * d, d,
                   net->qkv + (size_t)i * 3 * d);
        }
        attention(net);
    }
    for (i = 0; i < L; ++i) {
        double *h = net->h + (size_t)i * d;
        /* h = LN1(h + W_o o + b_o) */
        linear(ly->W_o, ly->b_o, net->o + (size_t)i * d, d, d, net->t);
        for (c = 0; c < d; ++c) {
            net->t[c] += h[c];
        }
        layer_norm(net->t, ly->ln1_g, ly->ln1_b, d, eps, h);
        /* h = LN2(h + W_2 relu(W_1 h + b_1) + b_2) */
        linear(ly->W_1, ly->b_1, h, net->ff, d, net->f);
        for (c = 0; c < net->ff; ++c) {
            net->f[c] = net->f[c] < 0.0 ? 0.0 : net->f[c]; /* a NaN stays NaN (reported) */
        }
        linear(ly->W_2, ly->b_2, net->f, d, net->ff, net->t);
        for (c = 0; c < d; ++c) {
            net->t[c] += h[c];
        }
        layer_norm(net->t, ly->ln2_g, ly->ln2_b, d, eps, h);
    }
}

static void nn_forward(tscvx_nn *net, const double *input, double *output)
{
    const int L = net->L, d = net->d;
    int i, c, l;
    for (i = 0; i < net->d_in; ++i) { /* standardization folded into the network */
        net->z[i] = (input[i] - net->in_mean[i]) * net->in_scale[i];
    }
    if (net->hdr.tokens == TSCVX_NN_TOKENS_SINGLE) {
        linear(net->enc_w, net->enc_b, net->z, d, net->d_in, net->h);
    } else {
        for (i = 0; i < L; ++i) {
            for (c = 0; c < d; ++c) {
                const size_t k = (size_t)i * d + c;
                net->h[k] = net->z[i] * net->enc_w[k] + net->enc_b[k];
            }
        }
    }
    for (i = 0; i < L * d; ++i) { /* learned positional encoding */
        net->h[i] += net->pos[i];
    }
    for (l = 0; l < net->n_layers; ++l) {
        encoder_layer(net, &net->layers[l]);
    }
    linear(net->W_d, net->b_d, net->h, net->d_out, L * d, output);
    for (i = 0; i < net->d_out; ++i) { /* de-standardization */
        output[i] = output[i] * net->out_std[i] + net->out_mean[i];
    }
}

tscvx_nn_status nn_run(tscvx_nn *net, const double *input, double *output)
{
    int i;
    for (i = 0; i < net->d_in; ++i) {
        if (!isfinite(input[i])) {
            return TSCVX_NN_BAD_INPUT;
        }
    }
    nn_forward(net, input, output);
    for (i = 0; i < net->d_out; ++i) {
        if (!isfinite(output[i])) {
            break;
        }
    }
    if (i < net->d_out) { /* not an answer: no entry of it left to be taken for one */
        for (i = 0; i < net->d_out; ++i) {
            output[i] = (double)NAN;
        }
        return TSCVX_NN_NUMERICAL_ERROR;
    }
    return TSCVX_NN_OK;
}

int nn_overlap(uintptr_t a, size_t na, uintptr_t b, size_t nb)
{
    return a <= b ? b - a < na : a - b < nb;
}

int nn_buffers_apart(const tscvx_nn *net, const void *input, size_t n_in, const void *output,
                     size_t n_out)
{
    const uintptr_t in = (uintptr_t)input, out = (uintptr_t)output;
    const uintptr_t blob = (uintptr_t)net->in_mean - TSCVX_NN_HEADER_BYTES;
    const size_t blob_len = TSCVX_NN_HEADER_BYTES + sizeof(double) * (size_t)net->hdr.n_values;
    if (nn_overlap(in, n_in, net->arena_at, net->arena_len) ||
        nn_overlap(out, n_out, net->arena_at, net->arena_len) ||
        nn_overlap(out, n_out, in, n_in)) {
        return 0;
    }
    return net->weights_in_arena || !nn_overlap(out, n_out, blob, blob_len);
}

tscvx_nn_status tscvx_nn_check_buffers(const tscvx_nn *net, const void *input,
                                       size_t input_bytes, const void *output,
                                       size_t output_bytes)
{
    if (!net || !input || !output) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    if (!nn_live(net)) {
        return TSCVX_NN_NOT_READY;
    }
    return nn_buffers_apart(net, input, input_bytes, output, output_bytes) ? TSCVX_NN_OK
                                                                            : TSCVX_NN_BAD_BUFFER;
}

tscvx_nn_status tscvx_nn_run(tscvx_nn *net, const double *input, int n_in, double *output,
                             int n_out)
{
    if (!net || !input || !output) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    if (!nn_live(net)) {
        return TSCVX_NN_NOT_READY;
    }
    if (n_in != net->d_in || n_out != net->d_out) {
        return TSCVX_NN_BAD_SIZE;
    }
    if (!nn_buffers_apart(net, input, sizeof(double) * (size_t)n_in, output,
                          sizeof(double) * (size_t)n_out)) {
        return TSCVX_NN_BAD_BUFFER;
    }
    return nn_run(net, input, output);
}
