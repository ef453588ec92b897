/*
 * nn_blob.c -- model blob validation and the net's set-up in the caller's arena.
 *
 * Everything that can be wrong with a model is found here, before any inference: magic,
 * version, header size, dimensions (range, consistency, sizes that overflow, the input and
 * output sizes against the kind and N), the blob's length against its header, the CRC-32,
 * non-finite values, non-positive scales.
 */
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "nn_internal.h"
#include "tscvx_fnv1a.h"

static const char *const status_messages[TSCVX_NN_NSTATUS] = {
    "ok",
    "a required pointer argument is NULL",
    "not a T-SCvx network blob (bad magic)",
    "unsupported network blob format version or header size",
    "network blob length does not match its header (truncated or trailing bytes)",
    "network blob checksum (CRC-32) mismatch: the blob is corrupt",
    "network dimensions out of range or inconsistent (token mode, sequence length, heads, or "
    "input/output sizes that do not fit the kind and N)",
    "network blob holds a NaN/inf value or one beyond the float32 range, a non-positive "
    "normalization scale, or a decision "
    "threshold or LayerNorm epsilon outside (0, 1)",
    "in-place weights need an 8-byte aligned blob (or the TSCVX_NN_COPY_WEIGHTS flag)",
    "arena smaller than tscvx_nn_arena_size()",
    "network not initialized (tscvx_nn_init) or its arena was overwritten",
    "input or output size differs from the network's",
    "an input value is NaN or infinite",
    "the network output is not finite (overflow inside the network)",
    "self-test failed: the recorded probe outputs are not reproduced",
    "unknown flag bits",
    "overlapping buffers: an input or output in the network's arena, the output over the "
    "input or the blob read in place, or the blob in the arena",
};

const char *tscvx_nn_status_message(tscvx_nn_status status)
{
    if ((int)status < 0 || status >= TSCVX_NN_NSTATUS) {
        return "unknown tscvx_nn_status";
    }
    return status_messages[status];
}

/* ---- little-endian field access (any host byte order, any alignment) --------------------- */

static uint32_t rd_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint64_t rd_u64(const unsigned char *p)
{
    return (uint64_t)rd_u32(p) | ((uint64_t)rd_u32(p + 4) << 32);
}

static double rd_f64(const unsigned char *p)
{
    uint64_t u = rd_u64(p);
    double v;
    memcpy(&v, &u, sizeof v); /* IEEE 754 binary64 with the integers' byte order */
    return v;
}

/* 1 when the host stores a double as the blob does (IEEE 754 binary64, little-endian), so the
 * weights can be read in place. */
int nn_host_is_little_endian(void)
{
    const double one = 1.0; /* 0x3FF0000000000000 */
    static const unsigned char le[8] = {0, 0, 0, 0, 0, 0, 0xF0, 0x3F};
    unsigned char b[8];
    memcpy(b, &one, sizeof b);
    return memcmp(b, le, sizeof b) == 0;
}

/* CRC-32 (reflected polynomial 0xEDB88320, as zlib.crc32); `crc` = 0 to start, or a previous
 * result to continue. The 1 KB table is built on the stack per call (init only). */
uint32_t nn_crc32(const unsigned char *p, size_t n, uint32_t crc)
{
    uint32_t table[256];
    uint32_t i, k, c;
    size_t j;
    for (i = 0; i < 256u; ++i) {
        c = i;
        for (k = 0; k < 8u; ++k) {
            c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        }
        table[i] = c;
    }
    crc = ~crc;
    for (j = 0; j < n; ++j) {
        crc = table[(crc ^ p[j]) & 0xFFu] ^ (crc >> 8);
    }
    return ~crc;
}

/* ---- sizes ------------------------------------------------------------------------------- */

/* a * b + c, setting *overflow when it does not fit in size_t. */
static size_t mad(size_t a, size_t b, size_t c, int *overflow)
{
    if (a != 0 && b > ((size_t)-1 - c) / a) {
        *overflow = 1;
        return 0;
    }
    return a * b + c;
}

