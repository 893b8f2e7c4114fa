// rve_ff.cpp -- FreeFEM plugin for mesorve: the C interface (include/rve.h) as FreeFEM
// functions vectorised over material points, so that a macro Newton iteration costs one
// interpreter call per assembly, not one per integration point.
//
// Build (scripts/test-freefem does this; no -auto: it is broken in the Debian package):
//   ff-c++ rve_ff.cpp -I../include -L../target/release -lrve -Wl,-rpath,$PWD/../target/release
// Load with `load "rve_ff"` and FF_LOADPATH="./;/usr/lib/freefem++/".
//
// A material point is one entry k of every array; with P0 fields, entry k is triangle k
// (pass `f[]` of a P0 function f). Conventions are the library's:
//   strain  [exx, eyy, gxy], ENGINEERING shear gxy = 2 eps_xy = du/dy + dv/dx;
//   stress  [sxx, syy, sxy];
//   tangent row-major D[3*i + j] = d stress_i / d strain_j, returned as nine arrays
//           d11 d12 d13 / d21 d22 d23 / d31 d32 d33 with dIJ = D[3*(I-1) + (J-1)]:
//           d12 = d sxx / d eyy, d21 = d syy / d exx (the consistent tangent need not be
//           symmetric, so the order matters).
//
// Functions (each returns an RveStatus number, 0 = success; on failure rveLastError()
// says what went wrong and outputs are left untouched; when one point of a vectorised
// update fails, the status is that point's, the message names it, and no point keeps a
// trial: the committed states are unchanged and rveCommit would report NO_TRIAL):
//   long   rveInit(string scene, long n, real[int] H)   n instances of the scene file;
//          H is resized to n and receives the handles (int64 ids, exact in a double)
//   long   rveUpdate(H, exx, eyy, gxy, sxx, syy, sxy, d11, ..., d33)  trial update of all
//          points, consistent tangent (16 arrays of equal length)
//   long   rveInitText(string toml, string baseDir, long n, real[int] H)   the same from
//          scene text (rve_init_text; relative paths in it against baseDir, "" = the
//          working directory): a script can derive a scene, e.g. a weaker ITZ
//   long   rveUpdateElastic(same 16 arrays)   same, tangent = elastic tangent of the virgin RVE
//   long   rveUpdateTimed(H, DT, exx, ..., d33)   rveUpdate over the host time increment
//          DT[k] of each point (rve_update_timed: IMPL-EX scales its extrapolation by
//          DT[k] / the DT of the committed increment; DT[k] <= 0: none, as rveUpdate),
//          17 arrays of equal length
//   real   rveStepRatio()   the smallest suggested_step_ratio of the points of the last
//          successful rveUpdateTimed (RvePointReport / RveInfo): < 1 redo the increment
//          that much smaller, > 1 (only under solver.step_tolerance) the next may be that
//          much larger; 1 before any timed update
//   real   rveErrorEstimate()   the largest error_estimate of those points (IMPL-EX's
//          estimate over solver.step_tolerance; 0 without a tolerance)
//   long   rveStress(H, exx, eyy, gxy, sxx, syy, sxy)   trial update, stress only
//   long   rveFastUpdates(H, real[int] N)   N is resized to n and receives each point's
//          updates answered without a solve (rve_fast_updates: the fast path's answers and,
//          with IMPL-EX, the updates that reuse their increment's factorization)
//   long   rveCommit(H)   accept the last trial of every point (end of a macro increment)
//   long   rveRevert(H)   discard the trials
//   long   rveFree(H)     free every instance and set its entry of H to 0 (a second
//                         rveFree(H) is then a no-op)
//   string rveLastError()            detailed message of the last failed rve* call
//   string rveStatusMessage(long st) static description of a status number
//   string rveVersion()
//
// Errors found by the plugin itself (arrays of different lengths, a handle that is not an
// integer) are reported as RVE_STATUS_INVALID_ARGUMENT / RVE_STATUS_BAD_HANDLE with their
// own message; everything else is the library's status and rve_last_error text.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "ff++.hpp"
#include "AFunction_ext.hpp"  // OneOperator4_

#include "rve.h"

using namespace std;

