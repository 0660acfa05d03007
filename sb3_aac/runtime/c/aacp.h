/*
 * aacp.h: greedy decisions of an exported sb3-aac policy (a `.aacp` file) in C or C++.
 *
 * One C99 header with no dependency beyond the C standard library (and libm: link with -lm). It reads
 * every file the Python reference reader (`sb3_aac.runtime.RuntimePolicy`) reads: format `sb3-aac-policy`
 * versions 2 to 4, scaled-input or Gaussian-RBF features (with or without the RBF window) under a linear or
 * one-tanh-layer head, tile coding, (version 3) the feed-forward networks of a DeepPolicy or HybridPPO (linear,
 * layer-norm and tanh/relu/leaky-relu layers), and (version 4) P-DQN's and MP-DQN's parameter actor and Q
 * network. It checks a file as that reader does (length, magic bytes, SHA-256, strict UTF-8 JSON header, format
 * and version, every field and array, finite values) and never reads past the buffer it is given; then
 * `aacp_act` returns the decision `RuntimePolicy.act` returns: the same action type, and that type's parameters
 * in the env's units (clipped to their bounds) within 1e-5. The file format is docs/export-format.md of sb3-aac;
 * `sb3-aac c-header` prints where this header is installed.
 *
 * Use (single-header style): include it anywhere for the declarations, and in exactly one C or C++ file
 *
 *     #define AACP_IMPLEMENTATION
 *     #include "aacp.h"
 *
 * for the implementation. Then
 *
 *     aacp_policy *policy;
 *     aacp_error error;
 *     if (aacp_load_file("dribbler.aacp", &policy, &error) != AACP_OK) {
 *         fprintf(stderr, "%s\n", error.message);   // says what is wrong with the file
 *         return 1;
 *     }
 *     double obs[10] = {...};                        // the env's observation, flattened in C order
 *     aacp_action action;
 *     if (aacp_act(policy, obs, 10, &action, &error) == AACP_OK) {
 *         // action.type: the env's action type (type_start + index); action.params[0 .. action.n_params-1]
 *     }
 *     aacp_free(policy);
 *
 * Every function returns AACP_OK (0) or one of the error codes below, and fills `*error` (if not NULL)
 * with the code and a one-line message naming what is wrong. A loaded policy is read-only except for its
 * scratch buffers: aacp_act on one policy is not thread-safe; give each thread its own (load it twice).
 *
 * Numbers: the arithmetic is the Python runtime's, operation for operation where it decides something (the
 * folded input scaling, the RBF window test, the tile coordinates, the layer norms), so window and tile
 * decisions are the same bit for bit; sums run in another order (outputs agree to ~1e-15, decisions could
 * differ only at exact ties of that size). Do not compile it with -ffast-math or -ffp-contract=fast.
 * Parameters are returned as double; Python casts them to each type's Box dtype (usually float32), so a
 * value differs from Python's by at most that cast's rounding.
 *
 * Differences from the Python reader, each only in what a file's free-form metadata may hold: the JSON
 * parser is strict (no NaN/Infinity literals), nests at most AACP_MAX_NESTING deep, holds at most
 * AACP_MAX_JSON_VALUES values, and refuses integers outside int64 where the header needs a number (type_start).
 * aacp_load_file reads a file header first, as the Python reader does, so a device or endless stream is
 * refused after its first 16 bytes (no magic); on POSIX systems a named pipe (FIFO), whose opening would wait
 * for a writer, is refused before it is opened (C99 alone cannot tell one from a file).
 *
 * License: MIT (part of sb3-aac).
 */
#ifndef AACP_H
#define AACP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define AACP_FORMAT_NAME "sb3-aac-policy"
#define AACP_MAX_HEADER_BYTES ((uint64_t)1 << 24) /* as the Python reader: a header is a few kilobytes */
#define AACP_MAX_BLOB_BYTES ((uint64_t)1 << 30)   /* as the Python reader: arrays of a sensible policy */
#define AACP_MAX_NESTING 512                      /* JSON arrays/objects inside each other */
#define AACP_MAX_JSON_VALUES (1L << 20)           /* JSON values in one header */
#define AACP_MESSAGE_SIZE 768

/* Return codes. */
enum aacp_code {
    AACP_OK = 0,
    AACP_ERR_ARGUMENT = 1,    /* a NULL pointer or a wrong observation size */
    AACP_ERR_IO = 2,          /* the file cannot be opened or read */
    AACP_ERR_TRUNCATED = 3,   /* the file ends early */
    AACP_ERR_MAGIC = 4,       /* not a policy file (no "SB3AACP\0" magic bytes) */
    AACP_ERR_CHECKSUM = 5,    /* SHA-256 mismatch: truncated, corrupted, altered or appended to */
    AACP_ERR_JSON = 6,        /* the header is not strict UTF-8 JSON (or nests too deeply) */
    AACP_ERR_FORMAT = 7,      /* another format, or a version this reader does not know */
    AACP_ERR_HEADER = 8,      /* a header field is missing, mistyped or inconsistent */
    AACP_ERR_ARRAY = 9,       /* an array is missing, misshapen or misplaced */
    AACP_ERR_VALUE = 10,      /* an array holds NaN/inf or values out of their range */
    AACP_ERR_MEMORY = 11,     /* out of memory */
    AACP_ERR_OBSERVATION = 12 /* the observation holds NaN or inf values, or values whose squares overflow */
};

typedef struct aacp_error {
    int code;                        /* an aacp_code */
    char message[AACP_MESSAGE_SIZE]; /* one line, what is wrong */
} aacp_error;

typedef struct aacp_policy aacp_policy; /* opaque */

typedef struct aacp_action {
    int64_t type;         /* the action type as the env numbers it: type_start + index */
    size_t index;         /* the 0-based type k */
    size_t n_params;      /* dim of type k */
    const double *params; /* its n_params parameters in env units (clipped to their bounds); they live in the
                             policy and hold until the next aacp_act on it */
} aacp_action;

/* Load and check a policy file: `path`, or `path` + ".aacp" when no file `path` opens and its name has no
   suffix (as sb3_aac.export_policy names files). On success *policy is a new policy (free it with aacp_free);
   on failure *policy is NULL. */
int aacp_load_file(const char *path, aacp_policy **policy, aacp_error *error);

/* Load and check a policy from the `size` bytes at `data` (read nothing beyond them; `data` may be freed after). */
int aacp_load_memory(const void *data, size_t size, aacp_policy **policy, aacp_error *error);

/* Free a policy (NULL is ignored). */
void aacp_free(aacp_policy *policy);

/* The greedy decision for one observation of `obs_size` (= aacp_obs_size) finite values. */
int aacp_act(aacp_policy *policy, const double *obs, size_t obs_size, aacp_action *action, aacp_error *error);

/* Decisions for `n` observations stored one after another (n * obs_size values): types[i] is the env action type
   of observation i, params[i * aacp_max_dim(policy) + j] for j < aacp_type_dim(policy, types[i] - type_start)
   its parameters (the rest of each row is left as it was). Stops at the first bad observation. */
int aacp_act_batch(aacp_policy *policy, const double *obs, size_t n, size_t obs_size, int64_t *types, double *params,
                   aacp_error *error);

size_t aacp_obs_size(const aacp_policy *policy);           /* D: values of one (flattened) observation */
size_t aacp_n_types(const aacp_policy *policy);            /* K: action types */
int64_t aacp_type_start(const aacp_policy *policy);        /* the env's number for type 0 */
size_t aacp_type_dim(const aacp_policy *policy, size_t k); /* parameters of 0-based type k (0 if k >= K) */
size_t aacp_max_dim(const aacp_policy *policy);            /* the largest type_dim */
const char *aacp_layout(const aacp_policy *policy);        /* "nested", "flat", "shared" or "oneof" */
const char *aacp_code_name(int code);                      /* "AACP_ERR_CHECKSUM", ... */

#ifdef __cplusplus
}
#endif

#endif /* AACP_H */

/* ================================================================================================ implementation */
#ifdef AACP_IMPLEMENTATION
#ifndef AACP_IMPLEMENTATION_DONE
#define AACP_IMPLEMENTATION_DONE

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__unix__) || defined(__APPLE__)
#include <sys/stat.h>
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The arrays are IEEE-754 binary64; this implementation reads them into double. */
typedef char aacp__double_is_binary64[(sizeof(double) == 8 && sizeof(uint64_t) == 8) ? 1 : -1];

#define AACP__PREAMBLE 16 /* magic (8) + header length (uint64 LE) */
#define AACP__DIGEST 32   /* SHA-256 at the end */
#define AACP__ALIGN 8
#define AACP__MAX_INT_DIGITS 4300 /* Python refuses to parse longer integers */
#define AACP__CHECKSUM_MISMATCH "SHA-256 checksum mismatch: the file is truncated, corrupted or was altered; export it again"
static const unsigned char aacp__magic[8] = {'S', 'B', '3', 'A', 'A', 'C', 'P', 0};
static const char *const aacp__layouts[4] = {"nested", "flat", "shared", "oneof"};
static const char *const aacp__param_dtypes[3] = {"float16", "float32", "float64"};

/* ------------------------------------------------------------------------------------------------- errors */

static int aacp__set(aacp_error *error, int code, const char *fmt, ...) {
    if (error) {
        va_list args;
        error->code = code;
        va_start(args, fmt);
        vsnprintf(error->message, sizeof error->message, fmt, args);
        va_end(args);
    }
    return code;
}

/* "<name> is not a usable sb3-aac policy file: <why>", the Python reader's wording. */
static int aacp__bad(aacp_error *error, const char *name, int code, const char *fmt, ...) {
    char why[AACP_MESSAGE_SIZE];
    va_list args;
    va_start(args, fmt);
    vsnprintf(why, sizeof why, fmt, args);
    va_end(args);
    if (strlen(name) > 300) /* keep room for the reason */
        return aacp__set(error, code, "...%s is not a usable sb3-aac policy file: %s", name + strlen(name) - 297, why);
    return aacp__set(error, code, "%s is not a usable sb3-aac policy file: %s", name, why);
}

const char *aacp_code_name(int code) {
    static const char *const names[] = {"AACP_OK",          "AACP_ERR_ARGUMENT", "AACP_ERR_IO",    "AACP_ERR_TRUNCATED",
                                        "AACP_ERR_MAGIC",   "AACP_ERR_CHECKSUM", "AACP_ERR_JSON",  "AACP_ERR_FORMAT",
                                        "AACP_ERR_HEADER",  "AACP_ERR_ARRAY",    "AACP_ERR_VALUE", "AACP_ERR_MEMORY",
                                        "AACP_ERR_OBSERVATION"};
    return code >= 0 && code < (int)(sizeof names / sizeof names[0]) ? names[code] : "AACP_ERR_UNKNOWN";
}

/* ------------------------------------------------------------------------------------------------ SHA-256 */
/* FIPS 180-4, one shot. */

