/*
 * fe2_plate_mpi.c -- FE^2 over MPI: a macroscopic plate whose material law at every
 * integration point is a mesorve RVE, with the points partitioned over the ranks.
 *
 * Macro problem (the "clamped" case of freefem_examples/macro_plate.edp on a structured
 * mesh): plate [0, LX] x [0, LY] mm, plane stress, thickness 1 mm, NX x NY rectangles cut
 * into two constant-strain triangles each, one RVE point per triangle. Tension by
 * displacement: u = (0, 0) on the left edge, u = (U, 0) on the right edge, U raised in
 * NINC increments to EPSEND * LX, EPSEND = 1.6e-4 by default (the uniaxial peak of the RVE
 * is near 2.2e-4; the restrained Poisson contraction makes the field inhomogeneous and
 * concentrates the strain at the clamped corners: at 1.8e-4 the last increment of the
 * 16 x 8 plate localises there and the macro Newton no longer converges). Macro Newton with
 * the consistent tangent; an increment starts from the last converged field scaled to the
 * new U. `-b NBACK` adds NBACK increments back down by the same step after the NINC up
 * (unloading; an IMPL-EX scene unloads secantly), without step control or checkpoints.
 *
 * With an IMPL-EX scene (-s scenes/paper_rve_host_implex.toml: the paper's own ITZ law)
 * every RVE is linear within an increment with a symmetric positive definite tangent, so
 * the plate goes past its peak (-e 4e-4 -n 16: the reaction falls from 51.0 to 41.4 N)
 * with one Newton correction per increment, and the banded LU below needs no pivoting
 * there either. The points are updated by rve_update_batch_timed with no time increment
 * (dtime 0): each increment counts as long as the last, which is exact for these equal
 * increments.
 *
 * Step control: with a scene that sets solver.step_tolerance (IMPL-EX; e.g.
 * scenes/paper_rve_host_step_control.toml) the host follows the smallest
 * suggested_step_ratio of all points (the batch call's RvePointReport, reduced over the
 * ranks with MPI_MIN), the rule of c_examples/localize.c: a converged increment whose
 * smallest ratio is below 1 is reverted (rve_revert) and redone that much smaller (not
 * below 1/1024 of the nominal step), and the next one is the last times the ratio when
 * that exceeds 1, up to the end of the nominal step (the NINC nominal steps are the
 * largest). Each update then passes its increment's dU as its time increment. The
 * increments are numbered as kept; stdout says how many were redone. Checkpoints (-c,
 * -r) are refused with such a scene (the checkpoint holds no step length).
 *
 * Answer sharing (-S TOL): the rank's instances are made from the scene with
 * `share_tolerance = TOL` added to its [solver] table (rve_init_text), so within each
 * batch call a point close to a point of the same rank already solved takes that point's
 * answer corrected to first order (docs/sharing.md). Sharing stays within a rank (a
 * batch holds one rank's points only); the points' states and strains never cross
 * ranks for it. The answers then depend on the rank count (which points meet in a batch)
 * but not on the threads per rank. stdout: each increment's solved and shared point
 * updates (from RvePointReport.shared_from, summed over the increment's Newton
 * iterations), in total and per rank, the residual the increment ended at, and the
 * per-rank table's `shared` column. A shared answer jumps (by up to about TOL of the
 * stress) when a point changes anchor or gets its own solve back between two Newton
 * iterations, so the macro residual can stall above FLOOR: with -S a stalled residual
 * (not halved by an iteration) below TOL / 10 counts as converged.
 *
 * Parallel layout (what a cluster host does):
 *   - rank r owns the points [r N / P, (r + 1) N / P) and their RVE instances, created on
 *     that rank (rve_init_file: the scene is meshed once per process, the instances of a
 *     rank share that model); instances never leave their rank;
 *   - each Newton iteration rank 0 broadcasts the macro displacement, every rank updates
 *     its own instances (rve_update_batch_timed, `-t` threads per rank) and sends back
 *     stress and tangent per point (MPI_Gatherv, global point order); rank 0 assembles in
 *     point order and solves. The assembly order, and so every floating-point sum, is independent of
 *     the rank count: the results are bit-identical for any P;
 *   - a converged increment is committed by every rank on its own instances.
 * Nothing of the library crosses ranks: only strains (as the displacement) go out and
 * stresses and tangents come back.
 *
 * Checkpoint and restart: `-c DIR -k K` stops after increment K and writes DIR/macro.bin
 * (rank 0: increment, rank count, macro displacement) and DIR/points.<r>.bin (rank r: its
 * points' committed RVE states, rve_state_save, one record per point with its global
 * index). `-r DIR` restarts from such a checkpoint with any rank count: each rank reads
 * the records of the points it owns now (rve_state_load) from whichever files hold them,
 * so points migrate between ranks, and goes on from increment K + 1.
 *
 * Output (rank 0): OUT.csv, one line per increment (U, reaction, macro iterations,
 * residual), then after the last increment one line per point (strain, stress), all with
 * 17 significant digits; a restart appends to it. stdout: per rank, the wall time, the
 * time spent in the RVE calls, the CPU time and the peak RSS (getrusage: ru_utime +
 * ru_stime, ru_maxrss), the instance updates, how many of them were answered without a
 * solve (rve_fast_updates, since the instances were created or loaded) and how many took
 * another point's answer (shared_from, -S); with -v 1 also each macro iteration's
 * residual.
 *
 * Usage: mpirun -n P fe2_plate_mpi [-s SCENE] [-o OUT.csv] [-x NX] [-y NY] [-n NINC]
 *                                  [-e EPSEND] [-b NBACK] [-t THREADS] [-S TOL]
 *                                  [-c DIR -k K | -r DIR] [-v 1]
 * Defaults: scenes/paper_rve_host.toml, fe2_plate_mpi.csv, 8 x 4, 8 increments, 1 thread.
 * Exit codes: 0 done, 1 a failed call or bad input (message on stderr), 2 no convergence.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include <mpi.h>

#include "rve.h"

#define LX 20.0
#define LY 10.0
#define MAXIT 8
#define TOL 1e-9    /* converged: |R on free dofs| / |reaction| */
#define FLOOR 1e-7  /* below this the RVE tolerance (1e-6 on its residual) dominates */
#define CKPT_MAGIC 0x4d52564543504b31ULL /* "MRVECPK1" */

