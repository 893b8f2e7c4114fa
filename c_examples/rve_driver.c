/*
 * rve_driver.c -- follows a scene's strain path through the C interface, like `rve run`:
 * for every increment of the scene's [[path]] (rve_path_point gives exactly the strains
 * `rve run` uses), a trial rve_update_ex with the consistent tangent, then rve_commit.
 * Writes CSV with the first 20 columns of `rve run`'s response.csv (step .. factorizations)
 * with %.17g, so the values compare bit for bit after parsing (tests/c_driver.rs).
 *
 * Usage: rve_driver [SCENE.toml [OUT.csv]]    (default output: stdout)
 * SCENE `-` or absent: the paper's RVE embedded in the library (rve_init with NULL), the
 * scene `rve run` solves when given none.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

static int fail(const char *what, uint32_t status) {
    char msg[512];
    rve_last_error(msg, sizeof msg);
    fprintf(stderr, "rve_driver: %s: status %u (%s): %s\n", what, (unsigned)status,
            rve_status_message(status), msg);
    return 1;
}

int main(int argc, char **argv) {
    RveHandle h = 0;
    size_t n = 0, i;
    uint32_t st;
    FILE *out = stdout;
    const char *scene = argc > 1 && strcmp(argv[1], "-") != 0 ? argv[1] : NULL;
    if (rve_abi_version() != RVE_ABI_VERSION) {
        fprintf(stderr, "rve_driver: library ABI %u, header ABI %d\n", (unsigned)rve_abi_version(),
                RVE_ABI_VERSION);
        return 1;
    }
    if ((st = rve_init(scene, &h)) != RVE_STATUS_OK) return fail("rve_init", st);
    if ((st = rve_path_len(h, &n)) != RVE_STATUS_OK) return fail("rve_path_len", st);
    if (argc > 2 && !(out = fopen(argv[2], "w"))) {
        perror(argv[2]);
        return 1;
    }
    fprintf(out, "step,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy,D11,D12,D13,D21,D22,D23,"
                 "D31,D32,D33,iterations,substeps,s_zz,factorizations\n");
    for (i = 0; i < n; i++) {
        double eps[3], sig[3], d[9];
        RveInfo info;
        int k;
        if ((st = rve_path_point(h, i, eps)) != RVE_STATUS_OK) return fail("rve_path_point", st);
        st = rve_update_ex(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT, &info);
        if (st != RVE_STATUS_OK) return fail("rve_update_ex", st);
        if ((st = rve_commit(h)) != RVE_STATUS_OK) return fail("rve_commit", st);
        fprintf(out, "%lu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", (unsigned long)(i + 1), eps[0],
                eps[1], eps[2], sig[0], sig[1], sig[2]);
        for (k = 0; k < 9; k++) fprintf(out, ",%.17g", d[k]);
        fprintf(out, ",%u,%u,%.17g,%u\n", (unsigned)info.iterations, (unsigned)info.substeps,
                info.s_zz, (unsigned)info.factorizations);
    }
    if (out != stdout) fclose(out);
    if ((st = rve_free(h)) != RVE_STATUS_OK) return fail("rve_free", st);
    fprintf(stderr, "rve_driver: %lu increments of %s\n", (unsigned long)n,
            scene ? scene : "the embedded paper RVE");
    return 0;
}