static const uint32_t aacp__sha_k[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98, 0x12835b01,
    0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc,
    0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147,
    0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08,
    0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208,
    0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

#define AACP__ROTR(x, n) (((x) >> (n)) | ((x) << (32 - (n))))

static void aacp__sha_block(uint32_t h[8], const unsigned char *block) {
    uint32_t w[64], a, b, c, d, e, f, g, hh;
    int t;
    for (t = 0; t < 16; t++)
        w[t] = (uint32_t)block[4 * t] << 24 | (uint32_t)block[4 * t + 1] << 16 | (uint32_t)block[4 * t + 2] << 8 |
               (uint32_t)block[4 * t + 3];
    for (t = 16; t < 64; t++) {
        uint32_t s0 = AACP__ROTR(w[t - 15], 7) ^ AACP__ROTR(w[t - 15], 18) ^ (w[t - 15] >> 3);
        uint32_t s1 = AACP__ROTR(w[t - 2], 17) ^ AACP__ROTR(w[t - 2], 19) ^ (w[t - 2] >> 10);
        w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (t = 0; t < 64; t++) {
        uint32_t t1 = hh + (AACP__ROTR(e, 6) ^ AACP__ROTR(e, 11) ^ AACP__ROTR(e, 25)) + ((e & f) ^ (~e & g)) +
                      aacp__sha_k[t] + w[t];
        uint32_t t2 = (AACP__ROTR(a, 2) ^ AACP__ROTR(a, 13) ^ AACP__ROTR(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        hh = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += hh;
}

static void aacp__sha256(const unsigned char *data, size_t n, unsigned char out[32]) {
    uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    unsigned char tail[128];
    size_t full = n - n % 64, rest = n % 64, padded, i;
    uint64_t bits = (uint64_t)n * 8;
    for (i = 0; i < full; i += 64)
        aacp__sha_block(h, data + i);
    memset(tail, 0, sizeof tail);
    if (rest)
        memcpy(tail, data + full, rest);
    tail[rest] = 0x80;
    padded = rest < 56 ? 64 : 128;
    for (i = 0; i < 8; i++)
        tail[padded - 1 - i] = (unsigned char)(bits >> (8 * i));
    aacp__sha_block(h, tail);
    if (padded == 128)
        aacp__sha_block(h, tail + 64);
    for (i = 0; i < 8; i++) {
        out[4 * i] = (unsigned char)(h[i] >> 24);
        out[4 * i + 1] = (unsigned char)(h[i] >> 16);
        out[4 * i + 2] = (unsigned char)(h[i] >> 8);
        out[4 * i + 3] = (unsigned char)h[i];
    }
}

/* ------------------------------------------------------------------------------------------- JSON parsing */
/* RFC 8259, as Python's json.loads reads it (numbers without '.'/exponent are integers, duplicate keys: the
   last wins), on text checked to be UTF-8 as Python's strict decoder checks it. */

enum { AACP__NULL, AACP__FALSE, AACP__TRUE, AACP__INT, AACP__FLOAT, AACP__STRING, AACP__ARRAY, AACP__OBJECT };

typedef struct aacp__node {
    int type;
    int big;          /* an integer outside int64 (its value is not kept) */
    int64_t i;        /* AACP__INT */
    double d;         /* AACP__FLOAT */
    size_t str, len;  /* AACP__STRING: offset of its decoded bytes in the strings buffer, length */
    size_t key, klen; /* a member of an object: its key, as str/len */
    long child, next; /* first element/member, next sibling; -1: none */
    size_t count;     /* elements or members */
} aacp__node;

typedef struct aacp__json {
    const unsigned char *p, *start, *end;
    aacp__node *nodes;
    long n, cap;
    char *strings;
    size_t used;
    int nomem;
    char why[160];
} aacp__json;

static long aacp__json_fail(aacp__json *j, const char *why) {
    if (!j->why[0])
        snprintf(j->why, sizeof j->why, "%s at byte %lu of the header", why, (unsigned long)(j->p - j->start));
    return -1;
}

static long aacp__node_new(aacp__json *j, int type) {
    aacp__node *node;
    if (j->n == j->cap) {
        long cap = j->cap ? 2 * j->cap : 64;
        aacp__node *grown;
        if (j->n >= AACP_MAX_JSON_VALUES)
            return aacp__json_fail(j, "more JSON values than a policy header holds");
        grown = (aacp__node *)realloc(j->nodes, (size_t)cap * sizeof *grown);
        if (!grown) {
            j->nomem = 1;
            return aacp__json_fail(j, "out of memory");
        }
        j->nodes = grown, j->cap = cap;
    }
    node = &j->nodes[j->n];
    memset(node, 0, sizeof *node);
    node->type = type, node->child = node->next = -1;
    return j->n++;
}

static void aacp__ws(aacp__json *j) {
    while (j->p < j->end && (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r'))
        j->p++;
}

static int aacp__utf8_ok(const unsigned char *s, size_t n) {
    size_t i = 0;
    while (i < n) {
        unsigned c = s[i];
        size_t extra, k;
        unsigned lo = 0x80, hi = 0xBF;
        if (c < 0x80) {
            i++;
            continue;
        }
        if (c >= 0xC2 && c <= 0xDF)
            extra = 1;
        else if (c >= 0xE0 && c <= 0xEF)
            extra = 2, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF; /* no overlongs, no surrogates */
        else if (c >= 0xF0 && c <= 0xF4)
            extra = 3, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF; /* at most U+10FFFF */
        else
            return 0;
        if (n - i <= extra)
            return 0;
        if (s[i + 1] < lo || s[i + 1] > hi)
            return 0;
        for (k = 2; k <= extra; k++)
            if (s[i + k] < 0x80 || s[i + k] > 0xBF)
                return 0;
        i += extra + 1;
    }
    return 1;
}

static int aacp__hex4(const unsigned char *p, unsigned *out) {
    unsigned v = 0;
    int i;
    for (i = 0; i < 4; i++) {
        unsigned c = p[i];
        v <<= 4;
        if (c >= '0' && c <= '9')
            v |= c - '0';
        else if (c >= 'a' && c <= 'f')
            v |= c - 'a' + 10;
        else if (c >= 'A' && c <= 'F')
            v |= c - 'A' + 10;
        else
            return 0;
    }
    *out = v;
    return 1;
}

static void aacp__put_utf8(aacp__json *j, unsigned cp) {
    char *o = j->strings + j->used;
    if (cp < 0x80)
        o[0] = (char)cp, j->used += 1;
    else if (cp < 0x800)
        o[0] = (char)(0xC0 | cp >> 6), o[1] = (char)(0x80 | (cp & 0x3F)), j->used += 2;
    else if (cp < 0x10000)
        o[0] = (char)(0xE0 | cp >> 12), o[1] = (char)(0x80 | ((cp >> 6) & 0x3F)), o[2] = (char)(0x80 | (cp & 0x3F)),
        j->used += 3;
    else
        o[0] = (char)(0xF0 | cp >> 18), o[1] = (char)(0x80 | ((cp >> 12) & 0x3F)), o[2] = (char)(0x80 | ((cp >> 6) & 0x3F)),
        o[3] = (char)(0x80 | (cp & 0x3F)), j->used += 4;
}

/* A string at j->p (its opening quote); its decoded bytes go to the strings buffer (never longer than the text). */
static int aacp__string(aacp__json *j, size_t *str, size_t *len) {
    j->p++;
    *str = j->used;
    for (;;) {
        unsigned c;
        if (j->p >= j->end)
            return (int)aacp__json_fail(j, "unterminated string");
        c = *j->p;
        if (c == '"') {
            j->p++;
            *len = j->used - *str;
            return 0;
        }
        if (c < 0x20)
            return (int)aacp__json_fail(j, "control character in a string");
        if (c != '\\') {
            j->strings[j->used++] = (char)c;
            j->p++;
            continue;
        }
        if (j->end - j->p < 2)
            return (int)aacp__json_fail(j, "unterminated string");
        c = j->p[1];
        j->p += 2;
        switch (c) {
        case '"': case '\\': case '/': j->strings[j->used++] = (char)c; break;
        case 'b': j->strings[j->used++] = '\b'; break;
        case 'f': j->strings[j->used++] = '\f'; break;
        case 'n': j->strings[j->used++] = '\n'; break;
        case 'r': j->strings[j->used++] = '\r'; break;
        case 't': j->strings[j->used++] = '\t'; break;
        case 'u': {
            unsigned cp, low;
            if (j->end - j->p < 4 || !aacp__hex4(j->p, &cp))
                return (int)aacp__json_fail(j, "invalid \\u escape");
            j->p += 4;
            if (cp >= 0xD800 && cp <= 0xDBFF && j->end - j->p >= 6 && j->p[0] == '\\' && j->p[1] == 'u' &&
                aacp__hex4(j->p + 2, &low) && low >= 0xDC00 && low <= 0xDFFF) {
                cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
                j->p += 6;
            }
            aacp__put_utf8(j, cp); /* a lone surrogate is kept as its 3-byte form, as Python keeps it */
            break;
        }
        default:
            j->p -= 2;
            return (int)aacp__json_fail(j, "invalid escape");
        }
    }
}

static int aacp__digit(const aacp__json *j, const unsigned char *p) { return p < j->end && *p >= '0' && *p <= '9'; }

static long aacp__number(aacp__json *j) {
    const unsigned char *start = j->p, *p = j->p;
    int is_float = 0;
    long index;
    aacp__node *node;
    if (*p == '-')
        p++;
    if (!aacp__digit(j, p))
        return aacp__json_fail(j, "invalid value");
    if (*p == '0')
        p++;
    else
        while (aacp__digit(j, p))
            p++;
    if (p < j->end && *p == '.' && aacp__digit(j, p + 1)) {
        p++, is_float = 1;
        while (aacp__digit(j, p))
            p++;
    }
    if (p < j->end && (*p == 'e' || *p == 'E')) {
        const unsigned char *q = p + 1;
        if (q < j->end && (*q == '+' || *q == '-'))
            q++;
        if (aacp__digit(j, q)) {
            p = q, is_float = 1;
            while (aacp__digit(j, p))
                p++;
        }
    }
    index = aacp__node_new(j, is_float ? AACP__FLOAT : AACP__INT);
    if (index < 0)
        return -1;
    node = &j->nodes[index];
    if (!is_float) {
        const unsigned char *q = start + (*start == '-');
        uint64_t magnitude = 0, limit = *start == '-' ? (uint64_t)INT64_MAX + 1 : (uint64_t)INT64_MAX;
        if (p - q > AACP__MAX_INT_DIGITS) {
            j->p = start;
            return aacp__json_fail(j, "an integer of more than 4300 digits");
        }
        for (; q < p; q++) {
            unsigned digit = (unsigned)(*q - '0');
            if (magnitude > (limit - digit) / 10) {
                node->big = 1;
                break;
            }
            magnitude = magnitude * 10 + digit;
        }
        if (!node->big)
            node->i = *start != '-' ? (int64_t)magnitude
                                    : magnitude == (uint64_t)INT64_MAX + 1 ? INT64_MIN : -(int64_t)magnitude;
    } else {
        /* strtod reads the locale's decimal point: give it that. */
        const char *point = localeconv()->decimal_point;
        size_t n = (size_t)(p - start), plen = point && *point ? strlen(point) : 1, i, o = 0;
        char small[96], *text = n + plen < sizeof small ? small : (char *)malloc(n + plen + 1);
        if (!text) {
            j->nomem = 1;
            return aacp__json_fail(j, "out of memory");
        }
        for (i = 0; i < n; i++) {
            if (start[i] == '.') {
                memcpy(text + o, point && *point ? point : ".", plen);
                o += plen;
            } else
                text[o++] = (char)start[i];
        }
        text[o] = 0;
        node->d = strtod(text, NULL); /* correctly rounded; overflow gives inf, as Python's float() */
        if (text != small)
            free(text);
    }
    j->p = p;
    return index;
}

static long aacp__value(aacp__json *j, int depth);

static long aacp__container(aacp__json *j, int depth, int object) {
    long index = aacp__node_new(j, object ? AACP__OBJECT : AACP__ARRAY), last = -1;
    if (index < 0)
        return -1;
    if (depth >= AACP_MAX_NESTING)
        return aacp__json_fail(j, "the header nests too deeply to be a policy header");
    j->p++;
    aacp__ws(j);
    if (j->p < j->end && *j->p == (object ? '}' : ']')) {
        j->p++;
        return index;
    }
    for (;;) {
        size_t key = 0, klen = 0;
        long child;
        if (object) {
            if (j->p >= j->end || *j->p != '"')
                return aacp__json_fail(j, "expected a property name in double quotes");
            if (aacp__string(j, &key, &klen))
                return -1;
            aacp__ws(j);
            if (j->p >= j->end || *j->p != ':')
                return aacp__json_fail(j, "expected ':'");
            j->p++;
            aacp__ws(j);
        }
        child = aacp__value(j, depth + 1);
        if (child < 0)
            return -1;
        j->nodes[child].key = key, j->nodes[child].klen = klen;
        if (last < 0)
            j->nodes[index].child = child;
        else
            j->nodes[last].next = child;
        last = child;
        j->nodes[index].count++;
        aacp__ws(j);
        if (j->p < j->end && *j->p == ',') {
            j->p++;
            aacp__ws(j);
            continue;
        }
        if (j->p < j->end && *j->p == (object ? '}' : ']')) {
            j->p++;
            return index;
        }
        return aacp__json_fail(j, object ? "expected ',' or '}'" : "expected ',' or ']'");
    }
}

static int aacp__literal(aacp__json *j, const char *word) {
    size_t n = strlen(word);
    if ((size_t)(j->end - j->p) < n || memcmp(j->p, word, n) != 0)
        return 0;
    j->p += n;
    return 1;
}

static long aacp__value(aacp__json *j, int depth) {
    long index;
    if (j->p >= j->end)
        return aacp__json_fail(j, "expected a value");
    switch (*j->p) {
    case '{': return aacp__container(j, depth, 1);
    case '[': return aacp__container(j, depth, 0);
    case '"': {
        size_t str, len;
        index = aacp__node_new(j, AACP__STRING);
        if (index < 0 || aacp__string(j, &str, &len))
            return -1;
        j->nodes[index].str = str, j->nodes[index].len = len;
        return index;
    }
    case 't': return aacp__literal(j, "true") ? aacp__node_new(j, AACP__TRUE) : aacp__json_fail(j, "invalid value");
    case 'f': return aacp__literal(j, "false") ? aacp__node_new(j, AACP__FALSE) : aacp__json_fail(j, "invalid value");
    case 'n': return aacp__literal(j, "null") ? aacp__node_new(j, AACP__NULL) : aacp__json_fail(j, "invalid value");
    default: return aacp__number(j);
    }
}

/* Parse `n` bytes of header text; node 0 is the root. 0, or -1 with j->why (and j->nomem) set. */
static int aacp__json_parse(aacp__json *j, const unsigned char *text, size_t n) {
    memset(j, 0, sizeof *j);
    j->p = j->start = text, j->end = text + n;
    if (!aacp__utf8_ok(text, n)) {
        snprintf(j->why, sizeof j->why, "it is not valid UTF-8");
        return -1;
    }
    j->strings = (char *)malloc(n + 1);
    if (!j->strings) {
        j->nomem = 1;
        snprintf(j->why, sizeof j->why, "out of memory");
        return -1;
    }
    aacp__ws(j);
    if (aacp__value(j, 0) < 0)
        return -1;
    aacp__ws(j);
    if (j->p != j->end)
        return (int)aacp__json_fail(j, "extra data after the JSON value");
    return 0;
}

static void aacp__json_free(aacp__json *j) {
    free(j->nodes);
    free(j->strings);
    j->nodes = NULL, j->strings = NULL;
}

/* -------------------------------------------------------------------------------------- JSON queries */

static const aacp__node *aacp__at(const aacp__json *j, long i) { return &j->nodes[i]; }

/* The member `key` of object `obj` (the last, if repeated), or -1 (none, or `obj` is not an object). */
static long aacp__member(const aacp__json *j, long obj, const char *key) {
    long i, found = -1;
    size_t n = strlen(key);
    if (obj < 0 || j->nodes[obj].type != AACP__OBJECT)
        return -1;
    for (i = j->nodes[obj].child; i >= 0; i = j->nodes[i].next)
        if (j->nodes[i].klen == n && memcmp(j->strings + j->nodes[i].key, key, n) == 0)
            found = i;
    return found;
}

static int aacp__is(const aacp__json *j, long i, int type) { return i >= 0 && j->nodes[i].type == type; }

static int aacp__string_is(const aacp__json *j, long i, const char *s) {
    return aacp__is(j, i, AACP__STRING) && j->nodes[i].len == strlen(s) &&
           memcmp(j->strings + j->nodes[i].str, s, j->nodes[i].len) == 0;
}

/* A whole number >= minimum (an integer: not a bool, not a float, as Python's `type(v) is int`). */
static int aacp__whole(const aacp__json *j, long i, int64_t minimum, int64_t *out) {
    if (!aacp__is(j, i, AACP__INT) || j->nodes[i].big || j->nodes[i].i < minimum)
        return 0;
    if (out)
        *out = j->nodes[i].i;
    return 1;
}

/* Python's `value == v` for a JSON value and an integer: true for the integer, float or bool of that value. */
static int aacp__equals(const aacp__json *j, long i, int64_t v) {
    const aacp__node *node;
    if (i < 0)
        return 0;
    node = aacp__at(j, i);
    switch (node->type) {
    case AACP__INT: return !node->big && node->i == v;
    case AACP__FLOAT: return node->d == (double)v;
    case AACP__TRUE: return v == 1;
    case AACP__FALSE: return v == 0;
    default: return 0;
    }
}

/* A short rendering of a value for messages. */
static const char *aacp__show(const aacp__json *j, long i, char *buf, size_t n) {
    const aacp__node *node;
    static const char *const names[] = {"null", "false", "true", "", "", "", "an array", "an object"};
    if (i < 0)
        return "nothing";
    node = aacp__at(j, i);
    if (node->type == AACP__INT && !node->big)
        snprintf(buf, n, "%lld", (long long)node->i);
    else if (node->type == AACP__INT)
        snprintf(buf, n, "an integer beyond 64 bits");
    else if (node->type == AACP__FLOAT)
        snprintf(buf, n, "%.17g", node->d);
    else if (node->type == AACP__STRING) { /* printable ASCII only, so that a message stays one clean line */
        size_t i, shown = node->len < 40 ? node->len : 40;
        snprintf(buf, n, "'%.*s'", (int)shown, j->strings + node->str);
        for (i = 1; i <= shown && i + 1 < n; i++)
            if ((unsigned char)buf[i] < 0x20 || (unsigned char)buf[i] >= 0x7f)
                buf[i] = '?';
    } else
        return names[node->type];
    return buf;
}

static void *aacp__alloc(size_t n, size_t size) { return malloc((n ? n : 1) * size); }

/* Saturating arithmetic on sizes (a crafted header may name any integers). */
#define AACP__HUGE INT64_MAX
static int64_t aacp__mul(int64_t a, int64_t b) {
    if (a == 0 || b == 0)
        return 0;
    return a > AACP__HUGE / b ? AACP__HUGE : a * b;
}
static int64_t aacp__add(int64_t a, int64_t b) { return a > AACP__HUGE - b ? AACP__HUGE : a + b; }

/* An array of whole numbers >= minimum: their product (saturated), or -1. */
static int64_t aacp__shape_product(const aacp__json *j, long i, int64_t minimum) {
    int64_t product = 1, v;
    long e;
    if (!aacp__is(j, i, AACP__ARRAY))
        return -1;
    for (e = j->nodes[i].child; e >= 0; e = j->nodes[e].next) {
        if (!aacp__whole(j, e, minimum, &v))
            return -1;
        product = aacp__mul(product, v);
    }
    return product;
}

/* ------------------------------------------------------------------------------------------ header checks */

enum { AACP__SCALED, AACP__RBF, AACP__TILES };
enum { AACP__LINEAR, AACP__TANH_MLP, AACP__NETWORKS, AACP__PDQN };
enum { AACP__LAYER_LINEAR, AACP__LAYER_NORM, AACP__LAYER_TANH, AACP__LAYER_RELU, AACP__LAYER_LEAKY_RELU };

typedef struct aacp__array_spec {
    char name[64];
    int ndim;
    int64_t shape[3];
    int64_t offset; /* in the blob, filled by the placement check */
} aacp__array_spec;

typedef struct aacp__layer_spec {
    int kind, affine; /* AACP__LAYER_*; a layer norm with weight and bias */
    int64_t in, out;  /* values read and written */
    double constant;  /* a layer norm's eps, a leaky ReLU's slope */
} aacp__layer_spec;

typedef struct aacp__network_spec {
    int64_t start, stop; /* the outputs it writes */
    size_t first, count; /* its layers */
} aacp__network_spec;

/* What a checked header says. */
typedef struct aacp__spec {
    int64_t d, k, start, n_params, a, f, m, h, c, g, blob_size;
    int features, head, layout;
    double window_z2; /* features with z*z above this are 0 (INFINITY: no window) */
    int64_t *offsets; /* K + 1 parameter offsets */
    int version;      /* the file's version: 2, 3 or 4 */
    int multi_pass;   /* a pdqn head: MP-DQN's K passes */
    long arrays;      /* the header's arrays table */
    int n_arrays, cap_arrays;
    aacp__array_spec *array;
    size_t n_networks, n_layers;
    aacp__network_spec *networks;
    aacp__layer_spec *layers;
} aacp__spec;

static void aacp__spec_free(aacp__spec *s) {
    free(s->offsets), free(s->array), free(s->networks), free(s->layers);
    s->offsets = NULL, s->array = NULL, s->networks = NULL, s->layers = NULL;
}

typedef struct aacp__ctx {
    aacp__json *j;
    aacp_error *error;
    const char *name;
} aacp__ctx;

/* The member `key` of `obj`, or -1 with the "lacks or mistypes" error (Python's KeyError/TypeError). */
static long aacp__need(aacp__ctx *c, long obj, const char *key, const char *where) {
    long i = aacp__member(c->j, obj, key);
    if (i < 0)
        aacp__bad(c->error, c->name, AACP_ERR_HEADER, "the header lacks or mistypes a required field (%s)", where);
    return i;
}

/* Add an expected array (0, or -1 out of memory). */
static int aacp__add_array(aacp__spec *s, const char *name, int ndim, int64_t d0, int64_t d1, int64_t d2) {
    aacp__array_spec *a;
    if (s->n_arrays == s->cap_arrays) {
        int cap = s->cap_arrays ? 2 * s->cap_arrays : 16;
        aacp__array_spec *grown = (aacp__array_spec *)realloc(s->array, (size_t)cap * sizeof *grown);
        if (!grown)
            return -1;
        s->array = grown, s->cap_arrays = cap;
    }
    a = &s->array[s->n_arrays++];
    snprintf(a->name, sizeof a->name, "%s", name);
    a->ndim = ndim, a->shape[0] = d0, a->shape[1] = d1, a->shape[2] = d2, a->offset = 0;
    return 0;
}

/* The arrays a checked header needs, with their shapes (Python: expected_array_shapes); 0, or -1 out of memory. */
static int aacp__expected_arrays(aacp__spec *s) {
    int bad = 0;
    size_t i, l;
    s->n_arrays = 0;
    bad |= aacp__add_array(s, "obs_low", 1, s->d, 0, 0);
    bad |= aacp__add_array(s, "obs_high", 1, s->d, 0, 0);
    bad |= aacp__add_array(s, "obs_mid", 1, s->d, 0, 0);
    bad |= aacp__add_array(s, "obs_half", 1, s->d, 0, 0);
    bad |= aacp__add_array(s, "param_low", 1, s->n_params, 0, 0);
    bad |= aacp__add_array(s, "param_high", 1, s->n_params, 0, 0);
    if (s->features == AACP__RBF) {
        bad |= aacp__add_array(s, "rbf_centers", 2, s->d, s->m, 0);
        bad |= aacp__add_array(s, "rbf_widths", 2, s->d, s->m, 0);
    }
    if (s->features == AACP__TILES) {
        bad |= aacp__add_array(s, "tile_inputs", 2, s->c, s->g, 0);
        bad |= aacp__add_array(s, "tile_offsets", 2, s->c, s->g, 0);
        bad |= aacp__add_array(s, "tile_resolution", 2, s->c, s->g, 0);
        bad |= aacp__add_array(s, "tile_strides", 2, s->c, s->g, 0);
        bad |= aacp__add_array(s, "tile_bases", 1, s->c, 0, 0);
        bad |= aacp__add_array(s, "tile_weight", 2, s->f, s->a, 0);
        bad |= aacp__add_array(s, "bias", 1, s->a, 0, 0);
    } else if (s->head == AACP__NETWORKS || s->head == AACP__PDQN) { /* layer l of network i: net{i}_{l}_weight/bias */
        for (i = 0; i < s->n_networks; i++)
            for (l = 0; l < s->networks[i].count; l++) {
                const aacp__layer_spec *layer = &s->layers[s->networks[i].first + l];
                char weight[64], bias[64];
                snprintf(weight, sizeof weight, "net%lu_%lu_weight", (unsigned long)i, (unsigned long)l);
                snprintf(bias, sizeof bias, "net%lu_%lu_bias", (unsigned long)i, (unsigned long)l);
                if (layer->kind == AACP__LAYER_LINEAR) {
                    bad |= aacp__add_array(s, weight, 2, layer->out, layer->in, 0);
                    bad |= aacp__add_array(s, bias, 1, layer->out, 0, 0);
                } else if (layer->kind == AACP__LAYER_NORM && layer->affine) {
                    bad |= aacp__add_array(s, weight, 1, layer->out, 0, 0);
                    bad |= aacp__add_array(s, bias, 1, layer->out, 0, 0);
                }
            }
    } else if (s->head == AACP__LINEAR) {
        bad |= aacp__add_array(s, "weight", 2, s->a, s->f, 0);
        bad |= aacp__add_array(s, "bias", 1, s->a, 0, 0);
    } else {
        bad |= aacp__add_array(s, "weight1", 3, s->a, s->h, s->f);
        bad |= aacp__add_array(s, "bias1", 2, s->a, s->h, 0);
        bad |= aacp__add_array(s, "weight2", 2, s->a, s->h, 0);
        bad |= aacp__add_array(s, "bias2", 1, s->a, 0, 0);
    }
    return bad;
}

/* The features and head sections (Python: _check_features_and_head). */
static int aacp__check_features_and_head(aacp__ctx *c, aacp__spec *s, long features, long head) {
    aacp__json *j = c->j;
    char b1[64], b2[64];
    long type = aacp__need(c, features, "type", "approximators.features.type"), head_type;
    if (type < 0)
        return AACP_ERR_HEADER;
    s->window_z2 = INFINITY;
    if (aacp__string_is(j, type, "rbf")) {
        long n_rbf = aacp__need(c, features, "n_rbf", "approximators.features.n_rbf"), window;
        if (n_rbf < 0)
            return AACP_ERR_HEADER;
        if (!aacp__whole(j, n_rbf, 1, &s->m) || s->f != aacp__mul(s->d, s->m))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "RBF features: n_rbf=%s, n_features=%lld, %lld inputs",
                             aacp__show(j, n_rbf, b1, sizeof b1), (long long)s->f, (long long)s->d);
        window = aacp__need(c, features, "rbf_window", "approximators.features.rbf_window"); /* null: dense */
        if (window < 0)
            return AACP_ERR_HEADER;
        if (!aacp__is(j, window, AACP__NULL)) {
            double r = aacp__is(j, window, AACP__INT) ? (j->nodes[window].big ? INFINITY : (double)j->nodes[window].i)
                                                       : j->nodes[window].d;
            if (!(aacp__is(j, window, AACP__INT) || aacp__is(j, window, AACP__FLOAT)) || !(r > 0 && r < INFINITY))
                return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                                 "rbf_window must be a finite number of standard deviations > 0, or None; got %s",
                                 aacp__show(j, window, b1, sizeof b1));
            s->window_z2 = 0.5 * (r * r); /* Python: 0.5 * float(rbf_window) ** 2 */
        }
        s->features = AACP__RBF;
    } else if (aacp__string_is(j, type, "scaled")) {
        if (s->f != s->d)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "scaled features: n_features=%lld for %lld inputs",
                             (long long)s->f, (long long)s->d);
        s->features = AACP__SCALED;
    } else if (aacp__string_is(j, type, "tiles")) {
        long codings = aacp__need(c, features, "n_codings", "approximators.features.n_codings"), size, linear;
        if (codings < 0)
            return AACP_ERR_HEADER;
        if (aacp__whole(j, codings, 1, &s->c)) {
            if ((size = aacp__need(c, features, "group_size", "approximators.features.group_size")) < 0)
                return AACP_ERR_HEADER;
            if (aacp__whole(j, size, 1, &s->g)) {
                if ((linear = aacp__need(c, head, "type", "approximators.head.type")) < 0)
                    return AACP_ERR_HEADER;
                if (aacp__string_is(j, linear, "linear")) {
                    s->features = AACP__TILES;
                    goto head;
                }
            }
        }
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "tile features need positive n_codings, group_size, n_features and a linear head");
    } else
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "unknown feature type %s (known: 'rbf', 'scaled', 'tiles')",
                         aacp__show(j, type, b1, sizeof b1));
head:
    if ((head_type = aacp__need(c, head, "type", "approximators.head.type")) < 0)
        return AACP_ERR_HEADER;
    if (aacp__string_is(j, head_type, "tanh_mlp")) {
        long units = aacp__need(c, head, "hidden_units", "approximators.head.hidden_units");
        if (units < 0)
            return AACP_ERR_HEADER;
        if (!aacp__whole(j, units, 1, &s->h))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "hidden_units=%s", aacp__show(j, units, b1, sizeof b1));
        s->head = AACP__TANH_MLP;
    } else if (aacp__string_is(j, head_type, "networks")) {
        if (s->version < 3 || s->features != AACP__SCALED)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "a networks head needs version >= 3 and scaled features");
        if (aacp__need(c, head, "networks", "approximators.head.networks") < 0)
            return AACP_ERR_HEADER;
        s->head = AACP__NETWORKS;
    } else if (aacp__string_is(j, head_type, "pdqn")) {
        long multi_pass;
        if (s->version < 4 || s->features != AACP__SCALED)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "a pdqn head needs version >= 4 and scaled features");
        if ((multi_pass = aacp__need(c, head, "multi_pass", "approximators.head.multi_pass")) < 0)
            return AACP_ERR_HEADER;
        if (!aacp__is(j, multi_pass, AACP__TRUE) && !aacp__is(j, multi_pass, AACP__FALSE))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "a pdqn head's multi_pass must be true or false, got %s",
                             aacp__show(j, multi_pass, b2, sizeof b2));
        if (aacp__need(c, head, "networks", "approximators.head.networks") < 0)
            return AACP_ERR_HEADER;
        s->head = AACP__PDQN, s->multi_pass = aacp__is(j, multi_pass, AACP__TRUE);
    } else if (aacp__string_is(j, head_type, "linear"))
        s->head = AACP__LINEAR;
    else
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "unknown head type %s (known: 'linear', 'tanh_mlp', 'networks', 'pdqn')",
                         aacp__show(j, head_type, b2, sizeof b2));
    return AACP_OK;
}

