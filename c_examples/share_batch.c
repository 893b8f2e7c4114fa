/*
 * share_batch.c -- answer sharing ([solver] share_tolerance, docs/sharing.md) through the
 * C ABI: rve_update_batch_timed with per-point reports, RvePointReport.shared_from.
 *
 * NPOINT points of two materials follow one strain path through the RVE's peak and
 * partly back (NINC increments, dtime 1), each point the path scaled by its own factor:
 * clusters of points on nearly the same path (equal factors, the twin points of a host,
 * and factors a few tenths of a percent apart), and points no other is near. Material A
 * is the scene (default scenes/paper_rve_host_implex.toml), material B the same scene
 * with sigma_c = 4.5; some B points follow A points' paths exactly. Four sets of
 * instances follow the path, each increment one call per set, then rve_commit:
 *   ref   rve_update_timed per point, scenes without the key (the exact path);
 *   off   rve_update_batch_timed on 2 threads, scenes without the key;
 *   on1   rve_update_batch_timed on the calling thread, scenes with share_tolerance TOL;
 *   on2   the same on 2 threads.
 * Checks, every increment:
 *   - off = ref bit for bit (stress, tangent, s_zz), every shared_from 0: sharing off is
 *     the exact path;
 *   - on2 = on1 bit for bit, reports too: sharing does not depend on the thread count;
 *   - every shared_from names an earlier point of the same material that solved itself;
 *   - a point on exactly its anchor's path (equal factor) has the exact stress bit for bit;
 *   - over all points and increments, the largest |stress(on) - stress(off)| is at most
 *     TOL times the largest |stress(off)| (the bound docs/sharing.md states for the
 *     default indicator), and some points were shared.
 * Prints each increment's solved and shared counts (from shared_from), the totals, the
 * largest difference, and the wall time of each set's calls.
 *
 * With OUT.csv, the sharing run's every increment and point (material, shared_from,
 * strain, stress; 17 digits) for tests/c_driver.rs, which replays it through the Rust
 * batch.
 *
 * Usage: share_batch [SCENE.toml [TOL [OUT.csv]]]   (default TOL 0.02). Exit 0 when every
 * check passed.
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rve.h"

#define NPOINT 32
#define NUP 14
#define NINC 24
#define MSG 256

enum { REF, OFF, ON1, ON2, NSET };
static const char *SET_NAME[NSET] = {"ref (rve_update_timed, no key)", "off (batch, 2 threads)",
                                     "on (batch, 1 thread)", "on (batch, 2 threads)"};

/* Each point's factor on the path and its material (0: A, 1: B). */
static const double SCALE[NPOINT] = {
    1.0,  1.0,    1.0005, 1.001,  1.002, 1.0,  0.999,  1.003, /* A, cluster at 1 */
    1.0,  1.0,    1.001,                                      /* B on A's paths */
    0.6,  0.6,    0.6003, 0.601,  0.6,   0.599,               /* A, cluster at 0.6 */
    0.6,  0.6,                                                /* B */
    0.25, 0.25,   0.2502, 0.251,  0.25,  0.2495,              /* A, cluster at 0.25 */
    0.25, 1.5,                                                /* B */
    1.5,  0.8,    0.4,    1.2,    0.05                        /* A, alone */
};
static const int MATERIAL[NPOINT] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0,
                                     0, 1, 1, 0, 0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0};

typedef struct {
    double sig[NPOINT][3], d[NPOINT][9];
    RvePointReport rep[NPOINT];
} Out;

static double seconds(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int checks = 0, failures = 0;

/* Counts a check; a failed one is said on stderr with where it failed. */
static void check(int ok, const char *what, int inc, int point) {
    checks++;
    if (ok) return;
    failures++;
    fprintf(stderr, "share_batch: FAILED: %s (increment %d, point %d)\n", what, inc, point);
}

/* Says which call failed, with the library's status and message; returns 1. */
static int fail(const char *what, uint32_t st) {
    static char msg[512];
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "share_batch: %s: %s: %s\n", what, rve_status_message(st), msg);
    return 1;
}

/* The path's position after increment i: up to past the peak, then partly back. */
static double along(int i) {
    return i < NUP ? (double)(i + 1) : (double)(2 * NUP - 1 - i) * 0.6 + 0.4 * NUP;
}

/* A uniaxial-like strain of size s times the path's step. */
static void strain(double s, double eps[3]) {
    double e = 1.6e-5 * s;
    eps[0] = e, eps[1] = -0.2 * e, eps[2] = 0.05 * e;
}

/* Reads the whole file at `path` (NUL-terminated, malloc'd), or NULL. */
static char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    char *text = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (text = malloc((size_t)n + 1)) != NULL) {
        if (fread(text, 1, (size_t)n, f) != (size_t)n) {
            free(text);
            text = NULL;
        } else {
            text[n] = '\0';
        }
    }
    fclose(f);
    return text;
}

