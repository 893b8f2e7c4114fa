/*
 * error_paths.c -- provokes every status code of the C interface and checks that
 * outputs are left untouched on failure and that a readable message is available
 * (WRITE_FAILED: rve_write_vtk to an unwritable path).
 * RVE_STATUS_INTERNAL and RVE_STATUS_PANIC mark bugs and cannot be provoked from C; the
 * panic boundary is exercised by the Rust tests.
 *
 * Usage: error_paths [SCENE_DIR]     (default scenes)
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rve.h"

static int failures = 0, checks = 0;

#define EXPECT(call, code)                                                                  \
    do {                                                                                    \
        uint32_t st_ = (call);                                                              \
        checks++;                                                                           \
        if (st_ != (uint32_t)(code)) {                                                      \
            char m_[512];                                                                   \
            rve_last_error(m_, sizeof m_);                                                  \
            fprintf(stderr, "line %d: %s gave %u (%s), expected %s: %s\n", __LINE__, #call, \
                    (unsigned)st_, rve_status_message(st_), #code, m_);                     \
            failures++;                                                                     \
        } else if (st_ != RVE_STATUS_OK && rve_last_error(NULL, 0) == 0) {                  \
            fprintf(stderr, "line %d: no message for %s\n", __LINE__, #code);               \
            failures++;                                                                     \
        }                                                                                   \
    } while (0)

static char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    long n;
    char *s;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    s = malloc((size_t)n + 1);
    if (fread(s, 1, (size_t)n, f) != (size_t)n) n = 0;
    s[n] = 0;
    fclose(f);
    return s;
}

/* Returns a new string: `text` with the first `from` replaced by `to`. */
static char *replace(const char *text, const char *from, const char *to) {
    const char *at = strstr(text, from);
    size_t a, n;
    char *out;
    if (!at) {
        fprintf(stderr, "scene has no `%s`\n", from);
        exit(1);
    }
    a = (size_t)(at - text);
    n = strlen(text) - strlen(from) + strlen(to);
    out = malloc(n + 1);
    memcpy(out, text, a);
    strcpy(out + a, to);
    strcat(out, at + strlen(from));
    return out;
}

struct hammer {
    RveHandle h;
    int busy, ok, bad;
};

static void *hammer_run(void *arg) {
    struct hammer *hm = arg;
    double eps[3] = {3e-5, 0.0, 0.0}, sig[3];
    int i;
    for (i = 0; i < 200 && !hm->busy; i++) {
        /* A new strain at every call: a trial repeated at the same strain is returned
         * without a solve, too short for the two threads to meet. */
        eps[0] = 3e-5 * (1.0 + 1e-3 * i);
        uint32_t st = rve_update(hm->h, eps, sig, NULL, RVE_TANGENT_REQUEST_NONE);
        if (st == RVE_STATUS_OK)
            hm->ok++;
        else if (st == RVE_STATUS_INSTANCE_BUSY)
            hm->busy++;
        else
            hm->bad++;
    }
    return NULL;
}