size_t nn_count_weights(const nn_header *hd)
{
    /* dimensions are at most TSCVX_NN_MAX_DIM (2^16) here, so the small sums cannot overflow;
     * the products can on a 32-bit size_t */
    size_t d = hd->d_model, L = hd->seq_len, ff = hd->d_ff, din = hd->d_in, dout = hd->d_out;
    int ovf = 0;
    size_t norm = 2 * din + 2 * dout;
    size_t enc = hd->tokens == TSCVX_NN_TOKENS_SINGLE ? mad(d, din, d, &ovf)
                                                      : mad(2 * L, d, 0, &ovf);
    size_t pos = mad(L, d, 0, &ovf);
    /* W_qkv + W_o (4 d^2), W_1 + W_2 (2 ff d); b_qkv, b_o, 2 LN, b_1, b_2, 2 LN (9 d + ff) */
    size_t layer = mad(2 * ff, d, mad(4 * d, d, 9 * d + ff, &ovf), &ovf);
    size_t layers = mad(layer, hd->n_layers, 0, &ovf);
    size_t dec = mad(dout, mad(L, d, 0, &ovf), dout, &ovf);
    size_t total = mad(1, mad(1, mad(1, norm + enc, pos, &ovf), layers, &ovf), dec, &ovf);
    return ovf ? 0 : total;
}

static int in_range(uint32_t v, uint32_t lo, uint32_t hi) { return v >= lo && v <= hi; }

/* The input and output sizes of a valid kind for its N: a header edited along with its CRC
 * must not pass (a solution network's outputs taken for logits, N not the one trained for). */
static int sizes_fit_kind(const nn_header *hd)
{
    const uint64_t N = hd->N;
    if (hd->kind == TSCVX_NN_KIND_CONSTRAINT) {
        return hd->d_in == NN_THETA_LEN + 1u && hd->d_out == NN_TIGHT_PER_NODE * N;
    }
    return hd->d_in == NN_THETA_LEN && hd->d_out == NN_SOLUTION_PER_NODE * N + 1u;
}

/* Non-finite binary64 bit pattern: exponent all ones. Positive: sign clear, not zero. */
static int f64_bits_finite(uint64_t u) { return ((u >> 52) & 0x7FFu) != 0x7FFu; }
/* |x| < 2^128 (biased exponent <= 1023 + 127): every float32 value the exporter writes is;
 * a larger one is a damaged or crafted blob. (Sums may still overflow: tscvx_nn_run reports
 * a non-finite output.) */
static int f64_bits_float32_range(uint64_t u) { return ((u >> 52) & 0x7FFu) <= 1150u; }
static int f64_bits_positive(uint64_t u)
{
    return !(u >> 63) && (u & 0x7FFFFFFFFFFFFFFFull) != 0;
}

/* Writes what is wrong into why (NN_WHY_LEN bytes, may be NULL) and returns the status. */
static tscvx_nn_status refuse(char *why, tscvx_nn_status st, const char *fmt, ...)
{
    va_list ap;
    if (why) {
        va_start(ap, fmt);
        vsnprintf(why, TSCVX_NN_MESSAGE_LEN, fmt, ap);
        va_end(ap);
    }
    return st;
}