static int aacp__by_start(const void *a, const void *b) {
    const aacp__network_spec *x = (const aacp__network_spec *)a, *y = (const aacp__network_spec *)b;
    return x->start < y->start ? -1 : x->start > y->start;
}

/* One layer reading `size` values (Python: _check_layer); its size after, or -1 with the error set. */
static int64_t aacp__check_layer(aacp__ctx *c, long layer, int64_t size, size_t i, size_t l, aacp__layer_spec *out) {
    aacp__json *j = c->j;
    long kind = aacp__need(c, layer, "type", "approximators.head.networks[].layers[].type");
    char b1[64];
    if (kind < 0)
        return -1;
    memset(out, 0, sizeof *out);
    out->in = out->out = size;
    if (aacp__string_is(j, kind, "linear")) {
        long in = aacp__need(c, layer, "in", "approximators.head.networks[].layers[].in"), n_out;
        if (in < 0 || (n_out = aacp__need(c, layer, "out", "approximators.head.networks[].layers[].out")) < 0)
            return -1;
        if (!aacp__whole(j, in, INT64_MIN, NULL) || j->nodes[in].i != size || !aacp__whole(j, n_out, 1, &out->out))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                             "network %lu, layer %lu: a linear layer on %lld values needs in=%lld and out >= 1",
                             (unsigned long)i, (unsigned long)l, (long long)size, (long long)size), -1;
        out->kind = AACP__LAYER_LINEAR;
    } else if (aacp__string_is(j, kind, "layernorm")) {
        long eps = aacp__need(c, layer, "eps", "approximators.head.networks[].layers[].eps"), n, affine;
        if (eps < 0 || (n = aacp__need(c, layer, "size", "approximators.head.networks[].layers[].size")) < 0)
            return -1;
        if (!aacp__equals(j, n, size))
            goto norm;
        if ((affine = aacp__need(c, layer, "affine", "approximators.head.networks[].layers[].affine")) < 0)
            return -1;
        if (!(aacp__is(j, affine, AACP__TRUE) || aacp__is(j, affine, AACP__FALSE)) || !aacp__is(j, eps, AACP__FLOAT) ||
            !(j->nodes[eps].d > 0 && j->nodes[eps].d < INFINITY))
            goto norm;
        out->kind = AACP__LAYER_NORM, out->affine = aacp__is(j, affine, AACP__TRUE), out->constant = j->nodes[eps].d;
    } else if (aacp__string_is(j, kind, "activation")) {
        long function = aacp__need(c, layer, "function", "approximators.head.networks[].layers[].function"), slope;
        if (function < 0)
            return -1;
        if (aacp__string_is(j, function, "tanh"))
            out->kind = AACP__LAYER_TANH;
        else if (aacp__string_is(j, function, "relu"))
            out->kind = AACP__LAYER_RELU;
        else if (aacp__string_is(j, function, "leaky_relu")) {
            if ((slope = aacp__need(c, layer, "slope", "approximators.head.networks[].layers[].slope")) < 0)
                return -1;
            if (!aacp__is(j, slope, AACP__FLOAT) || !isfinite(j->nodes[slope].d))
                return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "network %lu, layer %lu: leaky_relu needs a finite slope",
                                 (unsigned long)i, (unsigned long)l), -1;
            out->kind = AACP__LAYER_LEAKY_RELU, out->constant = j->nodes[slope].d;
        } else
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                             "network %lu, layer %lu: unknown activation %s (known: ['tanh', 'relu', 'leaky_relu'])",
                             (unsigned long)i, (unsigned long)l, aacp__show(j, function, b1, sizeof b1)), -1;
    } else
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "network %lu, layer %lu: unknown layer type %s (known: ['linear', 'layernorm', 'activation'])",
                         (unsigned long)i, (unsigned long)l, aacp__show(j, kind, b1, sizeof b1)), -1;
    return out->out;
