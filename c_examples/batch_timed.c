/*
 * batch_timed.c -- rve_update_batch_timed: per-point reports and messages, the host's
 * time increment, threads.
 *
 * NPOINT instances of an IMPL-EX scene (default scenes/paper_rve_host_implex.toml) follow
 * the strain path of implex_time.c scaled per point (point p at (p + 1) / NPOINT of it:
 * the last goes past the RVE's peak, the first stays nearly elastic), with non-uniform
 * time increments, so that IMPL-EX's extrapolation depends on dt_{n+1} / dt_n. Three sets
 * of instances follow it:
 *   ref   one rve_update_timed per point (RveInfo);
 *   one   rve_update_batch_timed on the calling thread (nthreads 1);
 *   two   rve_update_batch_timed on a pool of 2 threads;
 * and every increment, stresses, tangents (bit for bit) and reports (status, iterations,
 * sub-steps, factorizations, reliability, suggested step ratio, s_zz; shared_from 0, and
 * error_estimate 0 as the scene sets no step_tolerance) of the three must agree, every
 * message being "".
 * Then, on the committed states: a batch with a point at a NaN strain (BATCH_FAILED, its
 * status, report and message; the message as rve_update_timed's for that point, and
 * truncated in a short buffer; the other points' outputs written, the failed one's not),
 * NULL reports and messages, a non-finite dtime (INVALID_ARGUMENT, nothing written), and
 * rve_update_batch against rve_update_ex (dtime 0).
 *
 * Usage: batch_timed [SCENE.toml]. Exit 0 when every check passed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define NPOINT 6
#define NPAT 8
#define NSTEP (2 * NPAT)
#define MSG 256
#define H_EPS 1.490116119384765625e-08 /* 2^-26: the strain unit */

static const double DT_PATTERN[NPAT] = {1.0, 2.0, 0.5, 1.0, 3.0, 1.5, 1.0, 2.0}; /* sum 12 */
static const double DIRECTION[3] = {512.0, -103.0, 26.0}; /* in H_EPS per unit time */

enum { REF, ONE, TWO, NSET };

static int checks = 0, failures = 0;

static void check(int ok, const char *what, int step, int point) {
    checks++;
    if (!ok) {
        failures++;
        fprintf(stderr, "batch_timed: FAILED: %s (increment %d, point %d)\n", what, step, point);
    }
}

static int fail(const char *what, uint32_t st) {
    char msg[512];
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "batch_timed: %s: %s: %s\n", what, rve_status_message(st), msg);
    return 1;
}

/* The strain of point p after the increment that ends at `along` (in H_EPS). */
static void strain_of(double along, int p, double eps[3]) {
    int j;
    for (j = 0; j < 3; j++) eps[j] = along * DIRECTION[j] * H_EPS * (p + 1) / NPOINT;
}

/* Whether a report says what RveInfo says, for a point that succeeded. */
static int same_report(const RvePointReport *r, const RveInfo *i) {
    return r->status == RVE_STATUS_OK && r->iterations == i->iterations &&
           r->substeps == i->substeps && r->factorizations == i->factorizations &&
           r->reliability == i->reliability &&
           memcmp(&r->suggested_step_ratio, &i->suggested_step_ratio, sizeof(double)) == 0 &&
           memcmp(&r->s_zz, &i->s_zz, sizeof(double)) == 0 && r->shared_from == 0 &&
           r->error_estimate == 0.0;
}

typedef struct {
    double sig[NSET][NPOINT][3], d[NSET][NPOINT][9];
    RveInfo info[NPOINT];
    RvePointReport rep[2][NPOINT];
    char msg[2][NPOINT][MSG];
} Step;