/* `base` with `insert` put after the first occurrence of `after` and the first `from`
 * replaced by `to` (when `from` is not NULL), malloc'd; NULL when a text is missing. */
static char *variant(const char *base, const char *after, const char *insert, const char *from,
                     const char *to) {
    const char *at = strstr(base, after), *rep = from ? strstr(base, from) : NULL;
    size_t n = strlen(base) + strlen(insert) + (to ? strlen(to) : 0) + 1, k = 0;
    char *out = malloc(n);
    const char *c;
    if (!at || (from && !rep) || !out) {
        free(out);
        return NULL;
    }
    at += strlen(after);
    for (c = base; *c;) {
        if (c == at) k += (size_t)sprintf(out + k, "%s", insert);
        if (from && c == rep) {
            k += (size_t)sprintf(out + k, "%s", to);
            c += strlen(from);
        } else {
            out[k++] = *c++;
        }
    }
    out[k] = '\0';
    return out;
}

/* The instances of every set: sets ref and off from the scenes without the key, on1 and
 * on2 from those with it; material B with sigma_c = 4.5. */
static int make_instances(const char *scene, const char *base_dir, double tol,
                          RveHandle h[NSET][NPOINT]) {
    char key[64], *text = read_text(scene), *t[2][2];
    int m, k, b, p, bad = 0;
    uint32_t st = RVE_STATUS_OK;
    if (!text) return fprintf(stderr, "share_batch: cannot read %s\n", scene), 1;
    sprintf(key, "share_tolerance = %.17g\n", tol);
    for (k = 0; k < 2; k++) /* k: 0 without the key, 1 with it */
        for (m = 0; m < 2; m++) {
            t[k][m] = variant(text, "[solver]\n", k ? key : "", m ? "sigma_c = 4.0" : NULL,
                              "sigma_c = 4.5");
            bad |= t[k][m] == NULL;
        }
    for (b = 0; b < NSET && !bad && st == RVE_STATUS_OK; b++)
        for (p = 0; p < NPOINT && st == RVE_STATUS_OK; p++)
            st = rve_init_text(t[b >= ON1][MATERIAL[p]], base_dir, &h[b][p]);
    for (k = 0; k < 4; k++) free(t[k / 2][k % 2]);
    free(text);
    if (bad) return fprintf(stderr, "share_batch: %s has no [solver] or sigma_c = 4.0\n", scene), 1;
    return st == RVE_STATUS_OK ? 0 : fail("rve_init_text", st);
}

/* One increment of set b (timed into *elapsed), not yet committed. */
static int update(int b, RveHandle h[NPOINT], double eps[NPOINT][3], Out *o, double *elapsed) {
    static char msg[NPOINT][MSG];
    double t0 = seconds();
    int p;
    uint32_t st;
    if (b == REF) {
        for (p = 0; p < NPOINT; p++) {
            RveInfo info;
            st = rve_update_timed(h[p], eps[p], 1.0, o->sig[p], o->d[p],
                                  RVE_TANGENT_REQUEST_CONSISTENT, &info);
            if (st != RVE_STATUS_OK) return fail("rve_update_timed", st);
            memset(&o->rep[p], 0, sizeof o->rep[p]);
            o->rep[p].s_zz = info.s_zz;
        }
    } else {
        st = rve_update_batch_timed(h, NPOINT, &eps[0][0], 1.0, &o->sig[0][0], &o->d[0][0],
                                    RVE_TANGENT_REQUEST_CONSISTENT, o->rep, &msg[0][0], MSG,
                                    b == ON1 ? 1 : 2);
        if (st != RVE_STATUS_OK) return fail("rve_update_batch_timed", st);
    }
    *elapsed += seconds() - t0;
    return 0;
}

static int same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