norm:
    return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                     "network %lu, layer %lu: a layer norm on %lld values needs size=%lld, eps > 0 and affine true/false",
                     (unsigned long)i, (unsigned long)l, (long long)size, (long long)size), -1;
}

/* A networks head (Python: check_networks): feed-forward networks reading the D scaled inputs, whose columns cover
   the A outputs exactly once. A pdqn head (Python: check_pdqn_head): two networks, the parameter actor reading the
   D scaled inputs and writing the columns [K, K + P], then the Q network reading D + P values and writing [0, K]. */
static int aacp__check_networks(aacp__ctx *c, aacp__spec *s, long networks) {
    aacp__json *j = c->j;
    aacp__network_spec *sorted;
    size_t i, n_layers = 0;
    long net, layer;
    int64_t covered = 0;
    int pdqn = s->head == AACP__PDQN;
    if (pdqn && (!aacp__is(j, networks, AACP__ARRAY) || j->nodes[networks].count != 2))
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "a pdqn head holds two networks (the parameter actor, then the Q network)");
    if (!aacp__is(j, networks, AACP__ARRAY) || j->nodes[networks].count == 0)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "networks must be a non-empty list");
    for (net = j->nodes[networks].child; net >= 0; net = j->nodes[net].next) {
        long layers = aacp__member(j, net, "layers");
        n_layers += aacp__is(j, layers, AACP__ARRAY) ? j->nodes[layers].count : 0;
    }
    s->n_networks = j->nodes[networks].count;
    s->networks = (aacp__network_spec *)aacp__alloc(s->n_networks, sizeof *s->networks);
    s->layers = (aacp__layer_spec *)aacp__alloc(n_layers, sizeof *s->layers);
    if (!s->networks || !s->layers)
        return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory reading the networks");
    for (i = 0, net = j->nodes[networks].child; net >= 0; net = j->nodes[net].next, i++) {
        aacp__network_spec *spec = &s->networks[i];
        long columns = aacp__need(c, net, "columns", "approximators.head.networks[].columns"), layers;
        int64_t size = pdqn && i == 1 ? aacp__add(s->d, s->n_params) : s->d, l = 0; /* the Q network reads [x, p] */
        int64_t n_outputs = pdqn ? aacp__add(aacp__add(s->k, s->n_params), 1) : s->a;
        if (columns < 0)
            return AACP_ERR_HEADER;
        if (!aacp__is(j, columns, AACP__ARRAY) || j->nodes[columns].count != 2 ||
            !aacp__whole(j, j->nodes[columns].child, 0, &spec->start) ||
            !aacp__whole(j, j->nodes[j->nodes[columns].child].next, 0, &spec->stop) || !(spec->start < spec->stop) ||
            spec->stop > n_outputs)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "network %lu: columns must be [start, stop) within [0, %lld]",
                             (unsigned long)i, (long long)n_outputs);
        if ((layers = aacp__need(c, net, "layers", "approximators.head.networks[].layers")) < 0)
            return AACP_ERR_HEADER;
        if (!aacp__is(j, layers, AACP__ARRAY))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "network %lu: layers must be a list", (unsigned long)i);
        spec->first = s->n_layers, spec->count = j->nodes[layers].count;
        for (layer = j->nodes[layers].child; layer >= 0; layer = j->nodes[layer].next, l++)
            if ((size = aacp__check_layer(c, layer, size, i, (size_t)l, &s->layers[s->n_layers++])) < 0)
                return AACP_ERR_HEADER;
        if (size != spec->stop - spec->start)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "network %lu ends with %lld values for its %lld columns",
                             (unsigned long)i, (long long)size, (long long)(spec->stop - spec->start));
        if (pdqn && (i == 0 ? spec->start != s->k || spec->stop != aacp__add(s->k, s->n_params)
                            : spec->start != 0 || spec->stop != s->k))
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "network %lu of a pdqn head writes the columns [%lld, %lld]",
                             (unsigned long)i, (long long)(i == 0 ? s->k : 0),
                             (long long)(i == 0 ? s->k + s->n_params : s->k));
    }
    if (pdqn)
        return AACP_OK; /* V = max Q: no network writes it */
    /* Each output exactly once: sorted by start, the ranges must tile [0, A). */
    sorted = (aacp__network_spec *)aacp__alloc(s->n_networks, sizeof *sorted);
    if (!sorted)
        return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory reading the networks");
    memcpy(sorted, s->networks, s->n_networks * sizeof *sorted);
    qsort(sorted, s->n_networks, sizeof *sorted, aacp__by_start);
    for (i = 0; i < s->n_networks && sorted[i].start == covered; i++)
        covered = sorted[i].stop;
    free(sorted);
    if (i < s->n_networks || covered != s->a)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "the networks' columns must cover each of the %lld outputs exactly once", (long long)s->a);
    return AACP_OK;
}

/* `outputs` == {"q": [0, K], "params": [K, K + P], "value": K + P}, with Python's dict/list equality. */
static int aacp__outputs_ok(const aacp__json *j, long outputs, int64_t k, int64_t p) {
    long q = aacp__member(j, outputs, "q"), params = aacp__member(j, outputs, "params");
    long value = aacp__member(j, outputs, "value");
    long i;
    if (q < 0 || params < 0 || value < 0)
        return 0;
    for (i = j->nodes[outputs].child; i >= 0; i = j->nodes[i].next) { /* no other keys */
        const char *key = j->strings + j->nodes[i].key;
        size_t n = j->nodes[i].klen;
        if (!((n == 1 && key[0] == 'q') || (n == 6 && !memcmp(key, "params", 6)) || (n == 5 && !memcmp(key, "value", 5))))
            return 0;
    }
    if (!aacp__is(j, q, AACP__ARRAY) || j->nodes[q].count != 2 || !aacp__is(j, params, AACP__ARRAY) ||
        j->nodes[params].count != 2)
        return 0;
    return aacp__equals(j, j->nodes[q].child, 0) && aacp__equals(j, j->nodes[j->nodes[q].child].next, k) &&
           aacp__equals(j, j->nodes[params].child, k) && aacp__equals(j, j->nodes[j->nodes[params].child].next, k + p) &&
           aacp__equals(j, value, k + p);
}

