/*
 * kratos_umat.c -- the UMAT called the way Kratos's SmallStrainUMAT laws call `umat_`
 * (GeoMechanicsApplication, small_strain_umat_law.cpp), checked against the library's
 * STATEV-mode answers for a host that passes everything (the Abaqus/CalculiX protocol).
 *
 * Kratos's call: CMNAME a 1-byte buffer (here on the heap, one byte 0x9c) and no hidden
 * length; TIME one double (here a 1-double heap block, so that a read of TIME(2) is an
 * ASan/valgrind error); PNEWDT, RPL, DDSDDT, DRPLDE, DRPLDT, TEMP, DTEMP, PREDEF, DPRED,
 * COORDS, DROT, CELENT, DFGRD0, DFGRD1, LAYER and KSPT NULL; NOEL = NPT = 0 for every
 * point; KINC the Newton iteration; NTENS 6 (NDI 3, NSHR 3) with [xx, yy, zz, xy, 0, 0];
 * STATEV the start-of-increment values at every call; two calls per iteration (stress,
 * then tangent) with the same arguments. The scene comes from MESORVE_UMAT_SCENE, which
 * the program sets to SCENE before its first call (the library then never reads CMNAME).
 *
 * P points, each on its own strain path [a_p e, 0, 0, 0, 0, 0] (e up to 3e-4, through
 * the paper RVE's peak), INCREMENTS increments of two iterations (99 % of the step, then
 * the step's end). The reference: the same paths point by point on this thread through
 * rve_umat with PNEWDT, a two-double TIME, NOEL = p + 1, one call per iteration. The
 * Kratos-like run: T threads, each iteration over its points as Kratos's element loop
 * does. Every DDSDDE must equal the reference bit for bit, every STRESS too except where
 * the reference was asked for a smaller step (PNEWDT < 1: the RVE's step check past the
 * peak), where it must be all NaN; the two calls of an iteration must equal each other.
 *
 * Then, Kratos-like calls without PNEWDT: a corrupted STATEV fails with NaN in STRESS
 * (the signal Kratos cuts its step on) while a host with PNEWDT gets STRESS untouched
 * and PNEWDT < 1; NSTATV = 5 (table mode) is refused with NaN and a message that says
 * why.
 *
 * Usage: kratos_umat SCENE NSTATV [INCREMENTS]
 *   SCENE       a plane-strain scene file (calculix_examples/concrete.toml)
 *   NSTATV      its umat_nstatv (rve info SCENE --json)
 *   INCREMENTS  increments of the path (default 12)
 * Exit status 0 when every check passed.
 */
#define _POSIX_C_SOURCE 200112L /* setenv */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define P 6
#define T 2
#define NT 6
#define MIRRORS 5
#define EPS_MAX 3e-4

/* `umat_` as Kratos declares it: no hidden length of CMNAME after KINC. */
void umat_(double *stress, double *statev, double *ddsdde, double *sse, double *spd,
           double *scd, double *rpl, double *ddsddt, double *drplde, double *drpldt,
           const double *stran, const double *dstran, const double *time, const double *dtime,
           const double *temp, const double *dtemp, const double *predef, const double *dpred,
           const char *cmname, const int *ndi, const int *nshr, const int *ntens,
           const int *nstatv, const double *props, const int *nprops, const double *coords,
           const double *drot, double *pnewdt, const double *celent, const double *dfgrd0,
           const double *dfgrd1, const int *noel, const int *npt, const int *layer,
           const int *kspt, const int *kstep, const int *kinc);

static int nstatv, increments, checks, failures;
static pthread_mutex_t count_lock = PTHREAD_MUTEX_INITIALIZER;

static void expect(int ok, const char *what) {
    pthread_mutex_lock(&count_lock);
    checks++;
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s\n", what);
    }
    pthread_mutex_unlock(&count_lock);
}

/* One answer: STRESS then DDSDDE. */
typedef struct {
    double s[NT + NT * NT];
} Answer;

/* reference[p][k][i]: point p, increment k, iteration i; and the PNEWDT it got. */
static Answer *reference;
static double ref_pnewdt[P][64][2];
static int nan_answers;

static Answer *at(Answer *table, int p, int k, int i) {
    return &table[((size_t)p * (size_t)increments + (size_t)k) * 2 + (size_t)i];
}

/* Total strain of point p at iteration i of increment k. */
static void strain_of(int p, int k, int i, double eps[NT]) {
    double step = EPS_MAX / increments, a = 1.0 - 0.05 * p;
    memset(eps, 0, NT * sizeof eps[0]);
    eps[0] = a * step * (k + (i == 0 ? 0.99 : 1.0));
}

/* A call the way Kratos makes it; `kratos` 0 makes it the way CalculiX does instead
 * (PNEWDT, TIME(1:2), NOEL = p + 1, a named material with its length). Returns PNEWDT
 * (CalculiX way) or 1. */