typedef struct {
    int nx, ny, nnode, nelem, ndof;
    int (*tri)[3]; /* node numbers of each triangle, counter-clockwise */
    double *x, *y; /* node coordinates */
    int *fixed;    /* per dof: 1 prescribed (left/right edges) */
    int bw;        /* half bandwidth of the stiffness in the node numbering */
} Mesh;

static int rank, nranks;
/* This rank's point updates of the current increment: solved, and shared (-S). */
static long inc_solved, inc_shared;

static void die(const char *what, uint32_t st) {
    char msg[512];
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "fe2_plate_mpi: rank %d: %s: %s: %s\n", rank, what, rve_status_message(st),
            msg);
    MPI_Abort(MPI_COMM_WORLD, 1);
}

static void fail(const char *fmt, const char *arg) {
    fprintf(stderr, "fe2_plate_mpi: rank %d: ", rank);
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    MPI_Abort(MPI_COMM_WORLD, 1);
}

static void *xmalloc(size_t n) {
    void *p = malloc(n ? n : 1);
    if (!p) fail("out of memory%s", "");
    return p;
}

/* Nodes numbered column by column (x outer), so a triangle's nodes are at most NY + 2
 * apart: half bandwidth 2 (NY + 2) + 1 in dofs. */
static void make_mesh(Mesh *m, int nx, int ny) {
    int i, j, e = 0;
    m->nx = nx;
    m->ny = ny;
    m->nnode = (nx + 1) * (ny + 1);
    m->nelem = 2 * nx * ny;
    m->ndof = 2 * m->nnode;
    m->bw = 2 * (ny + 2) + 1;
    m->tri = xmalloc(sizeof *m->tri * (size_t)m->nelem);
    m->x = xmalloc(sizeof(double) * (size_t)m->nnode);
    m->y = xmalloc(sizeof(double) * (size_t)m->nnode);
    m->fixed = xmalloc(sizeof(int) * (size_t)m->ndof);
    for (i = 0; i <= nx; i++)
        for (j = 0; j <= ny; j++) {
            int n = i * (ny + 1) + j;
            m->x[n] = LX * i / nx;
            m->y[n] = LY * j / ny;
            m->fixed[2 * n] = m->fixed[2 * n + 1] = (i == 0 || i == nx);
        }
    for (i = 0; i < nx; i++)
        for (j = 0; j < ny; j++) {
            int a = i * (ny + 1) + j, b = a + ny + 1; /* a: lower left, b: lower right */
            m->tri[e][0] = a, m->tri[e][1] = b, m->tri[e][2] = b + 1, e++;
            m->tri[e][0] = a, m->tri[e][1] = b + 1, m->tri[e][2] = a + 1, e++;
        }
}

