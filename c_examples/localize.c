/*
 * localize.c -- a small 2D FE host whose specimen localizes, run twice in one process: with
 * the RVE's fast path (the default) and without it (the same scene text with
 * `fast_path = false` added under [solver]), to measure what the fast path saves in a
 * structure and to check that it changes nothing.
 *
 * Specimen: a strip of NX x NY bilinear quads (EL x EL mm, thickness 1 mm) with 2 x 2 Gauss
 * points, each point an RVE instance. The middle column of elements (the band) uses the
 * scene with materials.itz.sigma_c scaled by WEAK (0.9: 4.0 -> 3.6), a text made in
 * memory (rve_init_text); the other points use the scene file (rve_init_file). The 2D
 * formulation is the same in plane stress and plane strain (the RVE returns the in-plane
 * stress and tangent of its cell.analysis). Supports: u_x = 0 on the left end, u_y = 0 at
 * its lower node (no rigid motion, free lateral contraction); the right end's nodes share
 * one u_x = U, the controlled displacement; F is the force on that end.
 *
 * Loading: tension to U_TENSION (the band passes its peak and softens while the rest of
 * the strip unloads), unloading to U = 0 (where F = 0: every ITZ point is then on a
 * branch through the origin), compression to -U_COMP. The control is written as one
 * linear constraint c.u = U appended to the equilibrium equations (unknowns: the free
 * displacements and U). Global Newton with the consistent tangents the RVE returns:
 * a trial update of every instance per iteration, rve_commit of every instance once a
 * step has converged; the predictor of a step is the last converged tangent's response
 * to the step's displacement. A step whose Newton (or an RVE update) fails is halved:
 * nothing is committed, the next updates start from the committed states again.
 *
 * Time. The host's pseudo-time is the path length of U (a constant loading rate), so each
 * (sub-)step's time increment is |dU|, passed with rve_update_timed: 4e-4 mm in the
 * tension, 9.6e-4 in the unloading, 3.3e-4 in the compression, halved with a cut step.
 * IMPL-EX extrapolates the ITZ history over a step in proportion to dU / the last step's
 * dU; implicit integration ignores it. (LOCALIZE_NO_TIME=1 passes none, dtime = 0: every
 * step then extrapolates as far as the last, whatever its length.)
 *
 * The scenes. The default, scenes/paper_rve_host_implex.toml, is the paper's own ITZ law
 * and parameters (delta_c = 2e-4, penalty contact on both components) integrated by
 * IMPL-EX: within a step every RVE is linear with a symmetric positive definite tangent,
 * so the host converges in two iterations per step (one correction) through the band's
 * debonding and every later peak. Implicit RVEs of this law snap back when their ITZ
 * debonds (under a uniaxial stress the strain-driven stress drops by a quarter at one
 * strain); a strip with a narrower band then snaps back too, its points can jump one by
 * one, and this host's Newton wanders between the branches: scenes/paper_rve.toml (the
 * same law, implicit) gets through the band's jump (F 80.7 -> 72.4 N at U = 5.8e-3 mm)
 * and stops at U = 8.39e-3 mm, where the rest of the strip reaches its own peak (no
 * convergence after six halvings). IMPL-EX pays with a lag of the damage behind the
 * strain (its peak force is 92.1 N with these steps, 84.1 N with 8 times more). The runs
 * without the fast path refactorize at every update and must give the same curve bit for
 * bit.
 * scenes/paper_rve_host_ductile.toml, run too by scripts/test-c, is kept for the implicit
 * scheme (the default integration), whose fast path this host is the only structural test
 * of: scenes/paper_rve_host.toml with delta_c = 5e-4 instead of 2e-4, with which the RVE
 * softens continuously (slope above -6e3 N/mm^2 under a uniaxial stress); with the band a
 * third of the strip the strip's response has no snap-back. There the two runs agree to
 * round-off (CURVE_TOL), not bit for bit: the fast path answers D_b eps where the full
 * solve ends with a Newton correction.
 *
 * Printed: the load-displacement curves of both runs and their largest differences in F
 * and in the band's strain (relative to their largest values), the mean eps_xx of the
 * band and of the rest, the share of updates answered without a solve (rve_fast_updates:
 * the fast path's answers and, with IMPL-EX, the updates that reuse their step's
 * factorization), the RVE's factorizations (RveInfo), the host's iterations per step, and
 * the wall time spent inside rve_update_timed (clock_gettime around each call) per run,
 * per phase, per fast answer and per solve. Exit 1 when a step cannot be solved, the runs
 * take different steps, F or the band's strain differ by more than CURVE_TOL (implicit)
 * or at all (IMPL-EX), no update is answered without a solve, rve_fast_updates disagrees
 * with the updates seen answered without a solve (or counts any in the run without the
 * fast path), the band does not localize (no force drop after the first peak of the
 * tension with the band stretching and the rest contracting), F at U = 0 after the
 * unloading exceeds ZERO_F of the largest |F| (see check_zero_force), or the compression
 * is not stiffer than the unloading (see stiffness).
 *
 * Usage: localize [SCENE.toml [SCALE [REPEATS]]]
 *   SCENE    default scenes/paper_rve_host_implex.toml; must have materials.itz.sigma_c
 *            and must not set solver.fast_path itself
 *   SCALE    a positive integer multiplying the number of steps of every phase (default 1)
 *   REPEATS  run the pair this many times, alternating their order, and also print the
 *            least time of each (default 1; every repeat must give the same curves)
 * Before the runs one untimed update of an instance of the scene warms the process up
 * (its first update costs about 70 ms more than the same update later).
 * Step control. With a scene that sets solver.step_tolerance (IMPL-EX) the host follows
 * the RVEs' suggested_step_ratio (RveInfo): a converged sub-step whose smallest ratio is
 * below 1 is reverted and redone that much smaller (not below 1/1024 of the phase's
 * step), and the next sub-step is the last times the smallest ratio when that exceeds 1
 * (at most the rest of the nominal step: the deck's steps are the largest). Every step's
 * answer then keeps the RVEs' integration error within the tolerance.
 * LOCALIZE_IGNORE_RATIO=1 ignores the ratio: the steps are the nominal ones, and
 * rve_commit says once on stderr that an increment above the tolerance was kept.
 * LOCALIZE_VERBOSE=1 prints every Newton iteration with a map of the points
 * (F: answered without a solve; s, w: solved, strong and band points).
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rve.h"

#define NX 3          /* elements along the strip */
#define NY 2          /* elements across */
#define WEAK_COL 1    /* the band: this column of elements */
#define EL 10.0       /* element size (mm): the RVE cell's size */
#define NGP 4         /* 2 x 2 Gauss points per element */
#define WEAK 0.9      /* the band's sigma_c factor */
#define DEFAULT_SCENE "scenes/paper_rve_host_implex.toml"
#define U_TENSION 9.6e-3 /* end displacement at the end of the tension (mm) */
#define U_COMP 3.3e-3 /* end displacement at the end of the compression (mm) */
#define N_TENSION 24
#define N_UNLOAD 10
#define N_COMP 10
#define MAX_IT 12
#define TOL 1e-8      /* |residual| / force scale: converged */
#define FLOOR 1e-6    /* ... or below this and no longer falling (the RVE's tolerance) */
#define MAX_CUTS 6    /* a step may be halved this many times in a row */
#define CURVE_TOL 1e-10 /* implicit scenes: largest relative difference of the two runs */
#define ZERO_F 1e-8   /* |F| at U = 0 after the unloading / max |F| (check_zero_force) */

