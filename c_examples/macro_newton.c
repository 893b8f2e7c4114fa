/*
 * macro_newton.c -- one macroscopic material point under mixed control, the way a host
 * FE code uses the library: eps_xx is prescribed in steps through the peak of the uniaxial
 * curve and onto the post-peak branch, and eps_yy, gamma_xy are found so that
 * sig_yy = sig_xy = 0 (a uniaxial macro stress), by Newton's method with the consistent
 * tangent rve_update returns (trial updates, then one rve_commit per converged step).
 *
 * The scene is scenes/paper_rve_host.toml: the paper's RVE with the ITZ contact shear that
 * is continuous at closure (materials.itz.contact_shear = "cohesive"). The Poisson
 * contraction closes ITZ points while they slide; with the paper's own contact law
 * (penalty on both components) the RVE then has no equilibrium from eps_xx ~ 1.6e-4 on.
 *
 * Checks: every step converges in at most MAX_IT iterations, and once the residual is
 * small the convergence is quadratic: r_{k+1} <= C r_k^2 (relative residuals, C = 1e3)
 * until the floor set by the RVE's own tolerance.
 *
 * Usage: macro_newton [SCENE.toml]     (default scenes/paper_rve_host.toml)
 */
#include <math.h>
#include <stdio.h>

#include "rve.h"

#define STEPS 20
#define EPS_END 4e-4 /* the peak is near 2.2e-4 */
#define MAX_IT 6
#define TOL 1e-9    /* relative to |sig_xx| */
#define FLOOR 1e-7  /* below this the RVE tolerance (1e-6 on its residual) dominates */
#define C_QUAD 1e3

static int check(uint32_t st, const char *what) {
    if (st != RVE_STATUS_OK) {
        char msg[512];
        rve_last_error(msg, sizeof msg);
        fprintf(stderr, "macro_newton: %s: %s: %s\n", what, rve_status_message(st), msg);
        return 1;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : "scenes/paper_rve_host.toml";
    RveHandle h = 0;
    double eps[3] = {0.0, 0.0, 0.0};
    int step, failures = 0, quadratic_checks = 0;
    if (check(rve_init_file(scene, &h), "rve_init_file")) return 1;
    for (step = 1; step <= STEPS; step++) {
        double sig[3], d[9], r[MAX_IT + 2];
        int k, converged = 0;
        /* Predictor: scale the converged lateral strains with eps_xx. */
        if (step > 1) {
            eps[1] *= (double)step / (step - 1);
            eps[2] *= (double)step / (step - 1);
        }
        eps[0] = EPS_END * step / STEPS;
        printf("step %d  eps_xx = %.3e\n", step, eps[0]);
        for (k = 0; k <= MAX_IT; k++) {
            double det, de1, de2;
            if (check(rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT), "rve_update"))
                return 1;
            r[k] = sqrt(sig[1] * sig[1] + sig[2] * sig[2]) / fabs(sig[0]);
            printf("  it %d  |[sig_yy, sig_xy]| / |sig_xx| = %.3e\n", k, r[k]);
            if (k > 0 && r[k - 1] < 1e-3 && r[k - 1] > FLOOR) {
                quadratic_checks++;
                if (!(r[k] <= C_QUAD * r[k - 1] * r[k - 1] || r[k] <= FLOOR)) {
                    fprintf(stderr, "step %d: not quadratic: %.3e after %.3e\n", step, r[k],
                            r[k - 1]);
                    failures++;
                }
            }
            if (r[k] < TOL || (k > 0 && r[k] <= FLOOR && r[k] >= 0.5 * r[k - 1])) {
                converged = 1;
                break;
            }
            /* Solve [D22 D23; D32 D33] [de_yy; dg_xy] = -[sig_yy; sig_xy]. */
            det = d[4] * d[8] - d[5] * d[7];
            de1 = (-sig[1] * d[8] + sig[2] * d[5]) / det;
            de2 = (-sig[2] * d[4] + sig[1] * d[7]) / det;
            eps[1] += de1;
            eps[2] += de2;
        }
        if (!converged) {
            fprintf(stderr, "step %d: no convergence in %d iterations\n", step, MAX_IT);
            failures++;
        }
        if (check(rve_commit(h), "rve_commit")) return 1;
        printf("  converged: eps = [%.4e %.4e %.4e], sig_xx = %.4f\n", eps[0], eps[1], eps[2],
               sig[0]);
    }
    rve_free(h);
    if (quadratic_checks == 0) {
        fprintf(stderr, "no iteration tested the rate\n");
        failures++;
    }
    printf("%d rate checks, %s\n", quadratic_checks, failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