/* Constant-strain triangle: e = B u_e with e = [exx, eyy, gxy] (engineering shear),
 * u_e = [u1 v1 u2 v2 u3 v3]; returns the area. */
static double cst_b(const Mesh *m, int e, double b[3][6]) {
    const int *t = m->tri[e];
    double x1 = m->x[t[0]], y1 = m->y[t[0]], x2 = m->x[t[1]], y2 = m->y[t[1]];
    double x3 = m->x[t[2]], y3 = m->y[t[2]];
    double area2 = (x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1);
    double dy[3] = {y2 - y3, y3 - y1, y1 - y2}, dx[3] = {x3 - x2, x1 - x3, x2 - x1};
    int a;
    for (a = 0; a < 3; a++) {
        b[0][2 * a] = dy[a] / area2, b[0][2 * a + 1] = 0.0;
        b[1][2 * a] = 0.0, b[1][2 * a + 1] = dx[a] / area2;
        b[2][2 * a] = dx[a] / area2, b[2][2 * a + 1] = dy[a] / area2;
    }
    return 0.5 * area2;
}

static void element_strain(const Mesh *m, int e, const double *u, double eps[3]) {
    double b[3][6];
    int i, k;
    cst_b(m, e, b);
    for (i = 0; i < 3; i++) {
        eps[i] = 0.0;
        for (k = 0; k < 6; k++) eps[i] += b[i][k] * u[2 * m->tri[e][k / 2] + k % 2];
    }
}

/* Banded storage: K(i, j) with |i - j| <= bw at band[i * (2 bw + 1) + (j - i + bw)]. */
static double *band_at(double *band, int bw, int i, int j) {
    return &band[(size_t)i * (size_t)(2 * bw + 1) + (size_t)(j - i + bw)];
}

/* Updates of the instances h[0..count) answered without a solve (rve_fast_updates): the
 * fast path's answers and, with IMPL-EX, the updates that reuse their increment's
 * factorization. */
static unsigned long fast_updates(const RveHandle *h, int count) {
    unsigned long total = 0;
    int i;
    for (i = 0; i < count; i++) {
        uint64_t n = 0;
        uint32_t st = rve_fast_updates(h[i], &n);
        if (st != RVE_STATUS_OK) die("rve_fast_updates", st);
        total += (unsigned long)n;
    }
    return total;
}

/* Solves K x = r in place (r <- x) by banded LU without pivoting. The prescribed dofs carry
 * identity rows, so K is the free-dof stiffness; before the peak it is positive definite.
 * Returns 0, or 1 on a vanishing pivot. */
static int band_solve(double *band, int n, int bw, double *r) {
    int i, j, k;
    for (k = 0; k < n; k++) {
        double p = *band_at(band, bw, k, k);
        if (!(fabs(p) > 1e-300)) return 1;
        for (i = k + 1; i <= k + bw && i < n; i++) {
            double l = *band_at(band, bw, i, k) / p;
            if (l == 0.0) continue;
            for (j = k + 1; j <= k + bw && j < n; j++)
                *band_at(band, bw, i, j) -= l * *band_at(band, bw, k, j);
            r[i] -= l * r[k];
        }
    }
    for (k = n - 1; k >= 0; k--) {
        double s = r[k];
        for (j = k + 1; j <= k + bw && j < n; j++) s -= *band_at(band, bw, k, j) * r[j];
        r[k] = s / *band_at(band, bw, k, k);
    }
    return 0;
}

static double now(void) { return MPI_Wtime(); }

/* Whether the scene file sets solver.step_tolerance (the host then follows the ratio). */
static int follows_ratio(const char *scene) {
    char line[512];
    int found = 0;
    FILE *f = fopen(scene, "r");
    if (!f) fail("cannot read %s", scene);
    while (!found && fgets(line, sizeof line, f))
        found = strncmp(line, "step_tolerance", strlen("step_tolerance")) == 0;
    fclose(f);
    return found;
}

/* The scene file's text with `share_tolerance = tol` after its [solver] line (malloc'd). */
static char *scene_sharing(const char *scene, double tol) {
    char line[512];
    size_t len = 0, cap = 4096;
    char *text = xmalloc(cap);
    int added = 0;
    FILE *f = fopen(scene, "r");
    if (!f) fail("cannot read %s", scene);
    text[0] = '\0';
    while (fgets(line, sizeof line, f)) {
        size_t n = strlen(line);
        while (len + n + 64 >= cap) {
            char *grown = realloc(text, cap *= 2);
            if (!grown) fail("out of memory%s", "");
            text = grown;
        }
        memcpy(text + len, line, n + 1);
        len += n;
        if (!added && strncmp(line, "[solver]", 8) == 0) {
            len += (size_t)sprintf(text + len, "share_tolerance = %.17g\n", tol);
            added = 1;
        }
    }
    fclose(f);
    if (!added) fail("-S: %s has no [solver] table", scene);
    return text;
}