#define NNODE ((NX + 1) * (NY + 1))
#define NDOF (2 * NNODE)
#define NEL (NX * NY)
#define NPT (NEL * NGP)
#define FIXED (-1)
#define END (-2)

enum { TENSION, UNLOAD, COMPRESSION, NPHASE };
static const char *phase_name[NPHASE] = {"tension", "unloading", "compression"};

/* One converged step. */
typedef struct {
    int phase, iterations, cuts;
    double target, u, f;
    double eps_band, eps_rest; /* mean eps_xx of the band's points and of the others */
    unsigned long fast;    /* updates of the step answered without a solve */
    unsigned long updates; /* updates of the step (its last, converged attempt) */
    unsigned long factorizations; /* the RVEs' factorizations in the step (all attempts) */
    double rve_seconds;
} Step;

typedef struct {
    RveHandle h[NPT];
    uint64_t fast_seen[NPT];
    unsigned long n_fast;   /* updates seen answered without a solve */
    double t_fast, t_solved; /* time inside rve_update: fast answers, solves */
    Step *steps;
    int nsteps, cap, cuts;
    unsigned long updates, updates_phase[NPHASE], fast_phase[NPHASE];
    unsigned long factorizations, fact_phase[NPHASE];
    double dtime; /* the time increment of the step being solved (0: none passed) */
    double ratio; /* the smallest suggested_step_ratio of the last assembly's updates */
    int follow;   /* follow the ratio (scene with solver.step_tolerance) */
    int redos;    /* converged sub-steps redone smaller on the ratio */
    double rve_seconds, seconds, rve_phase[NPHASE];
    double f_max, f_zero;
    uint64_t fast_total;
} Run;

/* Times inside rve_update summed over runs of one kind. */
typedef struct {
    double phase[NPHASE], all, fast, solved, steps_all_fast;
    unsigned long n_fast, updates;
} Times;

static int verbose;
static int follow_ratio; /* the scene sets solver.step_tolerance and LOCALIZE_IGNORE_RATIO is unset */

static int report(uint32_t st, const char *what) {
    char msg[512];
    if (st == RVE_STATUS_OK) return 0;
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "localize: %s: %s: %s\n", what, rve_status_message(st), msg);
    return 1;
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    char *text = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        text = malloc((size_t)n + 1);
        if (text && fread(text, 1, (size_t)n, f) != (size_t)n) {
            free(text);
            text = NULL;
        } else if (text) {
            text[n] = '\0';
        }
    }
    fclose(f);
    return text;
}

/* Where the value of the first `key = value` of the scene text starts (a key outside a
 * comment, not the end of a longer name), or NULL. */
static const char *find_key(const char *text, const char *key) {
    const char *k = text;
    while ((k = strstr(k, key)) != NULL) {
        const char *line = k, *p = k + strlen(key);
        int comment = 0;
        while (line > text && line[-1] != '\n') comment |= *--line == '#';
        while (*p == ' ' || *p == '\t') p++;
        if (!comment && *p == '=' &&
            (k == text || strchr(" \t{,\n", k[-1]) != NULL)) {
            p++;
            while (*p == ' ' || *p == '\t') p++;
            return p;
        }
        k += strlen(key);
    }
    return NULL;
}

/* The scene text with the value of the first `sigma_c = X` multiplied by factor. */
static char *scale_sigma_c(const char *text, double factor) {
    const char *p = find_key(text, "sigma_c"), *end;
    char num[64], *out;
    double v;
    if (!p) return NULL;
    v = strtod(p, (char **)&end);
    if (end == p) return NULL;
    sprintf(num, "%.15g", v * factor);
    out = malloc(strlen(text) + strlen(num) + 1);
    if (!out) return NULL;
    memcpy(out, text, (size_t)(p - text));
    strcpy(out + (p - text), num);
    strcat(out, end);
    return out;
}

/* The scene text with `fast_path = false` as the first key of [solver] (a new [solver]
 * table at the end when there is none). */
static char *without_fast_path(const char *text) {
    const char *line = "fast_path = false\n", *s = text, *at = NULL;
    char *out = malloc(strlen(text) + strlen(line) + 16);
    if (!out) return NULL;
    while ((s = strstr(s, "[solver]")) != NULL) {
        if (s == text || s[-1] == '\n') {
            at = strchr(s, '\n');
            break;
        }
        s++;
    }
    if (at) {
        size_t head = (size_t)(at + 1 - text);
        memcpy(out, text, head);
        strcpy(out + head, line);
        strcat(out, at + 1);
    } else {
        sprintf(out, "%s\n[solver]\n%s", text, line);
    }
    return out;
}

static char *dir_of(const char *path) {
    const char *slash = strrchr(path, '/');
    char *d;
    size_t n = slash ? (size_t)(slash - path) : 1;
    d = malloc(n + 1);
    if (!d) return NULL;
    if (slash) memcpy(d, path, n);
    else d[0] = '.';
    d[n] = '\0';
    if (n == 0) strcpy(d, "/");
    return d;
}

