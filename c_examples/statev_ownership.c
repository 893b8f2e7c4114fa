/* The state a host hands over must be this point's: through `rve_umat`, in STATEV mode,
 * a valid STATEV that belongs to another point, an older increment, another scene, other
 * PROPS, another integration or an edited scene is refused with a message, PNEWDT < 1,
 * STRESS and STATEV untouched; the same state at its own strain answers at a new point;
 * a comment-only edit of the scene between two parts of a run is no change.
 *
 * Usage: MESORVE_SCENE_PATH=DIR statev_ownership NSTATV NSTATV_IMPLEX
 *   DIR            a scene directory holding PAPER.toml (the paper's
 *                  cycle), SHEAR.toml (the same with contact_shear = "cohesive"),
 *                  IMPLEX.toml (the same with IMPL-EX), EDIT_SIGMA.toml (sigma_c 3.8) and
 *                  EDIT_COMMENT.toml (PAPER.toml with comments added); scripts/test-c
 *                  writes them
 *   NSTATV         `rve info`'s umat_nstatv of PAPER.toml (SHEAR.toml's is the same)
 *   NSTATV_IMPLEX  that of IMPLEX.toml
 * Exit status 0 when every check passed. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define MIRRORS 3
#define UNTOUCHED 7.0
#define INCREMENT 1.15e-5 /* the paper cycle's tension step in eps_xx */

static int checks = 0, failures = 0;

static void expect(int ok, const char *what) {
    checks++;
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s\n", what);
    }
}

typedef struct {
    const char *cmname;
    double props[1];
    int nprops;
    int nstatv; /* umat_nstatv; arrays hold MIRRORS more */
} Material;

typedef struct {
    double stress[3], pnewdt;
    char msg[2048];
    int failed;
} Called;

/* Increment k (1-based KINC k) of point `noel`: STRAN = (k-1) steps, to k steps in
 * eps_xx, from `statev` (written on success). */
static Called call(const Material *m, int noel, int k, double *statev) {
    Called r;
    double stran[3] = {(k - 1) * INCREMENT, 0, 0}, dstran[3] = {INCREMENT, 0, 0};
    double time[2] = {0.1 * (k - 1), 0.1 * (k - 1)}, dtime = 0.1, temp = 20, zero = 0;
    double sse = 0, spd = 0, scd = 0, rpl = 0, ddsddt[3] = {0}, drplde[3] = {0}, drpldt = 0;
    double predef[1] = {0}, dpred[1] = {0}, coords[3] = {0}, celent = 1, ddsdde[9];
    double drot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, props[1];
    char name[80];
    int ndi = 2, nshr = 1, ntens = 3, nstatv = m->nstatv + MIRRORS, nprops = m->nprops,
        npt = 1, layer = 0, kspt = 0, kstep = 1, i;
    memcpy(props, m->props, sizeof props);
    for (i = 0; i < 3; i++) r.stress[i] = UNTOUCHED;
    memset(name, ' ', sizeof name);
    memcpy(name, m->cmname, strlen(m->cmname));
    r.pnewdt = 1e36;
    rve_umat(r.stress, statev, ddsdde, &sse, &spd, &scd, &rpl, ddsddt, drplde, &drpldt, stran,
             dstran, time, &dtime, &temp, &zero, predef, dpred, name, &ndi, &nshr, &ntens,
             &nstatv, props, &nprops, coords, drot, &r.pnewdt, &celent, drot, drot, &noel,
             &npt, &layer, &kspt, &kstep, &k, sizeof name);
    r.failed = rve_last_error(r.msg, sizeof r.msg) != 0;
    return r;
}

/* Point `noel` through increments 1..k from zeros; `statev` holds the state at the end. */
static int run(const Material *m, int noel, int k, double *statev) {
    int i;
    memset(statev, 0, (size_t)(m->nstatv + MIRRORS) * sizeof *statev);
    for (i = 1; i <= k; i++) {
        Called r = call(m, noel, i, statev);
        if (r.failed) {
            fprintf(stderr, "%s, point %d, increment %d: %s\n", m->cmname, noel, i, r.msg);
            return 1;
        }
    }
    return 0;
}

/* Hands `statev` (n entries) to `m`'s point `noel` at increment k: refused with `needle`
 * in the message, PNEWDT < 1, STRESS and STATEV untouched. */
static void refused(const char *what, const Material *m, int noel, int k, const double *statev,
                    const char *needle) {
    size_t n = (size_t)(m->nstatv + MIRRORS);
    double *copy = malloc(n * sizeof *copy);
    char line[256];
    Called r;
    memcpy(copy, statev, n * sizeof *copy);
    r = call(m, noel, k, copy);
    snprintf(line, sizeof line, "%s: refused, the message names it", what);
    expect(r.failed && strstr(r.msg, needle) != NULL, line);
    snprintf(line, sizeof line, "%s: PNEWDT < 1, STRESS and STATEV untouched", what);
    expect(r.pnewdt < 1 && r.stress[0] == UNTOUCHED && r.stress[1] == UNTOUCHED &&
               r.stress[2] == UNTOUCHED && memcmp(copy, statev, n * sizeof *copy) == 0,
           line);
    printf("%-58s %.150s\n", what, r.msg);
    free(copy);
}