/* This rank's instances: the first from the scene (with the sharing key when `sharing`;
 * the library checks the value; relative paths against the scene's directory), the
 * others share its model. */
static void make_instances(const char *scene, int sharing, double tol, RveHandle *h,
                           int count) {
    int i;
    for (i = 0; i < count; i++) {
        uint32_t st;
        if (i > 0) st = rve_clone_model(h[0], &h[i]);
        else if (!sharing) st = rve_init_file(scene, &h[0]);
        else {
            char dir[4096], *slash, *text = scene_sharing(scene, tol);
            snprintf(dir, sizeof dir, "%s", scene);
            slash = strrchr(dir, '/');
            if (slash) *slash = '\0';
            st = rve_init_text(text, slash ? dir : NULL, &h[0]);
            free(text);
        }
        if (st != RVE_STATUS_OK) die(i ? "rve_clone_model" : "rve_init_file/text", st);
    }
}

/* Prints (rank 0) this increment's solved and shared updates, in total and per rank, and
 * its final residual (rank 0's), and starts the next increment's counts. */
static void print_sharing(int inc, double residual) {
    long mine[2] = {inc_solved, inc_shared}, *every = NULL, sum[2] = {0, 0};
    int r;
    if (rank == 0) every = xmalloc(sizeof(long) * 2 * (size_t)nranks);
    MPI_Gather(mine, 2, MPI_LONG, every, 2, MPI_LONG, 0, MPI_COMM_WORLD);
    if (rank == 0) {
        for (r = 0; r < nranks; r++) sum[0] += every[2 * r], sum[1] += every[2 * r + 1];
        printf("sharing: increment %d (residual %.1e): solved %ld, shared %ld; per rank "
               "(solved/shared):", inc, residual, sum[0], sum[1]);
        for (r = 0; r < nranks; r++) printf(" %ld/%ld", every[2 * r], every[2 * r + 1]);
        printf("\n");
        free(every);
    }
    inc_solved = inc_shared = 0;
}

/* Trial-updates this rank's points over the time increment dtime (rve_update_batch_timed);
 * aborts every rank on a failure. Returns the smallest suggested_step_ratio of all points
 * of all ranks (MPI_MIN) when `reduce`, else 1. */
static double update_points(const RveHandle *h, int count, const double *eps, double dtime,
                            double *sig_tan, RvePointReport *reports, size_t nthreads,
                            int inc, int reduce) {
    double mine = INFINITY, all = 1.0;
    int bad = 0, anybad = 0, e;
    uint32_t st = rve_update_batch_timed(h, (size_t)count, eps, dtime, sig_tan,
                                         sig_tan + 3 * (size_t)count,
                                         RVE_TANGENT_REQUEST_CONSISTENT, reports, NULL, 0,
                                         nthreads);
    if (st != RVE_STATUS_OK && count > 0) {
        char msg[512];
        rve_last_error(msg, sizeof msg);
        fprintf(stderr, "fe2_plate_mpi: rank %d: increment %d: rve_update_batch_timed: %s: %s\n",
                rank, inc, rve_status_message(st), msg);
        bad = 1;
    }
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (anybad) MPI_Abort(MPI_COMM_WORLD, 1);
    for (e = 0; e < count; e++) {
        if (reports[e].shared_from) inc_shared++;
        else inc_solved++;
    }
    if (!reduce) return 1.0;
    for (e = 0; e < count; e++) mine = fmin(mine, reports[e].suggested_step_ratio);
    MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    return all;
}

/* Following the ratio: the next increment's length after one of length `taken` that was
 * kept with the smallest ratio `ratio`, ending at the nominal step's end when `at_end`
 * (a piece cut short by the step's end does not shorten the next). */
static double next_length(double length, double taken, double ratio, int at_end) {
    if (at_end && taken < length) return length;
    return taken * (ratio > 1.0 ? ratio : 1.0);
}

/* Checkpoint files. macro.bin: magic, increment, nranks, nx, ny, ninc, u[ndof].
 * points.<r>.bin: magic, then per point: global index, byte count, state bytes. */