/* One increment of the three sets, checked, then committed. */
static int step(RveHandle h[NSET][NPOINT], double eps[NPOINT][3], double dt, int s) {
    static Step o;
    int p, b;
    uint32_t st;
    memset(&o, 0xA5, sizeof o); /* a sentinel: must be overwritten */
    for (p = 0; p < NPOINT; p++) {
        st = rve_update_timed(h[REF][p], eps[p], dt, o.sig[REF][p], o.d[REF][p],
                              RVE_TANGENT_REQUEST_CONSISTENT, &o.info[p]);
        if (st != RVE_STATUS_OK) return fail("rve_update_timed", st);
    }
    for (b = 0; b < 2; b++) {
        st = rve_update_batch_timed(h[ONE + b], NPOINT, &eps[0][0], dt, &o.sig[ONE + b][0][0],
                                    &o.d[ONE + b][0][0], RVE_TANGENT_REQUEST_CONSISTENT,
                                    o.rep[b], &o.msg[b][0][0], MSG, (size_t)(b + 1));
        if (st != RVE_STATUS_OK) return fail("rve_update_batch_timed", st);
        for (p = 0; p < NPOINT; p++) {
            check(memcmp(o.sig[ONE + b][p], o.sig[REF][p], sizeof o.sig[REF][p]) == 0,
                  b ? "stress, 2 threads = rve_update_timed" : "stress, 1 thread = rve_update_timed",
                  s, p);
            check(memcmp(o.d[ONE + b][p], o.d[REF][p], sizeof o.d[REF][p]) == 0,
                  "tangent = rve_update_timed", s, p);
            check(same_report(&o.rep[b][p], &o.info[p]), "report = RveInfo", s, p);
            check(o.msg[b][p][0] == '\0', "message \"\" after a success", s, p);
        }
    }
    for (b = 0; b < NSET; b++)
        for (p = 0; p < NPOINT; p++)
            if ((st = rve_commit(h[b][p])) != RVE_STATUS_OK) return fail("rve_commit", st);
    return 0;
}

/* A batch with a point at a NaN strain, with full and with truncated messages. */
static int failing_point(RveHandle h[NPOINT], RveHandle ref, double eps[NPOINT][3]) {
    double sig[NPOINT][3], d[NPOINT][9], sig1[3], d1[9], nan3[3];
    RvePointReport rep[NPOINT];
    char msg[NPOINT][MSG], short_msg[NPOINT][16], expected[MSG];
    unsigned char sentinel[sizeof sig[0]];
    const int bad = 2;
    int p;
    uint32_t st;
    memcpy(nan3, eps[bad], sizeof nan3);
    nan3[1] = NAN;
    st = rve_update_ex(ref, nan3, sig1, d1, RVE_TANGENT_REQUEST_CONSISTENT, NULL);
    check(st == RVE_STATUS_NON_FINITE_STRAIN, "rve_update_ex at NaN: NON_FINITE_STRAIN", -1, bad);
    rve_last_error(expected, sizeof expected);
    memcpy(eps[bad], nan3, sizeof nan3);
    memset(sentinel, 0xA5, sizeof sentinel);
    memset(sig, 0xA5, sizeof sig);
    memset(rep, 0xA5, sizeof rep);
    memset(msg, 'x', sizeof msg);
    st = rve_update_batch_timed(h, NPOINT, &eps[0][0], 1.0, &sig[0][0], &d[0][0],
                                RVE_TANGENT_REQUEST_CONSISTENT, rep, &msg[0][0], MSG, 2);
    check(st == RVE_STATUS_BATCH_FAILED, "a NaN point: BATCH_FAILED", -1, bad);
    for (p = 0; p < NPOINT; p++) {
        if (p == bad) {
            check(rep[p].status == RVE_STATUS_NON_FINITE_STRAIN, "its status", -1, p);
            check(rep[p].reliability == RVE_RELIABILITY_FAILED, "its reliability", -1, p);
            check(strcmp(msg[p], expected) == 0 && strlen(expected) > 15,
                  "its message = rve_update_ex's", -1, p);
            check(memcmp(sig[p], sentinel, sizeof sig[p]) == 0, "its stress not written", -1, p);
        } else {
            check(rep[p].status == RVE_STATUS_OK && msg[p][0] == '\0',
                  "the other points: OK, message \"\"", -1, p);
        }
    }
    memset(short_msg, 'x', sizeof short_msg);
    st = rve_update_batch_timed(h, NPOINT, &eps[0][0], 1.0, &sig[0][0], &d[0][0],
                                RVE_TANGENT_REQUEST_CONSISTENT, NULL, &short_msg[0][0],
                                sizeof short_msg[0], 1);
    check(st == RVE_STATUS_BATCH_FAILED, "NULL reports: BATCH_FAILED", -1, bad);
    check(strlen(short_msg[bad]) == 15 && strncmp(short_msg[bad], expected, 15) == 0,
          "a 16-byte buffer: the first 15 bytes of the message", -1, bad);
    check(short_msg[0][0] == '\0' && short_msg[NPOINT - 1][0] == '\0',
          "a 16-byte buffer: \"\" for the others", -1, 0);
    return 0;
}