/* The header's dimensions, each with its range: the first one outside is named. */
static tscvx_nn_status check_dimensions(const nn_header *hd, char *why)
{
    const struct {
        const char *name;
        uint32_t value, lo, hi;
    } dims[] = {
        {"d_in", hd->d_in, 1, TSCVX_NN_MAX_DIM},
        {"d_out", hd->d_out, 1, TSCVX_NN_MAX_DIM},
        {"d_model", hd->d_model, 1, TSCVX_NN_MAX_DIM},
        {"d_ff", hd->d_ff, 1, TSCVX_NN_MAX_DIM},
        {"n_heads", hd->n_heads, 1, TSCVX_NN_MAX_HEADS},
        {"n_layers", hd->n_layers, 0, TSCVX_NN_MAX_LAYERS},
        {"n_probes", hd->n_probes, 0, TSCVX_NN_MAX_PROBES},
        {"N", hd->N, 1, 1u << 20},
        {"n_params", hd->n_params, 0, TSCVX_NN_MAX_PARAMS},
    };
    const uint32_t seq_len = hd->tokens == TSCVX_NN_TOKENS_SINGLE ? 1u : hd->d_in;
    size_t i;
    if (hd->kind != TSCVX_NN_KIND_CONSTRAINT && hd->kind != TSCVX_NN_KIND_SOLUTION) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS,
                      "kind %u is neither 1 (constraint) nor 2 (solution)", hd->kind);
    }
    if (hd->tokens != TSCVX_NN_TOKENS_SINGLE && hd->tokens != TSCVX_NN_TOKENS_SCALAR) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS,
                      "tokens %u is neither 0 (single) nor 1 (scalar)", hd->tokens);
    }
    for (i = 0; i < sizeof dims / sizeof dims[0]; ++i) {
        if (!in_range(dims[i].value, dims[i].lo, dims[i].hi)) {
            return refuse(why, TSCVX_NN_BAD_DIMENSIONS, "%s = %u is outside %u..%u",
                          dims[i].name, dims[i].value, dims[i].lo, dims[i].hi);
        }
    }
    if (!sizes_fit_kind(hd)) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS,
                      "d_in = %u, d_out = %u do not fit a %s network of N = %u", hd->d_in,
                      hd->d_out, hd->kind == TSCVX_NN_KIND_CONSTRAINT ? "constraint" : "solution",
                      hd->N);
    }
    if (hd->d_model % hd->n_heads != 0) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS, "d_model = %u is not a multiple of n_heads = %u",
                      hd->d_model, hd->n_heads);
    }
    if (hd->seq_len != seq_len) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS, "seq_len = %u, its token mode gives %u",
                      hd->seq_len, seq_len);
    }
    if ((uint64_t)hd->seq_len * 3u * hd->d_model > (uint64_t)INT_MAX) { /* int indices */
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS, "seq_len x 3 d_model exceeds INT_MAX");
    }
    return TSCVX_NN_OK;
}

/* Magic, header length and format: what must hold before any other field is read. Leaves hd
 * zeroed but for version and header_bytes. */
static tscvx_nn_status check_format(const unsigned char *p, size_t len, nn_header *hd, char *why)
{
    /* fewer than 8 bytes that begin the magic are a cut-off blob, not a foreign one */
    if (memcmp(p, NN_MAGIC, len < 8 ? len : 8) != 0) {
        return refuse(why, TSCVX_NN_BAD_MAGIC,
                      "the first %zu bytes are not those of \"TSCVXNN\\0\"",
                      len < 8 ? len : (size_t)8);
    }
    if (len < TSCVX_NN_HEADER_BYTES) {
        return refuse(why, TSCVX_NN_TRUNCATED, "%zu bytes, shorter than the %s%u-byte header",
                      len, len < 8 ? "8-byte magic and the " : "", TSCVX_NN_HEADER_BYTES);
    }
    memset(hd, 0, sizeof *hd);
    hd->version = rd_u32(p + 8);
    hd->header_bytes = rd_u32(p + 12);
    if (hd->version != TSCVX_NN_FORMAT_VERSION || hd->header_bytes != TSCVX_NN_HEADER_BYTES) {
        return refuse(why, TSCVX_NN_BAD_VERSION,
                      "format %u with a %u-byte header; this library reads format %u, %u bytes",
                      hd->version, hd->header_bytes, TSCVX_NN_FORMAT_VERSION,
                      TSCVX_NN_HEADER_BYTES);
    }
    return TSCVX_NN_OK;
}

/* The fields after version and header size (offsets: nn_internal.h), not yet checked. */
static void read_fields(const unsigned char *p, nn_header *hd)
{
    hd->kind = rd_u32(p + 16);
    hd->tokens = rd_u32(p + 20);
    hd->d_in = rd_u32(p + 24);
    hd->d_out = rd_u32(p + 28);
    hd->d_model = rd_u32(p + 32);
    hd->n_heads = rd_u32(p + 36);
    hd->n_layers = rd_u32(p + 40);
    hd->d_ff = rd_u32(p + 44);
    hd->seq_len = rd_u32(p + 48);
    hd->N = rd_u32(p + 52);
    hd->n_probes = rd_u32(p + 56);
    hd->n_params = rd_u32(p + 60);
    hd->ln_eps = rd_f64(p + 64);
    hd->threshold = rd_f64(p + 72);
    hd->n_values = rd_u64(p + 80);
    hd->n_weights = rd_u64(p + 88);
}