static int element_node(int e, int a) {
    int i = e % NX, j = e / NX;
    static const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
    return (j + dj[a]) * (NX + 1) + i + di[a];
}

/* B (3 x 8) and the weight det(J) of Gauss point g of element e. */
static double shape(int e, int g, double b[3][8]) {
    static const double xi_a[4] = {-1, 1, 1, -1}, eta_a[4] = {-1, -1, 1, 1};
    const double q = 1.0 / sqrt(3.0);
    double xi = xi_a[g] * q, eta = eta_a[g] * q, dxi[4], deta[4], j[2][2] = {{0, 0}, {0, 0}};
    double det;
    int k, a;
    for (k = 0; k < 4; k++) {
        int n = element_node(e, k);
        double x = EL * (n % (NX + 1)), y = EL * (n / (NX + 1));
        dxi[k] = 0.25 * xi_a[k] * (1 + eta_a[k] * eta);
        deta[k] = 0.25 * eta_a[k] * (1 + xi_a[k] * xi);
        j[0][0] += dxi[k] * x;
        j[0][1] += dxi[k] * y;
        j[1][0] += deta[k] * x;
        j[1][1] += deta[k] * y;
    }
    det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    for (k = 0; k < 4; k++) {
        double dx = (j[1][1] * dxi[k] - j[0][1] * deta[k]) / det;
        double dy = (-j[1][0] * dxi[k] + j[0][0] * deta[k]) / det;
        for (a = 0; a < 3; a++) b[a][2 * k] = b[a][2 * k + 1] = 0.0;
        b[0][2 * k] = dx;
        b[1][2 * k + 1] = dy;
        b[2][2 * k] = dy;
        b[2][2 * k + 1] = dx;
    }
    return det; /* Gauss weights 1 */
}

/* Solves a x = rhs (n x n, row-major, overwritten) by Gaussian elimination with partial
 * pivoting; the solution replaces rhs. Returns 1 on a singular matrix. */
static int solve(double *a, double *rhs, int n) {
    int i, j, c;
    for (c = 0; c < n; c++) {
        int p = c;
        double t;
        for (i = c + 1; i < n; i++)
            if (fabs(a[i * n + c]) > fabs(a[p * n + c])) p = i;
        if (a[p * n + c] == 0.0 || !isfinite(a[p * n + c])) return 1;
        if (p != c) {
            for (j = 0; j < n; j++) {
                t = a[c * n + j];
                a[c * n + j] = a[p * n + j];
                a[p * n + j] = t;
            }
            t = rhs[c];
            rhs[c] = rhs[p];
            rhs[p] = t;
        }
        for (i = c + 1; i < n; i++) {
            double m = a[i * n + c] / a[c * n + c];
            if (m == 0.0) continue;
            for (j = c; j < n; j++) a[i * n + j] -= m * a[c * n + j];
            rhs[i] -= m * rhs[c];
        }
    }
    for (i = n - 1; i >= 0; i--) {
        double s = rhs[i];
        for (j = i + 1; j < n; j++) s -= a[i * n + j] * rhs[j];
        rhs[i] = s / a[i * n + i];
    }
    return 0;
}


/* kind[d]: FIXED, END (the right end's u_x, all equal to U) or the index of a free dof. */
static int classify(int *kind) {
    int d, nf = 0;
    for (d = 0; d < NDOF; d++) {
        int node = d / 2, i = node % (NX + 1);
        if (d % 2 == 0 && i == 0) kind[d] = FIXED;
        else if (d % 2 == 0 && i == NX) kind[d] = END;
        else if (d == 1) kind[d] = FIXED; /* u_y of the lower left node */
        else kind[d] = nf++;
    }
    return nf;
}

/* The control c.u: the mean u_x of the right end's nodes (all equal to U). */
static void control(double *c) {
    int j;
    memset(c, 0, sizeof(double) * NDOF);
    for (j = 0; j <= NY; j++) c[2 * (j * (NX + 1) + NX)] = 1.0 / (NY + 1);
}

/* The Jacobian (m = nf + 1, row-major) of [free equilibrium equations; c.u - target] in
 * the unknowns [free dofs; U]. */
static void jacobian(const double *k, const double *c, const int *kind, int nf, double *jac) {
    int m = nf + 1, a, b;
    memset(jac, 0, sizeof(double) * (size_t)m * (size_t)m);
    for (a = 0; a < NDOF; a++) {
        int col = kind[a] == END ? nf : kind[a];
        if (col < 0) continue;
        for (b = 0; b < NDOF; b++)
            if (kind[b] >= 0) jac[kind[b] * m + col] += k[b * NDOF + a];
        jac[nf * m + col] += c[a];
    }
}

static void apply(double *u, const double *dz, const int *kind, int nf) {
    int d;
    for (d = 0; d < NDOF; d++) {
        if (kind[d] == END) u[d] += dz[nf];
        else if (kind[d] >= 0) u[d] += dz[kind[d]];
    }
}

/* Updates every point at the displacements u over the time increment run->dtime;
 * assembles the internal force and the tangent. Returns the first failed update's status. */