static void write_checkpoint(const char *dir, const Mesh *m, int inc, int ninc,
                             const double *u, const RveHandle *h, int first, int count) {
    char path[4096];
    FILE *f;
    uint64_t magic = CKPT_MAGIC;
    size_t cap = 0, written = 0;
    uint8_t *buf = NULL;
    int p;
    if (rank == 0) {
        int64_t head[5] = {inc, nranks, m->nx, m->ny, ninc};
        snprintf(path, sizeof path, "%s/macro.bin", dir);
        f = fopen(path, "wb");
        if (!f || fwrite(&magic, sizeof magic, 1, f) != 1 || fwrite(head, sizeof head, 1, f) != 1 ||
            fwrite(u, sizeof(double), (size_t)m->ndof, f) != (size_t)m->ndof || fclose(f) != 0)
            fail("cannot write %s", path);
    }
    snprintf(path, sizeof path, "%s/points.%d.bin", dir, rank);
    f = fopen(path, "wb");
    if (!f || fwrite(&magic, sizeof magic, 1, f) != 1) fail("cannot write %s", path);
    for (p = 0; p < count; p++) {
        uint64_t rec[2];
        uint32_t st = rve_state_size(h[p], &written);
        if (st != RVE_STATUS_OK) die("rve_state_size", st);
        if (written > cap) {
            free(buf);
            cap = written;
            buf = xmalloc(cap);
        }
        st = rve_state_save(h[p], buf, cap, &written);
        if (st != RVE_STATUS_OK) die("rve_state_save", st);
        rec[0] = (uint64_t)(first + p);
        rec[1] = written;
        if (fwrite(rec, sizeof rec, 1, f) != 1 || fwrite(buf, 1, written, f) != written)
            fail("cannot write %s", path);
    }
    if (fclose(f) != 0) fail("cannot write %s", path);
    free(buf);
}

/* Reads macro.bin on rank 0 and broadcasts it; every rank then loads the states of the
 * points it owns from the old ranks' files. Returns the increment checkpointed. */