/* Length first (a truncated blob says so, whatever its other fields), then the CRC, then the
 * reserved bytes (a corrupt blob is reported as corrupt, not as a later format). */
static tscvx_nn_status check_integrity(const unsigned char *p, size_t len, const nn_header *hd,
                                       char *why)
{
    uint32_t crc;
    size_t i;
    if (hd->n_values > ((uint64_t)(size_t)-1 - TSCVX_NN_HEADER_BYTES) / 8u
        || (uint64_t)len != TSCVX_NN_HEADER_BYTES + 8u * hd->n_values) {
        return refuse(why, TSCVX_NN_TRUNCATED, "%zu bytes; n_values = %llu asks for %u + 8 x %llu",
                      len, (unsigned long long)hd->n_values, TSCVX_NN_HEADER_BYTES,
                      (unsigned long long)hd->n_values);
    }
    crc = nn_crc32(p, NN_CRC_OFFSET, 0);
    crc = nn_crc32(p + TSCVX_NN_HEADER_BYTES, len - TSCVX_NN_HEADER_BYTES, crc);
    if (crc != rd_u32(p + NN_CRC_OFFSET)) {
        return refuse(why, TSCVX_NN_BAD_CHECKSUM, "CRC-32 of the blob is %08x, its header says %08x",
                      (unsigned)crc, (unsigned)rd_u32(p + NN_CRC_OFFSET));
    }
    for (i = 96; i < NN_CRC_OFFSET; ++i) { /* reserved: a later format's fields */
        if (p[i] != 0) {
            return refuse(why, TSCVX_NN_BAD_VERSION,
                          "reserved header byte %zu is %u: a later format's field", i,
                          (unsigned)p[i]);
        }
    }
    return TSCVX_NN_OK;
}

/* The value counts against the (checked) dimensions, then epsilon and threshold. */
static tscvx_nn_status check_counts(const nn_header *hd, char *why)
{
    const size_t n_weights = nn_count_weights(hd);
    const size_t n_probe_vals = (size_t)hd->n_probes * ((size_t)hd->d_in + hd->d_out);
    if (n_weights == 0 || hd->n_weights != (uint64_t)n_weights) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS, "n_weights = %llu, the dimensions give %zu",
                      (unsigned long long)hd->n_weights, n_weights);
    }
    if (hd->n_values != (uint64_t)n_weights + n_probe_vals + hd->n_params) {
        return refuse(why, TSCVX_NN_BAD_DIMENSIONS,
                      "n_values = %llu, weights, probes and parameters give %zu",
                      (unsigned long long)hd->n_values, n_weights + n_probe_vals + hd->n_params);
    }
    if (!(hd->ln_eps > 0.0 && hd->ln_eps < 1.0)) {
        return refuse(why, TSCVX_NN_BAD_WEIGHTS, "ln_eps = %g is outside (0, 1)", hd->ln_eps);
    }
    if (!(hd->threshold > 0.0 && hd->threshold < 1.0)) {
        return refuse(why, TSCVX_NN_BAD_WEIGHTS, "threshold = %g is outside (0, 1)",
                      hd->threshold);
    }
    return TSCVX_NN_OK;
}

/* The values after the header (w): all finite; in_scale and out_std positive. */
static tscvx_nn_status check_values(const unsigned char *w, const nn_header *hd, char *why)
{
    const size_t n_values = (size_t)hd->n_values;
    size_t i;
    for (i = 0; i < n_values; ++i) {
        if (!f64_bits_finite(rd_u64(w + 8 * i))) {
            return refuse(why, TSCVX_NN_BAD_WEIGHTS, "value %zu of %zu is NaN or infinite", i,
                          n_values);
        }
        if (!f64_bits_float32_range(rd_u64(w + 8 * i))) {
            return refuse(why, TSCVX_NN_BAD_WEIGHTS,
                          "value %zu of %zu = %g is beyond the float32 range the exporter "
                          "writes (|x| < 2^128)",
                          i, n_values, rd_f64(w + 8 * i));
        }
    }
    for (i = 0; i < hd->d_in; ++i) { /* in_scale */
        if (!f64_bits_positive(rd_u64(w + 8 * (hd->d_in + i)))) {
            return refuse(why, TSCVX_NN_BAD_WEIGHTS, "in_scale[%zu] = %g is not positive", i,
                          rd_f64(w + 8 * (hd->d_in + i)));
        }
    }
    for (i = 0; i < hd->d_out; ++i) { /* out_std */
        const size_t k = 2 * (size_t)hd->d_in + hd->d_out + i;
        if (!f64_bits_positive(rd_u64(w + 8 * k))) {
            return refuse(why, TSCVX_NN_BAD_WEIGHTS, "out_std[%zu] = %g is not positive", i,
                          rd_f64(w + 8 * k));
        }
    }
    return TSCVX_NN_OK;
}

