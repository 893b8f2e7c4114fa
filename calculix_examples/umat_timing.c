/* umat_timing.c -- a libRVE.so for ccx that times mesorve's UMAT: its UMAT forwards every
 * call to rve_umat (librve.so) and appends one line per call to the file named by
 * MESORVE_UMAT_TIMES (default umat_times.csv):
 *   KSTEP, KINC, TIME(2), DTIME, NOEL, NPT, CPU seconds of the call
 * (the calling thread's CPU time, CLOCK_THREAD_CPUTIME_ID: on a machine shared with other
 * jobs a wall clock would count the time the thread waited for a core)
 * scripts/test-calculix builds it with MESORVE_CCX_STUDY=1 (the RVE time per increment
 * in docs/calculix.md):
 *   cc -O2 -shared -fPIC -Iinclude -o DIR/libRVE.so calculix_examples/umat_timing.c \
 *      -LWORK -l:libRVE.so -lpthread
 * (WORK/libRVE.so a copy of target/release/librve.so), links DIR/librve.so.0 (librve's
 * soname) to that copy and runs ccx with LD_LIBRARY_PATH=DIR. The calls of one process
 * are written under a lock (ccx calls the UMAT from CCX_NPROC_RESULTS threads). */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "rve.h"

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static FILE *out;

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void record(const int *kstep, const int *kinc, const double *time,
                   const double *dtime, const int *noel, const int *npt, double seconds) {
  pthread_mutex_lock(&lock);
  if (!out) {
    const char *path = getenv("MESORVE_UMAT_TIMES");
    out = fopen(path ? path : "umat_times.csv", "w");
  }
  if (out) {
    fprintf(out, "%d,%d,%.17g,%.17g,%d,%d,%.9g\n", *kstep, *kinc, time[1], *dtime, *noel,
            *npt, seconds);
  }
  pthread_mutex_unlock(&lock);
}

__attribute__((destructor)) static void close_times(void) {
  if (out) fclose(out);
}

void UMAT(double *stress, double *statev, double *ddsdde, double *sse, double *spd,
          double *scd, double *rpl, double *ddsddt, double *drplde, double *drpldt,
          const double *stran, const double *dstran, const double *time,
          const double *dtime, const double *temp, const double *dtemp,
          const double *predef, const double *dpred, const char *cmname, const int *ndi,
          const int *nshr, const int *ntens, const int *nstatv, const double *props,
          const int *nprops, const double *coords, const double *drot, double *pnewdt,
          const double *celent, const double *dfgrd0, const double *dfgrd1,
          const int *noel, const int *npt, const int *layer, const int *kspt,
          const int *kstep, const int *kinc, size_t cmname_len) {
  double start = now();
  rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran,
           dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens,
           nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt,
           layer, kspt, kstep, kinc, cmname_len);
  record(kstep, kinc, time, dtime, noel, npt, now() - start);
}