static int aacp__check_action(aacp__ctx *c, aacp__spec *s, long action) {
    aacp__json *j = c->j;
    char b1[64], b2[64];
    long k = aacp__need(c, action, "n_types", "action.n_types");
    long start = aacp__need(c, action, "type_start", "action.type_start");
    long layout = aacp__need(c, action, "layout", "action.layout"), types = aacp__need(c, action, "types", "action.types");
    long t, n_params;
    int64_t offset = 0, index = 0;
    int i;
    if (k < 0 || start < 0 || layout < 0 || types < 0)
        return AACP_ERR_HEADER;
    s->layout = -1;
    for (i = 0; i < 4; i++)
        if (aacp__string_is(j, layout, aacp__layouts[i]))
            s->layout = i;
    if (s->layout < 0)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "unknown action layout %s (known: ['nested', 'flat', 'shared', 'oneof'])",
                         aacp__show(j, layout, b1, sizeof b1));
    if (aacp__is(j, start, AACP__INT) && j->nodes[start].big)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "action.type_start beyond 64 bits");
    if (!aacp__whole(j, k, 1, &s->k) || !aacp__whole(j, start, INT64_MIN, &s->start) || !aacp__is(j, types, AACP__ARRAY) ||
        (int64_t)j->nodes[types].count != s->k)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "action section: n_types=%s, type_start=%s must be whole numbers, with n_types types",
                         aacp__show(j, k, b1, sizeof b1), aacp__show(j, start, b2, sizeof b2));
    s->offsets = (int64_t *)malloc(((size_t)s->k + 1) * sizeof *s->offsets);
    if (!s->offsets)
        return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory reading the action types");
    for (t = j->nodes[types].child; t >= 0; t = j->nodes[t].next, index++) {
        long dim = aacp__need(c, t, "dim", "action.types[].dim"), shape = aacp__need(c, t, "shape", "action.types[].shape");
        long toff, dtype;
        int64_t d, product;
        int known = 0;
        if (dim < 0 || shape < 0)
            return AACP_ERR_HEADER;
        product = aacp__shape_product(j, shape, 0);
        if (!aacp__whole(j, dim, 0, &d) || product < 0 || product != d)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "action type %lld: dim %s and shape disagree",
                             (long long)index, aacp__show(j, dim, b1, sizeof b1));
        if ((toff = aacp__need(c, t, "offset", "action.types[].offset")) < 0)
            return AACP_ERR_HEADER;
        if (!aacp__whole(j, toff, 0, NULL) || j->nodes[toff].i != offset)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "action type %lld: offset %s, expected %lld",
                             (long long)index, aacp__show(j, toff, b1, sizeof b1), (long long)offset);
        if ((dtype = aacp__need(c, t, "dtype", "action.types[].dtype")) < 0)
            return AACP_ERR_HEADER;
        for (i = 0; i < 3; i++)
            known |= aacp__string_is(j, dtype, aacp__param_dtypes[i]);
        if (!known)
            return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                             "action type %lld: parameter dtype %s is not one of ['float16', 'float32', 'float64']",
                             (long long)index, aacp__show(j, dtype, b1, sizeof b1));
        s->offsets[index] = offset;
        offset = aacp__add(offset, d);
    }
    s->offsets[s->k] = offset;
    if ((n_params = aacp__need(c, action, "n_params", "action.n_params")) < 0)
        return AACP_ERR_HEADER;
    if (!aacp__whole(j, n_params, 0, &s->n_params) || s->n_params != offset)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "n_params is %s but the types' dims add up to %lld",
                         aacp__show(j, n_params, b1, sizeof b1), (long long)offset);
    return AACP_OK;
}

/* Format, version and every header field (Python: _parse_header and _check_header). */
static int aacp__check_header(aacp__ctx *c, aacp__spec *s) {
    aacp__json *j = c->j;
    char b1[64], b2[64];
    long format = aacp__member(j, 0, "format"), version = aacp__member(j, 0, "version");
    long obs, action, approx, size, shape, features, head, n_features, n_outputs, outputs, blob;
    int64_t product;
    int code;
    if (!aacp__string_is(j, format, AACP_FORMAT_NAME))
        return aacp__bad(c->error, c->name, AACP_ERR_FORMAT, "format is %s, expected '%s'",
                         aacp__show(j, format, b1, sizeof b1), AACP_FORMAT_NAME);
    for (s->version = 2; s->version <= 4 && !aacp__equals(j, version, s->version); s->version++)
        ;
    if (s->version > 4)
        return aacp__bad(c->error, c->name, AACP_ERR_FORMAT,
                         "unknown format version %s; this reader supports [2, 3, 4] "
                         "(a newer sb3-aac wrote it? use a newer aacp.h)",
                         aacp__show(j, version, b1, sizeof b1));
    if ((obs = aacp__need(c, 0, "observation", "observation")) < 0 || (action = aacp__need(c, 0, "action", "action")) < 0 ||
        (approx = aacp__need(c, 0, "approximators", "approximators")) < 0 ||
        (size = aacp__need(c, obs, "size", "observation.size")) < 0 ||
        (shape = aacp__need(c, obs, "shape", "observation.shape")) < 0)
        return AACP_ERR_HEADER;
    product = aacp__shape_product(j, shape, 1);
    if (!aacp__whole(j, size, 1, &s->d) || product != s->d)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "observation size %s and shape disagree",
                         aacp__show(j, size, b1, sizeof b1));
    if ((code = aacp__check_action(c, s, action)) != AACP_OK)
        return code;
    if ((features = aacp__need(c, approx, "features", "approximators.features")) < 0 ||
        (head = aacp__need(c, approx, "head", "approximators.head")) < 0 ||
        (n_features = aacp__need(c, features, "n_features", "approximators.features.n_features")) < 0 ||
        (n_outputs = aacp__need(c, approx, "n_outputs", "approximators.n_outputs")) < 0)
        return AACP_ERR_HEADER;
    if (!aacp__whole(j, n_features, 1, &s->f) || !aacp__whole(j, n_outputs, 1, &s->a))
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "n_features=%s, n_outputs=%s: both must be whole numbers >= 1",
                         aacp__show(j, n_features, b1, sizeof b1), aacp__show(j, n_outputs, b2, sizeof b2));
    if ((code = aacp__check_features_and_head(c, s, features, head)) != AACP_OK)
        return code;
    if ((s->head == AACP__NETWORKS || s->head == AACP__PDQN) &&
        (code = aacp__check_networks(c, s, aacp__member(j, head, "networks"))) != AACP_OK)
        return code;
    if ((outputs = aacp__need(c, approx, "outputs", "approximators.outputs")) < 0)
        return AACP_ERR_HEADER;
    if (s->a != aacp__add(aacp__add(s->k, s->n_params), 1) || !aacp__outputs_ok(j, outputs, s->k, s->n_params))
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "approximator outputs (n_outputs=%lld); "
                         "expected {'q': [0, %lld], 'params': [%lld, %lld], 'value': %lld}",
                         (long long)s->a, (long long)s->k, (long long)s->k, (long long)(s->k + s->n_params),
                         (long long)(s->k + s->n_params));
    if ((s->arrays = aacp__need(c, 0, "arrays", "arrays")) < 0 || (blob = aacp__need(c, 0, "blob_size", "blob_size")) < 0)
        return AACP_ERR_HEADER;
    if (!aacp__is(j, s->arrays, AACP__OBJECT) || !aacp__whole(j, blob, 1, &s->blob_size))
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER, "the arrays table or blob_size is malformed");
    if ((uint64_t)s->blob_size > AACP_MAX_BLOB_BYTES)
        return aacp__bad(c->error, c->name, AACP_ERR_HEADER,
                         "it announces %lld bytes of arrays, more than this reader accepts (%llu)", (long long)s->blob_size,
                         (unsigned long long)AACP_MAX_BLOB_BYTES);
    return AACP_OK;
}

/* Every needed array's entry: dtype, shape, offset and size inside the blob (Python: _array_placements). */
static int aacp__check_placements(aacp__ctx *c, aacp__spec *s) {
    aacp__json *j = c->j;
    int n;
    if (aacp__expected_arrays(s) != 0)
        return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory listing the arrays");
    for (n = 0; n < s->n_arrays; n++) {
        aacp__array_spec *a = &s->array[n];
        long entry = aacp__member(j, s->arrays, a->name), offset, nbytes, dtype, shape, e;
        int64_t size = 8, off, bytes, dim;
        int axis = 0, shape_ok;
        if (!aacp__is(j, entry, AACP__OBJECT))
            return aacp__bad(c->error, c->name, AACP_ERR_ARRAY, "missing array '%s'", a->name);
        offset = aacp__member(j, entry, "offset"), nbytes = aacp__member(j, entry, "nbytes");
        dtype = aacp__member(j, entry, "dtype"), shape = aacp__member(j, entry, "shape");
        if (offset < 0 || nbytes < 0 || dtype < 0 || shape < 0)
            return aacp__bad(c->error, c->name, AACP_ERR_ARRAY, "array '%s': malformed entry", a->name);
        if (!aacp__string_is(j, dtype, "<f8"))
            return aacp__bad(c->error, c->name, AACP_ERR_ARRAY,
                             "array '%s' has dtype other than '<f8'; every array is stored as '<f8'", a->name);
        shape_ok = aacp__is(j, shape, AACP__ARRAY) && (int)j->nodes[shape].count == a->ndim;
        for (e = shape_ok ? j->nodes[shape].child : -1; e >= 0; e = j->nodes[e].next, axis++)
            if (!aacp__whole(j, e, 0, &dim) || dim != a->shape[axis])
                shape_ok = 0;
        if (!shape_ok) {
            char want[96];
            if (a->ndim == 1)
                snprintf(want, sizeof want, "(%lld,)", (long long)a->shape[0]);
            else if (a->ndim == 2)
                snprintf(want, sizeof want, "(%lld, %lld)", (long long)a->shape[0], (long long)a->shape[1]);
            else
                snprintf(want, sizeof want, "(%lld, %lld, %lld)", (long long)a->shape[0], (long long)a->shape[1],
                         (long long)a->shape[2]);
            return aacp__bad(c->error, c->name, AACP_ERR_ARRAY,
                             "array '%s' has another shape than the header's sizes need, %s", a->name, want);
        }
        for (axis = 0; axis < a->ndim; axis++)
            size = aacp__mul(size, a->shape[axis]);
        if (!aacp__whole(j, offset, 0, &off) || off % AACP__ALIGN != 0 || aacp__add(off, size) > s->blob_size ||
            !aacp__whole(j, nbytes, 0, &bytes) || bytes != size)
            return aacp__bad(c->error, c->name, AACP_ERR_ARRAY, "array '%s': offset / nbytes do not fit the %lld-byte blob",
                             a->name, (long long)s->blob_size);
        a->offset = off;
    }
    return AACP_OK;
}

/* ------------------------------------------------------------------------------------------------ policy */

typedef struct aacp__layer {
    int kind;       /* AACP__LAYER_* */
    size_t in, out; /* values read and written */
    double constant; /* a layer norm's eps, a leaky ReLU's slope */
    double *w, *b;  /* linear: weight (out, in), bias (out); affine layer norm: weight, bias (out); else NULL */
} aacp__layer;

typedef struct aacp__network {
    size_t start, stop;  /* the outputs it writes */
    size_t first, count; /* its layers */
} aacp__network;

struct aacp_policy {
    size_t d, k, n_params, a, f, m, h, c, g, max_dim;
    int features, head, layout;
    int64_t start;
    size_t *offsets;          /* K + 1 */
    double window_z2;         /* RBF window (INFINITY: none) */
    double *feature_a, *feature_b; /* (D, m) or (D): feature z = s_i * a - b, folded as BankForward folds them */
    double *w, *b;            /* linear: weight (A, F), bias (A); MLP: weight1 (A*H, F), bias1 (A*H) */
    double *w2, *b2;          /* MLP: weight2 (A, H), bias2 (A) */
    double *param_low, *param_high;
    size_t *tile_inputs;      /* (C, k) */
    double *tile_a, *tile_b, *tile_limit; /* (C, k): coordinate s * a - b clipped to [0, limit] */
    int64_t *tile_strides;    /* (C, k) */
    int64_t *tile_bases;      /* (C) */
    double *tile_weight;      /* (F, A) */
    size_t n_networks, n_layers, width; /* networks and pdqn heads: the widest layer (or D) */
    int multi_pass;           /* pdqn head: MP-DQN's K passes */
    aacp__network *networks;
    aacp__layer *layers;
    double *h0, *h1;          /* scratch: a layer's input and output (width values each) */
    unsigned char *computed;  /* scratch: networks evaluated for this decision */
    double *phi;              /* scratch: features that are not 0 (pdqn: the Q network's input [x, p]) */
    size_t *active;           /* scratch: their indices (tiles: each coding's active feature) */
    double *outputs;          /* scratch: K outputs, then the chosen type's scaled parameters */
    double *params;           /* scratch: the chosen type's parameters */
};

