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
 * displacements and U). Global Newton with the consistent tangents rve_update returns:
 * a trial update of every instance per iteration, rve_commit of every instance once a
 * step has converged; the predictor of a step is the last converged tangent's response
 * to the step's displacement. A step whose Newton (or an RVE update) fails is halved:
 * nothing is committed, the next updates start from the committed states again.
 *
 * The scene. The default, scenes/paper_rve_host_ductile.toml, is scenes/paper_rve_host.toml
 * with delta_c = 5e-4 instead of 2e-4. With the paper's delta_c the RVE snaps back when
 * its ITZ debonds: under a uniaxial stress its strain-driven stress drops by a quarter at
 * one strain. A band narrower than the specimen then makes the end displacement snap back
 * whatever the specimen's length, and the points of the band can jump one by one; this
 * host's Newton then wanders between the branches and halving the step does not help
 * (run it with scenes/paper_rve_host.toml to see it stop). With delta_c = 5e-4 the RVE
 * softens continuously (slope above -6e3 N/mm^2 under a uniaxial stress), and with the
 * band a third of the strip the strip's response has no snap-back.
 *
 * Printed: the load-displacement curves of both runs and their largest differences in F
 * and in the band's strain (relative to their largest values), the mean eps_xx of the
 * band and of the rest, the share of rve_update calls answered without a solve
 * (rve_fast_updates), and the wall time spent inside rve_update (clock_gettime around
 * each call) per run, per phase, per fast answer and per solve. Exit 1 when a step cannot
 * be solved, the runs take different steps, F or the band's strain differ by more than
 * CURVE_TOL (1e-10), no update is answered by the fast path, rve_fast_updates disagrees
 * with the updates seen answered without a solve (or counts any in the run without the
 * fast path), or the band does not localize (no force drop after the first peak of the
 * tension with the band stretching and the rest contracting).
 *
 * Usage: localize [SCENE.toml [SCALE [REPEATS]]]
 *   SCENE    default scenes/paper_rve_host_ductile.toml; must have materials.itz.sigma_c
 *            and must not set solver.fast_path itself
 *   SCALE    a positive integer multiplying the number of steps of every phase (default 1)
 *   REPEATS  run the pair this many times, alternating their order, and also print the
 *            least time of each (default 1; every repeat must give the same curves)
 * Before the runs one untimed update of an instance of the scene warms the process up
 * (its first update costs about 70 ms more than the same update later).
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
#define DEFAULT_SCENE "scenes/paper_rve_host_ductile.toml"
#define U_TENSION 9.6e-3 /* end displacement at the end of the tension (mm) */
#define U_COMP 3.3e-3 /* end displacement at the end of the compression (mm) */
#define N_TENSION 24
#define N_UNLOAD 10
#define N_COMP 10
#define MAX_IT 12
#define TOL 1e-8      /* |residual| / force scale: converged */
#define FLOOR 1e-6    /* ... or below this and no longer falling (the RVE's tolerance) */
#define MAX_CUTS 6    /* a step may be halved this many times in a row */
#define CURVE_TOL 1e-10

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

/* Updates every point at the displacements u; assembles the internal force and the
 * tangent. Returns the first failed update's status. */