/* NULL reports and messages, a non-finite dtime, and rve_update_batch = rve_update_ex. */
static int other_calls(RveHandle h[NPOINT], RveHandle ref[NPOINT], double eps[NPOINT][3]) {
    double sig[2][NPOINT][3], d[2][NPOINT][9];
    RvePointReport rep[NPOINT], untouched[NPOINT];
    uint32_t statuses[NPOINT];
    char msg[NPOINT][MSG];
    int p;
    uint32_t st = rve_update_batch_timed(h, NPOINT, &eps[0][0], 0.5, &sig[0][0][0], &d[0][0][0],
                                         RVE_TANGENT_REQUEST_CONSISTENT, NULL, NULL, 0, 2);
    check(st == RVE_STATUS_OK, "NULL reports and messages: OK", -1, 0);
    memset(rep, 0x5A, sizeof rep);
    memcpy(untouched, rep, sizeof rep);
    msg[0][0] = 'x';
    st = rve_update_batch_timed(h, NPOINT, &eps[0][0], NAN, &sig[1][0][0], &d[1][0][0],
                                RVE_TANGENT_REQUEST_CONSISTENT, rep, &msg[0][0], MSG, 2);
    check(st == RVE_STATUS_INVALID_ARGUMENT, "dtime NaN: INVALID_ARGUMENT", -1, 0);
    check(memcmp(rep, untouched, sizeof rep) == 0 && msg[0][0] == 'x',
          "dtime NaN: reports and messages not written", -1, 0);
    st = rve_update_batch(h, NPOINT, &eps[0][0], &sig[0][0][0], &d[0][0][0], statuses,
                          RVE_TANGENT_REQUEST_CONSISTENT, 2);
    if (st != RVE_STATUS_OK) return fail("rve_update_batch", st);
    for (p = 0; p < NPOINT; p++) {
        st = rve_update_ex(ref[p], eps[p], sig[1][p], d[1][p], RVE_TANGENT_REQUEST_CONSISTENT,
                           NULL);
        if (st != RVE_STATUS_OK) return fail("rve_update_ex", st);
        check(statuses[p] == RVE_STATUS_OK && memcmp(sig[0][p], sig[1][p], sizeof sig[0][p]) == 0 &&
                  memcmp(d[0][p], d[1][p], sizeof d[0][p]) == 0,
              "rve_update_batch = rve_update_ex, bit for bit", -1, p);
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : "scenes/paper_rve_host_implex.toml";
    RveHandle h[NSET][NPOINT];
    double eps[NPOINT][3], along = 0.0;
    int b, p, s;
    uint32_t st;
    for (b = 0; b < NSET; b++)
        for (p = 0; p < NPOINT; p++)
            if ((st = rve_init_file(scene, &h[b][p])) != RVE_STATUS_OK) return fail(scene, st);
    for (s = 0; s < NSTEP; s++) {
        double dt = DT_PATTERN[s % NPAT];
        along += (s < NPAT ? 3.0 : -2.0) * dt; /* to 36 (past the peak), back to 12 */
        for (p = 0; p < NPOINT; p++) strain_of(along, p, eps[p]);
        if (step(h, eps, dt, s)) return 1;
    }
    if (other_calls(h[TWO], h[REF], eps)) return 1;
    if (failing_point(h[ONE], h[REF][2], eps)) return 1;
    for (b = 0; b < NSET; b++)
        for (p = 0; p < NPOINT; p++) rve_free(h[b][p]);
    printf("batch_timed: %d increments of %d points, %d checks, %d failed\n", NSTEP, NPOINT,
           checks, failures);
    return failures != 0;
}