/* The checks of one increment's outputs; counts this increment's shared points. */
static int check_increment(Out o[NSET], int i, double *largest, double *diff) {
    int p, shared = 0;
    for (p = 0; p < NPOINT; p++) {
        const RvePointReport *r = &o[ON1].rep[p];
        int k = (int)r->shared_from - 1, j;
        check(same_bits(o[OFF].sig[p], o[REF].sig[p], sizeof o[REF].sig[p]) &&
                  same_bits(o[OFF].d[p], o[REF].d[p], sizeof o[REF].d[p]) &&
                  same_bits(&o[OFF].rep[p].s_zz, &o[REF].rep[p].s_zz, sizeof(double)) &&
                  o[OFF].rep[p].shared_from == 0,
              "sharing off = rve_update_timed, bit for bit, nothing shared", i, p);
        check(same_bits(o[ON2].sig[p], o[ON1].sig[p], sizeof o[ON1].sig[p]) &&
                  same_bits(o[ON2].d[p], o[ON1].d[p], sizeof o[ON1].d[p]) &&
                  same_bits(&o[ON2].rep[p], r, sizeof *r),
              "sharing: 2 threads = 1 thread, bit for bit, reports too", i, p);
        if (k >= 0) {
            shared++;
            check(k < p && MATERIAL[k] == MATERIAL[p] && o[ON1].rep[k].shared_from == 0,
                  "shared_from: an earlier point of the same material that solved", i, p);
            if (k < p && SCALE[k] == SCALE[p])
                check(same_bits(o[ON1].sig[p], o[OFF].sig[p], sizeof o[OFF].sig[p]),
                      "a point on its anchor's path: the exact stress, bit for bit", i, p);
        }
        for (j = 0; j < 3; j++) {
            *largest = fmax(*largest, fabs(o[OFF].sig[p][j]));
            *diff = fmax(*diff, fabs(o[ON1].sig[p][j] - o[OFF].sig[p][j]));
        }
    }
    return shared;
}

/* The sharing run's increment i (on 1 thread) as CSV lines. */
static void write_rows(FILE *csv, int i, double eps[NPOINT][3], const Out *on) {
    int p;
    for (p = 0; p < NPOINT; p++)
        fprintf(csv, "%d,%d,%d,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", i + 1, p, MATERIAL[p],
                (unsigned)on->rep[p].shared_from, eps[p][0], eps[p][1], eps[p][2], on->sig[p][0],
                on->sig[p][1], on->sig[p][2]);
}

static int run(RveHandle h[NSET][NPOINT], double tol, FILE *csv) {
    static Out o[NSET];
    double eps[NPOINT][3], largest = 0.0, diff = 0.0, elapsed[NSET] = {0.0};
    int i, p, b, total = 0;
    uint32_t st;
    printf("increment  strain_xx(1)  solved  shared  (tol %g, %d points)\n", tol, NPOINT);
    for (i = 0; i < NINC; i++) {
        int shared;
        for (p = 0; p < NPOINT; p++) strain(along(i) * SCALE[p], eps[p]);
        memset(o, 0xA5, sizeof o);
        for (b = 0; b < NSET; b++)
            if (update(b, h[b], eps, &o[b], &elapsed[b])) return 1;
        shared = check_increment(o, i, &largest, &diff);
        total += shared;
        if (csv) write_rows(csv, i, eps, &o[ON1]);
        printf("%9d  %12.4e  %6d  %6d\n", i + 1, 1.6e-5 * along(i), NPOINT - shared, shared);
        for (b = 0; b < NSET; b++)
            for (p = 0; p < NPOINT; p++)
                if ((st = rve_commit(h[b][p])) != RVE_STATUS_OK) return fail("rve_commit", st);
    }
    check(total > 0, "some points shared", -1, -1);
    check(diff <= tol * largest, "largest stress difference <= tol x largest stress", -1, -1);
    printf("total: %d solved, %d shared of %d; largest stress difference %.3e of the largest "
           "stress (%.4g)\n", NPOINT * NINC - total, total, NPOINT * NINC, diff / largest, largest);
    for (b = 0; b < NSET; b++) printf("time %-32s %8.3f s\n", SET_NAME[b], elapsed[b]);
    return 0;
}

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : "scenes/paper_rve_host_implex.toml";
    double tol = argc > 2 ? atof(argv[2]) : 0.02;
    const char *csv_path = argc > 3 ? argv[3] : NULL;
    char dir[4096], *slash;
    FILE *csv = NULL;
    RveHandle h[NSET][NPOINT];
    int b, p, status;
    memset(h, 0, sizeof h);
    snprintf(dir, sizeof dir, "%s", scene);
    slash = strrchr(dir, '/');
    if (slash) *slash = '\0';
    else snprintf(dir, sizeof dir, ".");
    if (csv_path) {
        if (!(csv = fopen(csv_path, "w")))
            return fprintf(stderr, "share_batch: cannot write %s\n", csv_path), 1;
        fprintf(csv, "increment,point,material,shared_from,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,"
                     "sig_xy\n");
    }
    status = make_instances(scene, dir, tol, h) || run(h, tol, csv);
    if (csv && fclose(csv) != 0) {
        fprintf(stderr, "share_batch: cannot write %s\n", csv_path);
        status = 1;
    }
    for (b = 0; b < NSET; b++)
        for (p = 0; p < NPOINT; p++) rve_free(h[b][p]);
    printf("share_batch: %d increments of %d points, %d checks, %d failed\n", NINC, NPOINT, checks,
           failures);
    return status || failures != 0;
}
