/* umat_log.c -- a libRVE.so for ccx that records mesorve's UMAT calls bit for bit: its UMAT
 * forwards every call to rve_umat (librve.so) and appends one line per call to the file
 * named by MESORVE_UMAT_LOG (default umat_log.txt):
 *   KSTEP KINC TIME(2) DTIME NOEL NPT ENTRY STRAIN(1..NTENS) STRESS(1..NTENS) HASH TWIN MATCH
 * TIME(2) and DTIME as %.17g; the total strain STRAN + DSTRAN and STRESS in C's %a (the
 * doubles' exact bits: two logs agree only when the answers do bit for bit). ENTRY is what
 * STATEV(1:NSTATV) held when ccx called: `zero` when all zeros (a virgin RVE in STATEV
 * mode), otherwise the FNV-1a hash of its bits; HASH the same of STATEV after the call
 * (what ccx keeps when the increment converges). TWIN is `-` except for reset calls.
 *
 * MESORVE_UMAT_RESET="KSTEP:NOEL,NOEL,..." plays a host that hands the listed elements
 * zeroed state variables in increment 1 of step KSTEP (ccx 2.20 does not when *MODEL
 * CHANGE re-adds elements: docs/calculix.md): STATEV(1:NSTATV) is zeroed before the call
 * (ENTRY is then `reset`), and the same call is repeated for a twin point (element
 * NOEL + 1000000, never called before: a fresh RVE) with its own zeroed STATEV; TWIN says
 * whether the twin's STRESS equals the point's bit for bit (`same`) or not (`differ`).
 * MATCH is the largest |STRAN - the strain the handed STATEV was committed at| over
 * eps_xx, eps_yy, gamma_xy (%.3e), read from the state's payload (docs/statev.md: entries
 * 5-8 hold its first 24 bytes, the committed strain), or `-` for a zero STATEV: how far
 * the host's STRAN is from the library's own record (the UMAT refuses beyond 1e-9 of it).
 *
 * scripts/test-calculix builds it and runs the restart and model-change decks of
 * calculix_examples/statev_decks.py with it, MESORVE_UMAT_LOG=JOB.calls
 * (calculix_examples/statev_check.py reads them):
 *   cc -O2 -shared -fPIC -Iinclude -o DIR/libRVE.so calculix_examples/umat_log.c \
 *      -LWORK -l:libRVE.so -lpthread
 * (WORK/libRVE.so a copy of target/release/librve.so), links DIR/librve.so.0 (librve's
 * soname) to that copy and runs ccx with LD_LIBRARY_PATH=DIR. ccx calls the UMAT from
 * CCX_NPROC_RESULTS threads: lines are written under a lock, in no fixed order across
 * points (in call order for each point). */
#include <inttypes.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rve.h"

#define TWIN_OFFSET 1000000

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static FILE *out;

/* FNV-1a over the bits of n doubles; 0 when all of them are +0.0. */
static uint64_t hash(const double *v, int n) {
  uint64_t h = 1469598103934665603ull;
  int zero = 1;
  for (int i = 0; i < n; i++) {
    uint64_t bits;
    memcpy(&bits, &v[i], sizeof bits);
    zero &= bits == 0;
    for (int b = 0; b < 8; b++) {
      h ^= (bits >> (8 * b)) & 0xff;
      h *= 1099511628211ull;
    }
  }
  return zero ? 0 : h;
}

/* Whether MESORVE_UMAT_RESET names this call: increment 1 of its step, one of its elements. */
static int reset_call(int kstep, int kinc, int noel) {
  const char *spec = getenv("MESORVE_UMAT_RESET");
  if (!spec || kinc != 1) return 0;
  char *end;
  long step = strtol(spec, &end, 10);
  if (end == spec || *end != ':' || step != kstep) return 0;
  for (const char *p = end + 1; *p;) {
    long el = strtol(p, &end, 10);
    if (end == p) return 0;
    if (el == noel) return 1;
    p = *end == ',' ? end + 1 : end;
  }
  return 0;
}

/* The committed strain [eps_xx, eps_yy, gamma_xy] of a mesorve STATEV: the payload's first
 * 24 bytes, 6 per entry from entry 4 (0-based; docs/statev.md). */
