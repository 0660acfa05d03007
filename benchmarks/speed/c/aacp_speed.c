/*
 * Nanoseconds per aacp_act decision (sb3_aac/runtime/c/aacp.h), for benchmarks/speed/decisions.py (c).
 *
 *   aacp_speed POLICY OBS CALLS REPEATS   OBS: n x D float64 observations (raw); the decisions cycle through them.
 *                                         Prints the best of REPEATS runs of CALLS decisions, in ns per decision.
 */
#define AACP_IMPLEMENTATION
#include "aacp.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

int main(int argc, char **argv) {
    aacp_policy *policy;
    aacp_error error;
    FILE *f;
    double *obs, best = -1.0, sink = 0.0;
    long size, calls, repeats, r, i;
    size_t d, n;
    if (argc != 5 || (calls = atol(argv[3])) < 1 || (repeats = atol(argv[4])) < 1) {
        fprintf(stderr, "usage: aacp_speed POLICY OBS CALLS REPEATS\n");
        return 2;
    }
    if (aacp_load_file(argv[1], &policy, &error) != AACP_OK) {
        fprintf(stderr, "%s\n", error.message);
        return 1;
    }
    d = aacp_obs_size(policy);
    f = fopen(argv[2], "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < (long)(8 * d) || fseek(f, 0, SEEK_SET) != 0) {
        fprintf(stderr, "cannot read %s\n", argv[2]);
        return 2;
    }
    n = (size_t)size / (8 * d);
    obs = (double *)malloc(n * d * sizeof *obs);
    if (!obs || fread(obs, sizeof *obs, n * d, f) != n * d) {
        fprintf(stderr, "cannot read %s\n", argv[2]);
        return 2;
    }
    fclose(f);
    for (r = 0; r < repeats; r++) {
        clock_t start = clock();
        double ns;
        for (i = 0; i < calls; i++) {
            aacp_action action;
            if (aacp_act(policy, obs + ((size_t)i % n) * d, d, &action, &error) != AACP_OK) {
                fprintf(stderr, "%s\n", error.message);
                return 1;
            }
            sink += (double)action.type + (action.n_params ? action.params[0] : 0.0);
        }
        ns = (double)(clock() - start) / CLOCKS_PER_SEC * 1e9 / (double)calls;
        if (best < 0 || ns < best)
            best = ns;
    }
    printf("%.1f %g\n", best, sink); /* the sink keeps the decisions from being optimised away */
    free(obs);
    aacp_free(policy);
    return 0;
}