namespace {

// Message of the last failure of an rve* FreeFEM function (the library keeps its own per
// thread; this one also covers the plugin's own argument checks).
string g_last_error;
// Over the points of the last successful timed update: the smallest suggested step ratio
// and the largest error estimate (rveStepRatio, rveErrorEstimate).
double g_step_ratio = 1.0, g_error_estimate = 0.0;

long fail(const string &where, uint32_t st, const string &detail) {
  ostringstream m;
  m << where << ": " << rve_status_message(st) << " (status " << st << ")";
  if (!detail.empty()) m << ": " << detail;
  g_last_error = m.str();
  return (long)st;
}

// Status of a library call, with rve_last_error() captured on failure.
string library_error() {
  size_t len = rve_last_error(nullptr, 0);
  vector<char> buf(len + 1, '\0');
  rve_last_error(buf.data(), buf.size());
  return string(buf.data());
}

long check(const string &where, uint32_t st) {
  if (st == RVE_STATUS_OK) return 0;
  return fail(where, st, library_error());
}

// A handle stored in a double: must be an exact integer in int64 range (converting
// anything else to int64_t would be undefined behaviour). The library then checks that
// it is a live instance.
bool to_handle(double x, RveHandle *h) {
  if (!std::isfinite(x) || x != std::floor(x) || std::fabs(x) > 9.0e15) return false;
  *h = (RveHandle)x;
  return true;
}

long handles_of(const string &where, const KN<double> &H, vector<RveHandle> *out) {
  out->resize(H.N());
  for (long k = 0; k < H.N(); k++)
    if (!to_handle(H[k], &(*out)[k])) {
      ostringstream m;
      m << "entry " << k << " of the handle array (" << H[k] << ") is not an integer handle";
      return fail(where, RVE_STATUS_BAD_HANDLE, m.str());
    }
  return 0;
}

// ---- rveInit(string scene, long n, real[int] H), rveInitText(toml, baseDir, n, H) ----
// n instances: the first made by `first` (parses and meshes the scene), the others virgin
// clones of its model (no parsing or meshing); H is resized to n and receives the handles.
// On failure no instance is left behind and H is untouched.
template <class First>
long init_n(const string &where, long n, KN<double> *H, First first) {
  g_last_error.clear();
  if (n < 1) return fail(where, RVE_STATUS_INVALID_ARGUMENT, "n must be >= 1");
  vector<RveHandle> hs;
  hs.reserve(n);
  RveHandle h0 = 0;
  long st = check(where, first(&h0));
  if (st) return st;
  hs.push_back(h0);
  for (long k = 1; k < n && st == 0; k++) {
    RveHandle h = 0;
    st = check(where + " clone", rve_clone_model(h0, &h));
    if (st == 0) hs.push_back(h);
  }
  if (st) {  // leave nothing behind; keep the first error's message
    string msg = g_last_error;
    for (RveHandle h : hs)
      if (rve_free(h) != RVE_STATUS_OK) msg += " (and freeing a partial instance failed)";
    g_last_error = msg;
    return st;
  }
  H->resize(n);
  for (long k = 0; k < n; k++) (*H)[k] = (double)hs[k];
  return 0;
}

long rve_ff_init(string *const &scene, const long &n, KN<double> *const &H) {
  const char *path = scene->c_str();
  return init_n("rveInit(\"" + *scene + "\")", n, H,
                [path](RveHandle *h) { return rve_init_file(path, h); });
}

long rve_ff_init_text(string *const &toml, string *const &base, const long &n,
                      KN<double> *const &H) {
  const char *text = toml->c_str(), *dir = base->empty() ? nullptr : base->c_str();
  return init_n("rveInitText", n, H,
                [text, dir](RveHandle *h) { return rve_init_text(text, dir, h); });
}

// ---- rveUpdate / rveUpdateElastic / rveStress / rveUpdateTimed -------------------------
// Every point's trial update, statuses[k] its status, on this thread (nthreads = 1: the
// host may be parallel itself, and results do not depend on nthreads). Without times (dt
// NULL) one rve_update_batch call. With times equal at every point (a host increment) one
// rve_update_batch_timed call, whose reports give each point's suggested step ratio and
// error estimate; with different times rve_update_timed point by point (its RveInfo
// gives the ratio; every point is attempted, as the batch call does). Returns the
// status: OK, BATCH_FAILED (detail: the first failed point's message) or a status of the
// call itself. A timed update that succeeds sets g_step_ratio and g_error_estimate.
uint32_t update_timed_points(const vector<RveHandle> &hs, const double *dt,
                             const double *strain, double *stress, double *tangent,
                             uint32_t *statuses, int32_t request, string *detail) {
  const size_t n = hs.size();
  double ratio = 1.0, estimate = 0.0;
  uint32_t st = RVE_STATUS_OK;
  bool same = true;
  for (size_t k = 1; k < n; k++) same = same && dt[k] == dt[0];
  if (same) {
    vector<RvePointReport> reports(n);
    st = rve_update_batch_timed(hs.data(), n, strain, n ? dt[0] : 0.0, stress, tangent,
                                request, reports.data(), nullptr, 0, 1);
    if (st != RVE_STATUS_OK) *detail = library_error();
    for (size_t k = 0; k < n; k++) {
      statuses[k] = st == RVE_STATUS_OK || st == RVE_STATUS_BATCH_FAILED ? reports[k].status : st;
      ratio = k ? fmin(ratio, reports[k].suggested_step_ratio) : reports[k].suggested_step_ratio;
      estimate = fmax(estimate, reports[k].error_estimate);
    }
  } else {
    for (size_t k = 0; k < n; k++) {
      RveInfo info = {};
      statuses[k] = rve_update_timed(hs[k], strain + 3 * k, dt[k], stress + 3 * k,
                                     tangent ? tangent + 9 * k : nullptr, request, &info);
      ratio = k ? fmin(ratio, info.suggested_step_ratio) : info.suggested_step_ratio;
      if (statuses[k] != RVE_STATUS_OK && st == RVE_STATUS_OK) {
        st = RVE_STATUS_BATCH_FAILED;
        *detail = "item " + to_string(k) + ": " + library_error();
      }
    }
  }
  if (st == RVE_STATUS_OK) {
    g_step_ratio = n ? ratio : 1.0;
    g_error_estimate = estimate;
  }
  return st;
}
uint32_t update_points(const vector<RveHandle> &hs, const double *dt, const double *strain,
                       double *stress, double *tangent, uint32_t *statuses, int32_t request,
                       string *detail) {
  if (dt) return update_timed_points(hs, dt, strain, stress, tangent, statuses, request, detail);
  uint32_t st = rve_update_batch(hs.data(), hs.size(), strain, stress, tangent, statuses,
                                 request, 1);
  if (st != RVE_STATUS_OK) *detail = library_error();
  return st;
}
// args: H [, DT], exx, eyy, gxy, sxx, syy, sxy [, d11, ..., d33]
long update_all(const string &where, KN<double> *const *a, int nargs, int32_t request,
                bool timed) {
  g_last_error.clear();
  const KN<double> &H = *a[0];
  const long n = H.N();
  const int e0 = timed ? 2 : 1;  // the first strain array
  for (int i = 1; i < nargs; i++)
    if (a[i]->N() != n) {
      ostringstream m;
      m << "array " << i + 1 << " has " << a[i]->N() << " entries, the handle array " << n;
      return fail(where, RVE_STATUS_INVALID_ARGUMENT, m.str());
    }
  vector<RveHandle> hs;
  long st = handles_of(where, H, &hs);
  if (st) return st;
  vector<double> strain(3 * n), stress(3 * n), dt(timed ? n : 0);
  vector<double> tangent(request == RVE_TANGENT_REQUEST_NONE ? 0 : 9 * n);
  vector<uint32_t> statuses(n, RVE_STATUS_OK);
  for (long k = 0; k < n; k++) {
    for (int c = 0; c < 3; c++) strain[3 * k + c] = (*a[e0 + c])[k];
    if (timed) dt[k] = (*a[1])[k];
  }
  string detail;
  uint32_t raw = update_points(hs, timed ? dt.data() : nullptr, strain.data(), stress.data(),
                               tangent.empty() ? nullptr : tangent.data(), statuses.data(),
                               request, &detail);
  st = raw == RVE_STATUS_OK ? 0 : fail(where, raw, detail);
  // On BATCH_FAILED the script gets the first failed point's own status (ABSURD_STRAIN,
  // SOLVER_FAILED, ...), which says more than "some item failed".
  if (st == RVE_STATUS_BATCH_FAILED) {
    string msg = g_last_error;
    long first = 0;
    for (long k = 0; k < n; k++)
      if (statuses[k] != RVE_STATUS_OK && !first) {
        ostringstream m;
        m << where << ": point " << k << ": " << rve_status_message(statuses[k]) << " (status "
          << statuses[k] << "); " << msg;
        msg = m.str();
        first = (long)statuses[k];
      }
    // The points that succeeded hold a new trial; drop them too, so that after a failed
    // call no point has a trial to commit (the C rule for one instance, kept for the set).
    for (long k = 0; k < n; k++)
      if (statuses[k] == RVE_STATUS_OK && rve_revert(hs[k]) != RVE_STATUS_OK)
        msg += "; reverting point " + to_string(k) + " failed too";
    g_last_error = msg;
    return first;
  }
  if (st) return st;
  // Written only on success, as the C API does.
  for (long k = 0; k < n; k++) {
    for (int c = 0; c < 3; c++) (*a[e0 + 3 + c])[k] = stress[3 * k + c];
    if (!tangent.empty())
      for (int ij = 0; ij < 9; ij++) (*a[e0 + 6 + ij])[k] = tangent[9 * k + ij];  // row-major
  }
  return 0;
}

// A FreeFEM operator with `NARGS` arrays (the stock OneOperatorN_ stop at 7 or so).
template <int NARGS, int32_t REQUEST, bool TIMED = false>
class UpdateOp : public E_F0mps {
 public:
  typedef long Result;
  Expression e[NARGS];
  const char *name;
  UpdateOp(const basicAC_F0 &args, const char *nm) : name(nm) {
    args.SetNameParam(0, 0, 0);
    if (args.size() != NARGS) {
      ostringstream m;
      m << name << " takes " << NARGS << " real[int] arrays, got " << args.size();
      CompileError(m.str());
    }
    for (int i = 0; i < NARGS; i++) e[i] = to<KN<double> *>(args[i]);
  }
  AnyType operator()(Stack s) const {
    KN<double> *a[NARGS];
    for (int i = 0; i < NARGS; i++) a[i] = GetAny<KN<double> *>((*e[i])(s));
    return SetAny<long>(update_all(name, a, NARGS, REQUEST, TIMED));
  }
  operator aType() const { return atype<long>(); }
};

class UpdateConsistent : public UpdateOp<16, RVE_TANGENT_REQUEST_CONSISTENT> {
 public:
  UpdateConsistent(const basicAC_F0 &a) : UpdateOp(a, "rveUpdate") {}
  static ArrayOfaType typeargs() { return ArrayOfaType(atype<KN<double> *>(), true); }
  static E_F0 *f(const basicAC_F0 &a) { return new UpdateConsistent(a); }
};
class UpdateElastic : public UpdateOp<16, RVE_TANGENT_REQUEST_ELASTIC> {
 public:
  UpdateElastic(const basicAC_F0 &a) : UpdateOp(a, "rveUpdateElastic") {}
  static ArrayOfaType typeargs() { return ArrayOfaType(atype<KN<double> *>(), true); }
  static E_F0 *f(const basicAC_F0 &a) { return new UpdateElastic(a); }
};
class UpdateTimed : public UpdateOp<17, RVE_TANGENT_REQUEST_CONSISTENT, true> {
 public:
  UpdateTimed(const basicAC_F0 &a) : UpdateOp(a, "rveUpdateTimed") {}
  static ArrayOfaType typeargs() { return ArrayOfaType(atype<KN<double> *>(), true); }
  static E_F0 *f(const basicAC_F0 &a) { return new UpdateTimed(a); }
};
class UpdateStress : public UpdateOp<7, RVE_TANGENT_REQUEST_NONE> {
 public:
  UpdateStress(const basicAC_F0 &a) : UpdateOp(a, "rveStress") {}
  static ArrayOfaType typeargs() { return ArrayOfaType(atype<KN<double> *>(), true); }
  static E_F0 *f(const basicAC_F0 &a) { return new UpdateStress(a); }
};

// ---- rveCommit / rveRevert / rveFree ---------------------------------------------------
// Every point is attempted (a commit cannot be undone, so a failure part-way cannot be
// rolled back); the first failure is reported with its point index.
template <uint32_t (*CALL)(RveHandle), bool ZERO>
long each(const char *name, KN<double> *const &H) {
  g_last_error.clear();
  vector<RveHandle> hs;
  long st = handles_of(name, *H, &hs);
  if (st) return st;
  long first = 0;
  string msg;
  for (long k = 0; k < H->N(); k++) {
    ostringstream where;
    where << name << " point " << k;
    long s = check(where.str(), CALL(hs[k]));
    if (s == 0 && ZERO) (*H)[k] = 0.0;  // freed: rve_free(0) is a no-op
    if (s && !first) { first = s; msg = g_last_error; }
  }
  g_last_error = msg;
  return first;
}
long rve_ff_fast_updates(KN<double> *const &H, KN<double> *const &N) {
  g_last_error.clear();
  vector<RveHandle> hs;
  long st = handles_of("rveFastUpdates", *H, &hs);
  if (st) return st;
  vector<double> counts(hs.size());
  for (size_t k = 0; k < hs.size(); k++) {
    uint64_t n = 0;
    st = check("rveFastUpdates point " + to_string(k), rve_fast_updates(hs[k], &n));
    if (st) return st;
    counts[k] = (double)n;
  }
  N->resize(hs.size());
  for (long k = 0; k < (long)hs.size(); k++) (*N)[k] = counts[k];
  return 0;
}
long rve_ff_commit(KN<double> *const &H) { return each<rve_commit, false>("rveCommit", H); }
long rve_ff_revert(KN<double> *const &H) { return each<rve_revert, false>("rveRevert", H); }
long rve_ff_free(KN<double> *const &H) { return each<rve_free, true>("rveFree", H); }

// ---- strings -------------------------------------------------------------------------
// A FreeFEM function of no argument returning the string Get() gives (copied).
const char *last_error_text() { return g_last_error.c_str(); }
double step_ratio() { return g_step_ratio; }
double error_estimate() { return g_error_estimate; }
template <const char *(*Get)()>
class StringOf : public E_F0mps {
 public:
  typedef string *Result;
  StringOf(const basicAC_F0 &args) { args.SetNameParam(0, 0, 0); }
  static ArrayOfaType typeargs() { return ArrayOfaType(); }
  static E_F0 *f(const basicAC_F0 &a) { return new StringOf(a); }
  AnyType operator()(Stack s) const {
    return SetAny<string *>(Add2StackOfPtr2Free(s, new string(Get())));
  }
  operator aType() const { return atype<string *>(); }
};
class StatusMessage : public E_F0mps {
 public:
  typedef string *Result;
  Expression st;
  StatusMessage(const basicAC_F0 &args) {
    args.SetNameParam(0, 0, 0);
    st = to<long>(args[0]);
  }
  static ArrayOfaType typeargs() { return ArrayOfaType(atype<long>()); }
  static E_F0 *f(const basicAC_F0 &a) { return new StatusMessage(a); }
  AnyType operator()(Stack s) const {
    long code = GetAny<long>((*st)(s));
    const char *m = (code < 0 || code > 0xffffffffL) ? "unknown status code"
                                                     : rve_status_message((uint32_t)code);
    return SetAny<string *>(Add2StackOfPtr2Free(s, new string(m)));
  }
  operator aType() const { return atype<string *>(); }
};

}  // namespace

