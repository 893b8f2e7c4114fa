/*
 * statev_umat.c -- the UMAT in STATEV mode through rve_umat, as a host that keeps the RVE
 * state in its own state variables: NSTATV = `rve info SCENE --json`'s umat_nstatv + 3,
 * so STATEV(1:umat_nstatv) holds the RVE's committed state and the three entries after
 * it the inspection mirrors (point id, RVE Newton iterations, sub-steps). It keeps the
 * first three of the five mirrors (docs/guide.md's *DEPVAR rule, umat_nstatv + 5, gives
 * all five; the library fills those NSTATV leaves room for).
 *
 * The host protocol (Abaqus/Standard, CalculiX): every call of an increment receives the
 * STATEV of the start of the increment; when the increment converges the host keeps the
 * values the last call wrote. Here every increment of the scene's strain path has two
 * calls (a first iteration at 99 % of the strain step, then the step's end), plane
 * stress (NTENS 3), KSTEP 1, KINC = increment + 1, TIME(1) = TIME(2) = increment * DTIME,
 * DTIME = 1 / increments; the host does not cut back (PNEWDT < 1 from the RVE's step
 * check on a successful call is recorded, not acted on).
 *
 * With ANALYSES 2 the program runs the analysis twice in one process (same NOEL and NPT,
 * STATEV reset to zeros, KSTEP/KINC/TIME starting again) and writes the second one;
 * with 1 it runs it once. A test compares the second analysis of one process with the
 * only analysis of another, bit for bit (the output prints every double with %a). The
 * two analyses of one process are also compared in memory.
 *
 * After the analyses (ANALYSES 2 only) the STATEV handed to increment CHECK (default:
 * the increment after the peak stress) is corrupted in several ways; each call must fail:
 * PNEWDT < 1, a message in rve_last_error, STRESS and STATEV untouched. The intact values
 * must then give the analysis' answer again, bit for bit. A last analysis whose STATEV
 * is not reset (the second one's final values) must give other answers.
 *
 * Usage: statev_umat CMNAME NSTATV PATH_SCENE OUT ANALYSES [INCREMENTS]
 *   CMNAME      the material: a scene name searched in MESORVE_SCENE_PATH (PAPER_RVE)
 *   NSTATV      umat_nstatv of that scene (rve info SCENE --json)
 *   PATH_SCENE  the scene whose [[path]] gives the strains (scenes/paper_rve_cycle.toml)
 *   OUT         output file (one line per increment, then the final STATEV)
 *   ANALYSES    1 or 2
 *   INCREMENTS  only the first INCREMENTS of the path (default: all)
 * Exit status 0 when every check passed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define MIRRORS 3
#define UNTOUCHED 7.0
/* STATEV(1) of a state written by this library's format 2: "MESV" * 2^16 + 2. */
#define STATEV_TAG_V2 (1296388950.0 * 65536.0 + 2.0)

static int checks, failures;

static void expect(int ok, const char *what) {
    checks++;
    if (!ok) {
        failures++;
        fprintf(stderr, "FAILED: %s\n", what);
    }
}

/* What one converged increment gave the host. */
typedef struct {
    double stress[3], ddsdde[9], pnewdt;
    double iterations, substeps;
    size_t used; /* STATEV entries in use (up to the last non-zero one) */
} Answer;

typedef struct {
    const char *cmname;
    int nstatv; /* the model's umat_nstatv; the arrays hold MIRRORS more */
    size_t increments;
    double (*strain)[3]; /* the path's strains, [increments] */
} Host;

/* One call of increment k at the total strain `target` from the start-of-increment
 * `stran`: STATEV in/out (NSTATV + MIRRORS entries). Returns 0 on success, else 1 and
 * the message in `msg`. */