void aacp_free(aacp_policy *p) {
    if (!p)
        return;
    free(p->offsets), free(p->feature_a), free(p->feature_b), free(p->w), free(p->b), free(p->w2), free(p->b2);
    free(p->param_low), free(p->param_high), free(p->tile_inputs), free(p->tile_a), free(p->tile_b), free(p->tile_limit);
    free(p->tile_strides), free(p->tile_bases), free(p->tile_weight), free(p->phi), free(p->active), free(p->outputs);
    free(p->params);
    if (p->layers) {
        size_t l;
        for (l = 0; l < p->n_layers; l++)
            free(p->layers[l].w), free(p->layers[l].b);
    }
    free(p->networks), free(p->layers), free(p->h0), free(p->h1), free(p->computed);
    free(p);
}

static double aacp__f64(const unsigned char *p) {
    uint64_t bits = 0;
    double value;
    int i;
    for (i = 7; i >= 0; i--)
        bits = bits << 8 | p[i];
    memcpy(&value, &bits, sizeof value);
    return value;
}

static const aacp__array_spec *aacp__find(const aacp__spec *s, const char *name) {
    int n;
    for (n = 0; n < s->n_arrays; n++)
        if (!strcmp(s->array[n].name, name))
            return &s->array[n];
    return NULL;
}

static size_t aacp__elements(const aacp__array_spec *a) {
    size_t n = 1;
    int axis;
    for (axis = 0; axis < a->ndim; axis++)
        n *= (size_t)a->shape[axis];
    return n;
}

/* A checked array's values, copied out of the blob (NULL: out of memory). */
static double *aacp__array(const aacp__spec *s, const unsigned char *blob, const char *name, size_t *count) {
    const aacp__array_spec *a = aacp__find(s, name);
    size_t n = aacp__elements(a), i;
    double *out = (double *)malloc((n ? n : 1) * sizeof *out);
    if (out)
        for (i = 0; i < n; i++)
            out[i] = aacp__f64(blob + a->offset + 8 * i);
    if (count)
        *count = n;
    return out;
}

static int aacp__all_positive(const aacp__spec *s, const unsigned char *blob, const char *name) {
    const aacp__array_spec *a = aacp__find(s, name);
    size_t n = aacp__elements(a), i;
    for (i = 0; i < n; i++)
        if (!(aacp__f64(blob + a->offset + 8 * i) > 0))
            return 0;
    return 1;
}

/* Values (Python: check_array_values): finite (obs_low/high: no NaN), obs_half > 0, param_low <= param_high,
   rbf_widths > 0, tile index arrays whole and inside the table. */
static int aacp__check_values(aacp__ctx *c, const aacp__spec *s, const unsigned char *blob) {
    int n;
    size_t i, cc, jj;
    for (n = 0; n < s->n_arrays; n++) {
        const aacp__array_spec *a = &s->array[n];
        size_t count = aacp__elements(a);
        int bounds = !strcmp(a->name, "obs_low") || !strcmp(a->name, "obs_high");
        for (i = 0; i < count; i++) {
            double v = aacp__f64(blob + a->offset + 8 * i);
            if (bounds ? v != v : !isfinite(v))
                return aacp__bad(c->error, c->name, AACP_ERR_VALUE,
                                 bounds ? "array '%s' holds NaN" : "array '%s' holds NaN or inf values", a->name);
        }
    }
    if (!aacp__all_positive(s, blob, "obs_half"))
        return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "obs_half must be > 0 everywhere");
    {
        const aacp__array_spec *low = aacp__find(s, "param_low"), *high = aacp__find(s, "param_high");
        for (i = 0; i < (size_t)s->n_params; i++)
            if (!(aacp__f64(blob + low->offset + 8 * i) <= aacp__f64(blob + high->offset + 8 * i)))
                return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "param_low must be <= param_high everywhere");
    }
    if (s->features == AACP__RBF && !aacp__all_positive(s, blob, "rbf_widths"))
        return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "rbf_widths must be > 0 everywhere");
    if (s->features == AACP__TILES) {
        static const char *const whole[4] = {"tile_inputs", "tile_resolution", "tile_strides", "tile_bases"};
        const aacp__array_spec *in = aacp__find(s, "tile_inputs"), *res = aacp__find(s, "tile_resolution");
        const aacp__array_spec *stride = aacp__find(s, "tile_strides"), *base = aacp__find(s, "tile_bases");
        double most = -INFINITY;
        int w;
        for (w = 0; w < 4; w++) {
            const aacp__array_spec *a = aacp__find(s, whole[w]);
            size_t count = aacp__elements(a);
            for (i = 0; i < count; i++) {
                double v = aacp__f64(blob + a->offset + 8 * i);
                if (floor(v) != v || v < 0)
                    return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "array '%s' must hold whole numbers >= 0", whole[w]);
            }
        }
        for (i = 0; i < (size_t)(s->c * s->g); i++)
            if (aacp__f64(blob + in->offset + 8 * i) >= (double)s->d || aacp__f64(blob + res->offset + 8 * i) < 1)
                return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "tile_inputs must be < %lld and tile_resolution >= 1",
                                 (long long)s->d);
        for (cc = 0; cc < (size_t)s->c; cc++) { /* numpy: bases + (resolution * strides).sum(1), in float64 */
            double reach = 0;
            for (jj = 0; jj < (size_t)s->g; jj++)
                reach += aacp__f64(blob + res->offset + 8 * (cc * s->g + jj)) *
                         aacp__f64(blob + stride->offset + 8 * (cc * s->g + jj));
            reach = aacp__f64(blob + base->offset + 8 * cc) + reach;
            if (reach > most)
                most = reach;
        }
        if (!(most < (double)s->f))
            return aacp__bad(c->error, c->name, AACP_ERR_VALUE, "the tile grids reach past the %lld features of the table",
                             (long long)s->f);
    }
    return AACP_OK;
}

static double *aacp__array(const aacp__spec *s, const unsigned char *blob, const char *name, size_t *count);

/* A networks or pdqn head (NetworkForward, PDQNForward): the scaled inputs' constants, each layer and its arrays; 0, or
   -1 out of memory. */
static int aacp__build_networks(const aacp__spec *s, const unsigned char *blob, aacp_policy *p, const double *mid,
                                const double *half) {
    size_t i, l;
    p->n_networks = s->n_networks, p->n_layers = s->n_layers, p->width = p->d;
    p->networks = (aacp__network *)calloc(s->n_networks ? s->n_networks : 1, sizeof *p->networks);
    p->layers = (aacp__layer *)calloc(s->n_layers ? s->n_layers : 1, sizeof *p->layers);
    p->feature_a = (double *)aacp__alloc(p->d, sizeof *p->feature_a);
    p->feature_b = (double *)aacp__alloc(p->d, sizeof *p->feature_b);
    p->computed = (unsigned char *)aacp__alloc(s->n_networks, 1);
    p->multi_pass = s->multi_pass;
    /* the scaled inputs (pdqn: then the actor's P parameters, the Q network's input) */
    p->phi = (double *)aacp__alloc(p->d + (s->head == AACP__PDQN ? p->n_params : 0), sizeof *p->phi);
    if (!p->networks || !p->layers || !p->feature_a || !p->feature_b || !p->computed || !p->phi)
        return -1;
    for (i = 0; i < p->d; i++) { /* NetworkForward: a = 1 / half, b = mid * a */
        p->feature_a[i] = 1.0 / half[i];
        p->feature_b[i] = mid[i] * p->feature_a[i];
    }
    for (i = 0; i < s->n_networks; i++) {
        const aacp__network_spec *net = &s->networks[i];
        p->networks[i].start = (size_t)net->start, p->networks[i].stop = (size_t)net->stop;
        p->networks[i].first = net->first, p->networks[i].count = net->count;
        for (l = 0; l < net->count; l++) {
            const aacp__layer_spec *spec = &s->layers[net->first + l];
            aacp__layer *layer = &p->layers[net->first + l];
            layer->kind = spec->kind, layer->constant = spec->constant;
            layer->in = (size_t)spec->in, layer->out = (size_t)spec->out;
            if (layer->out > p->width)
                p->width = layer->out;
            if (spec->kind == AACP__LAYER_LINEAR || (spec->kind == AACP__LAYER_NORM && spec->affine)) {
                char weight[64], bias[64];
                snprintf(weight, sizeof weight, "net%lu_%lu_weight", (unsigned long)i, (unsigned long)l);
                snprintf(bias, sizeof bias, "net%lu_%lu_bias", (unsigned long)i, (unsigned long)l);
                layer->w = aacp__array(s, blob, weight, NULL), layer->b = aacp__array(s, blob, bias, NULL);
                if (!layer->w || !layer->b)
                    return -1;
            }
        }
    }
    p->h0 = (double *)aacp__alloc(p->width, sizeof *p->h0), p->h1 = (double *)aacp__alloc(p->width, sizeof *p->h1);
    return p->h0 && p->h1 ? 0 : -1;
}

/* The policy of a checked file: BankForward's, TileForward's or NetworkForward's constants, and scratch buffers. */
static int aacp__build(aacp__ctx *c, const aacp__spec *s, const unsigned char *blob, aacp_policy **out) {
    aacp_policy *p = (aacp_policy *)calloc(1, sizeof *p);
    double *mid = NULL, *half = NULL;
    size_t i, jj, n;
    int ok = 1;
    if (!p)
        return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory");
    p->d = (size_t)s->d, p->k = (size_t)s->k, p->n_params = (size_t)s->n_params, p->a = (size_t)s->a, p->f = (size_t)s->f;
    p->m = s->features == AACP__RBF ? (size_t)s->m : 0, p->h = s->head == AACP__TANH_MLP ? (size_t)s->h : 0;
    p->c = (size_t)s->c, p->g = (size_t)s->g, p->features = s->features, p->head = s->head, p->layout = s->layout;
    p->start = s->start, p->window_z2 = s->window_z2;
    p->offsets = (size_t *)aacp__alloc(p->k + 1, sizeof *p->offsets);
    mid = aacp__array(s, blob, "obs_mid", NULL), half = aacp__array(s, blob, "obs_half", NULL);
    p->param_low = aacp__array(s, blob, "param_low", NULL), p->param_high = aacp__array(s, blob, "param_high", NULL);
    if (!p->offsets || !mid || !half || !p->param_low || !p->param_high)
        goto nomem;
    for (i = 0; i <= p->k; i++)
        p->offsets[i] = (size_t)s->offsets[i];
    for (i = 0; i < p->k; i++)
        if (p->offsets[i + 1] - p->offsets[i] > p->max_dim)
            p->max_dim = p->offsets[i + 1] - p->offsets[i];
    p->params = (double *)aacp__alloc(p->max_dim, sizeof *p->params);
    p->outputs = (double *)aacp__alloc(p->a, sizeof *p->outputs); /* A >= K, A >= every dim */
    if (!p->params || !p->outputs)
        goto nomem;
    if (s->features == AACP__TILES) {
        double *inputs = aacp__array(s, blob, "tile_inputs", &n), *offsets = aacp__array(s, blob, "tile_offsets", NULL);
        double *strides = aacp__array(s, blob, "tile_strides", NULL), *bases = aacp__array(s, blob, "tile_bases", NULL);
        p->tile_limit = aacp__array(s, blob, "tile_resolution", NULL);
        p->tile_weight = aacp__array(s, blob, "tile_weight", NULL), p->b = aacp__array(s, blob, "bias", NULL);
        p->tile_inputs = (size_t *)aacp__alloc(n, sizeof *p->tile_inputs);
        p->tile_strides = (int64_t *)aacp__alloc(n, sizeof *p->tile_strides);
        p->tile_bases = (int64_t *)aacp__alloc(p->c, sizeof *p->tile_bases);
        p->tile_a = (double *)aacp__alloc(n, sizeof *p->tile_a), p->tile_b = (double *)aacp__alloc(n, sizeof *p->tile_b);
        p->active = (size_t *)aacp__alloc(p->c, sizeof *p->active);
        ok = inputs && offsets && strides && bases && p->tile_limit && p->tile_weight && p->b && p->tile_inputs &&
             p->tile_strides && p->tile_bases && p->tile_a && p->tile_b && p->active;
        if (ok) {
            for (i = 0; i < n; i++) { /* whole numbers, checked: inputs < D, strides * resolution < F */
                double res = p->tile_limit[i];
                p->tile_inputs[i] = (size_t)inputs[i];
                p->tile_strides[i] = (int64_t)strides[i];
                /* TileForward: a = res / (2 * half), b = mid * a - res / 2 - offset */
                p->tile_a[i] = res / (2 * half[p->tile_inputs[i]]);
                p->tile_b[i] = mid[p->tile_inputs[i]] * p->tile_a[i] - res / 2 - offsets[i];
            }
            for (i = 0; i < p->c; i++)
                p->tile_bases[i] = (int64_t)bases[i];
        }
        free(inputs), free(offsets), free(strides), free(bases);
        if (!ok)
            goto nomem;
    } else if (s->head == AACP__NETWORKS || s->head == AACP__PDQN) {
        if (aacp__build_networks(s, blob, p, mid, half) != 0)
            goto nomem;
    } else {
        size_t m = p->m ? p->m : 1;
        p->feature_a = (double *)aacp__alloc(p->d * m, sizeof *p->feature_a);
        p->feature_b = (double *)aacp__alloc(p->d * m, sizeof *p->feature_b);
        p->phi = (double *)aacp__alloc(p->f, sizeof *p->phi);
        p->active = (size_t *)aacp__alloc(p->f, sizeof *p->active);
        if (!p->feature_a || !p->feature_b || !p->phi || !p->active)
            goto nomem;
        if (p->m) {
            double *centers = aacp__array(s, blob, "rbf_centers", NULL), *widths = aacp__array(s, blob, "rbf_widths", NULL);
            ok = centers && widths;
            for (i = 0; ok && i < p->d; i++) {
                /* BankForward: scale = 1 / half, shift = mid * scale, inv_w = sqrt(0.5) / w,
                   a = scale * inv_w, b = (shift + c) * inv_w */
                double scale = 1.0 / half[i], shift = mid[i] * scale;
                for (jj = 0; jj < p->m; jj++) {
                    double inv_w = sqrt(0.5) / widths[i * p->m + jj];
                    p->feature_a[i * p->m + jj] = scale * inv_w;
                    p->feature_b[i * p->m + jj] = (shift + centers[i * p->m + jj]) * inv_w;
                }
            }
            free(centers), free(widths);
            if (!ok)
                goto nomem;
        } else
            for (i = 0; i < p->d; i++) {
                double scale = 1.0 / half[i];
                p->feature_a[i] = scale, p->feature_b[i] = mid[i] * scale;
            }
        if (p->head == AACP__LINEAR) {
            p->w = aacp__array(s, blob, "weight", NULL), p->b = aacp__array(s, blob, "bias", NULL);
            ok = p->w && p->b;
        } else {
            p->w = aacp__array(s, blob, "weight1", NULL), p->b = aacp__array(s, blob, "bias1", NULL);
            p->w2 = aacp__array(s, blob, "weight2", NULL), p->b2 = aacp__array(s, blob, "bias2", NULL);
            ok = p->w && p->b && p->w2 && p->b2;
        }
        if (!ok)
            goto nomem;
    }
    free(mid), free(half);
    *out = p;
    return AACP_OK;
nomem:
    free(mid), free(half);
    aacp_free(p);
    return aacp__set(c->error, AACP_ERR_MEMORY, "out of memory building the policy");
}

