/*
 * implex_time.c -- the host's time increment through the C interface (rve_update_timed)
 * on an IMPL-EX scene, along a strain path with non-uniform time increments, so that the
 * ratio dt_{n+1} / dt_n of consecutive increments, by which IMPL-EX scales its
 * extrapolation of the ITZ history, changes from one increment to the next.
 *
 * The path: tension along [1, -0.2, 0.05] past the RVE's peak (eps_xx = 2.75e-4; the
 * stress peaks at 2.40e-4 on this path), then back along the same line through zero into
 * compression (eps_xx = -1.8e-4), at a constant strain rate per unit time. Each phase repeats the time increments DT_PATTERN
 * (0.5 to 3 units), 64 increments in all. Every strain and time is an integer multiple of
 * a power of two small enough that the sums and differences a host forms (the strain at
 * the start of an increment plus its increment, TIME + DTIME) are exact: a UMAT given
 * STRAN and DSTRAN = eps - STRAN sees exactly the strain written here.
 *
 * One instance per run, one rve_update_timed with the consistent tangent per increment,
 * then rve_commit. Runs and checks:
 *   timed      dt as given; written to OUT.csv (%.17g): step, time at the end of the
 *              increment, dtime, strain, stress, tangent (row-major D11..D33), the RVE's
 *              iterations, sub-steps and factorizations (RveInfo). fortran_examples/
 *              implex_time.f90 repeats it through the Fortran module and the UMAT and
 *              compares bit for bit (scripts/test-fortran).
 *   scaled     every dt times 4 (exact): only the ratios count, so bit-identical to timed;
 *   uniform    dt = 1 for every increment: every ratio is 1, which is what "no time"
 *              (dtime <= 0) means, so bit-identical to
 *   untimed    rve_update_ex (dtime 0);
 *   and timed must differ from untimed (else this path would not test the ratio).
 *
 * Usage: implex_time [SCENE.toml [OUT.csv]]   (default scenes/paper_rve_host_implex.toml,
 *        no CSV). Exit 0 when every check passed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define NPHASE 2
#define CYCLES_TOTAL 8 /* forth 3 cycles of DT_PATTERN, back 5 */
#define NPAT 8
#define NSTEP (CYCLES_TOTAL * NPAT)
#define H_EPS 1.490116119384765625e-08 /* 2^-26: the strain unit */

static const double DT_PATTERN[NPAT] = {1.0, 2.0, 0.5, 1.0, 3.0, 1.5, 1.0, 2.0}; /* sum 12 */
static const int CYCLES[NPHASE] = {3, 5};
static const double RATE[NPHASE] = {1.0, -1.0}; /* along the direction, per unit time */
static const double DIRECTION[3] = {512.0, -103.0, 26.0}; /* in H_EPS per unit time */

typedef enum { TIMED, SCALED, UNIFORM, UNTIMED, NRUN } RunKind;
static const char *run_name[NRUN] = {"timed", "scaled x4", "uniform", "untimed"};

typedef struct {
    double time[NSTEP], dt[NSTEP], eps[NSTEP][3], sig[NSTEP][3], d[NSTEP][9];
    RveInfo info[NSTEP];
} Path;

static int fail(const char *what, uint32_t st) {
    char msg[512];
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "implex_time: %s: %s: %s\n", what, rve_status_message(st), msg);
    return 1;
}

/* The path's times and strains (exact: small integers times powers of two). */
static void make_path(Path *p) {
    double t = 0.0, along = 0.0; /* time; position along the direction, in H_EPS */
    int ph, c, k, n = 0, j;
    for (ph = 0; ph < NPHASE; ph++)
        for (c = 0; c < CYCLES[ph]; c++)
            for (k = 0; k < NPAT; k++, n++) {
                t += DT_PATTERN[k];
                along += RATE[ph] * DT_PATTERN[k];
                p->time[n] = t;
                p->dt[n] = DT_PATTERN[k];
                for (j = 0; j < 3; j++) p->eps[n][j] = along * DIRECTION[j] * H_EPS;
            }
}

