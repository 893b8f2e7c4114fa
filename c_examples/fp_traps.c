/* A host that traps invalid floating-point operations and divisions by zero, as debug
 * builds of Fortran codes do (gfortran -ffpe-trap=invalid,zero): the library must not
 * raise them, also where a value would be discarded. Runs the paper's section 5.2.1 path
 * (implicit, through its snap-back), the 5.2.2 cycle and the IMPL-EX host scene with
 * traps on; SIGFPE would kill the program. Usage: fp_traps (from the repository root). */
#define _GNU_SOURCE
#include <fenv.h>
#include <stdio.h>

#include "rve.h"

static int follow(const char *scene) {
    RveHandle h = 0;
    size_t n = 0;
    double strain[3], stress[3], tangent[9];
    if (rve_init_file(scene, &h) != RVE_STATUS_OK || rve_path_len(h, &n) != RVE_STATUS_OK) {
        fprintf(stderr, "%s: init failed\n", scene);
        return 1;
    }
    for (size_t i = 0; i < n; i++) {
        if (rve_path_point(h, i, strain) != RVE_STATUS_OK ||
            rve_update_timed(h, strain, 1.0, stress, tangent, RVE_TANGENT_REQUEST_CONSISTENT,
                             NULL) != RVE_STATUS_OK ||
            rve_commit(h) != RVE_STATUS_OK) {
            fprintf(stderr, "%s: increment %zu failed\n", scene, i + 1);
            return 1;
        }
    }
    printf("%s: %zu increments with FE_INVALID and FE_DIVBYZERO trapped, s_xx %.6g\n", scene,
           n, stress[0]);
    return rve_free(h) != RVE_STATUS_OK;
}

int main(void) {
    const char *scenes[] = {"scenes/paper_rve.toml", "scenes/paper_rve_cycle.toml",
                            "scenes/paper_rve_host_implex.toml"};
    feenableexcept(FE_INVALID | FE_DIVBYZERO);
    for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; s++) {
        if (follow(scenes[s]) != 0) {
            return 1;
        }
    }
    printf("fp_traps: passed\n");
    return 0;
}