/* A whole file in memory, checked in the documented order; `name` names it in messages. */
static int aacp__load(const unsigned char *data, size_t size, const char *name, aacp_policy **policy, aacp_error *error) {
    uint64_t header_len = 0;
    unsigned char digest[AACP__DIGEST];
    aacp__json j;
    aacp__spec s;
    aacp__ctx c;
    int i, code;
    size_t blob_start;
    if (size < AACP__PREAMBLE)
        return aacp__bad(error, name, AACP_ERR_TRUNCATED, "only %lu bytes (truncated?)", (unsigned long)size);
    if (memcmp(data, aacp__magic, 8) != 0)
        return aacp__bad(error, name, AACP_ERR_MAGIC,
                         "it does not start with the magic bytes b'SB3AACP\\x00'; export one with sb3_aac.export_policy");
    for (i = 15; i >= 8; i--)
        header_len = header_len << 8 | data[i];
    if (header_len > AACP_MAX_HEADER_BYTES || (AACP__PREAMBLE + header_len) % AACP__ALIGN)
        return aacp__bad(error, name, AACP_ERR_HEADER, "header length %llu: at most %llu bytes, ending on a multiple of 8",
                         (unsigned long long)header_len, (unsigned long long)AACP_MAX_HEADER_BYTES);
    blob_start = AACP__PREAMBLE + (size_t)header_len;
    if (size < blob_start)
        return aacp__bad(error, name, AACP_ERR_TRUNCATED, "it ends inside the header (%lu of %llu bytes; truncated?)",
                         (unsigned long)(size - AACP__PREAMBLE), (unsigned long long)header_len);
    if (size - blob_start < AACP__DIGEST)
        return aacp__bad(error, name, AACP_ERR_TRUNCATED, "it ends inside the arrays and checksum (truncated?)");
    aacp__sha256(data, size - AACP__DIGEST, digest);
    if (memcmp(digest, data + size - AACP__DIGEST, AACP__DIGEST) != 0)
        return aacp__bad(error, name, AACP_ERR_CHECKSUM,
                         AACP__CHECKSUM_MISMATCH);
    if (aacp__json_parse(&j, data + AACP__PREAMBLE, (size_t)header_len) != 0) {
        code = j.nomem ? AACP_ERR_MEMORY : AACP_ERR_JSON;
        aacp__bad(error, name, code, "the header is not UTF-8 JSON (%s)", j.why);
        aacp__json_free(&j);
        return code;
    }
    memset(&s, 0, sizeof s);
    c.j = &j, c.error = error, c.name = name;
    code = aacp__check_header(&c, &s);
    if (code == AACP_OK && (uint64_t)(size - blob_start - AACP__DIGEST) != (uint64_t)s.blob_size)
        code = aacp__bad(error, name, AACP_ERR_TRUNCATED, "the header announces %lld bytes of arrays, the file holds %lu",
                         (long long)s.blob_size, (unsigned long)(size - blob_start - AACP__DIGEST));
    if (code == AACP_OK)
        code = aacp__check_placements(&c, &s);
    if (code == AACP_OK)
        code = aacp__check_values(&c, &s, data + blob_start);
    if (code == AACP_OK)
        code = aacp__build(&c, &s, data + blob_start, policy);
    aacp__spec_free(&s);
    aacp__json_free(&j);
    return code;
}

int aacp_load_memory(const void *data, size_t size, aacp_policy **policy, aacp_error *error) {
    if (!policy)
        return aacp__set(error, AACP_ERR_ARGUMENT, "aacp_load_memory: policy is NULL");
    *policy = NULL;
    if (!data && size)
        return aacp__set(error, AACP_ERR_ARGUMENT, "aacp_load_memory: data is NULL");
    return aacp__load((const unsigned char *)(data ? data : ""), data ? size : 0, "<memory>", policy, error);
}

/* ------------------------------------------------------------------------------------------------ files */

/* Append up to `want` bytes of `f` to *buf (of *len bytes), growing it as bytes arrive (a lying size cannot make us
   allocate it). Returns AACP_OK (check *len for a short read), or an I/O or memory error. */
static int aacp__read(FILE *f, unsigned char **buf, size_t *len, size_t want, const char *path, aacp_error *error) {
    size_t target = *len + want;
    while (*len < target) {
        size_t chunk = target - *len < ((size_t)1 << 20) ? target - *len : ((size_t)1 << 20), got;
        unsigned char *grown = (unsigned char *)realloc(*buf, *len + chunk);
        if (!grown)
            return aacp__set(error, AACP_ERR_MEMORY, "out of memory reading %s", path);
        *buf = grown;
        got = fread(*buf + *len, 1, chunk, f);
        *len += got;
        if (got < chunk) {
            if (ferror(f))
                return aacp__set(error, AACP_ERR_IO, "cannot read %s (a directory?)", path);
            break;
        }
    }
    return AACP_OK;
}

/* Read a policy file header first, never further than its header declares (as the Python reader reads). */
static int aacp__load_stream(FILE *f, const char *path, aacp_policy **policy, aacp_error *error) {
    unsigned char *buf = NULL;
    size_t len = 0, header_end;
    uint64_t header_len = 0;
    aacp__json j;
    aacp__spec s;
    aacp__ctx c;
    int code, i, header_code;
    if ((code = aacp__read(f, &buf, &len, AACP__PREAMBLE, path, error)) != AACP_OK)
        goto done;
    if (len < AACP__PREAMBLE || memcmp(buf, aacp__magic, 8) != 0) {
        code = aacp__load(buf, len, path, policy, error); /* the truncation or magic error */
        goto done;
    }
    for (i = 15; i >= 8; i--)
        header_len = header_len << 8 | buf[i];
    if (header_len > AACP_MAX_HEADER_BYTES || (AACP__PREAMBLE + header_len) % AACP__ALIGN) {
        code = aacp__load(buf, len, path, policy, error); /* the header length error */
        goto done;
    }
    if ((code = aacp__read(f, &buf, &len, (size_t)header_len, path, error)) != AACP_OK)
        goto done;
    header_end = len;
    if (len < AACP__PREAMBLE + header_len) {
        code = aacp__load(buf, len, path, policy, error); /* ends inside the header */
        goto done;
    }
    /* The header's own checks, to learn blob_size before reading the arrays. */
    memset(&s, 0, sizeof s);
    c.j = &j, c.error = error, c.name = path;
    if (aacp__json_parse(&j, buf + AACP__PREAMBLE, (size_t)header_len) != 0)
        header_code = aacp__bad(error, path, j.nomem ? AACP_ERR_MEMORY : AACP_ERR_JSON, "the header is not UTF-8 JSON (%s)",
                                j.why);
    else
        header_code = aacp__check_header(&c, &s);
    aacp__json_free(&j);
    aacp__spec_free(&s);
    if (header_code != AACP_OK) {
        /* A seekable file of sane size whose checksum fails: say that (an altered byte is the likelier story). */
        aacp_error saved;
        long here = ftell(f), end = -1;
        memset(&saved, 0, sizeof saved);
        if (error)
            saved = *error;
        if (here >= 0 && fseek(f, 0, SEEK_END) == 0)
            end = ftell(f);
        code = here >= 0 && end >= here && fseek(f, here, SEEK_SET) == 0 ? AACP_OK : AACP_ERR_IO;
        if (code == AACP_OK && (uint64_t)(end - here) >= AACP__DIGEST &&
            (uint64_t)(end - here) <= AACP_MAX_BLOB_BYTES + AACP__DIGEST)
            code = aacp__read(f, &buf, &len, (size_t)(end - here), path, error);
        else
            code = AACP_ERR_IO;
        if (code == AACP_OK && len == header_end + (size_t)(end - here)) {
            unsigned char digest[AACP__DIGEST];
            aacp__sha256(buf, len - AACP__DIGEST, digest);
            if (memcmp(digest, buf + len - AACP__DIGEST, AACP__DIGEST) != 0) {
                code = aacp__bad(error, path, AACP_ERR_CHECKSUM,
                                 AACP__CHECKSUM_MISMATCH);
                goto done;
            }
        }
        if (error)
            *error = saved;
        code = header_code;
        goto done;
    }
    if ((code = aacp__read(f, &buf, &len, (size_t)s.blob_size + AACP__DIGEST, path, error)) != AACP_OK)
        goto done;
    if (len < header_end + (size_t)s.blob_size + AACP__DIGEST) {
        code = aacp__bad(error, path, AACP_ERR_TRUNCATED,
                         "it ends inside the arrays and checksum (%lu of %llu bytes; truncated?)",
                         (unsigned long)(len - header_end), (unsigned long long)(s.blob_size + AACP__DIGEST));
        goto done;
    }
    if (fgetc(f) != EOF) {
        code = aacp__bad(error, path, AACP_ERR_CHECKSUM,
                         "bytes follow its SHA-256 checksum (trailing data: the file was altered); export it again");
        goto done;
    }
    code = aacp__load(buf, len, path, policy, error);
done:
    free(buf);
    return code;
}

/* 1 if path names a named pipe (FIFO): opening one to read waits for a writer, maybe for ever (POSIX only). */
static int aacp__is_fifo(const char *path) {
#if defined(__unix__) || defined(__APPLE__)
    struct stat st;
    return stat(path, &st) == 0 && S_ISFIFO(st.st_mode);
#else
    (void)path;
    return 0;
#endif
}

int aacp_load_file(const char *path, aacp_policy **policy, aacp_error *error) {
    FILE *f;
    int code;
    if (!policy || !path)
        return aacp__set(error, AACP_ERR_ARGUMENT, "aacp_load_file: path or policy is NULL");
    *policy = NULL;
    if (aacp__is_fifo(path))
        return aacp__set(error, AACP_ERR_IO, "cannot read %s: it is a named pipe (FIFO), not a policy file", path);
    f = fopen(path, "rb");
    if (!f) {
        /* sb3_aac.export_policy appends ".aacp" to a name without a suffix; accept that name too. */
        const char *base = strrchr(path, '/'), *dot;
        base = base ? base + 1 : path;
        while (*base == '.')
            base++;
        dot = strchr(base, '.');
        if (*base && !dot) {
            size_t n = strlen(path);
            char *named = (char *)malloc(n + 6);
            if (!named)
                return aacp__set(error, AACP_ERR_MEMORY, "out of memory");
            memcpy(named, path, n);
            memcpy(named + n, ".aacp", 6);
            f = fopen(named, "rb");
            if (f) {
                code = aacp__load_stream(f, named, policy, error);
                fclose(f);
                free(named);
                return code;
            }
            free(named);
        }
        return aacp__set(error, AACP_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    }
    code = aacp__load_stream(f, path, policy, error);
    fclose(f);
    return code;
}

/* ------------------------------------------------------------------------------------------------ acting */

/* Dot products in four partial sums (independent chains the CPU overlaps; the order is fixed, so every build of
   this header sums alike): row[0..n) . x[0..n), and row[index[f]] * x[f] over f < n. */
static double aacp__dot(const double *row, const double *x, size_t n) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        s0 += row[k] * x[k];
        s1 += row[k + 1] * x[k + 1];
        s2 += row[k + 2] * x[k + 2];
        s3 += row[k + 3] * x[k + 3];
    }
    for (; k < n; k++)
        s0 += row[k] * x[k];
    return (s0 + s1) + (s2 + s3);
}

