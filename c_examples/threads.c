/*
 * threads.c -- T pthreads x M instances each follow the same loading path (each instance
 * with its own amplitude) with rve_update/rve_commit; every stress and tangent must be
 * bit-identical to a serial run. Distinct instances need no locking by the host.
 *
 * Usage: threads [SCENE.toml]     (default scenes/paper_rve.toml)
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define T 2
#define M 3
#define STEPS 6

static const char *scene;
static double serial_out[T * M][STEPS][12];
static double threaded_out[T * M][STEPS][12];
static int errors = 0;

/* Runs instance `k` (amplitude depends on k) through the path, storing outputs. */
static int run_instance(RveHandle h, int k, double out[STEPS][12]) {
    int s;
    for (s = 0; s < STEPS; s++) {
        double eps[3], d[9];
        eps[0] = 1.2e-5 * (s + 1) * (1.0 + 0.1 * k);
        eps[1] = 0.0;
        eps[2] = 1e-6 * k * (s + 1);
        if (rve_update(h, eps, out[s], d, RVE_TANGENT_REQUEST_CONSISTENT) != RVE_STATUS_OK ||
            rve_commit(h) != RVE_STATUS_OK) {
            char msg[512];
            rve_last_error(msg, sizeof msg);
            fprintf(stderr, "instance %d step %d: %s\n", k, s, msg);
            return 1;
        }
        memcpy(out[s] + 3, d, sizeof d);
    }
    return 0;
}

static void *worker(void *arg) {
    int t = *(int *)arg, m;
    RveHandle h[M];
    for (m = 0; m < M; m++)
        if (rve_init_file(scene, &h[m]) != RVE_STATUS_OK) errors++;
    for (m = 0; m < M; m++)
        if (run_instance(h[m], t * M + m, threaded_out[t * M + m])) errors++;
    for (m = 0; m < M; m++) rve_free(h[m]);
    return NULL;
}

int main(int argc, char **argv) {
    pthread_t th[T];
    int ids[T], k, t;
    scene = argc > 1 ? argv[1] : "scenes/paper_rve.toml";
    for (k = 0; k < T * M; k++) {
        RveHandle h = 0;
        if (rve_init_file(scene, &h) != RVE_STATUS_OK || run_instance(h, k, serial_out[k])) {
            fprintf(stderr, "serial run failed\n");
            return 1;
        }
        rve_free(h);
    }
    for (t = 0; t < T; t++) {
        ids[t] = t;
        pthread_create(&th[t], NULL, worker, &ids[t]);
    }
    for (t = 0; t < T; t++) pthread_join(th[t], NULL);
    if (errors) {
        fprintf(stderr, "%d errors in threads\n", errors);
        return 1;
    }
    if (memcmp(serial_out, threaded_out, sizeof serial_out) != 0) {
        fprintf(stderr, "threaded results differ from serial\n");
        return 1;
    }
    printf("%d threads x %d instances x %d steps: bit-identical to serial\n", T, M, STEPS);
    return 0;
}
