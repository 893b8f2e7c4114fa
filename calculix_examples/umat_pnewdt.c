/* umat_pnewdt.c -- a libRVE.so for ccx that records the PNEWDT of mesorve's UMAT calls: its
 * UMAT forwards every call to rve_umat (librve.so) and appends one line per call to the file
 * named by MESORVE_UMAT_LOG (default umat_pnewdt.txt):
 *   KSTEP KINC TIME(2) DTIME NOEL NPT STRAIN(1) PNEWDT_IN PNEWDT_LIB PNEWDT_OUT STRESS(1)
 * PNEWDT_IN is what ccx handed over (ccx 2.20 hands -1: resultsmech.f sets qa(3) = -1 and
 * reads a positive value back as a request to cut), PNEWDT_LIB what the library left in the
 * value it was given, PNEWDT_OUT what ccx gets back.
 *
 * With MESORVE_UMAT_LARGE=1 the library is handed Abaqus's convention instead (a large
 * PNEWDT, which a UMAT lowers to ask for a smaller step), and a value below 1 that it
 * returns is passed on to ccx: this shows what ccx does once the step check's request
 * reaches it. Without it ccx's value is passed through unchanged and PNEWDT_OUT is what
 * the library returns to ccx itself.
 *
 * scripts/test-calculix builds it as umat_log.c (docs/calculix.md, "An increment across the
 * snap-back"):
 *   cc -O2 -shared -fPIC -Iinclude -o DIR/libRVE.so calculix_examples/umat_pnewdt.c \
 *      -LWORK -l:libRVE.so -lpthread
 * and runs ccx with LD_LIBRARY_PATH=DIR (DIR/librve.so.0 a link to WORK/libRVE.so). */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

#include "rve.h"

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static FILE *out;

__attribute__((destructor)) static void close_log(void) {
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
  const char *large = getenv("MESORVE_UMAT_LARGE");
  int abaqus = large && large[0] == '1';
  double in = *pnewdt, lib = abaqus ? 1e36 : in;
  rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran,
           dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens,
           nstatv, props, nprops, coords, drot, &lib, celent, dfgrd0, dfgrd1, noel, npt,
           layer, kspt, kstep, kinc, cmname_len);
  if (!abaqus || (lib < 1 && (in <= 0 || lib < in))) *pnewdt = lib;
  pthread_mutex_lock(&lock);
  if (!out) {
    const char *path = getenv("MESORVE_UMAT_LOG");
    out = fopen(path ? path : "umat_pnewdt.txt", "w");
  }
  if (out)
    fprintf(out, "%d %d %.17g %.17g %d %d %.17g %g %g %g %.17g\n", *kstep, *kinc, time[1],
            *dtime, *noel, *npt, stran[0] + dstran[0], in, lib, *pnewdt, stress[0]);
  pthread_mutex_unlock(&lock);
}