static double aacp__sparse_dot(const double *row, const size_t *index, const double *x, size_t n) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        s0 += row[index[k]] * x[k];
        s1 += row[index[k + 1]] * x[k + 1];
        s2 += row[index[k + 2]] * x[k + 2];
        s3 += row[index[k + 3]] * x[k + 3];
    }
    for (; k < n; k++)
        s0 += row[index[k]] * x[k];
    return (s0 + s1) + (s2 + s3);
}

/* Output a of a bank head on the features phi[0..n) at indices active[0..n) (the others are 0; n == F: all). */
static double aacp__output(const aacp_policy *p, size_t a, size_t n) {
    size_t u;
    if (p->head == AACP__TANH_MLP) {
        double acc = 0.0;
        for (u = 0; u < p->h; u++) {
            const double *row = p->w + (a * p->h + u) * p->f;
            double s = n == p->f ? aacp__dot(row, p->phi, n) : aacp__sparse_dot(row, p->active, p->phi, n);
            acc += tanh(s + p->b[a * p->h + u]) * p->w2[a * p->h + u];
        }
        return acc + p->b2[a];
    } else {
        const double *row = p->w + a * p->f;
        return (n == p->f ? aacp__dot(row, p->phi, n) : aacp__sparse_dot(row, p->active, p->phi, n)) + p->b[a];
    }
}

/* Outputs first .. first + count - 1 of a tile head, into out: one pass over the codings' rows of the (F, A) table. */
static void aacp__tile_outputs(const aacp_policy *p, size_t first, size_t count, double *out) {
    size_t c, a;
    for (a = 0; a < count; a++)
        out[a] = 0.0;
    for (c = 0; c < p->c; c++) {
        const double *row = p->tile_weight + p->active[c] * p->a + first;
        for (a = 0; a < count; a++)
            out[a] += row[a];
    }
    for (a = 0; a < count; a++)
        out[a] += p->b[first + a];
}

/* Network i on its n inputs x (ScaledNetworks.network): its last layer's values (in h0 or h1, or x itself). */
static const double *aacp__run_network(aacp_policy *p, size_t i, const double *x, size_t n) {
    const aacp__network *net = &p->networks[i];
    const double *h = x;
    double *out = p->h0;
    size_t l, o, k;
    for (l = 0; l < net->count; l++) {
        const aacp__layer *layer = &p->layers[net->first + l];
        if (layer->kind == AACP__LAYER_LINEAR) {
            for (o = 0; o < layer->out; o++)
                out[o] = aacp__dot(layer->w + o * layer->in, h, layer->in) + layer->b[o];
            n = layer->out;
        } else if (layer->kind == AACP__LAYER_NORM) {
            /* (h - mean) / sqrt(mean squared deviation + eps), then * weight + bias if affine */
            double mean = 0.0, square = 0.0, inv_std;
            for (k = 0; k < n; k++)
                mean += h[k];
            mean /= (double)n;
            for (k = 0; k < n; k++) {
                out[k] = h[k] - mean;
                square += out[k] * out[k];
            }
            inv_std = 1.0 / sqrt(square / (double)n + layer->constant);
            for (k = 0; k < n; k++)
                out[k] *= inv_std;
            if (layer->w)
                for (k = 0; k < n; k++)
                    out[k] = out[k] * layer->w[k] + layer->b[k];
        } else if (layer->kind == AACP__LAYER_TANH) {
            for (k = 0; k < n; k++)
                out[k] = tanh(h[k]);
        } else if (layer->kind == AACP__LAYER_RELU) {
            for (k = 0; k < n; k++)
                out[k] = h[k] > 0.0 ? h[k] : 0.0;
        } else {
            for (k = 0; k < n; k++)
                out[k] = h[k] > 0.0 ? h[k] : layer->constant * h[k];
        }
        h = out; /* the next layer reads this one's values and writes the other buffer */
        out = out == p->h0 ? p->h1 : p->h0;
    }
    return h;
}

/* Network i of a networks head on the scaled inputs x (NetworkForward): its values go to outputs[start .. stop). */
static void aacp__network_outputs(aacp_policy *p, size_t i, const double *x) {
    const aacp__network *net = &p->networks[i];
    memcpy(p->outputs + net->start, aacp__run_network(p, i, x, p->d), (net->stop - net->start) * sizeof *x);
}

/* A pdqn head (PDQNForward) on the scaled inputs in phi[0 .. D): the actor's P parameters into outputs[K .. K + P)
   and phi[D .. D + P), then Q into outputs[0 .. K): one pass, or pass k with only type k's parameters, giving Q_k. */
static void aacp__pdqn_outputs(aacp_policy *p) {
    size_t jj, k, n_in = p->d + p->n_params;
    double *x = p->outputs + p->k;
    memcpy(x, aacp__run_network(p, 0, p->phi, p->d), p->n_params * sizeof *x);
    if (!p->multi_pass) {
        memcpy(p->phi + p->d, x, p->n_params * sizeof *x);
        memcpy(p->outputs, aacp__run_network(p, 1, p->phi, n_in), p->k * sizeof *x);
        return;
    }
    for (k = 0; k < p->k; k++) {
        for (jj = 0; jj < p->n_params; jj++)
            p->phi[p->d + jj] = jj >= p->offsets[k] && jj < p->offsets[k + 1] ? x[jj] : 0.0;
        p->outputs[k] = aacp__run_network(p, 1, p->phi, n_in)[k];
    }
}

/* Evaluate every network not yet computed that writes one of the outputs [first, stop). */
static void aacp__networks_for(aacp_policy *p, size_t first, size_t stop, const double *x) {
    size_t i;
    for (i = 0; i < p->n_networks; i++)
        if (!p->computed[i] && p->networks[i].start < stop && first < p->networks[i].stop) {
            aacp__network_outputs(p, i, x);
            p->computed[i] = 1;
        }
}

/* unscale_value: the affine map [-1, 1] -> [low, high], clipped to the bounds. */
static double aacp__unscale(double scaled, double low, double high) {
    double weight = 0.5 * scaled, value = low * (0.5 - weight) + high * (0.5 + weight);
    value = value < low ? low : value; /* Python: min(max(value, low), high) */
    return high < value ? high : value;
}

static int aacp__act(aacp_policy *p, const double *x, aacp_action *action, aacp_error *error) {
    size_t i, jj, n = 0, k = 0, dim, start;
    double total = 0.0, best;
    int tiles = p->features == AACP__TILES, networks = p->head == AACP__NETWORKS, pdqn = p->head == AACP__PDQN;
    for (i = 0; i < p->d; i++)
        total += x[i] * x[i];
    if (!isfinite(total)) { /* one reduction, as RuntimePolicy: NaN, inf (and absurd magnitudes) reach the sum */
        for (i = 0; i < p->d; i++)
            if (!isfinite(x[i]))
                return aacp__set(error, AACP_ERR_OBSERVATION, "the observation holds NaN or inf values");
        return aacp__set(error, AACP_ERR_OBSERVATION,
                         "the observation holds values too large to compute with (their squares overflow double)");
    }
    if (tiles) {
        for (i = 0; i < p->c; i++) {
            int64_t feature = p->tile_bases[i];
            for (jj = 0; jj < p->g; jj++) {
                size_t e = i * p->g + jj;
                double position;
                int64_t coordinate;
                if (p->tile_strides[e] == 0)
                    continue; /* a padded slot */
                /* clip(floor(position), 0, resolution) for a whole resolution, without a libm call (NaN: 0) */
                position = x[p->tile_inputs[e]] * p->tile_a[e] - p->tile_b[e];
                if (!(position >= 0))
                    coordinate = 0;
                else if (position >= p->tile_limit[e])
                    coordinate = (int64_t)p->tile_limit[e];
                else
                    coordinate = (int64_t)position; /* truncation is floor for position >= 0 */
                feature += coordinate * p->tile_strides[e];
            }
            p->active[i] = (size_t)feature;
        }
    } else if (networks || pdqn) { /* the scaled inputs, x * a - b */
        for (i = 0; i < p->d; i++)
            p->phi[i] = x[i] * p->feature_a[i] - p->feature_b[i];
        if (pdqn)
            aacp__pdqn_outputs(p); /* Q needs every type's parameters */
        else {
            memset(p->computed, 0, p->n_networks);
            aacp__networks_for(p, 0, p->k, p->phi); /* the networks that write Q */
        }
    } else if (p->m) {
        for (i = 0; i < p->d; i++)
            for (jj = 0; jj < p->m; jj++) {
                size_t e = i * p->m + jj;
                double z = x[i] * p->feature_a[e] - p->feature_b[e];
                if (z * z <= p->window_z2) {
                    p->phi[n] = exp(-(z * z));
                    p->active[n++] = e;
                }
            }
    } else {
        for (i = 0; i < p->d; i++) {
            p->phi[i] = x[i] * p->feature_a[i] - p->feature_b[i];
            p->active[i] = i;
        }
        n = p->d;
    }
    if (tiles)
        aacp__tile_outputs(p, 0, p->k, p->outputs);
    else if (!networks && !pdqn)
        for (i = 0; i < p->k; i++)
            p->outputs[i] = aacp__output(p, i, n);
    for (i = 1, best = p->outputs[0]; i < p->k; i++) /* the first maximum */
        if (p->outputs[i] > best)
            best = p->outputs[i], k = i;
    start = p->offsets[k], dim = p->offsets[k + 1] - start;
    if (tiles)
        aacp__tile_outputs(p, p->k + start, dim, p->outputs);
    else if (networks || pdqn) { /* the chosen type's parameters (computed already for pdqn), moved to the front */
        if (networks)
            aacp__networks_for(p, p->k + start, p->k + start + dim, p->phi);
        memmove(p->outputs, p->outputs + p->k + start, dim * sizeof *p->outputs);
    } else
        for (jj = 0; jj < dim; jj++)
            p->outputs[jj] = aacp__output(p, p->k + start + jj, n);
    for (jj = 0; jj < dim; jj++)
        p->params[jj] = aacp__unscale(p->outputs[jj], p->param_low[start + jj], p->param_high[start + jj]);
    action->type = p->start + (int64_t)k, action->index = k, action->n_params = dim, action->params = p->params;
    return AACP_OK;
}

int aacp_act(aacp_policy *policy, const double *obs, size_t obs_size, aacp_action *action, aacp_error *error) {
    if (!policy || !obs || !action)
        return aacp__set(error, AACP_ERR_ARGUMENT, "aacp_act: policy, obs or action is NULL");
    if (obs_size != policy->d)
        return aacp__set(error, AACP_ERR_ARGUMENT, "expected one observation of %lu values, got %lu", (unsigned long)policy->d,
                         (unsigned long)obs_size);
    return aacp__act(policy, obs, action, error);
}

int aacp_act_batch(aacp_policy *policy, const double *obs, size_t n, size_t obs_size, int64_t *types, double *params,
                   aacp_error *error) {
    size_t i, jj;
    aacp_action action;
    if (!policy || (n && (!obs || !types || (!params && policy->max_dim))))
        return aacp__set(error, AACP_ERR_ARGUMENT, "aacp_act_batch: a NULL pointer");
    if (obs_size != policy->d)
        return aacp__set(error, AACP_ERR_ARGUMENT, "expected observations of %lu values, got %lu", (unsigned long)policy->d,
                         (unsigned long)obs_size);
    for (i = 0; i < n; i++) {
        int code = aacp__act(policy, obs + i * obs_size, &action, error);
        if (code != AACP_OK) {
            if (error)
                snprintf(error->message + strlen(error->message), sizeof error->message - strlen(error->message),
                         " (observation %lu of the batch)", (unsigned long)i);
            return code;
        }
        types[i] = action.type;
        for (jj = 0; jj < action.n_params; jj++)
            params[i * policy->max_dim + jj] = action.params[jj];
    }
    return AACP_OK;
}

size_t aacp_obs_size(const aacp_policy *policy) { return policy ? policy->d : 0; }
size_t aacp_n_types(const aacp_policy *policy) { return policy ? policy->k : 0; }
int64_t aacp_type_start(const aacp_policy *policy) { return policy ? policy->start : 0; }
size_t aacp_type_dim(const aacp_policy *policy, size_t k) {
    return policy && k < policy->k ? policy->offsets[k + 1] - policy->offsets[k] : 0;
}
size_t aacp_max_dim(const aacp_policy *policy) { return policy ? policy->max_dim : 0; }
const char *aacp_layout(const aacp_policy *policy) { return policy ? aacp__layouts[policy->layout] : ""; }

#ifdef __cplusplus
}
#endif

#endif /* AACP_IMPLEMENTATION_DONE */
#endif /* AACP_IMPLEMENTATION */