/* Follows the path's strains with one run's time increments into out. */
static int follow(const char *scene, const Path *path, RunKind kind, Path *out) {
    RveHandle h = 0;
    uint32_t st;
    int n;
    if ((st = rve_init_file(scene, &h)) != RVE_STATUS_OK) return fail("rve_init_file", st);
    for (n = 0; n < NSTEP; n++) {
        double dt = kind == TIMED ? path->dt[n] : kind == SCALED ? 4.0 * path->dt[n] : 1.0;
        if (kind == UNTIMED)
            st = rve_update_ex(h, path->eps[n], out->sig[n], out->d[n],
                               RVE_TANGENT_REQUEST_CONSISTENT, &out->info[n]);
        else
            st = rve_update_timed(h, path->eps[n], dt, out->sig[n], out->d[n],
                                  RVE_TANGENT_REQUEST_CONSISTENT, &out->info[n]);
        if (st != RVE_STATUS_OK || (st = rve_commit(h)) != RVE_STATUS_OK) {
            fprintf(stderr, "implex_time: %s run, increment %d\n", run_name[kind], n + 1);
            rve_free(h);
            return fail("rve_update_timed / rve_commit", st);
        }
    }
    rve_free(h);
    return 0;
}

/* The first increment (1-based) at which b's stress or tangent differs from a's in any
 * bit, 0 when none does. */
static int first_difference(const Path *a, const Path *b) {
    int n;
    for (n = 0; n < NSTEP; n++)
        if (memcmp(a->sig[n], b->sig[n], sizeof a->sig[n]) != 0 ||
            memcmp(a->d[n], b->d[n], sizeof a->d[n]) != 0)
            return n + 1;
    return 0;
}

static int write_csv(const char *file, const Path *path, const Path *r) {
    FILE *f = fopen(file, "w");
    int n, k;
    if (!f) {
        perror(file);
        return 1;
    }
    fprintf(f, "step,time,dtime,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy,D11,D12,D13,D21,"
               "D22,D23,D31,D32,D33,iterations,substeps,factorizations\n");
    for (n = 0; n < NSTEP; n++) {
        fprintf(f, "%d,%.17g,%.17g", n + 1, path->time[n], path->dt[n]);
        for (k = 0; k < 3; k++) fprintf(f, ",%.17g", path->eps[n][k]);
        for (k = 0; k < 3; k++) fprintf(f, ",%.17g", r->sig[n][k]);
        for (k = 0; k < 9; k++) fprintf(f, ",%.17g", r->d[n][k]);
        fprintf(f, ",%u,%u,%u\n", (unsigned)r->info[n].iterations,
                (unsigned)r->info[n].substeps, (unsigned)r->info[n].factorizations);
    }
    return fclose(f) != 0;
}

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : "scenes/paper_rve_host_implex.toml";
    static Path path, run[NRUN];
    int k, failures = 0, d_scaled, d_uniform, d_untimed, peak = 0;
    make_path(&path);
    for (k = 0; k < NRUN; k++)
        if (follow(scene, &path, (RunKind)k, &run[k])) return 1;
    if (argc > 2 && write_csv(argv[2], &path, &run[TIMED])) return 1;
    d_scaled = first_difference(&run[TIMED], &run[SCALED]);
    d_uniform = first_difference(&run[UNTIMED], &run[UNIFORM]);
    d_untimed = first_difference(&run[TIMED], &run[UNTIMED]);
    for (k = 1; k < NSTEP; k++)
        if (run[TIMED].sig[k][0] > run[TIMED].sig[peak][0]) peak = k;
    printf("implex_time: %s, %d increments, dt %.2g to %.2g; timed: peak sig_xx %.4f at "
           "increment %d, last %.4f\n",
           scene, NSTEP, 0.5, 3.0, run[TIMED].sig[peak][0], peak + 1,
           run[TIMED].sig[NSTEP - 1][0]);
    printf("  dt x 4 against dt: %s\n", d_scaled ? "DIFFERENT" : "bit-identical");
    printf("  dt = 1 against no time (rve_update_ex): %s\n",
           d_uniform ? "DIFFERENT" : "bit-identical");
    printf("  dt against no time: first difference at increment %d (sig_xx %.6f against "
           "%.6f)\n", d_untimed, d_untimed ? run[TIMED].sig[d_untimed - 1][0] : 0.0,
           d_untimed ? run[UNTIMED].sig[d_untimed - 1][0] : 0.0);
    failures += d_scaled != 0;
    failures += d_uniform != 0;
    failures += d_untimed == 0;
    printf("implex_time: %s\n", failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