int main(int argc, char **argv) {
    const char *dir = argc > 1 ? argv[1] : "scenes";
    char path[1024], other_path[1024];
    char *paper, *text;
    RveHandle h = 0, h2 = 0, freed = 0, other = 0, untouched = 777;
    double eps[3] = {5e-5, 0.0, 0.0}, sig[3] = {7, 7, 7}, d[9], bad[3];
    uint8_t *bytes;
    size_t size = 0, written = 0, n = 0;
    RveInfo info;
    RveHandle handles[2];
    double strains[6] = {1e-5, 0, 0, 2e-5, 0, 0}, stresses[6], tangents[18];
    uint32_t statuses[2];
    int i;

    snprintf(path, sizeof path, "%s/paper_rve.toml", dir);
    snprintf(other_path, sizeof other_path, "%s/gmsh_two_circles.toml", dir);
    paper = read_file(path);
    if (!paper) {
        perror(path);
        return 1;
    }

    /* OK and NULL_ARGUMENT */
    EXPECT(rve_init_file(path, &h), RVE_STATUS_OK);
    EXPECT(rve_init_file(NULL, &untouched), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_init_file(path, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_init_text(NULL, NULL, &untouched), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_init(NULL, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_init(path, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_update(h, NULL, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_update(h, eps, NULL, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_update(h, eps, sig, NULL, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_state_size(h, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_fast_updates(h, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_state_load(h, NULL, 10), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_path_len(h, NULL), RVE_STATUS_NULL_ARGUMENT);
    EXPECT(rve_update_batch(NULL, 2, strains, stresses, tangents, statuses,
                            RVE_TANGENT_REQUEST_CONSISTENT, 1),
           RVE_STATUS_NULL_ARGUMENT);
    if (untouched != 777 || sig[0] != 7) {
        fprintf(stderr, "an output was written on failure\n");
        failures++;
    }

    /* BAD_SCENE: missing file, malformed text, invalid value, non-UTF-8 */
    EXPECT(rve_init_file("/nonexistent/scene.toml", &untouched), RVE_STATUS_BAD_SCENE);
    EXPECT(rve_init("/nonexistent/scene.toml", &untouched), RVE_STATUS_BAD_SCENE);
    EXPECT(rve_init(dir, &untouched), RVE_STATUS_BAD_SCENE); /* a directory */
    EXPECT(rve_init_text("[cell\nsize = ", NULL, &untouched), RVE_STATUS_BAD_SCENE);
    text = replace(paper, "delta_c = 0.0002", "delta_c = -1.0");
    EXPECT(rve_init_text(text, NULL, &untouched), RVE_STATUS_BAD_SCENE);
    free(text);
    EXPECT(rve_init_text("\xff\xfe", NULL, &untouched), RVE_STATUS_BAD_SCENE);

    /* MESH_FAILED: a placement that cannot succeed */
    text = replace(paper, "area_fraction = 0.45", "area_fraction = 0.7\nmax_rounds = 1\nmax_attempts = 10");
    EXPECT(rve_init_text(text, NULL, &untouched), RVE_STATUS_MESH_FAILED);
    free(text);

    /* BAD_HANDLE: zero, foreign, freed (and never valid again) */
    EXPECT(rve_update(0, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_BAD_HANDLE);
    EXPECT(rve_update(12345, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_BAD_HANDLE);
    EXPECT(rve_commit(-1), RVE_STATUS_BAD_HANDLE);
    {
        uint64_t count = 77;
        EXPECT(rve_fast_updates(0, &count), RVE_STATUS_BAD_HANDLE);
        if (count != 77) {
            fprintf(stderr, "rve_fast_updates wrote its output on failure\n");
            return 1;
        }
    }
    EXPECT(rve_init_file(path, &freed), RVE_STATUS_OK);
    EXPECT(rve_free(freed), RVE_STATUS_OK);
    EXPECT(rve_free(freed), RVE_STATUS_BAD_HANDLE);
    EXPECT(rve_init_file(path, &h2), RVE_STATUS_OK); /* may reuse the slot, not the id */
    EXPECT(rve_update(freed, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_BAD_HANDLE);
    EXPECT(rve_free(0), RVE_STATUS_OK);

    /* NON_FINITE_STRAIN and ABSURD_STRAIN */
    bad[0] = NAN; bad[1] = 0; bad[2] = 0;
    EXPECT(rve_update(h, bad, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_NON_FINITE_STRAIN);
    bad[0] = 0; bad[1] = -INFINITY;
    EXPECT(rve_update(h, bad, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_NON_FINITE_STRAIN);
    bad[1] = 0; bad[2] = 1e3;
    EXPECT(rve_update(h, bad, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_ABSURD_STRAIN);
    if (sig[0] != 7) {
        fprintf(stderr, "stress written on failure\n");
        failures++;
    }

    /* NO_TRIAL: after a failed update, after commit, after revert */
    EXPECT(rve_commit(h), RVE_STATUS_NO_TRIAL);
    EXPECT(rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_OK);
    EXPECT(rve_revert(h), RVE_STATUS_OK);
    EXPECT(rve_commit(h), RVE_STATUS_NO_TRIAL);
    EXPECT(rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_OK);
    EXPECT(rve_commit(h), RVE_STATUS_OK);
    EXPECT(rve_commit(h), RVE_STATUS_NO_TRIAL);

    /* INVALID_ARGUMENT */
    EXPECT(rve_update(h, eps, sig, d, 3), RVE_STATUS_INVALID_ARGUMENT);
    EXPECT(rve_update(h, eps, sig, d, -1), RVE_STATUS_INVALID_ARGUMENT);
    EXPECT(rve_path_len(h, &n), RVE_STATUS_OK);
    EXPECT(rve_path_point(h, n, bad), RVE_STATUS_INVALID_ARGUMENT);

    /* BUFFER_TOO_SMALL, BAD_STATE, STATE_VERSION, STATE_MISMATCH */
    EXPECT(rve_state_size(h, &size), RVE_STATUS_OK);
    bytes = malloc(size);
    EXPECT(rve_state_save(h, bytes, size - 1, &written), RVE_STATUS_BUFFER_TOO_SMALL);
    if (written != size) {
        fprintf(stderr, "required size not reported\n");
        failures++;
    }
    EXPECT(rve_state_save(h, bytes, size, &written), RVE_STATUS_OK);
    EXPECT(rve_state_load(h2, bytes, size), RVE_STATUS_OK);
    EXPECT(rve_state_load(h2, (const uint8_t *)"garbage", 7), RVE_STATUS_BAD_STATE);
    EXPECT(rve_state_load(h2, bytes, size / 2), RVE_STATUS_BAD_STATE);
    bytes[8] ^= 0x7f; /* format version: the checksum covers it */
    EXPECT(rve_state_load(h2, bytes, size), RVE_STATUS_BAD_STATE);
    bytes[8] ^= 0x7f;
    bytes[size / 2] ^= 0x10; /* one flipped bit anywhere */
    EXPECT(rve_state_load(h2, bytes, size), RVE_STATUS_BAD_STATE);
    bytes[size / 2] ^= 0x10;
    EXPECT(rve_state_load(h2, bytes, size), RVE_STATUS_OK);
    EXPECT(rve_init_file(other_path, &other), RVE_STATUS_OK);
    EXPECT(rve_state_load(other, bytes, size), RVE_STATUS_STATE_MISMATCH);
    free(bytes);

    /* SOLVER_FAILED: no fallbacks, one iteration; committed state intact */
    text = replace(paper, "max_iterations = 40",
                   "max_iterations = 1\npath_following = false\nmax_secant_iterations = 0\n"
                   "max_substep_depth = 0");
    {
        RveHandle weak = 0;
        double big[3] = {3e-4, 0.0, 0.0};
        size_t ws = 0, w0 = 0, w1 = 0;
        uint8_t *b0, *b1;
        EXPECT(rve_init_text(text, NULL, &weak), RVE_STATUS_OK);
        EXPECT(rve_state_size(weak, &ws), RVE_STATUS_OK);
        b0 = malloc(ws);
        b1 = malloc(ws);
        EXPECT(rve_state_save(weak, b0, ws, &w0), RVE_STATUS_OK);
        info.suggested_step_ratio = 99;
        sig[0] = 7;
        EXPECT(rve_update_ex(weak, big, sig, d, RVE_TANGENT_REQUEST_CONSISTENT, &info),
               RVE_STATUS_SOLVER_FAILED);
        if (!(info.reliability == RVE_RELIABILITY_FAILED && info.suggested_step_ratio > 0 &&
              info.suggested_step_ratio < 1)) {
            fprintf(stderr, "bad info after solver failure: ratio %g\n", info.suggested_step_ratio);
            failures++;
        }
        if (sig[0] != 7) {
            fprintf(stderr, "stress written on solver failure\n");
            failures++;
        }
        EXPECT(rve_commit(weak), RVE_STATUS_NO_TRIAL);
        EXPECT(rve_state_save(weak, b1, ws, &w1), RVE_STATUS_OK);
        if (w0 != w1 || memcmp(b0, b1, w0) != 0) {
            fprintf(stderr, "committed state changed by a failed update\n");
            failures++;
        }
        free(b0);
        free(b1);
        EXPECT(rve_free(weak), RVE_STATUS_OK);
    }
    free(text);

    /* BATCH_FAILED: one foreign handle among good ones */
    handles[0] = h;
    handles[1] = 999;
    EXPECT(rve_update_batch(handles, 2, strains, stresses, tangents, statuses,
                            RVE_TANGENT_REQUEST_CONSISTENT, 1),
           RVE_STATUS_BATCH_FAILED);
    if (statuses[0] != RVE_STATUS_OK || statuses[1] != RVE_STATUS_BAD_HANDLE) {
        fprintf(stderr, "batch statuses %u %u\n", (unsigned)statuses[0], (unsigned)statuses[1]);
        failures++;
    }

    /* INSTANCE_BUSY: two threads on one instance; never anything else */
    {
        pthread_t t[2];
        struct hammer hm[2];
        int busy = 0;
        for (i = 0; i < 2; i++) {
            hm[i].h = h;
            hm[i].busy = hm[i].ok = hm[i].bad = 0;
            pthread_create(&t[i], NULL, hammer_run, &hm[i]);
        }
        for (i = 0; i < 2; i++) {
            pthread_join(t[i], NULL);
            busy += hm[i].busy;
            if (hm[i].bad) failures++;
        }
        checks++;
        if (busy == 0) {
            fprintf(stderr, "INSTANCE_BUSY never seen\n");
            failures++;
        }
    }

    /* The UMAT (Abaqus arguments; CMNAME `@ABAQUS_RVE_UMAT` names no scene: the embedded
     * paper RVE, plane stress, NTENS 3): the answer of rve_update on rve_init(NULL); a
     * NULL argument sets PNEWDT < 1 and the message, never a crash. */
    {
        double stress[3] = {7, 7, 7}, ddsdde[9], statev[3] = {0}, zero3[3] = {0}, strain[3] =
            {6e-5, 1e-5, 2e-5}, t[2] = {0, 0}, dt = 1, r = 0, pnewdt = 1e36, eye[9] = {0};
        double ref_s[3], ref_d[9];
        const char name[80] = "@ABAQUS_RVE_UMAT";
        int ndi = 2, nshr = 1, ntens = 3, nstatv = 3, nprops = 0, noel = 1, npt = 1, zero = 0,
            one = 1;
        RveHandle he = 0;
        checks++;
        EXPECT(rve_init(NULL, &he), RVE_STATUS_OK);
        EXPECT(rve_update(he, strain, ref_s, ref_d, RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_OK);
        rve_umat(stress, statev, ddsdde, &r, &r, &r, &r, ddsdde, ddsdde, &r, zero3, strain, t,
                 &dt, &r, &r, &r, &r, name, &ndi, &nshr, &ntens, &nstatv, eye, &nprops, eye,
                 eye, &pnewdt, &r, eye, eye, &noel, &npt, &zero, &zero, &one, &one,
                 strlen(name));
        if (memcmp(stress, ref_s, sizeof ref_s) != 0 || ddsdde[1] != ref_d[3] ||
            ddsdde[3] != ref_d[1] || pnewdt != 1e36 || statev[0] < 1) {
            fprintf(stderr, "rve_umat differs from rve_update: %g %g\n", stress[0], ref_s[0]);
            failures++;
        }
        checks++;
        stress[0] = 7;
        rve_umat(stress, statev, NULL, &r, &r, &r, &r, ddsdde, ddsdde, &r, zero3, strain, t,
                 &dt, &r, &r, &r, &r, name, &ndi, &nshr, &ntens, &nstatv, eye, &nprops, eye,
                 eye, &pnewdt, &r, eye, eye, &noel, &npt, &zero, &zero, &one, &one,
                 strlen(name));
        {
            char m[256];
            rve_last_error(m, sizeof m);
            if (!(pnewdt < 1) || stress[0] != 7 || !strstr(m, "DDSDDE")) {
                fprintf(stderr, "rve_umat with DDSDDE = NULL: PNEWDT %g, message '%s'\n",
                        pnewdt, m);
                failures++;
            }
        }
        EXPECT(rve_free(he), RVE_STATUS_OK);
    }

    /* rve_write_vtk: the committed state to a .vtu file; NULL path, zero, foreign and
     * freed handles, unwritable paths; the instance is unchanged (same state bytes, and
     * a pending trial can still be committed). */
    {
        char vtu[128], line[256];
        size_t s0 = 0, s1 = 0, w0 = 0, w1 = 0;
        uint8_t *b0, *b1;
        double eps2[3] = {1e-4, 0.0, 0.0};
        int found = 0;
        FILE *f;
        snprintf(vtu, sizeof vtu, "/tmp/rve_error_paths_%ld.vtu", (long)getpid());
        EXPECT(rve_state_size(h, &s0), RVE_STATUS_OK);
        b0 = malloc(s0);
        EXPECT(rve_state_save(h, b0, s0, &w0), RVE_STATUS_OK);
        EXPECT(rve_update(h, eps2, sig, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK);
        EXPECT(rve_write_vtk(h, vtu), RVE_STATUS_OK);
        EXPECT(rve_write_vtk(h, NULL), RVE_STATUS_NULL_ARGUMENT);
        EXPECT(rve_write_vtk(0, vtu), RVE_STATUS_BAD_HANDLE);
        EXPECT(rve_write_vtk(12345, vtu), RVE_STATUS_BAD_HANDLE);
        EXPECT(rve_write_vtk(freed, vtu), RVE_STATUS_BAD_HANDLE);
        EXPECT(rve_write_vtk(h, "/nonexistent/dir/state.vtu"), RVE_STATUS_WRITE_FAILED);
        EXPECT(rve_write_vtk(h, ""), RVE_STATUS_WRITE_FAILED);
        EXPECT(rve_write_vtk(h, "/tmp"), RVE_STATUS_WRITE_FAILED); /* a directory */
        EXPECT(rve_state_size(h, &s1), RVE_STATUS_OK);
        b1 = malloc(s1);
        EXPECT(rve_state_save(h, b1, s1, &w1), RVE_STATUS_OK);
        if (w0 != w1 || memcmp(b0, b1, w0) != 0) {
            fprintf(stderr, "rve_write_vtk changed the committed state\n");
            failures++;
        }
        EXPECT(rve_commit(h), RVE_STATUS_OK); /* the trial survived the writes */
        f = fopen(vtu, "r");
        while (f && fgets(line, sizeof line, f))
            found += strstr(line, "Name=\"max_opening_ratio\"") != NULL;
        if (!f || found != 1) {
            fprintf(stderr, "%s: no max_opening_ratio array\n", vtu);
            failures++;
        }
        if (f) fclose(f);
        remove(vtu);
        free(b0);
        free(b1);
    }

    /* Unknown status codes have a message too. */
    if (strcmp(rve_status_message(RVE_STATUS_PANIC), "unknown status code") == 0 ||
        strcmp(rve_status_message(4242u), "unknown status code") != 0)
        failures++;

    EXPECT(rve_free(h), RVE_STATUS_OK);
    EXPECT(rve_free(h2), RVE_STATUS_OK);
    EXPECT(rve_free(other), RVE_STATUS_OK);
    free(paper);
    printf("%d checks, %d failed\n", checks, failures);
    return failures ? 1 : 0;
}