static uint32_t assemble(Run *run, const double *u, double *fint, double *k, double *eps_xx,
                         int phase, char *map) {
    int e, g, a, c, r;
    memset(fint, 0, sizeof(double) * NDOF);
    memset(k, 0, sizeof(double) * NDOF * NDOF);
    run->ratio = INFINITY;
    for (e = 0; e < NEL; e++) {
        int dofs[8];
        for (a = 0; a < 4; a++) {
            dofs[2 * a] = 2 * element_node(e, a);
            dofs[2 * a + 1] = dofs[2 * a] + 1;
        }
        for (g = 0; g < NGP; g++) {
            int pt = e * NGP + g;
            double b[3][8], eps[3] = {0, 0, 0}, sig[3], d[9], db[3][8], w, t0, t1;
            RveInfo info;
            uint32_t st;
            w = shape(e, g, b);
            for (r = 0; r < 3; r++)
                for (a = 0; a < 8; a++) eps[r] += b[r][a] * u[dofs[a]];
            eps_xx[pt] = eps[0];
            t0 = now();
            st = rve_update_timed(run->h[pt], eps, run->dtime, sig, d,
                                  RVE_TANGENT_REQUEST_CONSISTENT, &info);
            t1 = now();
            if (st == RVE_STATUS_OK && info.suggested_step_ratio < run->ratio)
                run->ratio = info.suggested_step_ratio;
            if (st == RVE_STATUS_OK || st == RVE_STATUS_SOLVER_FAILED) {
                run->factorizations += info.factorizations;
                run->fact_phase[phase] += info.factorizations;
            }
            run->rve_seconds += t1 - t0;
            run->rve_phase[phase] += t1 - t0;
            run->updates++;
            run->updates_phase[phase]++;
            if (st != RVE_STATUS_OK) {
                run->t_solved += t1 - t0;
                if (verbose) report(st, "rve_update");
                return st;
            }
            { /* was it answered without a solve? (outside the timed call) */
                uint64_t n = 0;
                int answered;
                if (report(rve_fast_updates(run->h[pt], &n), "rve_fast_updates"))
                    return RVE_STATUS_INTERNAL;
                answered = n > run->fast_seen[pt];
                run->fast_seen[pt] = n;
                run->n_fast += (unsigned long)answered;
                run->t_fast += answered ? t1 - t0 : 0.0;
                run->t_solved += answered ? 0.0 : t1 - t0;
                map[pt] = answered ? 'F' : e % NX == WEAK_COL ? 'w' : 's';
            }
            for (r = 0; r < 3; r++)
                for (a = 0; a < 8; a++)
                    db[r][a] = d[3 * r] * b[0][a] + d[3 * r + 1] * b[1][a] + d[3 * r + 2] * b[2][a];
            for (a = 0; a < 8; a++) {
                fint[dofs[a]] += w * (b[0][a] * sig[0] + b[1][a] * sig[1] + b[2][a] * sig[2]);
                for (c = 0; c < 8; c++)
                    k[dofs[a] * NDOF + dofs[c]] +=
                        w * (b[0][a] * db[0][c] + b[1][a] * db[1][c] + b[2][a] * db[2][c]);
            }
        }
    }
    return RVE_STATUS_OK;
}

static double end_force(const double *fint, const int *kind) {
    int d;
    double f = 0.0;
    for (d = 0; d < NDOF; d++)
        if (kind[d] == END) f += fint[d];
    return f;
}

static double dot(const double *a, const double *b) {
    int d;
    double s = 0.0;
    for (d = 0; d < NDOF; d++) s += a[d] * b[d];
    return s;
}

static uint64_t fast_count(const Run *run) {
    uint64_t total = 0, n;
    int i;
    for (i = 0; i < NPT; i++)
        if (rve_fast_updates(run->h[i], &n) == RVE_STATUS_OK) total += n;
    return total;
}

/* One step from the converged state (u, k_conv) to c.u = target: predictor and Newton.
 * Returns 0 with u, k_conv and *f updated, or 1 (nothing changed but the trials). */
static int newton(Run *run, int phase, const double *c, double target, double *u,
                  double *k_conv, int have_k, Step *step) {
    static double w[NDOF], fint[NDOF], k[NDOF * NDOF], eps_xx[NPT];
    static double jac[(NDOF + 1) * (NDOF + 1)], rhs[NDOF + 1];
    int kind[NDOF], nf = classify(kind), m = nf + 1, it, i;
    char map[NPT + 1];
    double r_last = 0.0;
    memset(map, '.', NPT);
    map[NPT] = '\0';
    memcpy(w, u, sizeof w);
    if (have_k) { /* predictor: the converged tangent's response to the control's step */
        jacobian(k_conv, c, kind, nf, jac);
        memset(rhs, 0, sizeof rhs);
        rhs[nf] = target - dot(c, w);
        if (!solve(jac, rhs, m)) apply(w, rhs, kind, nf);
    }
    for (it = 0; it <= MAX_IT; it++) {
        double r = 0.0, g, scale;
        if (assemble(run, w, fint, k, eps_xx, phase, map) != RVE_STATUS_OK) return 1;
        step->f = end_force(fint, kind);
        scale = fabs(step->f) > run->f_max ? fabs(step->f) : run->f_max;
        if (scale == 0.0) scale = 1.0;
        for (i = 0; i < NDOF; i++)
            if (kind[i] >= 0) r += fint[i] * fint[i];
        r = sqrt(r) / scale;
        g = dot(c, w) - target;
        if (verbose)
            printf("  %s  target %.5e it %d  |r|/F %.3e  c.u - target %.1e  U %.6e  F %.6e\n",
                   map, target, it, r, g, w[2 * NX], step->f);
        if (fabs(g) <= 1e-12 * (fabs(target) + 1e-6) &&
            (r <= TOL || (it > 0 && r <= FLOOR && r >= 0.5 * r_last))) {
            memcpy(u, w, sizeof w);
            memcpy(k_conv, k, sizeof k);
            step->iterations = it + 1;
            step->u = u[2 * NX];
            step->eps_band = step->eps_rest = 0.0;
            for (i = 0; i < NPT; i++) {
                if ((i / NGP) % NX == WEAK_COL) step->eps_band += eps_xx[i] / (NY * NGP);
                else step->eps_rest += eps_xx[i] / (NPT - NY * NGP);
            }
            return 0;
        }
        r_last = r;
        jacobian(k, c, kind, nf, jac);
        for (i = 0; i < NDOF; i++)
            if (kind[i] >= 0) rhs[kind[i]] = -fint[i];
        rhs[nf] = -g;
        if (solve(jac, rhs, m)) return 1;
        apply(w, rhs, kind, nf);
    }
    return 1;
}

static int push_step(Run *run, Step s) {
    if (run->nsteps == run->cap) {
        int cap = run->cap ? 2 * run->cap : 64;
        Step *n = realloc(run->steps, sizeof(Step) * (size_t)cap);
        if (!n) return 1;
        run->steps = n;
        run->cap = cap;
    }
    run->steps[run->nsteps++] = s;
    return 0;
}

/* Creates the instances: the band's from weak_text, the others from strong_text (the
 * scene file when strong_text is NULL). Returns 1 on a failure (reported). */