static int call(const Host *h, size_t k, const double stran[3], const double target[3],
                double *statev, double stress[3], double ddsdde[9], double *pnewdt, char *msg,
                size_t msg_len) {
    double dstran[3], time[2], dtime = 1.0 / (double)h->increments, zero = 0, temp = 20;
    double sse = 0, spd = 0, scd = 0, rpl = 0, ddsddt[3] = {0}, drplde[3] = {0}, drpldt = 0;
    double predef[1] = {0}, dpred[1] = {0}, coords[3] = {1, 2, 0}, celent = 1, props[1] = {0};
    double drot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    char name[80];
    int ndi = 2, nshr = 1, ntens = 3, nstatv = h->nstatv + MIRRORS, nprops = 0, noel = 1,
        npt = 1, layer = 0, kspt = 0, kstep = 1, kinc = (int)k + 1, i, j;
    /* DSTRAN with STRAN + DSTRAN == target bit for bit (target - stran may round). */
    for (i = 0; i < 3; i++) {
        dstran[i] = target[i] - stran[i];
        for (j = 0; j < 8 && stran[i] + dstran[i] != target[i]; j++)
            dstran[i] = nextafter(dstran[i], stran[i] + dstran[i] < target[i] ? 1.0 : -1.0);
    }
    time[0] = time[1] = (double)k * dtime;
    memset(name, ' ', sizeof name);
    memcpy(name, h->cmname, strlen(h->cmname));
    *pnewdt = 1e36;
    rve_umat(stress, statev, ddsdde, &sse, &spd, &scd, &rpl, ddsddt, drplde, &drpldt, stran,
             dstran, time, &dtime, &temp, &zero, predef, dpred, name, &ndi, &nshr, &ntens,
             &nstatv, props, &nprops, coords, drot, pnewdt, &celent, drot, drot, &noel, &npt,
             &layer, &kspt, &kstep, &kinc, sizeof name);
    if (rve_last_error(msg, msg_len) == 0) return 0;
    return 1;
}

/* Increment k as the host runs it: two calls, each from the start-of-increment values in
 * `statev` (which receives the last call's values). Returns 0 on success. */
static int increment(const Host *h, size_t k, double *statev, Answer *a) {
    size_t n = (size_t)h->nstatv + MIRRORS, i;
    double *work = malloc(n * sizeof *work), near[3], stran[3] = {0, 0, 0};
    char msg[1024];
    int c, st = 0;
    if (k > 0) memcpy(stran, h->strain[k - 1], sizeof stran);
    for (i = 0; i < 3; i++) near[i] = stran[i] + 0.99 * (h->strain[k][i] - stran[i]);
    for (c = 0; c < 2 && st == 0; c++) {
        memcpy(work, statev, n * sizeof *work);
        st = call(h, k, stran, c == 0 ? near : h->strain[k], work, a->stress, a->ddsdde,
                  &a->pnewdt, msg, sizeof msg);
        if (st) fprintf(stderr, "increment %zu, call %d failed: %s\n", k + 1, c + 1, msg);
    }
    if (st == 0) {
        memcpy(statev, work, n * sizeof *work); /* converged: keep the last call's values */
        a->iterations = statev[h->nstatv + 1];
        a->substeps = statev[h->nstatv + 2];
        for (a->used = (size_t)h->nstatv; a->used > 0 && statev[a->used - 1] == 0; a->used--) {
        }
    }
    free(work);
    return st;
}

/* One analysis from a virgin point (STATEV all zeros; with `keep`, from the values
 * `statev` holds); `start_of` receives the STATEV handed to increment `check`. Returns 0
 * on success. */
static int analysis(const Host *h, Answer *answers, double *statev, int keep, size_t check,
                    double *start_of) {
    size_t n = (size_t)h->nstatv + MIRRORS, k;
    if (!keep) memset(statev, 0, n * sizeof *statev);
    for (k = 0; k < h->increments; k++) {
        if (k == check && start_of) memcpy(start_of, statev, n * sizeof *statev);
        if (increment(h, k, statev, &answers[k])) return 1;
    }
    return 0;
}

static void write_output(FILE *f, const Host *h, const Answer *answers, const double *statev) {
    size_t k, i;
    fprintf(f, "# %s NSTATV %d: kinc eps_xx eps_yy gamma_xy s_xx s_yy s_xy "
               "DDSDDE(1:9) pnewdt iterations substeps used_entries\n",
            h->cmname, h->nstatv);
    for (k = 0; k < h->increments; k++) {
        const Answer *a = &answers[k];
        fprintf(f, "%zu", k + 1);
        for (i = 0; i < 3; i++) fprintf(f, " %a", h->strain[k][i]);
        for (i = 0; i < 3; i++) fprintf(f, " %a", a->stress[i]);
        for (i = 0; i < 9; i++) fprintf(f, " %a", a->ddsdde[i]);
        fprintf(f, " %a %.0f %.0f %zu\n", a->pnewdt, a->iterations, a->substeps, a->used);
    }
    fprintf(f, "# final STATEV(1:%d) (and the mirrors after it)\n", h->nstatv + MIRRORS);
    for (i = 0; i < (size_t)h->nstatv + MIRRORS; i++) fprintf(f, "%.17g\n", statev[i]);
}