static void committed_strain(const double *statev, double strain[3]) {
  unsigned char bytes[24];
  for (int e = 0; e < 4; e++) {
    uint64_t v = (uint64_t)statev[4 + e];
    for (int b = 0; b < 6; b++) bytes[6 * e + b] = (unsigned char)(v >> (8 * b));
  }
  memcpy(strain, bytes, sizeof bytes); /* little-endian doubles, as on x86_64 */
}

/* The MATCH column: |STRAN - committed strain| (infinity norm), or "-". */
static void strain_match(const double *statev, int nstatv, const double *stran, int ntens,
                         char *buf, size_t len) {
  if (nstatv < 8 || hash(statev, nstatv) == 0 || (ntens != 3 && ntens != 4 && ntens != 6)) {
    snprintf(buf, len, "-");
    return;
  }
  double stored[3], host[3] = {stran[0], stran[1], stran[ntens == 3 ? 2 : 3]}, worst = 0;
  committed_strain(statev, stored);
  for (int i = 0; i < 3; i++) {
    double d = stored[i] > host[i] ? stored[i] - host[i] : host[i] - stored[i];
    if (d > worst) worst = d;
  }
  snprintf(buf, len, "%.3e", worst);
}

__attribute__((destructor)) static void close_log(void) {
  if (out) fclose(out);
}

#define MAX_NTENS 6

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
  int n = *ntens < MAX_NTENS ? *ntens : MAX_NTENS;
  int reset = reset_call(*kstep, *kinc, *noel);
  uint64_t entry = hash(statev, *nstatv);
  char match[32];
  strain_match(statev, *nstatv, stran, *ntens, match, sizeof match);
  /* The twin's inputs, copied before the call changes them. */
  double twin_stress[MAX_NTENS], twin_ddsdde[MAX_NTENS * MAX_NTENS], twin_pnewdt = *pnewdt;
  double *twin_statev = NULL;
  if (reset) {
    memset(statev, 0, sizeof(double) * (size_t)*nstatv);
    memcpy(twin_stress, stress, sizeof(double) * (size_t)n);
    twin_statev = calloc((size_t)*nstatv + 1, sizeof(double));
  }
  rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran,
           dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens,
           nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt,
           layer, kspt, kstep, kinc, cmname_len);
  const char *twin = "-";
  if (reset) {
    int twin_noel = *noel + TWIN_OFFSET;
    rve_umat(twin_stress, twin_statev, twin_ddsdde, sse, spd, scd, rpl, ddsddt, drplde,
             drpldt, stran, dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi,
             nshr, ntens, nstatv, props, nprops, coords, drot, &twin_pnewdt, celent,
             dfgrd0, dfgrd1, &twin_noel, npt, layer, kspt, kstep, kinc, cmname_len);
    twin = memcmp(twin_stress, stress, sizeof(double) * (size_t)n) == 0 ? "same" : "differ";
    free(twin_statev);
  }
  char line[2048];
  int k = snprintf(line, sizeof line, "%d %d %.17g %.17g %d %d ", *kstep, *kinc, time[1],
                   *dtime, *noel, *npt);
  if (reset) {
    k += snprintf(line + k, sizeof line - k, "reset");
  } else if (entry == 0) {
    k += snprintf(line + k, sizeof line - k, "zero");
  } else {
    k += snprintf(line + k, sizeof line - k, "%016" PRIx64, entry);
  }
  for (int i = 0; i < n; i++) k += snprintf(line + k, sizeof line - k, " %a", stran[i] + dstran[i]);
  for (int i = 0; i < n; i++) k += snprintf(line + k, sizeof line - k, " %a", stress[i]);
  snprintf(line + k, sizeof line - k, " %016" PRIx64 " %s %s\n", hash(statev, *nstatv), twin,
           match);
  pthread_mutex_lock(&lock);
  if (!out) {
    const char *path = getenv("MESORVE_UMAT_LOG");
    out = fopen(path ? path : "umat_log.txt", "w");
  }
  if (out) fputs(line, out);
  pthread_mutex_unlock(&lock);
}