/* The checks in the order the refusals are reported: format, integrity, dimensions, counts,
 * values (the first failing one names its field). */
tscvx_nn_status nn_parse(const void *blob, size_t len, nn_header *hd, char *why)
{
    const unsigned char *p = (const unsigned char *)blob;
    tscvx_nn_status st;

    if (!blob || !hd) {
        return refuse(why, TSCVX_NN_NULL_ARGUMENT, "blob is NULL");
    }
    st = check_format(p, len, hd, why);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    read_fields(p, hd);
    st = check_integrity(p, len, hd, why);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    st = check_dimensions(hd, why);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    st = check_counts(hd, why);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    st = check_values(p + TSCVX_NN_HEADER_BYTES, hd, why);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    return refuse(why, TSCVX_NN_OK, "ok");
}

tscvx_nn_status tscvx_nn_check_blob(const void *blob, size_t len, char *message)
{
    nn_header hd;
    return nn_parse(blob, len, &hd, message);
}

/* ---- arena layout ------------------------------------------------------------------------ */

#define ALIGN 16u

static size_t round_up(size_t n) { return (n + (ALIGN - 1)) & ~(size_t)(ALIGN - 1); }

/* Arena bytes after its base is aligned: the struct, the layer table, activations (doubles),
 * the weights when copied. 0 when the total does not fit in size_t (a 32-bit target). */
static size_t layout_bytes(const nn_header *hd, int copy)
{
    const uint64_t d = hd->d_model, L = hd->seq_len, pad = ALIGN;
    uint64_t b = 0;
    b += sizeof(struct tscvx_nn) + pad;
    b += sizeof(nn_layer) * (uint64_t)(hd->n_layers ? hd->n_layers : 1) + pad;
    b += 8 * (2 * (uint64_t)hd->d_in + pad);      /* z, xb */
    b += 8 * (L * d + L * 3 * d + L * d) + 3 * pad; /* h, qkv, o */
    b += 8 * (d + (uint64_t)hd->d_ff + L + hd->d_out) + 4 * pad; /* t, f, sc, yb */
    if (copy) {
        if (hd->n_values > (UINT64_MAX - b) / 8) {
            return 0;
        }
        b += 8 * hd->n_values + pad;
    }
    return b + pad > (uint64_t)(size_t)-1 ? 0 : (size_t)b; /* + pad: the base alignment */
}

static int must_copy(unsigned flags)
{
    return (flags & TSCVX_NN_COPY_WEIGHTS) || !nn_host_is_little_endian();
}

/* What tscvx_nn_arena_size and tscvx_nn_init both refuse, in this order: the flags, the blob
 * (nn_parse), its layout and, for weights read in place, the blob's alignment. *copy: weights
 * go into the arena; *need: the arena bytes, alignment slack included. */
static tscvx_nn_status check_layout(const void *blob, size_t len, unsigned flags,
                                    nn_header *hd, int *copy, size_t *need)
{
    tscvx_nn_status st;
    if (flags & ~TSCVX_NN_COPY_WEIGHTS) {
        return TSCVX_NN_BAD_FLAGS;
    }
    st = nn_parse(blob, len, hd, NULL);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    *copy = must_copy(flags);
    *need = layout_bytes(hd, *copy);
    if (*need == 0) {
        return TSCVX_NN_BAD_DIMENSIONS;
    }
    *need += ALIGN; /* slack to align the base */
    if (!*copy && ((uintptr_t)blob % sizeof(double)) != 0) {
        return TSCVX_NN_BAD_ALIGNMENT;
    }
    return TSCVX_NN_OK;
}