/* A scene edited between the two parts of a restart: the second part is a new process,
 * which resolves the material's name to the edited file. Here the second part's material
 * names a copy of the file with the edit (the name is not part of the fingerprint, the
 * file's content is): a comment-only edit goes on as if nothing happened, a changed
 * sigma_c is refused. */
static void edited_scene(const Material *paper, double *statev, double *whole) {
    Material comment = {"EDIT_COMMENT", {0}, 0, paper->nstatv},
             sigma = {"EDIT_SIGMA", {0}, 0, paper->nstatv};
    size_t n = (size_t)(paper->nstatv + MIRRORS);
    double *half = malloc(n * sizeof *half);
    int k, ok = 1;
    if (run(paper, 30, 12, whole) || run(paper, 31, 8, half)) {
        expect(0, "the edited scene's runs");
        free(half);
        return;
    }
    memcpy(statev, half, n * sizeof *half);
    for (k = 9; k <= 12; k++) ok &= !call(&comment, 31, k, statev).failed;
    expect(ok, "a comment-only edit between the parts: accepted");
    expect(memcmp(statev, whole, (size_t)paper->nstatv * sizeof *statev) == 0,
           "a comment-only edit between the parts: the whole run's state bit for bit");
    printf("%-58s accepted, the whole run's STATEV bit for bit\n",
           "a comment-only edit of the scene between the parts");
    refused("the scene edited between the parts (sigma_c 3.8)", &sigma, 32, 9, half,
            "fingerprint");
    free(half);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: MESORVE_SCENE_PATH=DIR statev_ownership NSTATV NSTATV_IMPLEX\n");
        return 2;
    }
    int n = atoi(argv[1]), n_implex = atoi(argv[2]);
    size_t room = (size_t)(n_implex > n ? n_implex : n) + MIRRORS;
    Material paper = {"PAPER", {0}, 0, n}, shear = {"SHEAR", {0}, 0, n},
             implex = {"IMPLEX", {0}, 0, n_implex}, weak = {"PAPER", {3.6}, 1, n},
             four = {"PAPER", {4.0}, 1, n};
    double *damaged = calloc(room, sizeof(double)), *elastic = calloc(room, sizeof(double)),
           *at_10 = calloc(room, sizeof(double)), *other = calloc(room, sizeof(double)),
           *work = calloc(room, sizeof(double)), *whole = calloc(room, sizeof(double));
    Called own, moved;
    if (n < 5 || n_implex < n) return 2;
    if (run(&paper, 1, 20, damaged) || run(&paper, 2, 5, elastic) || run(&paper, 3, 10, at_10))
        return 1;
    refused("another point's, damaged, to a point at a smaller strain", &paper, 4, 6, damaged,
            "not the state of this point");
    refused("another point's, elastic, to a damaged point", &paper, 5, 21, elastic,
            "not the state of this point");
    refused("a stale one (written two increments earlier)", &paper, 6, 13, at_10,
            "not the state of this point");
    /* The same state at its own strain, at a new point: the answer of its own point. */
    memcpy(work, at_10, room * sizeof *work);
    memcpy(other, at_10, room * sizeof *other);
    own = call(&paper, 3, 11, work);
    moved = call(&paper, 7, 11, other);
    expect(!own.failed && !moved.failed && memcmp(own.stress, moved.stress, sizeof own.stress) == 0,
           "the same state at its own strain answers at a new point");
    if (run(&shear, 8, 10, other)) return 1;
    refused("another scene's of the same size (cohesive shear)", &paper, 9, 11, other,
            "fingerprint");
    if (run(&weak, 10, 10, other)) return 1;
    refused("written under PROPS(1) 3.6, handed with 4", &four, 11, 11, other, "fingerprint");
    refused("written under PROPS(1) 4 (the scene's), handed with 3.6", &weak, 12, 11, at_10,
            "fingerprint");
    memset(other, 0, room * sizeof *other);
    memcpy(other, at_10, (size_t)n * sizeof *other);
    refused("an implicit scene's, handed to IMPL-EX", &implex, 13, 11, other, "fingerprint");
    if (run(&paper, 14, 8, other)) return 1;
    refused("PROPS changed in the middle of an analysis", &weak, 14, 9, other, "fingerprint");
    memset(other, 0, room * sizeof *other);
    refused("all zeros at a strained point (a lost state)", &paper, 15, 11, other,
            "contact pair");
    edited_scene(&paper, work, whole);
    printf("statev_ownership: %d checks, %d failed\n", checks, failures);
    free(damaged), free(elastic), free(at_10), free(other), free(work), free(whole);
    return failures ? 1 : 0;
}