static int init_points(Run *run, const char *scene_file, const char *strong_text,
                       const char *weak_text, const char *base_dir) {
    int e, g;
    for (e = 0; e < NEL; e++)
        for (g = 0; g < NGP; g++) {
            RveHandle *h = &run->h[e * NGP + g];
            uint32_t st;
            if (e % NX == WEAK_COL) st = rve_init_text(weak_text, base_dir, h);
            else if (strong_text) st = rve_init_text(strong_text, base_dir, h);
            else st = rve_init_file(scene_file, h);
            if (report(st, "rve_init")) return 1;
        }
    return 0;
}

/* Commits every instance and records the converged step st (its counters: the run's
 * since `before`, taken at the start of the step's converged attempt). */
static int record_step(Run *run, Step st, const Run *before) {
    int i;
    for (i = 0; i < NPT; i++)
        if (report(rve_commit(run->h[i]), "rve_commit")) return 1;
    st.fast = run->n_fast - before->n_fast;
    st.updates = run->updates - before->updates;
    st.factorizations = run->factorizations - before->factorizations;
    st.rve_seconds = run->rve_seconds - before->rve_seconds;
    run->fast_phase[st.phase] += st.fast;
    if (push_step(run, st)) return 1;
    if (fabs(st.f) > run->f_max) run->f_max = fabs(st.f);
    return 0;
}

/* Following the ratio (run->follow): whether the converged sub-step of |dU| = taken must
 * be redone smaller, the RVEs' smallest suggested_step_ratio being below 1; then *length
 * is the smaller |dU|. Not below 1/1024 of the phase's step `nominal`: a sub-step that
 * small is kept whatever the ratio (rve_commit then says so). */
static int redo_smaller(Run *run, double taken, double nominal, double *length) {
    if (!run->follow || !(run->ratio < 1.0) || taken <= nominal / 1024.0 * (1 + 1e-9)) return 0;
    *length = fmax(taken * run->ratio, nominal / 1024.0);
    run->redos++;
    return 1;
}

/* The whole analysis with the given scene texts (strong points: the file when
 * strong_text is NULL). Each sub-step passes its time increment |dU| (none with
 * no_time). */
static int analyse(Run *run, const char *scene_file, const char *strong_text,
                   const char *weak_text, const char *base_dir, int scale, int no_time) {
    static double u[NDOF], k_conv[NDOF * NDOF], c[NDOF], u_save[NDOF], k_save[NDOF * NDOF];
    static Run before; /* the counters at the start of an attempt */
    int p, i, have_k = 0, failed = 1;
    double length = 0.0; /* following the ratio: the next sub-step's |dU| (0: the step's) */
    const int nsteps[NPHASE] = {N_TENSION * scale, N_UNLOAD * scale, N_COMP * scale};
    double t_start = now();
    memset(u, 0, sizeof u);
    run->follow = follow_ratio;
    if (init_points(run, scene_file, strong_text, weak_text, base_dir)) goto out;
    control(c);
    for (p = 0; p < NPHASE; p++) { /* the nominal ends: the same targets in every run */
        const double ends[NPHASE] = {U_TENSION, 0.0, -U_COMP};
        double start = p == 0 ? 0.0 : ends[p - 1], end = ends[p], done = start;
        int s;
        for (s = 1; s <= nsteps[p]; s++) {
            double target = start + (end - start) * s / nsteps[p];
            int cuts = 0;
            if (s == nsteps[p]) target = end;
            while (done != target) { /* sub-steps, halved on failure */
                double next = cuts == 0 ? target : done + (target - done) / (double)(1 << cuts);
                double taken;
                Step st;
                if (run->follow && length > 0.0 && fabs(next - done) > length * (1 + 1e-9))
                    next = done + (target > done ? length : -length);
                taken = fabs(next - done);
                before = *run;
                run->dtime = no_time ? 0.0 : taken;
                memcpy(u_save, u, sizeof u);
                memcpy(k_save, k_conv, sizeof k_conv);
                if (newton(run, p, c, next, u, k_conv, have_k, &st) ||
                    redo_smaller(run, taken, fabs(end - start) / nsteps[p], &length)) {
                    memcpy(u, u_save, sizeof u);
                    memcpy(k_conv, k_save, sizeof k_conv);
                    for (i = 0; i < NPT; i++)
                        if (report(rve_revert(run->h[i]), "rve_revert")) goto out;
                    if (run->follow && length > 0.0 && length < taken) continue; /* redo smaller */
                    run->cuts++;
                    if (++cuts > MAX_CUTS) {
                        fprintf(stderr, "localize: %s: no convergence at %.6e after %d cuts\n",
                                phase_name[p], next, MAX_CUTS);
                        goto out;
                    }
                    continue;
                }
                st.phase = p;
                st.cuts = cuts;
                st.target = next;
                if (record_step(run, st, &before)) goto out;
                have_k = 1;
                done = next;
                if (cuts > 0) cuts--; /* then try a longer sub-step again */
                if (run->follow && !(next == target && taken < length))
                    /* the next sub-step: this one times the ratio, if it grows (a piece cut
                     * short by the step's end does not shorten the next) */
                    length = taken * (run->ratio > 1.0 && isfinite(run->ratio) ? run->ratio : 1.0);
            }
        }
        if (p == UNLOAD) run->f_zero = run->steps[run->nsteps - 1].f;
    }
    failed = 0;
out:
    run->fast_total = fast_count(run);
    for (i = 0; i < NPT; i++) {
        if (run->h[i]) rve_free(run->h[i]);
        run->h[i] = 0;
    }
    run->seconds = now() - t_start;
    return failed;
}

static double rel(double a, double b, double scale) { return fabs(a - b) / scale; }

/* Adds a run's times; steps_all_fast: over the steps the fast run `ref` (of the same
 * pair, on the same steps) answered entirely without a solve. */
static void add_times(Times *t, const Run *run, const Run *ref) {
    int i, p;
    for (p = 0; p < NPHASE; p++) t->phase[p] += run->rve_phase[p];
    t->all += run->rve_seconds;
    t->fast += run->t_fast;
    t->solved += run->t_solved;
    t->n_fast += run->n_fast;
    t->updates += run->updates;
    for (i = 0; i < run->nsteps && i < ref->nsteps; i++)
        if (ref->steps[i].fast == ref->steps[i].updates)
            t->steps_all_fast += run->steps[i].rve_seconds;
}

/* Localization in the tension of a run: the first peak of the force (a step followed by
 * a lower force) and the end of the fall after it (the next step followed by a higher
 * force, or the last step of the tension). Returns 1 when the force falls after the peak
 * while the band stretches and the rest of the specimen contracts. */