tscvx_nn_status tscvx_nn_arena_size(const void *blob, size_t len, unsigned flags, size_t *bytes)
{
    nn_header hd;
    int copy = 0;
    size_t need = 0;
    tscvx_nn_status st;
    if (bytes) {
        *bytes = 0; /* 0 when refused, a NULL blob too */
    }
    if (!blob || !bytes) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    st = check_layout(blob, len, flags, &hd, &copy, &need);
    *bytes = st == TSCVX_NN_OK ? need : 0;
    return st;
}

/* Bump allocation from the aligned arena (sizes were checked against layout_bytes). */
static void *take(unsigned char **cur, size_t n)
{
    void *p = *cur;
    *cur += round_up(n);
    return p;
}

/* Everything init refuses after its NULL checks: tscvx_nn_arena_size's refusals, then the
 * arena's size. */
static tscvx_nn_status check_init(size_t arena_bytes, const void *blob, size_t len,
                                  unsigned flags, nn_header *hd, int *copy, size_t *need)
{
    const tscvx_nn_status st = check_layout(blob, len, flags, hd, copy, need);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    return arena_bytes < *need ? TSCVX_NN_ARENA_TOO_SMALL : TSCVX_NN_OK;
}

/* The net's struct at the arena's first aligned byte, zeroed (its padding too: nn_layout_sum
 * hashes it), with the header and its dimensions. */
static tscvx_nn *place_net(unsigned char **cur, const nn_header *hd, size_t need)
{
    tscvx_nn *net;
    *cur += (ALIGN - (uintptr_t)*cur % ALIGN) % ALIGN;
    net = (tscvx_nn *)take(cur, sizeof *net);
    memset(net, 0, sizeof *net);
    net->hdr = *hd;
    net->d_in = (int)hd->d_in;
    net->d_out = (int)hd->d_out;
    net->d = (int)hd->d_model;
    net->heads = (int)hd->n_heads;
    net->n_layers = (int)hd->n_layers;
    net->ff = (int)hd->d_ff;
    net->L = (int)hd->seq_len;
    net->arena_bytes = need;
    return net;
}

/* The layer table and the activations after the struct (their sizes: layout_bytes). */
static void place_buffers(tscvx_nn *net, unsigned char **cur)
{
    const nn_header *hd = &net->hdr;
    const size_t d = hd->d_model, L = hd->seq_len, ff = hd->d_ff;
    net->layers = (nn_layer *)take(cur, sizeof(nn_layer) * (hd->n_layers ? hd->n_layers : 1));
    net->z = (double *)take(cur, sizeof(double) * hd->d_in);
    net->h = (double *)take(cur, sizeof(double) * L * d);
    net->qkv = (double *)take(cur, sizeof(double) * L * 3 * d);
    net->o = (double *)take(cur, sizeof(double) * L * d);
    net->t = (double *)take(cur, sizeof(double) * d);
    net->f = (double *)take(cur, sizeof(double) * ff);
    net->sc = (double *)take(cur, sizeof(double) * L);
    net->xb = (double *)take(cur, sizeof(double) * hd->d_in);
    net->yb = (double *)take(cur, sizeof(double) * hd->d_out);
}

/* The values as doubles: in place in the (aligned, checked) blob, or copied into the arena
 * after the activations in the host's byte order. */
static const double *place_values(tscvx_nn *net, unsigned char **cur, const void *blob, int copy)
{
    const unsigned char *src = (const unsigned char *)blob + TSCVX_NN_HEADER_BYTES;
    const size_t n_values = (size_t)net->hdr.n_values;
    double *dst;
    size_t i;
    net->weights_in_arena = copy;
    if (!copy) {
        return (const double *)(const void *)src;
    }
    dst = (double *)take(cur, sizeof(double) * n_values);
    for (i = 0; i < n_values; ++i) {
        dst[i] = rd_f64(src + 8 * i);
    }
    return dst;
}