static int same_answers(const Answer *a, const Answer *b, size_t n) {
    size_t k;
    for (k = 0; k < n; k++) {
        if (memcmp(a[k].stress, b[k].stress, sizeof a[k].stress) ||
            memcmp(a[k].ddsdde, b[k].ddsdde, sizeof a[k].ddsdde) ||
            memcmp(&a[k].pnewdt, &b[k].pnewdt, sizeof a[k].pnewdt) ||
            a[k].iterations != b[k].iterations || a[k].substeps != b[k].substeps ||
            a[k].used != b[k].used)
            return 0;
    }
    return 1;
}

/* Corruptions of the start-of-increment STATEV of increment `k`: each call fails with
 * PNEWDT < 1, a message, STRESS and STATEV untouched; then the intact values answer as
 * in the analysis. */
static void corruptions(const Host *h, size_t k, const double *intact, const Answer *want) {
    size_t n = (size_t)h->nstatv + MIRRORS, used, mid, i, c;
    double *s = malloc(n * sizeof *s), *given = malloc(n * sizeof *given);
    double stress[3], ddsdde[9], pnewdt, stran[3] = {0, 0, 0};
    const char *what[] = {"one bit flipped (bit 20 of a payload entry)",
                          "an entry in the middle set to 0",
                          "shortened: the last used entry set to 0",
                          "0.5 added to a payload entry",
                          "the CRC-32C entry (STATEV(4)) + 1",
                          "NaN in a payload entry"};
    char msg[1024], line[1400];
    uint64_t bits;
    for (used = (size_t)h->nstatv; used > 0 && intact[used - 1] == 0; used--) {
    }
    /* A non-zero payload entry near the middle of the used ones. */
    for (mid = used / 2; mid < used && intact[mid] == 0; mid++) {
    }
    if (k > 0) memcpy(stran, h->strain[k - 1], sizeof stran);
    printf("corruptions of the STATEV handed to increment %zu (%zu entries in use, entry "
           "changed: STATEV(%zu)):\n",
           k + 1, used, mid + 1);
    for (c = 0; c < sizeof what / sizeof *what; c++) {
        memcpy(s, intact, n * sizeof *s);
        switch (c) {
        case 0:
            memcpy(&bits, &s[mid], sizeof bits);
            bits ^= (uint64_t)1 << 20;
            memcpy(&s[mid], &bits, sizeof bits);
            break;
        case 1: s[mid] = 0; break;
        case 2: s[used - 1] = 0; break;
        case 3: s[mid] += 0.5; break;
        case 4: s[3] += 1; break;
        default: s[mid] = nan(""); break;
        }
        memcpy(given, s, n * sizeof *s);
        for (i = 0; i < 3; i++) stress[i] = UNTOUCHED;
        msg[0] = 0;
        if (call(h, k, stran, h->strain[k], s, stress, ddsdde, &pnewdt, msg, sizeof msg) == 0) {
            snprintf(line, sizeof line, "%s: the call succeeded", what[c]);
            expect(0, line);
            continue;
        }
        printf("  %s: PNEWDT %g, \"%s\"\n", what[c], pnewdt, msg);
        snprintf(line, sizeof line, "%s: PNEWDT < 1", what[c]);
        expect(pnewdt < 1, line);
        snprintf(line, sizeof line, "%s: the message names STATEV", what[c]);
        expect(strstr(msg, "STATEV") != NULL, line);
        snprintf(line, sizeof line, "%s: STRESS untouched", what[c]);
        expect(stress[0] == UNTOUCHED && stress[1] == UNTOUCHED && stress[2] == UNTOUCHED,
               line);
        snprintf(line, sizeof line, "%s: STATEV untouched", what[c]);
        expect(memcmp(s, given, n * sizeof *s) == 0, line);
    }
    /* The intact values: the analysis' answer, bit for bit. */
    memcpy(s, intact, n * sizeof *s);
    {
        Answer again;
        expect(increment(h, k, s, &again) == 0, "intact STATEV after the corruptions: success");
        expect(same_answers(&again, want, 1),
               "intact STATEV after the corruptions: the analysis' answer bit for bit");
    }
    free(s);
    free(given);
}