static int localized(const Run *run, int *peak, int *low) {
    int i, n = 0;
    while (n < run->nsteps && run->steps[n].phase == TENSION) n++;
    *peak = *low = -1;
    for (i = 0; i + 1 < n && *peak < 0; i++)
        if (run->steps[i + 1].f < run->steps[i].f) *peak = i;
    if (*peak < 0) return 0;
    for (i = *peak + 1; i < n && *low < 0; i++)
        if (i + 1 == n || run->steps[i + 1].f >= run->steps[i].f) *low = i;
    return run->steps[*low].f < run->steps[*peak].f &&
           run->steps[*low].eps_band > run->steps[*peak].eps_band &&
           run->steps[*low].eps_rest < run->steps[*peak].eps_rest;
}

/* The largest differences of run b from run a in the force and in the band's strain
 * (relative to a's largest |F| and |eps_band|); 1 when they took other steps. */
static int compare(const Run *a, const Run *b, double *de, double *df) {
    int i;
    double e_scale = 0.0, f_scale = 0.0;
    *de = *df = 0.0;
    for (i = 0; i < a->nsteps; i++) {
        if (fabs(a->steps[i].f) > f_scale) f_scale = fabs(a->steps[i].f);
        if (fabs(a->steps[i].eps_band) > e_scale) e_scale = fabs(a->steps[i].eps_band);
    }
    if (a->nsteps != b->nsteps || f_scale == 0.0 || e_scale == 0.0) return 1;
    for (i = 0; i < a->nsteps; i++) {
        const Step *x = &a->steps[i], *y = &b->steps[i];
        if (x->phase != y->phase || x->target != y->target) return 1;
        if (rel(x->eps_band, y->eps_band, e_scale) > *de)
            *de = rel(x->eps_band, y->eps_band, e_scale);
        if (rel(x->f, y->f, f_scale) > *df) *df = rel(x->f, y->f, f_scale);
    }
    return 0;
}

/* The scene texts of the runs: the file's, the band's (sigma_c x WEAK) and both without
 * the fast path; the file's directory (relative paths in the texts); IMPL-EX or not. */
typedef struct {
    const char *scene;
    char *text, *weak, *off, *weak_off, *base;
    int implex;
} Scenes;

/* Both kinds of run (the first of each, kept for the report) and the times of all. */
typedef struct {
    Run fast, slow;
    Times tf, to;
    double min_fast, min_off;
    int repeats, scale, no_time;
} Pair;

static int prepare(Scenes *sc, const char *scene) {
    const char *v;
    memset(sc, 0, sizeof *sc);
    sc->scene = scene;
    if (!(sc->text = read_file(scene))) {
        perror(scene);
        return 1;
    }
    if (find_key(sc->text, "fast_path")) {
        fprintf(stderr, "localize: %s sets solver.fast_path; the runs set it themselves\n", scene);
        return 1;
    }
    v = find_key(sc->text, "integration");
    sc->implex = v && strncmp(v, "\"implex\"", 8) == 0;
    sc->weak = scale_sigma_c(sc->text, WEAK);
    sc->off = without_fast_path(sc->text);
    sc->weak_off = sc->weak ? without_fast_path(sc->weak) : NULL;
    sc->base = dir_of(scene);
    if (!sc->weak || !sc->off || !sc->weak_off || !sc->base) {
        fprintf(stderr, "localize: %s: no `sigma_c = <number>` (or out of memory)\n", scene);
        return 1;
    }
    return 0;
}

static void release(Scenes *sc) {
    free(sc->text);
    free(sc->weak);
    free(sc->off);
    free(sc->weak_off);
    free(sc->base);
}

/* One untimed update: the process's first update pays for what its later ones reuse. */
static int warm_up(const char *scene) {
    RveHandle h = 0;
    double eps[3] = {1e-5, 0.0, 0.0}, sig[3], d[9];
    int failed = report(rve_init_file(scene, &h), "rve_init_file") ||
                 report(rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), "rve_update");
    rve_free(h);
    return failed;
}

/* One analysis with (fast = 1) or without the fast path. */
static int analyse_kind(Run *run, const Scenes *sc, const Pair *pr, int fast) {
    return analyse(run, sc->scene, fast ? NULL : sc->off, fast ? sc->weak : sc->weak_off,
                   sc->base, pr->scale, pr->no_time);
}

static void print_stopped(const Run *run, const char *which) {
    int i;
    printf("the run %s the fast path stopped; its converged steps:\n", which);
    for (i = 0; i < run->nsteps; i++)
        printf("%-11s %4d  U %11.4e  F %10.4f  eps band %9.3e  rest %9.3e  it %d  cuts %d\n",
               phase_name[run->steps[i].phase], i + 1, run->steps[i].u, run->steps[i].f,
               run->steps[i].eps_band, run->steps[i].eps_rest, run->steps[i].iterations,
               run->steps[i].cuts);
}

/* The first pair, then the repeats (alternating the order; every run must give the first
 * fast run's curve to curve_tol). Returns the number of failures. */
static int run_pairs(Pair *pr, const Scenes *sc, double curve_tol) {
    static Run again[2];
    int r, failures = 0;
    if (analyse_kind(&pr->fast, sc, pr, 1) || analyse_kind(&pr->slow, sc, pr, 0)) {
        print_stopped(pr->slow.nsteps ? &pr->slow : &pr->fast,
                      pr->slow.nsteps ? "without" : "with");
        return 1;
    }
    pr->min_fast = pr->fast.rve_seconds;
    pr->min_off = pr->slow.rve_seconds;
    add_times(&pr->tf, &pr->fast, &pr->fast);
    add_times(&pr->to, &pr->slow, &pr->fast);
    if (pr->repeats > 1)
        printf("time in rve_update (s), fast / off:  %.3f / %.3f", pr->min_fast, pr->min_off);
    for (r = 1; r < pr->repeats && !failures; r++) {
        double de, df;
        Run *f = &again[r % 2], *o = &again[1 - r % 2];
        memset(again, 0, sizeof again);
        if (analyse_kind(&again[0], sc, pr, r % 2 == 0) ||
            analyse_kind(&again[1], sc, pr, r % 2 == 1)) {
            failures = 1;
        } else {
            if (compare(&pr->fast, f, &de, &df) || de > curve_tol || df > curve_tol ||
                compare(&pr->fast, o, &de, &df) || de > curve_tol || df > curve_tol) {
                fprintf(stderr, "\nlocalize: repeat %d: another curve\n", r + 1);
                failures++;
            }
            printf(",  %.3f / %.3f", f->rve_seconds, o->rve_seconds);
            add_times(&pr->tf, f, f);
            add_times(&pr->to, o, f);
            if (f->rve_seconds < pr->min_fast) pr->min_fast = f->rve_seconds;
            if (o->rve_seconds < pr->min_off) pr->min_off = o->rve_seconds;
        }
        free(again[0].steps);
        free(again[1].steps);
    }
    if (pr->repeats > 1) printf("\n");
    return failures;
}