/* One encoder layer's weights from w on, in the blob's order; returns what follows them. */
static const double *carve_layer(nn_layer *ly, const double *w, size_t d, size_t ff)
{
    ly->W_qkv = w;
    w += 3 * d * d;
    ly->b_qkv = w;
    w += 3 * d;
    ly->W_o = w;
    w += d * d;
    ly->b_o = w;
    w += d;
    ly->ln1_g = w;
    w += d;
    ly->ln1_b = w;
    w += d;
    ly->W_1 = w;
    w += ff * d;
    ly->b_1 = w;
    w += ff;
    ly->W_2 = w;
    w += d * ff;
    ly->b_2 = w;
    w += d;
    ly->ln2_g = w;
    w += d;
    ly->ln2_b = w;
    w += d;
    return w;
}

/* Points the net at its weights, probes and parameters, in the blob's order (nn_internal.h). */
static void carve_values(tscvx_nn *net, const double *w)
{
    const nn_header *hd = &net->hdr;
    const size_t d = hd->d_model, L = hd->seq_len;
    uint32_t l;
    net->in_mean = w;
    w += hd->d_in;
    net->in_scale = w;
    w += hd->d_in;
    net->out_mean = w;
    w += hd->d_out;
    net->out_std = w;
    w += hd->d_out;
    net->enc_w = w;
    w += hd->tokens == TSCVX_NN_TOKENS_SINGLE ? d * hd->d_in : L * d;
    net->enc_b = w;
    w += hd->tokens == TSCVX_NN_TOKENS_SINGLE ? d : L * d;
    net->pos = w;
    w += L * d;
    for (l = 0; l < hd->n_layers; ++l) {
        w = carve_layer(&net->layers[l], w, d, hd->d_ff);
    }
    net->W_d = w;
    w += hd->d_out * L * d;
    net->b_d = w;
    w += hd->d_out;
    net->probe_in = w;
    w += (size_t)hd->n_probes * hd->d_in;
    net->probe_out = w;
    w += (size_t)hd->n_probes * hd->d_out;
    net->params = w;
}

tscvx_nn_status tscvx_nn_init(tscvx_nn **out, void *arena, size_t arena_bytes, const void *blob,
                              size_t len, unsigned flags)
{
    nn_header hd;
    tscvx_nn_status st;
    tscvx_nn *net;
    unsigned char *cur = (unsigned char *)arena;
    size_t need;
    int copy;

    if (!out) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    *out = NULL; /* whatever is refused below: no net */
    if (!arena || !blob) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    st = check_init(arena_bytes, blob, len, flags, &hd, &copy, &need);
    if (st != TSCVX_NN_OK) {
        return st;
    }
    if (nn_overlap((uintptr_t)blob, len, (uintptr_t)arena, arena_bytes)) {
        return TSCVX_NN_BAD_BUFFER; /* the net would be laid out over the values it reads */
    }
    net = place_net(&cur, &hd, need);
    net->arena_at = (uintptr_t)arena; /* tscvx_nn_run keeps its buffers out of it */
    net->arena_len = arena_bytes;
    place_buffers(net, &cur);
    carve_values(net, place_values(net, &cur, blob, copy));
    net->cookie = NN_COOKIE; /* cookie and checksum last: nn_live only for a complete net */
    net->layout_sum = nn_layout_sum(net);
    net->table_sum = nn_table_sum(net);
    *out = net;
    return TSCVX_NN_OK;
}

uint64_t nn_layout_sum(const tscvx_nn *net)
{
    return tscvx_fnv1a(TSCVX_FNV1A_START, net, offsetof(tscvx_nn, layout_sum));
}

uint64_t nn_table_sum(const tscvx_nn *net)
{
    return tscvx_fnv1a(TSCVX_FNV1A_START, net->layers, sizeof(nn_layer) * net->hdr.n_layers);
}

/* The second checksum covers the layer table, so it reads through net->layers for
 * hdr.n_layers entries: both must first be what init set, the pointer right after the
 * struct (place_buffers) and the count vouched for by the struct's checksum, or a flipped
 * or overwritten field would be followed (past a small arena's end) before a checksum
 * could refuse it. */