static int read_checkpoint(const char *dir, const Mesh *m, int ninc, double *u, RveHandle *h,
                           int first, int count) {
    char path[4096];
    FILE *f;
    uint64_t magic = 0;
    int64_t head[5] = {0, 0, 0, 0, 0};
    int r, loaded = 0, total = 0;
    if (rank == 0) {
        snprintf(path, sizeof path, "%s/macro.bin", dir);
        f = fopen(path, "rb");
        if (!f || fread(&magic, sizeof magic, 1, f) != 1 || magic != CKPT_MAGIC ||
            fread(head, sizeof head, 1, f) != 1)
            fail("%s is not a checkpoint of fe2_plate_mpi", path);
        if (head[2] != m->nx || head[3] != m->ny || head[4] != ninc)
            fail("%s: checkpoint of another mesh or increment count", path);
        if (fread(u, sizeof(double), (size_t)m->ndof, f) != (size_t)m->ndof)
            fail("%s: truncated", path);
        fclose(f);
    }
    MPI_Bcast(head, 5, MPI_INT64_T, 0, MPI_COMM_WORLD);
    MPI_Bcast(u, m->ndof, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    for (r = 0; r < (int)head[1]; r++) {
        uint64_t rec[2];
        snprintf(path, sizeof path, "%s/points.%d.bin", dir, r);
        f = fopen(path, "rb");
        if (!f || fread(&magic, sizeof magic, 1, f) != 1 || magic != CKPT_MAGIC)
            fail("%s is not a checkpoint of fe2_plate_mpi", path);
        while (fread(rec, sizeof rec, 1, f) == 1) {
            int g = (int)rec[0];
            if (rec[0] >= (uint64_t)m->nelem || rec[1] > ((uint64_t)1 << 32))
                fail("%s: bad record", path);
            total++;
            if (g >= first && g < first + count) {
                uint8_t *buf = xmalloc((size_t)rec[1]);
                uint32_t st;
                if (fread(buf, 1, (size_t)rec[1], f) != (size_t)rec[1]) fail("%s: truncated", path);
                st = rve_state_load(h[g - first], buf, (size_t)rec[1]);
                if (st != RVE_STATUS_OK) die("rve_state_load", st);
                free(buf);
                loaded++;
            } else if (fseek(f, (long)rec[1], SEEK_CUR) != 0) {
                fail("%s: truncated", path);
            }
        }
        fclose(f);
    }
    if (total != m->nelem || loaded != count) fail("%s: points missing from the checkpoint", dir);
    return (int)head[0];
}

int main(int argc, char **argv) {
    const char *scene = "scenes/paper_rve_host.toml", *out = "fe2_plate_mpi.csv";
    const char *ckpt_dir = NULL, *restart_dir = NULL;
    int nx = 8, ny = 4, ninc = 8, stop_after = -1, verbose = 0, i, inc, inc0 = 0, s;
    int follow, redos = 0, sharing = 0, nback = 0;
    double epsend = 1.6e-4, done = 0.0, length = 0.0, min_ratio = INFINITY, share_tol = 0.0;
    double stall; /* a residual that stops halving below this counts as converged */
    size_t nthreads = 1;
    Mesh m;
    int first, count, *counts, *displs;
    RveHandle *h;
    double *u, *du, *u_save, *eps, *sig_tan, *all = NULL, *band = NULL, *res = NULL;
    double t_start, t_rve = 0.0, t_init;
    long updates = 0, shared = 0; /* this rank's instance updates, and shared ones */
    RvePointReport *reports;
    FILE *csv = NULL;

    MPI_Init(&argc, &argv);
    t_start = now();
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &nranks);
    for (i = 1; i + 1 < argc; i += 2) {
        const char *o = argv[i], *v = argv[i + 1];
        if (!strcmp(o, "-s")) scene = v;
        else if (!strcmp(o, "-o")) out = v;
        else if (!strcmp(o, "-x")) nx = atoi(v);
        else if (!strcmp(o, "-y")) ny = atoi(v);
        else if (!strcmp(o, "-n")) ninc = atoi(v);
        else if (!strcmp(o, "-b")) nback = atoi(v);
        else if (!strcmp(o, "-e")) epsend = atof(v);
        else if (!strcmp(o, "-t")) nthreads = (size_t)atoi(v);
        else if (!strcmp(o, "-c")) ckpt_dir = v;
        else if (!strcmp(o, "-k")) stop_after = atoi(v);
        else if (!strcmp(o, "-r")) restart_dir = v;
        else if (!strcmp(o, "-v")) verbose = atoi(v);
        else if (!strcmp(o, "-S")) share_tol = atof(v), sharing = 1;
        else fail("unknown option %s", o);
    }
    if (i != argc) fail("option %s needs a value", argv[argc - 1]);
    if (nx < 1 || ny < 1 || ninc < 1 || nthreads < 1) fail("-x, -y, -n, -t must be >= 1%s", "");
    if (nback < 0 || nback > ninc) fail("-b NBACK: 0 <= NBACK <= NINC%s", "");
    if ((ckpt_dir != NULL) != (stop_after >= 1) || stop_after > ninc)
        fail("-c DIR and -k K (1 <= K <= NINC) go together%s", "");
    stall = sharing ? fmax(FLOOR, 0.1 * share_tol) : FLOOR;
    follow = follows_ratio(scene);
    if (nback && (follow || ckpt_dir || restart_dir))
        fail("-b: no unloading with step control (%s) or checkpoints", scene);
    if (follow && (ckpt_dir || restart_dir))
        fail("-c/-r: a run that follows the step ratio (%s sets solver.step_tolerance) cannot "
             "be checkpointed", scene);
    make_mesh(&m, nx, ny);
    if (nranks > m.nelem) fail("more ranks than points%s", "");

    /* Contiguous blocks of points in global order. */
    counts = xmalloc(sizeof(int) * (size_t)nranks);
    displs = xmalloc(sizeof(int) * (size_t)nranks);
    for (i = 0; i < nranks; i++) {
        int lo = (int)((long)m.nelem * i / nranks), hi = (int)((long)m.nelem * (i + 1) / nranks);
        counts[i] = 12 * (hi - lo);
        displs[i] = 12 * lo;
    }
    first = displs[rank] / 12;
    count = counts[rank] / 12;

    /* This rank's instances: the first is meshed from the scene, the others share it. */
    h = xmalloc(sizeof(RveHandle) * (size_t)count);
    make_instances(scene, sharing, share_tol, h, count);
    t_init = now() - t_start;

    u = xmalloc(sizeof(double) * (size_t)m.ndof);
    du = xmalloc(sizeof(double) * (size_t)m.ndof);
    u_save = xmalloc(sizeof(double) * (size_t)m.ndof);
    eps = xmalloc(sizeof(double) * 3 * (size_t)count);
    sig_tan = xmalloc(sizeof(double) * 12 * (size_t)count);
    reports = xmalloc(sizeof(RvePointReport) * (size_t)count);
    memset(u, 0, sizeof(double) * (size_t)m.ndof);
    if (rank == 0) {
        all = xmalloc(sizeof(double) * 12 * (size_t)m.nelem);
        band = xmalloc(sizeof(double) * (size_t)m.ndof * (size_t)(2 * m.bw + 1));
        res = xmalloc(sizeof(double) * (size_t)m.ndof);
    }
    if (restart_dir) inc0 = read_checkpoint(restart_dir, &m, ninc, u, h, first, count);
    if (rank == 0) {
        csv = fopen(out, restart_dir ? "a" : "w");
        if (!csv) fail("cannot open %s", out);
        if (!restart_dir) fprintf(csv, "increment,U,reaction,iterations,residual\n");
    }

    inc = inc0; /* kept increments */
    s = inc0 + 1; /* the nominal step */
    while (s <= ninc + nback) {
        double target = epsend * LX * (s <= ninc ? s : 2 * ninc - s) / ninc;
        double nominal = epsend * LX / ninc;
        double U = target, r_prev = HUGE_VAL, reaction = 0.0, r = 0.0, ratio = 1.0;
        int it, converged = 0, n, last;
        if (follow && length > 0.0 && target - done > length * (1 + 1e-9)) U = done + length;
        inc++;
        memcpy(u_save, u, sizeof(double) * (size_t)m.ndof);
        /* Predictor: the last converged field scaled to the new U (linear at the start). */
        for (n = 0; n < m.nnode; n++) {
            double scale = follow || s > ninc ? U / done : (double)inc / (inc - 1);
            if (inc == 1) {
                u[2 * n] = U * m.x[n] / LX;
                u[2 * n + 1] = 0.0;
            } else {
                u[2 * n] *= scale;
                u[2 * n + 1] *= scale;
            }
        }
        for (it = 0; it <= MAXIT; it++) {
            int e;
            double t0;
            MPI_Bcast(u, m.ndof, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            for (e = 0; e < count; e++) element_strain(&m, first + e, u, &eps[3 * e]);
            t0 = now();
            updates += count;
            ratio = update_points(h, count, eps, follow ? U - done : 0.0, sig_tan, reports,
                                  nthreads, inc, follow);
            t_rve += now() - t0;
            /* Pack [stress(3), tangent(9)] per point for the gather in global order. */
            {
                double *packed = xmalloc(sizeof(double) * 12 * (size_t)count);
                for (e = 0; e < count; e++) {
                    memcpy(&packed[12 * e], &sig_tan[3 * e], 3 * sizeof(double));
                    memcpy(&packed[12 * e + 3], &sig_tan[3 * (size_t)count + 9 * e],
                           9 * sizeof(double));
                }
                MPI_Gatherv(packed, 12 * count, MPI_DOUBLE, all, counts, displs, MPI_DOUBLE, 0,
                            MPI_COMM_WORLD);
                free(packed);
            }
            if (rank == 0) {
                double rn = 0.0;
                int bw = m.bw, w = 2 * bw + 1, a, b, k;
                memset(res, 0, sizeof(double) * (size_t)m.ndof);
                memset(band, 0, sizeof(double) * (size_t)m.ndof * (size_t)w);
                for (e = 0; e < m.nelem; e++) {
                    double bm[3][6], db[3][6];
                    const double *s = &all[12 * e], *d = &all[12 * e + 3];
                    double area = cst_b(&m, e, bm);
                    for (a = 0; a < 3; a++)
                        for (b = 0; b < 6; b++)
                            db[a][b] = d[3 * a] * bm[0][b] + d[3 * a + 1] * bm[1][b] +
                                       d[3 * a + 2] * bm[2][b];
                    for (a = 0; a < 6; a++) {
                        int ga = 2 * m.tri[e][a / 2] + a % 2;
                        res[ga] += area * (bm[0][a] * s[0] + bm[1][a] * s[1] + bm[2][a] * s[2]);
                        if (m.fixed[ga]) continue;
                        for (b = 0; b < 6; b++) {
                            int gb = 2 * m.tri[e][b / 2] + b % 2;
                            if (m.fixed[gb]) continue;
                            *band_at(band, bw, ga, gb) +=
                                area * (bm[0][a] * db[0][b] + bm[1][a] * db[1][b] +
                                        bm[2][a] * db[2][b]);
                        }
                    }
                }
                reaction = 0.0;
                for (n = 0; n <= m.ny; n++) reaction += res[2 * (m.nx * (m.ny + 1) + n)];
                for (k = 0; k < m.ndof; k++) {
                    if (m.fixed[k]) {
                        *band_at(band, bw, k, k) = 1.0;
                        du[k] = 0.0;
                    } else {
                        rn += res[k] * res[k];
                        du[k] = -res[k];
                    }
                }
                r = sqrt(rn) / fabs(reaction);
                if (verbose) printf("increment %d  it %d  residual %.3e\n", inc, it, r);
                converged = r < TOL || (it > 0 && r <= stall && r >= 0.5 * r_prev);
                if (!converged && it < MAXIT) {
                    if (band_solve(band, m.ndof, bw, du))
                        fail("increment %s: singular macro stiffness", "");
                    for (k = 0; k < m.ndof; k++) u[k] += du[k];
                }
                r_prev = r;
            }
            MPI_Bcast(&converged, 1, MPI_INT, 0, MPI_COMM_WORLD);
            if (converged) break;
        }
        if (!converged) {
            if (rank == 0)
                fprintf(stderr, "fe2_plate_mpi: increment %d: no convergence in %d iterations\n",
                        inc, MAXIT);
            MPI_Abort(MPI_COMM_WORLD, 2);
        }
        if (follow) {
            double taken = U - done;
            min_ratio = fmin(min_ratio, ratio);
            if (ratio < 1.0 && taken > nominal / 1024.0 * (1 + 1e-9)) { /* redo smaller */
                for (i = 0; i < count; i++) {
                    uint32_t st = rve_revert(h[i]);
                    if (st != RVE_STATUS_OK) die("rve_revert", st);
                }
                memcpy(u, u_save, sizeof(double) * (size_t)m.ndof);
                length = fmax(taken * ratio, nominal / 1024.0);
                redos++;
                inc--;
                inc_solved = inc_shared = 0;
                continue;
            }
            length = next_length(length, taken, ratio, U == target);
        }
        last = U == target && s == ninc + nback;
        done = U;
        if (U == target) s++;
        for (i = 0; i < count; i++) {
            uint32_t st = rve_commit(h[i]);
            if (st != RVE_STATUS_OK) die("rve_commit", st);
        }
        if (rank == 0) fprintf(csv, "%d,%.17g,%.17g,%d,%.17g\n", inc, U, reaction, it, r);
        shared += inc_shared;
        if (sharing) print_sharing(inc, r);
        if (last && rank == 0) {
            int e;
            fprintf(csv, "point,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy\n");
            for (e = 0; e < m.nelem; e++) {
                double ee[3];
                element_strain(&m, e, u, ee);
                fprintf(csv, "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", e, ee[0], ee[1], ee[2],
                        all[12 * e], all[12 * e + 1], all[12 * e + 2]);
            }
        }
        if (inc == stop_after) {
            MPI_Bcast(u, m.ndof, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            write_checkpoint(ckpt_dir, &m, inc, ninc, u, h, first, count);
            break;
        }
    }
    if (rank == 0 && fclose(csv) != 0) fail("cannot write %s", out);

    /* Per-rank figures, printed by rank 0 in rank order. */
    {
        struct rusage ru;
        double mine[8], *every = rank == 0 ? xmalloc(sizeof(double) * 8 * (size_t)nranks) : NULL;
        getrusage(RUSAGE_SELF, &ru);
        mine[0] = now() - t_start;
        mine[1] = t_init;
        mine[2] = t_rve;
        mine[3] = (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                  1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
        mine[4] = (double)ru.ru_maxrss / 1024.0; /* Linux: KiB */
        mine[5] = (double)updates;
        mine[6] = (double)fast_updates(h, count);
        mine[7] = (double)shared;
        MPI_Gather(mine, 8, MPI_DOUBLE, every, 8, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        if (rank == 0) {
            printf("ranks %d, points %d, increments %d..%d, threads per rank %zu\n", nranks,
                   m.nelem, inc0 + 1, stop_after > 0 ? stop_after : inc, nthreads);
            if (follow)
                printf("step control: %d increments kept, %d redone smaller, smallest ratio "
                       "%.4g\n", inc, redos, min_ratio);
            printf("rank  points  wall_s  init_s  rve_s   cpu_s  peak_rss_MiB  updates  fast  "
                   "shared\n");
            for (i = 0; i < nranks; i++)
                printf("%4d  %6d  %6.2f  %6.2f  %5.2f  %6.2f  %12.1f  %7.0f  %4.0f  %6.0f\n", i,
                       counts[i] / 12, every[8 * i], every[8 * i + 1], every[8 * i + 2],
                       every[8 * i + 3], every[8 * i + 4], every[8 * i + 5], every[8 * i + 6],
                       every[8 * i + 7]);
            free(every);
        }
    }
    for (i = 0; i < count; i++) rve_free(h[i]);
    free(h), free(u), free(du), free(u_save), free(eps), free(sig_tan), free(reports), free(all);
    free(band);
    free(res), free(counts), free(displs), free(m.tri), free(m.x), free(m.y), free(m.fixed);
    MPI_Finalize();
    return 0;
}