/* The two curves side by side; returns the number of steps answered only without a solve. */
static int print_steps(const Run *fast, const Run *slow, double f_scale) {
    int i, all_fast = 0;
    printf("\n%-11s %4s %11s %10s %10s %8s %9s %9s %5s %10s %5s %13s\n", "phase", "step",
           "U (mm)", "F (N)", "F off (N)", "dF/Fmax", "eps band", "eps rest", "it", "fast/upd",
           "fact", "RVE ms / off");
    for (i = 0; i < fast->nsteps && i < slow->nsteps; i++) {
        const Step *a = &fast->steps[i], *b = &slow->steps[i];
        printf("%-11s %4d %11.4e %10.4f %10.4f %8.1e %9.3e %9.3e %2d/%-2d %3lu/%-6lu %5lu "
               "%6.1f/%-6.1f\n",
               phase_name[a->phase], i + 1, a->u, a->f, b->f, rel(a->f, b->f, f_scale),
               a->eps_band, a->eps_rest, a->iterations, b->iterations, a->fast, a->updates,
               a->factorizations, 1e3 * a->rve_seconds, 1e3 * b->rve_seconds);
        all_fast += a->fast == a->updates;
    }
    return all_fast;
}

/* Per phase and in all: updates, fast answers, factorizations, host iterations, times. */
static void print_phases(const Pair *pr) {
    const Run *f = &pr->fast, *o = &pr->slow;
    int p, i, steps[NPHASE] = {0, 0, 0}, its[NPHASE] = {0, 0, 0};
    for (i = 0; i < f->nsteps; i++) {
        steps[f->steps[i].phase]++;
        its[f->steps[i].phase] += f->steps[i].iterations;
    }
    printf("\n%-11s %5s %6s %15s %7s %15s %9s %9s %8s   (times summed over %d run%s of each)\n",
           "phase", "steps", "it", "updates", "fast", "factorizations", "RVE s", "RVE s off",
           "off/fast", pr->repeats, pr->repeats > 1 ? "s" : "");
    for (p = 0; p < NPHASE; p++)
        printf("%-11s %5d %6d %7lu/%-7lu %7lu %7lu/%-7lu %9.3f %9.3f %8.2f\n", phase_name[p],
               steps[p], its[p], f->updates_phase[p], o->updates_phase[p], f->fast_phase[p],
               f->fact_phase[p], o->fact_phase[p], pr->tf.phase[p], pr->to.phase[p],
               pr->tf.phase[p] > 0 ? pr->to.phase[p] / pr->tf.phase[p] : 0.0);
    printf("%-11s %5d %6d %7lu/%-7lu %7lu %7lu/%-7lu %9.3f %9.3f %8.2f\n", "all", f->nsteps,
           its[0] + its[1] + its[2], f->updates, o->updates, (unsigned long)f->fast_total,
           f->factorizations, o->factorizations, pr->tf.all, pr->to.all,
           pr->tf.all > 0 ? pr->to.all / pr->tf.all : 0.0);
}

/* Shares and times of the pair. */
static void print_times(const Pair *pr, int all_fast) {
    const Run *f = &pr->fast, *o = &pr->slow;
    const Times *tf = &pr->tf, *to = &pr->to;
    double share = f->updates ? (double)f->fast_total / (double)f->updates : 0.0;
    printf("\nfast share: %.3f (%lu of %lu updates answered without a solve; without the fast "
           "path: %lu)\n",
           share, (unsigned long)f->fast_total, f->updates, (unsigned long)o->fast_total);
    printf("time in rve_update: %.3f s with the fast path, %.3f s without: ratio %.2f "
           "(first runs; whole runs %.3f s and %.3f s; steps cut %d and %d)\n",
           f->rve_seconds, o->rve_seconds, f->rve_seconds > 0 ? o->rve_seconds / f->rve_seconds : 0.0,
           f->seconds, o->seconds, f->cuts, o->cuts);
    if (f->follow)
        printf("step control (solver.step_tolerance): %d converged sub-steps redone smaller on the "
               "RVEs' suggested_step_ratio (%d without the fast path); %d steps in all\n",
               f->redos, o->redos, f->nsteps);
    if (pr->repeats > 1)
        printf("  least of %d runs each: %.3f s and %.3f s: ratio %.2f; summed: ratio %.2f\n",
               pr->repeats, pr->min_fast, pr->min_off, pr->min_off / pr->min_fast,
               to->all / tf->all);
    if (tf->n_fast > 0 && tf->updates > tf->n_fast && to->updates > 0)
        printf("per update: fast answer %.1f us, solve %.3f ms (%.3f ms without the fast path); "
               "the %d steps answered only by the fast path: %.2f ms against %.2f ms per run\n",
               1e6 * tf->fast / (double)tf->n_fast,
               1e3 * tf->solved / (double)(tf->updates - tf->n_fast),
               1e3 * to->solved / (double)to->updates, all_fast,
               1e3 * tf->steps_all_fast / pr->repeats, 1e3 * to->steps_all_fast / pr->repeats);
}

/* F at U = 0 after the unloading must vanish. Every ITZ point is then on a branch through
 * the origin (secant unloading, eq. 24; penalty contact, eqs. 36-37: with IMPL-EX the
 * step's extrapolated history and held contact status keep each point on such a branch)
 * and the bulk is linear, so u = 0 is the equilibrium and F = 0 in exact arithmetic. What
 * is left is the host's residual (its Newton stops below TOL of the force scale) and
 * round-off (1e-16 of it), so |F| <= ZERO_F max |F| with ZERO_F = TOL: zero to the
 * accuracy of every other force of the curve. A residual deformation would not pass: a
 * residual strain of 1e-9 in the band alone leaves about 1e-9 x 2.5e4 N/mm^2 x 20 mm^2 =
 * 5e-4 N, against a bound near 1e-6 N. */