int main(int argc, char **argv) {
    Host h;
    RveHandle path = 0;
    size_t len = 0, k, n, peak = 0, check;
    Answer *first = NULL, *second;
    double *statev, *start_of;
    int analyses;
    FILE *out;
    if (argc < 6) {
        fprintf(stderr, "usage: statev_umat CMNAME NSTATV PATH_SCENE OUT ANALYSES [INCREMENTS]\n");
        return 2;
    }
    h.cmname = argv[1];
    h.nstatv = atoi(argv[2]);
    analyses = atoi(argv[5]);
    if (h.nstatv < 4 || (analyses != 1 && analyses != 2) || strlen(h.cmname) > 80) {
        fprintf(stderr, "statev_umat: bad NSTATV or ANALYSES\n");
        return 2;
    }
    if (rve_init(argv[3], &path) != RVE_STATUS_OK || rve_path_len(path, &len) != RVE_STATUS_OK) {
        char m[512];
        rve_last_error(m, sizeof m);
        fprintf(stderr, "statev_umat: %s: %s\n", argv[3], m);
        return 1;
    }
    h.increments = len;
    if (argc > 6 && (size_t)atoi(argv[6]) < len) h.increments = (size_t)atoi(argv[6]);
    h.strain = malloc(h.increments * sizeof *h.strain);
    for (k = 0; k < h.increments; k++) rve_path_point(path, k, h.strain[k]);
    rve_free(path);
    n = (size_t)h.nstatv + MIRRORS;
    statev = malloc(n * sizeof *statev);
    start_of = malloc(n * sizeof *start_of);
    second = malloc(h.increments * sizeof *second);
    if (analyses == 2) first = malloc(h.increments * sizeof *first);

    if (analyses == 2 && analysis(&h, first, statev, 0, (size_t)-1, NULL)) return 1;
    for (k = 1; analyses == 2 && k < h.increments; k++)
        if (first[k].stress[0] > first[peak].stress[0]) peak = k;
    check = peak + 1 < h.increments ? peak + 1 : h.increments - 1;
    if (analysis(&h, second, statev, 0, check, start_of)) return 1;
    expect(statev[0] == STATEV_TAG_V2, "STATEV(1) = 'MESV' * 2^16 + 2 (the format tag)");
    expect(statev[h.nstatv] >= 1, "STATEV(NSTATV+1) holds the point id");
    for (k = 0; k < h.increments; k++) {
        char what[128];
        snprintf(what, sizeof what, "increment %zu: STATEV used within the model's %d", k + 1,
                 h.nstatv);
        expect(second[k].used > 4 && second[k].used <= (size_t)h.nstatv, what);
    }
    out = fopen(argv[4], "w");
    if (!out) {
        perror(argv[4]);
        return 1;
    }
    write_output(out, &h, second, statev);
    fclose(out);
    {
        size_t most = 0, asked = 0;
        double peak_stress = 0, last = second[h.increments - 1].stress[0];
        for (k = 0; k < h.increments; k++) {
            if (second[k].used > most) most = second[k].used;
            if (second[k].pnewdt < 1) asked++;
            if (second[k].stress[0] > peak_stress) peak_stress = second[k].stress[0];
        }
        printf("%s, NSTATV %d + %d: %zu increments x 2 calls; peak s_xx %.6g MPa, last %.6g "
               "MPa; at most %zu STATEV entries in use; PNEWDT < 1 (step check) on %zu\n",
               h.cmname, h.nstatv, MIRRORS, h.increments, peak_stress, last, most, asked);
    }
    if (analyses == 2) {
        expect(same_answers(first, second, h.increments),
               "second analysis in the process: the first one's answers bit for bit");
        printf("two analyses in one process: %s\n",
               same_answers(first, second, h.increments) ? "bit-identical" : "DIFFERENT");
        expect(first[peak].stress[0] > first[h.increments - 1].stress[0] || h.increments < 3,
               "the path passes the peak");
        corruptions(&h, check, start_of, &second[check]);
        /* The control: a third analysis whose host forgets to reset STATEV (the second
         * one's final values handed to increment 1, STRAN = 0) is refused: the state is
         * what STATEV holds, and that state was committed at another strain. */
        {
            size_t n = (size_t)h.nstatv + MIRRORS;
            double *kept = malloc(n * sizeof *kept), zero3[3] = {0, 0, 0}, stress[3] = {7, 7, 7};
            double ddsdde[9], pnewdt;
            char msg[2048];
            int failed;
            memcpy(kept, statev, n * sizeof *kept);
            failed = call(&h, 0, zero3, h.strain[0], kept, stress, ddsdde, &pnewdt, msg,
                          sizeof msg);
            expect(failed && strstr(msg, "not the state of this point") != NULL && pnewdt < 1 &&
                       stress[0] == 7 && memcmp(kept, statev, n * sizeof *kept) == 0,
                   "an analysis from the last STATEV instead of zeros is refused");
            printf("control: an analysis from the previous one's final STATEV instead of zeros: "
                   "%s\n", failed ? "refused" : "ANSWERED (wrong)");
            free(kept);
        }
    }
    printf("statev_umat: %d checks, %d failed\n", checks, failures);
    free(h.strain);
    free(statev);
    free(start_of);
    free(second);
    free(first);
    return failures ? 1 : 0;
}
