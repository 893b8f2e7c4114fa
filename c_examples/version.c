/*
 * version.c -- the smallest C program against librve: checks that the header and the
 * library agree on the version and that status messages are available.
 *
 * Build: cc -std=c99 -Wall -Wextra -pedantic -Werror -Iinclude c_examples/version.c \
 *           -Ltarget/release -lrve -Wl,-rpath,$PWD/target/release -o version
 */
#include <stdio.h>
#include <string.h>

#include "rve.h"

int main(void) {
    const char *v = rve_version();
    unsigned packed = RVE_VERSION_MAJOR * 10000u + RVE_VERSION_MINOR * 100u + RVE_VERSION_PATCH;
    printf("header %s (ABI %d), library %s\n", RVE_VERSION, RVE_ABI_VERSION, v);
    if (strcmp(v, RVE_VERSION) != 0 || rve_version_number() != packed) {
        fprintf(stderr, "version mismatch between rve.h and librve\n");
        return 1;
    }
    if (strcmp(rve_status_message(RVE_STATUS_OK), "ok") != 0 ||
        strcmp(rve_status_message(12345u), "unknown status code") != 0) {
        fprintf(stderr, "unexpected status messages\n");
        return 1;
    }
    printf("1 passed, 0 failed\n");
    return 0;
}