static void Load_Init() {
  if (rve_abi_version() != RVE_ABI_VERSION) {
    cerr << "rve_ff: librve ABI " << rve_abi_version() << " but built against "
         << RVE_ABI_VERSION << endl;
    ExecError("rve_ff: librve ABI mismatch");
  }
  Global.Add("rveInit", "(", new OneOperator3_<long, string *, long, KN<double> *>(rve_ff_init));
  Global.Add("rveInitText", "(",
             new OneOperator4_<long, string *, string *, long, KN<double> *>(rve_ff_init_text));
  Global.Add("rveUpdate", "(", new OneOperatorCode<UpdateConsistent>());
  Global.Add("rveUpdateTimed", "(", new OneOperatorCode<UpdateTimed>());
  Global.Add("rveUpdateElastic", "(", new OneOperatorCode<UpdateElastic>());
  Global.Add("rveStress", "(", new OneOperatorCode<UpdateStress>());
  Global.Add("rveFastUpdates", "(",
             new OneOperator2_<long, KN<double> *, KN<double> *>(rve_ff_fast_updates));
  Global.Add("rveCommit", "(", new OneOperator1_<long, KN<double> *>(rve_ff_commit));
  Global.Add("rveRevert", "(", new OneOperator1_<long, KN<double> *>(rve_ff_revert));
  Global.Add("rveFree", "(", new OneOperator1_<long, KN<double> *>(rve_ff_free));
  Global.Add("rveLastError", "(", new OneOperatorCode<StringOf<last_error_text>>());
  Global.Add("rveStepRatio", "(", new OneOperator0<double>(step_ratio));
  Global.Add("rveErrorEstimate", "(", new OneOperator0<double>(error_estimate));
  Global.Add("rveVersion", "(", new OneOperatorCode<StringOf<rve_version>>());
  Global.Add("rveStatusMessage", "(", new OneOperatorCode<StatusMessage>());
}

LOADFUNC(Load_Init)