int nn_live(const tscvx_nn *net)
{
    const unsigned char *table = (const unsigned char *)net + round_up(sizeof *net);
    return net->cookie == NN_COOKIE && (const unsigned char *)net->layers == table &&
           net->layout_sum == nn_layout_sum(net) && net->hdr.n_layers <= TSCVX_NN_MAX_LAYERS &&
           net->table_sum == nn_table_sum(net);
}

tscvx_nn_status tscvx_nn_get_info(const tscvx_nn *net, tscvx_nn_info *info)
{
    if (!net || !info) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    if (!nn_live(net)) {
        return TSCVX_NN_NOT_READY;
    }
    info->kind = (int)net->hdr.kind;
    info->tokens = (int)net->hdr.tokens;
    info->d_in = net->d_in;
    info->d_out = net->d_out;
    info->d_model = net->d;
    info->n_heads = net->heads;
    info->n_layers = net->n_layers;
    info->d_ff = net->ff;
    info->seq_len = net->L;
    info->N = (int)net->hdr.N;
    info->n_probes = (int)net->hdr.n_probes;
    info->threshold = net->hdr.threshold;
    info->ln_eps = net->hdr.ln_eps;
    info->n_weights = (size_t)net->hdr.n_weights;
    info->n_params = (int)net->hdr.n_params;
    info->params = net->params;
    info->arena_bytes = net->arena_bytes;
    info->weights_in_arena = net->weights_in_arena;
    return TSCVX_NN_OK;
}

tscvx_nn_status tscvx_nn_tight_mask(const tscvx_nn *net, const double *logits, int n,
                                    unsigned char *mask)
{
    int i;
    if (!net || !logits || !mask) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    if (!nn_live(net)) {
        return TSCVX_NN_NOT_READY;
    }
    if (net->hdr.kind != TSCVX_NN_KIND_CONSTRAINT || n != net->d_out) {
        return TSCVX_NN_BAD_SIZE;
    }
    if (!nn_buffers_apart(net, logits, sizeof(double) * (size_t)n, mask, (size_t)n)) {
        return TSCVX_NN_BAD_BUFFER; /* mask bytes over the logits or the net's memory */
    }
    for (i = 0; i < n; ++i) {
        if (isnan(logits[i])) {
            return TSCVX_NN_BAD_INPUT;
        }
    }
    for (i = 0; i < n; ++i) { /* the same formula as guidance.nn.infer.ConstraintModel */
        mask[i] = (unsigned char)(1.0 / (1.0 + exp(-logits[i])) >= net->hdr.threshold);
    }
    return TSCVX_NN_OK;
}

tscvx_nn_status tscvx_nn_self_test(tscvx_nn *net, double *max_rel_err)
{
    uint32_t k;
    int i;
    double worst = 0.0;
    tscvx_nn_status st;
    if (!net) {
        return TSCVX_NN_NULL_ARGUMENT;
    }
    if (!nn_live(net)) {
        return TSCVX_NN_NOT_READY;
    }
    for (k = 0; k < net->hdr.n_probes; ++k) {
        const double *xin = net->probe_in + (size_t)k * net->d_in;
        const double *yrec = net->probe_out + (size_t)k * net->d_out;
        for (i = 0; i < net->d_in; ++i) {
            net->xb[i] = xin[i];
        }
        st = nn_run(net, net->xb, net->yb); /* its own buffers, in the arena */
        if (st != TSCVX_NN_OK) { /* a non-finite input or output: a damaged value */
            worst = HUGE_VAL;
            break;
        }
        for (i = 0; i < net->d_out; ++i) {
            double ref = yrec[i];
            double err = fabs(net->yb[i] - ref) / (fabs(ref) > 1.0 ? fabs(ref) : 1.0);
            /* a NaN recorded output is no match either (NaN compares false) */
            worst = err <= worst ? worst : (isnan(err) ? HUGE_VAL : err);
        }
    }
    if (net->hdr.n_probes == 0) { /* nothing tested is not a pass */
        worst = NAN;
    }
    if (max_rel_err) {
        *max_rel_err = worst;
    }
    return worst <= NN_SELF_TEST_TOL ? TSCVX_NN_OK : TSCVX_NN_SELF_TEST_FAILED;
}