static uint32_t assemble(Run *run, const double *u, double *fint, double *k, double *eps_xx,
                         int phase, char *map) {
    int e, g, a, c, r;
    memset(fint, 0, sizeof(double) * NDOF);
    memset(k, 0, sizeof(double) * NDOF * NDOF);
    for (e = 0; e < NEL; e++) {
        int dofs[8];
        for (a = 0; a < 4; a++) {
            dofs[2 * a] = 2 * element_node(e, a);
            dofs[2 * a + 1] = dofs[2 * a] + 1;
        }
        for (g = 0; g < NGP; g++) {
            int pt = e * NGP + g;
            double b[3][8], eps[3] = {0, 0, 0}, sig[3], d[9], db[3][8], w, t0, t1;
            uint32_t st;
            w = shape(e, g, b);
            for (r = 0; r < 3; r++)
                for (a = 0; a < 8; a++) eps[r] += b[r][a] * u[dofs[a]];
            eps_xx[pt] = eps[0];
            t0 = now();
            st = rve_update(run->h[pt], eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT);
            t1 = now();
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

/* The whole analysis with the given scene texts (strong points: the file when
 * strong_text is NULL). */
static int analyse(Run *run, const char *scene_file, const char *strong_text,
                   const char *weak_text, const char *base_dir, int scale) {
    static double u[NDOF], k_conv[NDOF * NDOF], c[NDOF];
    int p, e, g, i, have_k = 0, failed = 1;
    const int nsteps[NPHASE] = {N_TENSION * scale, N_UNLOAD * scale, N_COMP * scale};
    double t_start = now();
    memset(u, 0, sizeof u);
    for (e = 0; e < NEL; e++)
        for (g = 0; g < NGP; g++) {
            RveHandle *h = &run->h[e * NGP + g];
            uint32_t st;
            if (e % NX == WEAK_COL) st = rve_init_text(weak_text, base_dir, h);
            else if (strong_text) st = rve_init_text(strong_text, base_dir, h);
            else st = rve_init_file(scene_file, h);
            if (report(st, "rve_init")) goto out;
        }
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
                double rve_before = run->rve_seconds;
                unsigned long updates_before = run->updates, fast_before = run->n_fast;
                Step st;
                if (newton(run, p, c, next, u, k_conv, have_k, &st)) {
                    for (i = 0; i < NPT; i++)
                        if (report(rve_revert(run->h[i]), "rve_revert")) goto out;
                    run->cuts++;
                    if (++cuts > MAX_CUTS) {
                        fprintf(stderr, "localize: %s: no convergence at %.6e after %d cuts\n",
                                phase_name[p], next, MAX_CUTS);
                        goto out;
                    }
                    continue;
                }
                for (i = 0; i < NPT; i++)
                    if (report(rve_commit(run->h[i]), "rve_commit")) goto out;
                have_k = 1;
                done = next;
                st.phase = p;
                st.cuts = cuts;
                st.target = next;
                st.fast = run->n_fast - fast_before;
                st.updates = run->updates - updates_before;
                st.rve_seconds = run->rve_seconds - rve_before;
                run->fast_phase[p] += st.fast;
                if (push_step(run, st)) goto out;
                if (fabs(st.f) > run->f_max) run->f_max = fabs(st.f);
                if (cuts > 0) cuts--; /* then try a longer sub-step again */
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

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : DEFAULT_SCENE;
    int scale = argc > 2 ? atoi(argv[2]) : 1, repeats = argc > 3 ? atoi(argv[3]) : 1;
    int failures = 0, i, p, r, peak, low, loc, all_fast = 0;
    char *text = NULL, *weak = NULL, *off = NULL, *weak_off = NULL, *base = NULL;
    static Run fast, slow, again[2];
    static Times tf, to;
    double diff_f = 0.0, diff_e = 0.0, f_scale = 0.0, e_scale = 0.0, share;
    double min_fast, min_off;
    verbose = getenv("LOCALIZE_VERBOSE") != NULL;
    if (scale < 1 || repeats < 1 || argc > 4) {
        fprintf(stderr, "usage: localize [SCENE.toml [SCALE >= 1 [REPEATS >= 1]]]\n");
        return 2;
    }
    if (!(text = read_file(scene))) {
        perror(scene);
        return 1;
    }
    if (find_key(text, "fast_path")) {
        fprintf(stderr, "localize: %s sets solver.fast_path; the runs set it themselves\n", scene);
        free(text);
        return 1;
    }
    weak = scale_sigma_c(text, WEAK);
    off = without_fast_path(text);
    weak_off = weak ? without_fast_path(weak) : NULL;
    base = dir_of(scene);
    if (!weak || !off || !weak_off || !base) {
        fprintf(stderr, "localize: %s: no `sigma_c = <number>` (or out of memory)\n", scene);
        failures = 1;
        goto done;
    }
    printf("localize: %s, %d x %d quads, %d RVEs (band: column %d, sigma_c x %.2f); "
           "%d + %d + %d steps; %d run%s with and without the fast path\n",
           scene, NX, NY, NPT, WEAK_COL, WEAK, N_TENSION * scale, N_UNLOAD * scale,
           N_COMP * scale, repeats, repeats > 1 ? "s each" : " each");
    fflush(stdout);
    { /* warm-up, not timed: the process's first update pays for what its later ones reuse */
        RveHandle h = 0;
        double eps[3] = {1e-5, 0.0, 0.0}, sig[3], d[9];
        if (report(rve_init_file(scene, &h), "rve_init_file") ||
            report(rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), "rve_update")) {
            rve_free(h);
            failures = 1;
            goto done;
        }
        rve_free(h);
    }
    if (analyse(&fast, scene, NULL, weak, base, scale) ||
        analyse(&slow, scene, off, weak_off, base, scale)) {
        const Run *run = slow.nsteps ? &slow : &fast;
        printf("the run %s the fast path stopped; its converged steps:\n",
               run == &slow ? "without" : "with");
        for (i = 0; i < run->nsteps; i++)
            printf("%-11s %4d  U %11.4e  F %10.4f  eps band %9.3e  rest %9.3e  it %d  cuts %d\n",
                   phase_name[run->steps[i].phase], i + 1, run->steps[i].u, run->steps[i].f,
                   run->steps[i].eps_band, run->steps[i].eps_rest, run->steps[i].iterations,
                   run->steps[i].cuts);
        failures = 1;
        goto done;
    }
    min_fast = fast.rve_seconds;
    min_off = slow.rve_seconds;
    add_times(&tf, &fast, &fast);
    add_times(&to, &slow, &fast);
    if (repeats > 1) printf("time in rve_update (s), fast / off:  %.3f / %.3f", min_fast, min_off);
    for (r = 1; r < repeats; r++) { /* alternate the order; every run must give the same curve */
        double de, df;
        Run *f = &again[r % 2], *o = &again[1 - r % 2];
        memset(again, 0, sizeof again);
        if (analyse(&again[0], scene, r % 2 ? off : NULL, r % 2 ? weak_off : weak, base, scale) ||
            analyse(&again[1], scene, r % 2 ? NULL : off, r % 2 ? weak : weak_off, base, scale)) {
            failures = 1;
        } else {
            if (compare(&fast, f, &de, &df) || de > CURVE_TOL || df > CURVE_TOL ||
                compare(&fast, o, &de, &df) || de > CURVE_TOL || df > CURVE_TOL) {
                fprintf(stderr, "\nlocalize: repeat %d: another curve\n", r + 1);
                failures++;
            }
            printf(",  %.3f / %.3f", f->rve_seconds, o->rve_seconds);
            add_times(&tf, f, f);
            add_times(&to, o, f);
            if (f->rve_seconds < min_fast) min_fast = f->rve_seconds;
            if (o->rve_seconds < min_off) min_off = o->rve_seconds;
        }
        free(again[0].steps);
        free(again[1].steps);
        if (failures) goto done;
    }
    if (repeats > 1) printf("\n");
    if (compare(&fast, &slow, &diff_e, &diff_f)) {
        fprintf(stderr, "localize: the runs took different steps (%d and %d)\n", fast.nsteps,
                slow.nsteps);
        failures++;
    }
    for (i = 0; i < fast.nsteps; i++) {
        if (fabs(fast.steps[i].f) > f_scale) f_scale = fabs(fast.steps[i].f);
        if (fabs(fast.steps[i].eps_band) > e_scale) e_scale = fabs(fast.steps[i].eps_band);
    }
    printf("\n%-11s %4s %11s %10s %10s %8s %9s %9s %5s %10s %13s\n", "phase", "step", "U (mm)",
           "F (N)", "F off (N)", "dF/Fmax", "eps band", "eps rest", "it", "fast/upd",
           "RVE ms / off");
    for (i = 0; i < fast.nsteps && i < slow.nsteps; i++) {
        const Step *a = &fast.steps[i], *b = &slow.steps[i];
        printf("%-11s %4d %11.4e %10.4f %10.4f %8.1e %9.3e %9.3e %2d/%-2d %3lu/%-6lu %6.1f/%-6.1f\n",
               phase_name[a->phase], i + 1, a->u, a->f, b->f, rel(a->f, b->f, f_scale),
               a->eps_band, a->eps_rest, a->iterations, b->iterations, a->fast, a->updates,
               1e3 * a->rve_seconds, 1e3 * b->rve_seconds);
        all_fast += a->fast == a->updates;
    }
    share = fast.updates ? (double)fast.fast_total / (double)fast.updates : 0.0;
    printf("\n%-11s %15s %7s %11s %11s %8s   (times summed over %d run%s of each)\n", "phase",
           "updates", "fast", "RVE s", "RVE s off", "off/fast", repeats, repeats > 1 ? "s" : "");
    for (p = 0; p < NPHASE; p++)
        printf("%-11s %7lu/%-7lu %7lu %11.3f %11.3f %8.2f\n", phase_name[p], fast.updates_phase[p],
               slow.updates_phase[p], fast.fast_phase[p], tf.phase[p], to.phase[p],
               tf.phase[p] > 0 ? to.phase[p] / tf.phase[p] : 0.0);
    printf("%-11s %7lu/%-7lu %7lu %11.3f %11.3f %8.2f\n", "all", fast.updates, slow.updates,
           (unsigned long)fast.fast_total, tf.all, to.all, tf.all > 0 ? to.all / tf.all : 0.0);
    printf("\nfast share: %.3f (%lu of %lu updates answered without a solve; without the fast "
           "path: %lu)\n",
           share, (unsigned long)fast.fast_total, fast.updates, (unsigned long)slow.fast_total);
    printf("time in rve_update: %.3f s with the fast path, %.3f s without: ratio %.2f "
           "(first runs; whole runs %.3f s and %.3f s; steps cut %d and %d)\n",
           fast.rve_seconds, slow.rve_seconds,
           fast.rve_seconds > 0 ? slow.rve_seconds / fast.rve_seconds : 0.0, fast.seconds,
           slow.seconds, fast.cuts, slow.cuts);
    if (repeats > 1)
        printf("  least of %d runs each: %.3f s and %.3f s: ratio %.2f; summed: ratio %.2f\n",
               repeats, min_fast, min_off, min_off / min_fast, to.all / tf.all);
    if (tf.n_fast > 0 && tf.updates > tf.n_fast && to.updates > 0)
        printf("per update: fast answer %.1f us, solve %.3f ms (%.3f ms without the fast path); "
               "the %d steps answered only by the fast path: %.2f ms against %.2f ms per run\n",
               1e6 * tf.fast / (double)tf.n_fast,
               1e3 * tf.solved / (double)(tf.updates - tf.n_fast),
               1e3 * to.solved / (double)to.updates, all_fast, 1e3 * tf.steps_all_fast / repeats,
               1e3 * to.steps_all_fast / repeats);
    loc = localized(&fast, &peak, &low);
    if (peak >= 0 && low >= 0)
        printf("localization: F %.4f N at the peak (step %d) -> %.4f N (step %d); band eps_xx "
               "%.3e -> %.3e, rest %.3e -> %.3e\n",
               fast.steps[peak].f, peak + 1, fast.steps[low].f, low + 1,
               fast.steps[peak].eps_band, fast.steps[low].eps_band, fast.steps[peak].eps_rest,
               fast.steps[low].eps_rest);
    printf("F at U = 0 after the unloading: %.1e N\n", fast.f_zero);
    printf("largest difference of the runs: F %.1e of max |F| = %.4f N, band eps_xx %.1e of its "
           "max %.3e (limit %.0e)\n",
           diff_f, f_scale, diff_e, e_scale, CURVE_TOL);
    fflush(stdout);
    if (!(diff_f <= CURVE_TOL && diff_e <= CURVE_TOL)) {
        fprintf(stderr, "localize: the curves differ by more than %.0e\n", CURVE_TOL);
        failures++;
    }
    if (!(share > 0.0)) {
        fprintf(stderr, "localize: no update was answered by the fast path\n");
        failures++;
    }
    if (fast.n_fast != fast.fast_total || slow.fast_total != 0) {
        fprintf(stderr, "localize: rve_fast_updates counts %lu and %lu; seen %lu and %lu\n",
                (unsigned long)fast.fast_total, (unsigned long)slow.fast_total, fast.n_fast,
                slow.n_fast);
        failures++;
    }
    if (!loc) {
        fprintf(stderr, "localize: the band did not localize (no force drop after the peak with "
                        "the band stretching and the rest contracting)\n");
        failures++;
    }
done:
    free(fast.steps);
    free(slow.steps);
    free(text);
    free(weak);
    free(off);
    free(weak_off);
    free(base);
    printf("localize: %s\n", failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
