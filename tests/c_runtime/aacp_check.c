/*
 * The test driver of sb3_aac/runtime/c/aacp.h (tests/test_c_runtime.py compiles and runs it).
 *
 *   aacp_check act POLICY OBS OUT   decisions for the float64 observations in OBS (n x D, raw little-endian),
 *                                   written to OUT as n rows of 1 + max_dim float64 (the env action type, then
 *                                   the chosen type's parameters, NaN-padded); one call per observation, and
 *                                   aacp_act_batch, which must agree
 *   aacp_check load FILE...         for each file one line "CODE TYPE MESSAGE": aacp_load_file's return code and
 *                                   message (aacp_load_memory must load or refuse the file as it does, or the
 *                                   driver fails), and the action type for an all-zero observation (or -)
 *   aacp_check file PATH...         the same with aacp_load_file alone (for names, devices and directories)
 *
 * Each file is given to aacp_load_memory in a heap buffer of exactly its size, so that a sanitizer build catches
 * any read past it.
 */
#define AACP_IMPLEMENTATION
#include "aacp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned char *read_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    unsigned char *data = NULL;
    long n;
    if (!f)
        return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        data = (unsigned char *)malloc(n ? (size_t)n : 1);
        if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
            free(data);
            data = NULL;
        }
        *size = (size_t)n;
    }
    fclose(f);
    return data;
}

/* The policy from aacp_load_memory; aacp_load_file must load it too, or both refuse it (*error: aacp_load_file's,
   which names the file; the two may name different faults: the file reader stops where a truncated file ends). */
static aacp_policy *load_both(const char *path, aacp_error *error, int *code) {
    aacp_policy *from_file = NULL, *from_memory = NULL;
    aacp_error memory_error;
    size_t size = 0;
    unsigned char *data = read_all(path, &size);
    int memory_code;
    if (!data) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(2);
    }
    *code = aacp_load_file(path, &from_file, error);
    memory_code = aacp_load_memory(data, size, &from_memory, &memory_error);
    free(data);
    if ((*code == AACP_OK) != (memory_code == AACP_OK) || (*code == AACP_OK) != (from_file != NULL) ||
        (memory_code == AACP_OK) != (from_memory != NULL)) {
        fprintf(stderr, "%s: aacp_load_file gives %d (%s), aacp_load_memory %d (%s)\n", path, *code,
                *code ? error->message : "", memory_code, memory_code ? memory_error.message : "");
        exit(3);
    }
    if (memory_code != AACP_OK && strncmp(memory_error.message, "<memory> is not a usable", 24) != 0 &&
        memory_code != AACP_ERR_MEMORY) {
        fprintf(stderr, "%s: aacp_load_memory says %s\n", path, memory_error.message);
        exit(3);
    }
    aacp_free(from_file);
    return from_memory;
}

static int act(const char *policy_path, const char *obs_path, const char *out_path) {
    aacp_error error;
    int code;
    aacp_policy *policy = load_both(policy_path, &error, &code);
    size_t size = 0, d, n, width, i, j;
    unsigned char *raw;
    double *obs, *out, *batch_params;
    int64_t *batch_types;
    FILE *f;
    if (!policy) {
        fprintf(stderr, "%s\n", error.message);
        return 1;
    }
    raw = read_all(obs_path, &size);
    d = aacp_obs_size(policy), width = 1 + aacp_max_dim(policy), n = size / (8 * d);
    obs = (double *)malloc(n * d * sizeof *obs + 1);
    out = (double *)malloc(n * width * sizeof *out + 1);
    batch_types = (int64_t *)malloc(n * sizeof *batch_types + 1);
    batch_params = (double *)malloc(n * aacp_max_dim(policy) * sizeof *batch_params + 1);
    if (!raw || !obs || !out || !batch_types || !batch_params || size != n * d * 8) {
        fprintf(stderr, "bad observation file %s\n", obs_path);
        return 2;
    }
    memcpy(obs, raw, size); /* the test runs on little-endian machines */
    for (i = 0; i < n; i++) {
        aacp_action action;
        if (aacp_act(policy, obs + i * d, d, &action, &error) != AACP_OK) {
            fprintf(stderr, "observation %lu: %s\n", (unsigned long)i, error.message);
            return 1;
        }
        out[i * width] = (double)action.type;
        for (j = 0; j < width - 1; j++)
            out[i * width + 1 + j] = j < action.n_params ? action.params[j] : NAN;
    }
    if (aacp_act_batch(policy, obs, n, d, batch_types, batch_params, &error) != AACP_OK) {
        fprintf(stderr, "batch: %s\n", error.message);
        return 1;
    }
    for (i = 0; i < n; i++) {
        size_t dim = aacp_type_dim(policy, (size_t)(batch_types[i] - aacp_type_start(policy)));
        int same = (double)batch_types[i] == out[i * width];
        for (j = 0; j < dim; j++)
            same = same && batch_params[i * (width - 1) + j] == out[i * width + 1 + j];
        if (!same) {
            fprintf(stderr, "aacp_act_batch differs from aacp_act at observation %lu\n", (unsigned long)i);
            return 1;
        }
    }
    f = fopen(out_path, "wb");
    if (!f || fwrite(out, sizeof *out, n * width, f) != n * width || fclose(f) != 0) {
        fprintf(stderr, "cannot write %s\n", out_path);
        return 2;
    }
    printf("%lu decisions, %lu inputs, %lu types, layout %s\n", (unsigned long)n, (unsigned long)d,
           (unsigned long)aacp_n_types(policy), aacp_layout(policy));
    free(raw), free(obs), free(out), free(batch_types), free(batch_params);
    aacp_free(policy);
    return 0;
}

static int load(int n, char **paths) {
    int i;
    for (i = 0; i < n; i++) {
        aacp_error error;
        int code;
        aacp_policy *policy = load_both(paths[i], &error, &code);
        if (policy) {
            size_t d = aacp_obs_size(policy);
            double *zeros = (double *)calloc(d, sizeof *zeros);
            aacp_action action;
            if (!zeros || aacp_act(policy, zeros, d, &action, &error) != AACP_OK) {
                fprintf(stderr, "%s: loads but cannot act: %s\n", paths[i], error.message);
                return 1;
            }
            printf("0 %lld ok\n", (long long)action.type);
            free(zeros);
            aacp_free(policy);
        } else {
            if (strchr(error.message, '\n')) {
                fprintf(stderr, "%s: a message of more than one line\n", paths[i]);
                return 1;
            }
            printf("%d - %s\n", code, error.message);
        }
    }
    return 0;
}

static int load_files(int n, char **paths) {
    int i;
    for (i = 0; i < n; i++) {
        aacp_error error;
        aacp_policy *policy = NULL;
        int code = aacp_load_file(paths[i], &policy, &error);
        if ((code == AACP_OK) != (policy != NULL)) {
            fprintf(stderr, "%s: code %d with policy %p\n", paths[i], code, (void *)policy);
            return 1;
        }
        if (policy)
            printf("0 - ok\n");
        else
            printf("%d - %s\n", code, error.message);
        aacp_free(policy);
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 5 && !strcmp(argv[1], "act"))
        return act(argv[2], argv[3], argv[4]);
    if (argc >= 2 && !strcmp(argv[1], "load"))
        return load(argc - 2, argv + 2);
    if (argc >= 2 && !strcmp(argv[1], "file"))
        return load_files(argc - 2, argv + 2);
    fprintf(stderr, "usage: aacp_check act POLICY OBS OUT | aacp_check load FILE... | aacp_check file PATH...\n");
    return 2;
}