static int check_zero_force(const Run *run) {
    int ok = fabs(run->f_zero) <= ZERO_F * run->f_max;
    printf("F at U = 0 after the unloading: %.1e N (%.1e of max |F|; limit %.0e)\n", run->f_zero,
           fabs(run->f_zero) / run->f_max, ZERO_F);
    if (!ok) fprintf(stderr, "localize: F at U = 0 is not zero\n");
    return !ok;
}

/* The secant stiffness F/U at each step's target U (the step's U up to the control's
 * 1e-12; at the target U = 0 both are round-off): the largest over the unloading's steps
 * but that one (the damaged stiffness the unloading follows back to the origin), the least
 * over the compression's (closed cracks carry load again: the unilateral effect), and the
 * first tension step's (the virgin strip), for reference. Returns 1 when the compression
 * is not stiffer than the unloading. */
static int stiffness(const Run *run) {
    double k_unload = 0.0, k_comp = HUGE_VAL;
    double k_virgin = run->steps[0].f / run->steps[0].target;
    int i;
    for (i = 0; i < run->nsteps; i++) {
        const Step *st = &run->steps[i];
        double k = st->f / st->target;
        if (st->phase == UNLOAD && st->target != 0.0 && k > k_unload) k_unload = k;
        if (st->phase == COMPRESSION && k < k_comp) k_comp = k;
    }
    printf("secant stiffness F/U (N/mm): unloading at most %.1f, compression at least %.1f "
           "(%.2f times), virgin %.1f\n", k_unload, k_comp, k_comp / k_unload, k_virgin);
    if (k_comp > k_unload) return 0;
    fprintf(stderr, "localize: the compression is not stiffer than the unloading\n");
    return 1;
}

/* Localization, equality of the runs, the fast path's counts, F at zero, the stiffness. */
static int check_runs(const Pair *pr, double curve_tol) {
    const Run *f = &pr->fast, *o = &pr->slow;
    int failures = 0, peak, low, loc = localized(f, &peak, &low);
    double diff_e = 0.0, diff_f = 0.0;
    if (compare(f, o, &diff_e, &diff_f)) {
        fprintf(stderr, "localize: the runs took different steps (%d and %d)\n", f->nsteps,
                o->nsteps);
        failures++;
    }
    if (peak >= 0 && low >= 0)
        printf("localization: F %.4f N at the peak (step %d) -> %.4f N (step %d); band eps_xx "
               "%.3e -> %.3e, rest %.3e -> %.3e\n",
               f->steps[peak].f, peak + 1, f->steps[low].f, low + 1, f->steps[peak].eps_band,
               f->steps[low].eps_band, f->steps[peak].eps_rest, f->steps[low].eps_rest);
    failures += check_zero_force(f);
    failures += stiffness(f);
    printf("largest difference of the runs: F %.1e of max |F| = %.4f N, band eps_xx %.1e "
           "(limit %.0e)\n", diff_f, f->f_max, diff_e, curve_tol);
    fflush(stdout);
    if (!(diff_f <= curve_tol && diff_e <= curve_tol)) {
        fprintf(stderr, "localize: the curves differ by more than %.0e\n", curve_tol);
        failures++;
    }
    if (f->fast_total == 0) {
        fprintf(stderr, "localize: no update was answered without a solve\n");
        failures++;
    }
    if (f->n_fast != f->fast_total || o->fast_total != 0) {
        fprintf(stderr, "localize: rve_fast_updates counts %lu and %lu; seen %lu and %lu\n",
                (unsigned long)f->fast_total, (unsigned long)o->fast_total, f->n_fast,
                o->n_fast);
        failures++;
    }
    if (!loc) {
        fprintf(stderr, "localize: the band did not localize (no force drop after the peak with "
                        "the band stretching and the rest contracting)\n");
        failures++;
    }
    return failures;
}

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : DEFAULT_SCENE;
    static Pair pr;
    Scenes sc;
    int failures = 1, all_fast;
    double curve_tol;
    pr.scale = argc > 2 ? atoi(argv[2]) : 1;
    pr.repeats = argc > 3 ? atoi(argv[3]) : 1;
    pr.no_time = getenv("LOCALIZE_NO_TIME") != NULL;
    verbose = getenv("LOCALIZE_VERBOSE") != NULL;
    if (pr.scale < 1 || pr.repeats < 1 || argc > 4) {
        fprintf(stderr, "usage: localize [SCENE.toml [SCALE >= 1 [REPEATS >= 1]]]\n");
        return 2;
    }
    if (prepare(&sc, scene) || warm_up(scene)) goto done;
    follow_ratio = strstr(sc.text, "step_tolerance") != NULL && !getenv("LOCALIZE_IGNORE_RATIO");
    curve_tol = sc.implex ? 0.0 : CURVE_TOL; /* IMPL-EX: bit-identical (see the header) */
    printf("localize: %s (%s%s), %d x %d quads, %d RVEs (band: column %d, sigma_c x %.2f); "
           "%d + %d + %d steps; %d run%s with and without the fast path\n",
           scene, sc.implex ? "IMPL-EX" : "implicit",
           pr.no_time ? ", no time increments passed" : ", time increment |dU|", NX, NY, NPT,
           WEAK_COL, WEAK, N_TENSION * pr.scale, N_UNLOAD * pr.scale, N_COMP * pr.scale,
           pr.repeats, pr.repeats > 1 ? "s each" : " each");
    fflush(stdout);
    failures = run_pairs(&pr, &sc, curve_tol);
    if (failures || pr.fast.nsteps == 0) goto done;
    all_fast = print_steps(&pr.fast, &pr.slow, pr.fast.f_max);
    print_phases(&pr);
    print_times(&pr, all_fast);
    failures = check_runs(&pr, curve_tol);
done:
    free(pr.fast.steps);
    free(pr.slow.steps);
    release(&sc);
    printf("localize: %s\n", failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