static double call(int kratos, int p, int k, int i, const double stran[NT],
                   const double target[NT], double *statev, int n_statev, Answer *out) {
    double dstran[NT], sse = 0, spd = 0, scd = 0, dtime = 1.0 / increments, pnewdt = -1;
    double props[1] = {0};
    int ndi = 3, nshr = 3, ntens = NT, nprops = 1, kstep = 1, kinc = kratos ? i + 1 : k + 1;
    int noel = kratos ? 0 : p + 1, npt = kratos ? 0 : 1, j;
    for (j = 0; j < NT; j++) dstran[j] = target[j] - stran[j];
    memset(out, 0, sizeof *out);
    if (kratos) {
        double *time = malloc(sizeof *time);
        char *cmname = malloc(1);
        *cmname = (char)0x9c; /* not a name (Kratos's is uninitialised) */
        *time = k * dtime;
        umat_(out->s, statev, out->s + NT, &sse, &spd, &scd, NULL, NULL, NULL, NULL, stran,
              dstran, time, &dtime, NULL, NULL, NULL, NULL, cmname, &ndi, &nshr, &ntens,
              &n_statev, props, &nprops, NULL, NULL, NULL, NULL, NULL, NULL, &noel, &npt, NULL,
              NULL, &kstep, &kinc);
        free(cmname);
        free(time);
        return 1;
    } else {
        double time[2], temp = 20, zero = 0, coords[3] = {0}, drot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        double celent = 1, dfgrd[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, rpl = 0, ddsddt[NT] = {0};
        double drplde[NT] = {0}, drpldt = 0, predef[1] = {0}, dpred[1] = {0};
        int layer = 1, kspt = 1;
        time[0] = time[1] = k * dtime;
        rve_umat(out->s, statev, out->s + NT, &sse, &spd, &scd, &rpl, ddsddt, drplde, &drpldt,
                 stran, dstran, time, &dtime, &temp, &zero, predef, dpred, "KRATOS_REF", &ndi,
                 &nshr, &ntens, &n_statev, props, &nprops, coords, drot, &pnewdt, &celent,
                 dfgrd, dfgrd, &noel, &npt, &layer, &kspt, &kstep, &kinc, 10);
        return pnewdt;
    }
}

/* The reference: every point's path through the CalculiX-way calls. */
static void run_reference(void) {
    int p, k, i;
    for (p = 0; p < P; p++) {
        double *committed = calloc((size_t)(nstatv + MIRRORS), sizeof(double));
        double *trial = malloc((size_t)(nstatv + MIRRORS) * sizeof(double));
        double stran[NT] = {0}, target[NT];
        for (k = 0; k < increments; k++) {
            for (i = 0; i < 2; i++) {
                memcpy(trial, committed, (size_t)(nstatv + MIRRORS) * sizeof(double));
                strain_of(p, k, i, target);
                ref_pnewdt[p][k][i] =
                    call(0, p, k, i, stran, target, trial, nstatv + MIRRORS, at(reference, p, k, i));
            }
            memcpy(committed, trial, (size_t)(nstatv + MIRRORS) * sizeof(double));
            memcpy(stran, target, sizeof stran);
        }
        free(trial);
        free(committed);
    }
}

/* Kratos's per-point data: the finalized strain and STATEV, and the values of the last
 * call (mStateVariables), which FinalizeMaterialResponse keeps. */
typedef struct {
    double stran[NT];
    double *finalized, *current;
} KPoint;

static int same(const Answer *a, const Answer *b) { return memcmp(a, b, sizeof *a) == 0; }

static int all_nan(const double *s, int n) {
    int j;
    for (j = 0; j < n; j++)
        if (!isnan(s[j])) return 0;
    return 1;
}

/* The Kratos-like answer `a` against the reference `r`, which got `pnewdt`: DDSDDE equal
 * bit for bit; STRESS equal too, or all NaN exactly when the reference was asked for a
 * smaller step (PNEWDT < 1). */
static int same_or_nan(const Answer *a, const Answer *r, double pnewdt) {
    int asked = pnewdt > 0 && pnewdt < 1;
    if (memcmp(a->s + NT, r->s + NT, NT * NT * sizeof(double)) != 0) return 0;
    if (asked) {
        pthread_mutex_lock(&count_lock);
        nan_answers++;
        pthread_mutex_unlock(&count_lock);
        return all_nan(a->s, NT);
    }
    return memcmp(a->s, r->s, NT * sizeof(double)) == 0;
}

/* Iteration i of increment k at point p: the stress call, then the tangent call, each
 * from the finalized STATEV. */
static void kratos_iteration(KPoint *pt, int p, int k, int i, int n) {
    Answer stress_call, tangent_call;
    double target[NT];
    char what[160];
    strain_of(p, k, i, target);
    memcpy(pt->current, pt->finalized, (size_t)n * sizeof(double));
    call(1, p, k, i, pt->stran, target, pt->current, n, &stress_call);
    memcpy(pt->current, pt->finalized, (size_t)n * sizeof(double));
    call(1, p, k, i, pt->stran, target, pt->current, n, &tangent_call);
    snprintf(what, sizeof what, "point %d, increment %d, iteration %d: = the reference", p, k, i);
    expect(same_or_nan(&stress_call, at(reference, p, k, i), ref_pnewdt[p][k][i]), what);
    snprintf(what, sizeof what, "point %d, increment %d, iteration %d: stress call = tangent call", p, k, i);
    expect(same(&stress_call, &tangent_call), what);
    if (i == 1) { /* FinalizeMaterialResponse */
        memcpy(pt->finalized, pt->current, (size_t)n * sizeof(double));
        memcpy(pt->stran, target, sizeof pt->stran);
    }
}

/* One thread of the Kratos-like run: its points, iteration by iteration. */
static void *kratos_thread(void *arg) {
    int t = *(int *)arg, k, i, p, n = nstatv + MIRRORS;
    KPoint pts[P];
    for (p = t; p < P; p += T) {
        memset(pts[p].stran, 0, sizeof pts[p].stran);
        pts[p].finalized = calloc((size_t)n, sizeof(double));
        pts[p].current = calloc((size_t)n, sizeof(double));
    }
    for (k = 0; k < increments; k++)
        for (i = 0; i < 2; i++)
            for (p = t; p < P; p += T) kratos_iteration(&pts[p], p, k, i, n);
    for (p = t; p < P; p += T) {
        free(pts[p].finalized);
        free(pts[p].current);
    }
    return NULL;
}

/* Failures without PNEWDT: NaN in STRESS; with PNEWDT: STRESS untouched, PNEWDT < 1. */
static void check_failures(void) {
    int n = nstatv + MIRRORS;
    double *statev = calloc((size_t)n, sizeof(double));
    double stran[NT] = {0}, target[NT], pnewdt;
    Answer out, first;
    char msg[1024];
    strain_of(0, 2, 1, target);
    call(1, 0, 0, 1, stran, target, statev, n, &first); /* a valid state at 2.x steps */
    memcpy(stran, target, sizeof stran);
    statev[3] += 1.0; /* corrupted */
    strain_of(0, 3, 1, target);
    call(1, 0, 3, 1, stran, target, statev, n, &out);
    expect(all_nan(out.s, NT), "a corrupted STATEV without PNEWDT: STRESS is NaN");
    expect(rve_last_error(msg, sizeof msg) > 0 && strstr(msg, "checksum") != NULL,
           "a corrupted STATEV: rve_last_error says its checksum failed");
    pnewdt = call(0, 0, 3, 1, stran, target, statev, n, &out);
    expect(out.s[0] == 0.0 && out.s[1] == 0.0, "a corrupted STATEV with PNEWDT: STRESS untouched");
    expect(pnewdt > 0 && pnewdt < 1, "a corrupted STATEV with PNEWDT: PNEWDT < 1");
    memset(statev, 0, (size_t)n * sizeof(double));
    call(1, 0, 0, 1, stran, target, statev, MIRRORS, &out);
    expect(all_nan(out.s, NT), "NSTATV = 5 without PNEWDT (table mode): refused, STRESS NaN");
    expect(rve_last_error(msg, sizeof msg) > 0 && strstr(msg, "PNEWDT") != NULL,
           "table mode refused: the message names PNEWDT");
    expect(strstr(msg, "is being updated by another thread") == NULL, "no point lock");
    free(statev);
}

int main(int argc, char **argv) {
    pthread_t threads[T];
    int ids[T], t;
    if (argc < 3 || setenv("MESORVE_UMAT_SCENE", argv[1], 1) != 0) {
        fprintf(stderr, "usage: kratos_umat SCENE NSTATV [INCREMENTS]\n");
        return 2;
    }
    nstatv = atoi(argv[2]);
    increments = argc > 3 ? atoi(argv[3]) : 12;
    if (nstatv <= MIRRORS || increments < 4 || increments > 64) {
        fprintf(stderr, "kratos_umat: NSTATV %d or INCREMENTS %d too small\n", nstatv, increments);
        return 2;
    }
    reference = calloc((size_t)P * (size_t)increments * 2, sizeof(Answer));
    run_reference();
    for (t = 0; t < T; t++) {
        ids[t] = t;
        pthread_create(&threads[t], NULL, kratos_thread, &ids[t]);
    }
    for (t = 0; t < T; t++) pthread_join(threads[t], NULL);
    check_failures();
    free(reference);
    printf("kratos_umat: %d points x %d increments x 2 iterations x 2 calls on %d threads = "
           "the PNEWDT host's answers bit for bit (%d stress calls NaN where it got PNEWDT < 1); "
           "failures as NaN: %d/%d checks passed\n",
           P, increments, T, nan_answers, checks - failures, checks);
    return failures == 0 ? 0 : 1;
}
