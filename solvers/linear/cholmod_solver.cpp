// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (solvers/CMakeLists.txt defines
// HARAP_HAVE_CHOLMOD); register_solvers.cpp registers it under the same condition.
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_solver.h"

#include <cholmod.h>
#include <cholmod_modify.h>
#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "framework/error.h"
#include "solvers/linear/elimination_tree_solve.h"
#include "solvers/linear/partial_supernodal_factor.h"
#include "solvers/linear/solver_checks.h"

namespace harap {
namespace {

// Why mode = "auto" factors supernodally and then converts the factor to simplicial form: the
// supernodal (BLAS) factorization is 1.5–10× faster than the simplicial one, while solves with a
// simplicial factor are 1.3–3× faster (3 right-hand sides are too few for the dense supernodal
// blocks to pay). ARAP factors once and solves 5–300 times, so neither pure mode is right for all
// runs; converting (cholmod_change_factor, O(nnz(L))) gets the fast factorization and the fast
// solves. Measured (thread CPU time, OpenBLAS 1 thread,
// CHOLMOD 3.0.14 on a shared 2-vCPU Xeon; reduced cotangent Laplacians of jittered triangulated
// grids with two pinned 10×10 patches, and 7-point Laplacians of cubes with one face pinned, as
// tetrahedral meshes fill in); times are factorization / solve with 3 right-hand sides:
//
//   matrix           n     order  nnz(L)   f    simplicial LDLᵀ     supernodal LLᵀ      k*
//   2D grid 100²     9.8K  amd    0.22M   60      18 ms / 1.2 ms      18 ms / 3.7 ms      0
//   2D grid 224²     50K   amd    1.66M  144     177 ms / 10.5 ms    105 ms / 13.5 ms    24
//   2D grid 317²     100K  amd    3.85M  201     786 ms / 22.8 ms    246 ms / 31.3 ms    64
//   2D grid 417²     174K  amd    7.26M  251   1.3–1.9 s / 30–40 ms  0.32–0.50 s / 48–56 ms  48–111
//   2D grid 417²     174K  metis  6.14M  173   0.8–1.2 s / 28–35 ms  0.28–0.40 s / 47–54 ms  16–73
//   3D cube 20³      8K    metis  0.61M  234     145 ms / 2.7 ms      37 ms / 5.3 ms     41
//   3D cube 20³      8K    amd    0.84M  366     303 ms / 3.7 ms      45 ms / 6.2 ms    107
//   3D cube 25³      16K   metis  1.93M  442     899 ms / 8.9 ms     109 ms / 12.2 ms   245
//   3D cube 30³      27K   metis  4.13M  631    2.25 s / 13.3 ms     191 ms / 26.9 ms   151
//   3D cube 30³      27K   amd    5.61M  901    5.13 s / 21.1 ms     356 ms / 25.2 ms  1182
//
// k* = solves per factorization above which pure simplicial beats pure supernodal overall
// (ranges: repeated runs on a loaded VM, ±30%); "auto" needs no such break-even. See
// docs/benchmarks.md for the armadillo figures.

std::string_view OrderingName(int cholmod_ordering) {
  switch (cholmod_ordering) {
    case CHOLMOD_NATURAL:
      return "natural";
    case CHOLMOD_GIVEN:
      return "given";
    case CHOLMOD_AMD:
      return "amd";
    case CHOLMOD_METIS:
      return "metis";
    case CHOLMOD_NESDIS:
      return "nesdis";
    case CHOLMOD_COLAMD:
      return "colamd";
    case CHOLMOD_POSTORDERED:
      return "postordered";
    default:
      return "unknown";
  }
}

// A non-owning CHOLMOD view of an Eigen matrix. With stype = -1 CHOLMOD reads only the entries
// on and below the diagonal and ignores the upper ones, so full storage needs no copy.
cholmod_sparse LowerTriangleView(const SparseMatrix& a) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(a.rows());
  view.ncol = static_cast<size_t>(a.cols());
  view.nzmax = static_cast<size_t>(a.data().allocatedSize());
  // CHOLMOD's inputs are not const-qualified but analyze/factorize only read A.
  view.p = const_cast<int*>(a.outerIndexPtr());
  view.i = const_cast<int*>(a.innerIndexPtr());
  view.x = const_cast<double*>(a.valuePtr());
  view.nz = a.isCompressed() ? nullptr : const_cast<int*>(a.innerNonZeroPtr());
  view.stype = -1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;  // Eigen keeps the inner indices of each column sorted.
  view.packed = a.isCompressed() ? 1 : 0;
  return view;
}

// The same view without values, for CHOLMOD's analysis: the ordering and the symbolic
// factorization read only the pattern, and the transposes they make of A then copy no values.
cholmod_sparse PatternView(const SparseMatrix& a) {
  cholmod_sparse view = LowerTriangleView(a);
  view.x = nullptr;
  view.xtype = CHOLMOD_PATTERN;
  return view;
}

// A non-owning CHOLMOD view of `columns` packed, unsymmetric columns of `rows` rows in
// compressed column form (column_start, row_index, value; room for `capacity` entries), as
// cholmod_updown and cholmod_rowadd take their modifications.
cholmod_sparse ColumnsView(Index rows, size_t columns, int* column_start, int* row_index,
                           double* value, size_t capacity, bool sorted) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(rows);
  view.ncol = columns;
  view.nzmax = capacity;
  view.p = column_start;
  view.i = row_index;
  view.x = value;
  view.stype = 0;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = sorted ? 1 : 0;
  view.packed = 1;
  return view;
}

// Column j's pivot d_j (LDLᵀ) or L_jj² (LLᵀ) of a numeric factor, in the factor's order.
template <class Visit>
void ForEachPivot(const cholmod_factor& factor, Visit&& visit) {
  const auto* x = static_cast<const double*>(factor.x);
  if (factor.is_super) {
    const auto* super = static_cast<const int*>(factor.super);
    const auto* pi = static_cast<const int*>(factor.pi);
    const auto* px = static_cast<const int*>(factor.px);
    for (size_t s = 0; s < factor.nsuper; ++s) {
      const int first = super[s];
      const int rows = pi[s + 1] - pi[s];  // Leading dimension of the supernode's dense block.
      for (int j = first; j < super[s + 1]; ++j) {
        const double l = x[px[s] + static_cast<size_t>(j - first) * (rows + 1)];
        visit(j, l * l);
      }
    }
  } else {
    const auto* p = static_cast<const int*>(factor.p);
    for (size_t j = 0; j < factor.n; ++j) {
      const double d = x[p[j]];  // The diagonal is the first entry of each column.
      visit(static_cast<int>(j), factor.is_ll ? d * d : d);
    }
  }
}

// cholmod_solve2 on a simplicial factor asks for Y as max(4, k)×n (it solves 4 columns at a
// time, row-major) and then reshapes Y's header to the columns of the last chunk (3×n for k = 3).
// On the next call the shapes differ and it frees and reallocates Y, on every solve. Putting the
// header back before each call (the buffer is unchanged and large enough) keeps Solve()
// allocation-free; if a CHOLMOD version asks for another shape, it simply reallocates.
void RestoreSimplicialWorkspaceShape(const cholmod_factor* factor, Eigen::Index columns,
                                     cholmod_dense* y) {
  if (factor->is_super || y == nullptr) return;
  const size_t rows = std::max<size_t>(4, static_cast<size_t>(columns));
  if (y->nzmax < rows * factor->n) return;
  y->nrow = rows;
  y->ncol = factor->n;
  y->d = rows;
}

std::string OutOfMemoryMessage(std::string_view stage, const cholmod_common& common,
                               const SparseMatrix& a, CholmodSolver::Ordering ordering) {
  // After the analysis CHOLMOD knows nnz(L); a simplicial factor stores a value and a row index
  // per entry (a supernodal one a little more, for its dense blocks).
  const std::string factor_size =
      common.lnz > 0 ? fmt::format("; its Cholesky factor has {:.3g} nonzeros (at least {:.0f} MB)",
                                   common.lnz, common.lnz * 12.0 / 1e6)
                     : std::string();
  const std::string less_fill = ordering == CholmodSolver::Ordering::kMetis
                                    ? std::string()
                                    : ", or ordering = \"metis\" (less fill than AMD on meshes)";
  return fmt::format(
      "cholmod: out of memory during the {} of a {}×{} matrix with {} nonzeros{}. "
      "{}{}, or a coarser mesh.",
      stage, a.rows(), a.cols(), a.nonZeros(), factor_size, solver_checks::kOutOfMemoryAdvice,
      less_fill);
}

// OpenBLAS (Debian's BLAS for CHOLMOD) allocates a work buffer of 128 MiB of address space on a
// thread's first BLAS call and, if that allocation fails, retries forever. CHOLMOD's supernodal
// factorization makes its first BLAS call (dpotrf) only after allocating the factor, i.e. when
// memory may be nearly exhausted: under an address-space limit (`ulimit -v`) running out of
// memory then hung instead of failing (measured: built-in 200K-vertex cylinder, `ulimit -v`
// 525000–650000 kB; docs/robustness.md). So before the first supernodal factorization on a
// thread, probe whether twice that much can still be allocated and, if so, factor a 1×1 matrix
// supernodally: OpenBLAS allocates its buffer then, and keeps it for later calls. If the probe
// fails, the caller reports out of memory instead of entering OpenBLAS.
constexpr size_t kBlasBufferProbeBytes = size_t{256} << 20;

bool EnsureBlasWorkBuffer() {
  thread_local bool ready = false;
  if (ready) return true;
  void* probe = std::malloc(kBlasBufferProbeBytes);
  if (probe == nullptr) return false;
  std::free(probe);
  cholmod_common common;
  cholmod_start(&common);
  common.print = 0;
  common.error_handler = nullptr;
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_sparse* one = cholmod_speye(1, 1, CHOLMOD_REAL, &common);
  if (one != nullptr) {
    one->stype = -1;
    cholmod_factor* factor = cholmod_analyze(one, &common);
    if (factor != nullptr) ready = cholmod_factorize(one, factor, &common) != 0;
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&one, &common);
  }
  cholmod_finish(&common);
  return ready;
}

// CHOLMOD's own parallelism (Options::native_threads): the OpenMP loops of its supernodal
// factorization and the BLAS it calls. The controls are looked up at run time: they exist only
// when CHOLMOD was built with OpenMP and the BLAS behind libblas.so.3 is OpenBLAS, and harap
// itself is not compiled with -fopenmp (that would also switch on Eigen's OpenMP code paths).
struct NativeThreadControls {
  using GetInt = int (*)();
  using SetInt = void (*)(int);
  GetInt omp_get_dynamic = nullptr;
  GetInt omp_get_max_threads = nullptr;
  SetInt omp_set_dynamic = nullptr;
  SetInt omp_set_num_threads = nullptr;
  SetInt openblas_set_num_threads = nullptr;
  // As the environment set it, read before harap changed anything: native_threads = 0 restores
  // it.
  int default_blas_threads = 0;
  std::mutex blas_mutex;
  int applied_blas_threads = 0;

  static NativeThreadControls& Get() {
    static NativeThreadControls controls;
    return controls;
  }
  bool has_openmp() const { return omp_set_num_threads != nullptr; }

 private:
  NativeThreadControls() {
    const auto get = [](const char* name) {
      return reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, name));
    };
    const auto set = [](const char* name) {
      return reinterpret_cast<SetInt>(dlsym(RTLD_DEFAULT, name));
    };
    omp_get_dynamic = get("omp_get_dynamic");
    omp_get_max_threads = get("omp_get_max_threads");
    omp_set_dynamic = set("omp_set_dynamic");
    omp_set_num_threads = set("omp_set_num_threads");
    if (!omp_get_dynamic || !omp_get_max_threads || !omp_set_dynamic || !omp_set_num_threads) {
      omp_set_num_threads = nullptr;
    }
    const GetInt openblas_get_num_threads = get("openblas_get_num_threads");
    openblas_set_num_threads = set("openblas_set_num_threads");
    if (!openblas_get_num_threads || !openblas_set_num_threads) {
      openblas_set_num_threads = nullptr;
    } else {
      default_blas_threads = applied_blas_threads = openblas_get_num_threads();
    }
  }
};

// Caps CHOLMOD's own parallelism at `threads` (0: as the environment set it) while it lives.
//
// OpenMP's controls are per thread: this thread's are set, and restored at the end, so only the
// factorization is capped. CHOLMOD's loops say num_threads(4), which omp_set_num_threads alone
// does not override; with dynamic adjustment on, libgomp bounds the team by this thread's
// nthreads-var (OpenMP 5.2, §2.6.1: with dyn-var true the implementation may deliver fewer
// threads than requested). The solves are left alone: libgomp allocates a new team for every
// one-thread region (it caches only larger teams), and Solve() must not allocate.
//
// OpenBLAS's thread count is process-wide and not restored: it is set only when it changes, so
// concurrent factorizations with the same setting never touch it while another is inside BLAS.
class ScopedNativeThreads {
 public:
  explicit ScopedNativeThreads(int threads) : controls_(NativeThreadControls::Get()) {
    if (threads > 0 && controls_.has_openmp()) {
      saved_dynamic_ = controls_.omp_get_dynamic();
      saved_threads_ = controls_.omp_get_max_threads();
      controls_.omp_set_dynamic(1);
      controls_.omp_set_num_threads(threads);
    }
    if (controls_.openblas_set_num_threads != nullptr) {
      const int blas_threads = threads > 0 ? threads : controls_.default_blas_threads;
      const std::lock_guard lock(controls_.blas_mutex);
      if (blas_threads != controls_.applied_blas_threads) {
        controls_.openblas_set_num_threads(blas_threads);
        controls_.applied_blas_threads = blas_threads;
      }
    }
  }
  ~ScopedNativeThreads() {
    if (saved_threads_ > 0) {
      controls_.omp_set_dynamic(saved_dynamic_);
      controls_.omp_set_num_threads(saved_threads_);
    }
  }
  ScopedNativeThreads(const ScopedNativeThreads&) = delete;
  ScopedNativeThreads& operator=(const ScopedNativeThreads&) = delete;

 private:
  NativeThreadControls& controls_;
  int saved_dynamic_ = 0;
  int saved_threads_ = 0;  // 0: nothing to restore
};

bool SamePattern(const SparseMatrix& x, const SparseMatrix& y) {
  if (x.rows() != y.rows() || x.cols() != y.cols()) return false;
  for (Index j = 0; j < x.cols(); ++j) {
    const auto [xb, xe] = ColumnRange(x, j);
    const auto [yb, ye] = ColumnRange(y, j);
    if (xe - xb != ye - yb ||
        !std::equal(x.innerIndexPtr() + xb, x.innerIndexPtr() + xe, y.innerIndexPtr() + yb)) {
      return false;
    }
  }
  return true;
}

// Row (= column, `a` is symmetric) j of `a` is the identity's: what a handle's row becomes in
// the masked matrix, and what cholmod_rowdel leaves in the factor.
bool IsIdentityRow(const SparseMatrix& a, Index j) {
  const auto [begin, end] = ColumnRange(a, j);
  bool diagonal_one = false;
  for (Index e = begin; e < end; ++e) {
    const double value = a.valuePtr()[e];
    if (a.innerIndexPtr()[e] == j) {
      diagonal_one = value == 1.0;
    } else if (value != 0.0) {
      return false;
    }
  }
  return diagonal_one;
}

}  // namespace

struct CholmodSolver::Impl {
  explicit Impl(const Options& options) : options(options) {
    cholmod_start(&common);
    // Library code never prints: no messages, and errors come back through common.status.
    common.print = 0;
    common.error_handler = nullptr;
    // LDLᵀ for simplicial factors (CHOLMOD's default, kept explicit): no square roots, and the
    // pivots d_k are what the positive-definiteness check reads.
    common.final_ll = 0;
    switch (options.mode) {
      case Mode::kAuto:
        // Supernodal factorization, then converted by cholmod_factorize itself to a packed
        // simplicial LDLᵀ, re-symbolled so the explicit zeros of relaxed supernodes are dropped
        // (without final_resymbol the converted factor keeps them and solves ~35% slower).
        common.supernodal = CHOLMOD_SUPERNODAL;
        common.final_asis = 0;
        common.final_super = 0;
        common.final_pack = 1;
        common.final_monotonic = 1;
        common.final_resymbol = 1;
        break;
      case Mode::kSupernodal:
        common.supernodal = CHOLMOD_SUPERNODAL;
        break;
      case Mode::kSimplicial:
        common.supernodal = CHOLMOD_SIMPLICIAL;
        break;
    }
    switch (options.ordering) {
      case Ordering::kMetis:
        common.nmethods = 1;
        common.method[0].ordering = CHOLMOD_METIS;
        break;
      case Ordering::kAmd:
        common.nmethods = 1;
        common.method[0].ordering = CHOLMOD_AMD;
        break;
      case Ordering::kBest:
        common.nmethods = 0;
        break;  // AMD, then METIS if AMD fills a lot.
    }
    common.postorder = 1;
  }

  ~Impl() {
    FreeFactor();
    FreeSymbolic();
    FreeAnalysis();
    FreeSuper();
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_finish(&common);
  }

  // The numeric supernodal LLᵀ factorization of `a` into `f` (a supernodal analysis, or a
  // numeric supernodal factor of the same analysis), as cholmod_factorize's supernodal step
  // computes it: PartialSupernodalFactor::FactorAll runs the same left-looking algorithm
  // (bit-identical values) with independent subtrees on the context's threads, and reads A
  // through the permutation instead of making the permuted copies of A that cholmod_factorize
  // makes first (armadillo-bend's finest matrix: 0.093 s instead of 0.178 s; docs/solvers.md).
  // With native_threads ≠ 1 the BLAS has threads of its own: one thread here.
  // numeric = "cholmod": cholmod_factorize itself. False, with common.status and f->minor set as
  // CHOLMOD sets them, on failure.
  bool FactorSupernodal(cholmod_factor* f, cholmod_sparse& view, const SparseMatrix& a,
                        const Context& context) {
    if (options.numeric == Numeric::kCholmod) {
      const int final_asis = common.final_asis;
      common.final_asis = 1;  // keep the supernodal LLᵀ factor
      cholmod_factorize(&view, f, &common);
      common.final_asis = final_asis;
      return common.status == CHOLMOD_OK || common.status == CHOLMOD_DSMALL;
    }
    if (f->xtype == CHOLMOD_PATTERN &&
        !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/1, /*to_packed=*/1,
                               /*to_monotonic=*/1, f, &common)) {
      return false;  // out of memory (common.status says so)
    }
    const int n = static_cast<int>(f->n);
    const auto* perm = static_cast<const int*>(f->Perm);
    std::vector<int> inverse(n);
    for (int j = 0; j < n; ++j) inverse[perm ? perm[j] : j] = j;
    const SupernodalFactorView layout = SupernodalView(*f);
    const int threads = options.native_threads == 1 ? context.arena->max_concurrency() : 1;
    PartialSupernodalFactor numeric;
    // Each thread needs its own BLAS work buffer (see EnsureBlasWorkBuffer), the one that
    // Run() runs this on too (an arena worker if the caller's thread could not join the arena).
    // Out of memory in harap's own buffers is reported as CHOLMOD reports its own.
    constexpr int kNoMemory = -2;
    int bad_column = -1;
    try {
      bad_column = context.Run([&] {
        if (!EnsureBlasWorkBuffer()) return kNoMemory;
        return numeric.FactorAll(layout, a, inverse, threads, &EnsureBlasWorkBuffer);
      });
    } catch (const std::bad_alloc&) {
      bad_column = kNoMemory;
    }
    if (bad_column == kNoMemory) {
      common.status = CHOLMOD_OUT_OF_MEMORY;
      return false;
    }
    info.numeric_subtrees = numeric.subtrees();
    info.numeric_subtree_work = numeric.subtree_work_fraction();
    info.numeric_largest_subtree = numeric.largest_subtree_fraction();
    if (bad_column >= 0) {
      f->minor = static_cast<size_t>(bad_column);
      common.status = CHOLMOD_NOT_POSDEF;
      return false;
    }
    f->minor = f->n;
    common.status = CHOLMOD_OK;
    return true;
  }

  // Numeric supernodal factorization of `a` into the kept `super` (its analysis), left as the
  // supernodal LLᵀ for partial refactorization; on failure `super` becomes `factor` so
  // ThrowOnFailure reports the failed pivot.
  void FactorizeKeptSupernodal(cholmod_sparse& view, const SparseMatrix& a,
                               const Context& context) {
    if (!FactorSupernodal(super, view, a, context)) {
      FreeFactor();
      factor = super;
      super = nullptr;
      ThrowOnFailure("factorization", a);
    }
  }

  void FreeFactor() {
    if (factor) cholmod_free_factor(&factor, &common);
    factor = nullptr;
  }
  void FreeSymbolic() {
    if (symbolic) cholmod_free_factor(&symbolic, &common);
    symbolic = nullptr;
  }
  void FreeAnalysis() {
    if (analysis) cholmod_free_factor(&analysis, &common);
    analysis = nullptr;
    analysis_outer = {};
    analysis_inner = {};
  }

  // Whether compressed `a` has the pattern Analyze() was given.
  bool IsAnalysisPattern(const SparseMatrix& a) const {
    return static_cast<size_t>(a.outerSize()) + 1 == analysis_outer.size() &&
           static_cast<size_t>(a.nonZeros()) == analysis_inner.size() &&
           std::equal(analysis_outer.begin(), analysis_outer.end(), a.outerIndexPtr()) &&
           std::equal(analysis_inner.begin(), analysis_inner.end(), a.innerIndexPtr());
  }

  // The analysis (ordering, symbolic factor) of `a`, timed: Analyze()'s kept one if it was made
  // for this very pattern, else a new one.
  cholmod_factor* TakeOrMakeAnalysis(const SparseMatrix& a) {
    if (analysis != nullptr && a.isCompressed() && IsAnalysisPattern(a)) {
      cholmod_factor* kept = analysis;
      analysis = nullptr;
      analysis_outer = {};
      analysis_inner = {};
      common.lnz = analysis_of.lnz;  // restored: other CHOLMOD calls may have changed them
      common.fl = analysis_of.fl;
      info.analysis_seconds = analysis_of.seconds;
      return kept;
    }
    FreeAnalysis();
    const Stopwatch clock;
    cholmod_sparse pattern = PatternView(a);
    cholmod_factor* made = cholmod_analyze(&pattern, &common);
    ThrowOnFailure("analysis (ordering)", a);
    HARAP_CHECK(made != nullptr, "cholmod_analyze returned no factor (status {})", common.status);
    info.analysis_seconds = clock.Seconds();
    return made;
  }

  void FreeSuper() {
    if (super) cholmod_free_factor(&super, &common);
    super = nullptr;
    super_current = false;
  }
  // Keeps `super`, the numeric supernodal factor, for partial refactorizations: mode auto (the
  // solves use the simplicial factor made from it), route partial, or any route but full after
  // PrepareForRefactor() (set_refactor() may switch to partial later).
  bool keeps_super() const {
    return options.mode == Mode::kAuto && options.refactor != RefactorChoice::kFull &&
           (options.refactor == RefactorChoice::kPartial || prepared_for_refactor);
  }
  // A numeric supernodal factor as PartialSupernodalFactor reads it.
  static SupernodalFactorView SupernodalView(const cholmod_factor& f) {
    SupernodalFactorView view;
    view.n = static_cast<int>(f.n);
    view.num_supernodes = static_cast<int>(f.nsuper);
    view.first = static_cast<const int*>(f.super);
    view.row_start = static_cast<const int*>(f.pi);
    view.value_start = static_cast<const int*>(f.px);
    view.row = static_cast<const int*>(f.s);
    view.value = static_cast<double*>(f.x);
    view.permutation = static_cast<const int*>(f.Perm);
    return view;
  }
  SupernodalFactorView SuperView() const { return SupernodalView(*super); }

  // Factorize()'s numeric factorization when the supernodal factor is kept: the supernodal
  // factorization into `super` (a copy of the analysis), then `factor` made from a copy of it as
  // cholmod_factorize makes it (cholmod_change_factor to a packed simplicial LDLᵀ, then
  // cholmod_resymbol to drop the relaxed supernodes' zeros): the same values.
  void FactorNumericKeepingSuper(cholmod_sparse& view, const SparseMatrix& a,
                                 const Context& context) {
    const Stopwatch clock;
    FreeSuper();
    super = cholmod_copy_factor(factor, &common);
    ThrowOnFailure("copy of the analysis", a);
    FactorizeKeptSupernodal(view, a, context);
    FreeFactor();
    factor = cholmod_copy_factor(super, &common);
    ThrowOnFailure("copy of the factor", a);
    ConvertToFinal(view, a);
    super_current = true;
    partial.Setup(SuperView());
    info.numeric_seconds = clock.Seconds();
  }

  // Copies the columns of the supernodes `partial` marked (all if `all`) from `super` into the
  // simplicial LDLᵀ `factor` of the same analysis: d_j = L_jj², l_ij = L_ij / L_jj on the
  // simplicial pattern (a subset of the supernode's rows). False if the patterns do not match.
  bool CopySuperToSimplicial(bool all) {
    const auto* ls = static_cast<const int*>(super->s);
    const auto* pi = static_cast<const int*>(super->pi);
    const auto* px = static_cast<const int*>(super->px);
    const auto* first = static_cast<const int*>(super->super);
    const auto* sx = static_cast<const double*>(super->x);
    const auto* lp = static_cast<const int*>(factor->p);
    const auto* lnz = static_cast<const int*>(factor->nz);
    const auto* li = static_cast<const int*>(factor->i);
    auto* lx = static_cast<double*>(factor->x);
    const std::vector<char>& marked = partial.marked();
    for (size_t s = 0; s < super->nsuper; ++s) {
      if (!all && !marked[s]) continue;
      const int rows = pi[s + 1] - pi[s];
      for (int j = first[s]; j < first[s + 1]; ++j) {
        const int local = j - first[s];
        const double* column = sx + px[s] + static_cast<size_t>(local) * rows;
        const double diagonal = column[local];
        lx[lp[j]] = diagonal * diagonal;
        // Both row lists are sorted; the simplicial one is a subset of the supernode's.
        int r = local + 1;
        for (int e = lp[j] + 1; e < lp[j] + lnz[j]; ++e) {
          while (r < rows && ls[pi[s] + r] < li[e]) ++r;
          if (r == rows || ls[pi[s] + r] != li[e]) return false;
          lx[e] = column[r] / diagonal;
        }
      }
    }
    return true;
  }

  // Keeps copies for Refactor() (the matrix also for check_residual): with an explicit
  // numeric or update route, or with auto after PrepareForRefactor() (a one-shot run that never
  // refactors keeps nothing: ~110 bytes per vertex and the copying time on a surface mesh).
  bool keeps_copies() const {
    return options.refactor == RefactorChoice::kNumeric ||
           options.refactor == RefactorChoice::kUpdate ||
           options.refactor == RefactorChoice::kPartial ||
           (options.refactor == RefactorChoice::kAuto && prepared_for_refactor);
  }
  bool prepared_for_refactor = false;

  // The numeric factorization of `view` into `factor` (symbolic on entry), timed: a supernodal
  // analysis by FactorSupernodal(), then converted to the final kind as cholmod_factorize
  // converts it (mode auto: a packed simplicial LDLᵀ without the relaxed supernodes' zeros), a
  // simplicial one by cholmod_factorize.
  void FactorNumeric(cholmod_sparse& view, const SparseMatrix& a, const Context& context) {
    const Stopwatch clock;
    if (factor->is_super) {
      FactorSupernodal(factor, view, a, context);
      ThrowOnFailure("factorization", a);
      ConvertToFinal(view, a);
    } else {
      cholmod_factorize(&view, factor, &common);
      ThrowOnFailure("factorization", a);
    }
    info.numeric_seconds = clock.Seconds();
  }

  // What cholmod_factorize does after a supernodal factorization unless final_asis: the
  // conversion to the final kind of factor, and the re-symbolic pass of a simplicial one.
  void ConvertToFinal(cholmod_sparse& view, const SparseMatrix& a) {
    if (common.final_asis) return;
    if (!cholmod_change_factor(CHOLMOD_REAL, common.final_ll, common.final_super, common.final_pack,
                               common.final_monotonic, factor, &common)) {
      ThrowOnFailure("conversion of the factor", a);
    }
    if (common.final_resymbol && !factor->is_super &&
        !cholmod_resymbol(&view, nullptr, 0, common.final_pack, factor, &common)) {
      ThrowOnFailure("symbolic refactorization", a);
    }
  }

  // Mode auto's numeric refactorization into the current simplicial LDLᵀ factor's own arrays:
  // a supernodal LLᵀ factorization with a copy of the analysis, then d_j = L_jj² and
  // l_ij = L_ij / L_jj for the entries of the simplicial pattern. That is what cholmod_factorize's
  // conversion computes (cholmod_change_factor, then cholmod_resymbol to drop the relaxed
  // supernodes' zeros), but the pattern is known from the last factorization of the same
  // analysis, so neither the conversion's copy nor the re-symbolic pass is needed, and the
  // solve's plan stays valid. Returns false, before changing anything, if the factor is not
  // such a factor; throws like Factorize() (leaving the supernodal factor for the message).
  bool FactorNumericInPlace(cholmod_sparse& view, const SparseMatrix& a, const Context& context) {
    if (options.mode != Mode::kAuto || symbolic == nullptr || !symbolic->is_super ||
        factor == nullptr || factor->is_super || factor->is_ll || factor->n != symbolic->n) {
      return false;
    }
    const Stopwatch clock;
    // Into the kept supernodal factor if there is one (its structure is the analysis'), else a
    // copy of the analysis freed afterwards.
    if (super == nullptr || !keeps_super()) {
      FreeSuper();
      super = cholmod_copy_factor(symbolic, &common);
      if (super == nullptr) {
        ThrowOnFailure("copy of the analysis", a);
        return false;
      }
    }
    super_current = false;
    FactorizeKeptSupernodal(view, a, context);
    const bool matches = CopySuperToSimplicial(/*all=*/true);
    if (keeps_super() && matches) {
      super_current = true;
      if (!partial.ready()) partial.Setup(SuperView());
    } else {
      FreeSuper();
    }
    if (!matches) return false;  // the caller factors the usual way, overwriting the values
    info.numeric_seconds = clock.Seconds();
    return true;
  }

  // After a numeric factorization or modification: the pivot check, the statistics, the
  // parallel solve's plan (`same_arrays`: the factor was modified in place without changing its
  // pattern, so the plan only needs the new pivots; `same_pattern`: a numeric refactorization
  // with the same analysis, whose pattern EliminationTreeSolve::Rebind verifies), and the copy
  // of `a`.
  void FinishFactor(const SparseMatrix& a, const Eigen::VectorXd& diagonal, const Context& context,
                    bool same_arrays = false, bool same_pattern = false) {
    CheckPivots(a, diagonal);
    info.supernodal = factor->is_super != 0;
    info.ordering = OrderingName(factor->ordering);
    info.nnz_l = common.lnz;
    info.flops = common.fl;
    use_tree_solve = false;
    if (options.parallel_solve && !factor->is_super && !factor->is_ll) {
      const cholmod_factor& f = *factor;
      LdltFactorView view;
      view.n = static_cast<Index>(f.n);
      view.column_start = static_cast<const int*>(f.p);
      view.column_count = static_cast<const int*>(f.nz);
      view.row = static_cast<const int*>(f.i);
      view.value = static_cast<const double*>(f.x);
      view.permutation = static_cast<const int*>(f.Perm);
      const Stopwatch setup_clock;
      if (same_arrays && view.row != nullptr && tree_view.row == view.row &&
          tree_view.value == view.value && tree_view.column_start == view.column_start &&
          tree_view.column_count == view.column_count && tree_view.n == view.n) {
        tree_solve.RefreshPivots();
      } else if (!(same_pattern && tree_solve.Rebind(view))) {
        tree_solve.Setup(view, context.arena->max_concurrency());
        plan_seconds = setup_clock.Seconds();
      }
      tree_view = view;
      info.solve_setup_seconds = setup_clock.Seconds();
      use_tree_solve = true;
      info.solve_blocks = tree_solve.num_blocks();
      info.solve_critical_path = tree_solve.critical_path_fraction();
      ReleaseRowsOfOneShotFactor();
    }
    if (options.check_residual || keeps_copies()) {
      if (SamePattern(matrix, a) && matrix.isCompressed() && a.isCompressed()) {
        std::copy(a.valuePtr(), a.valuePtr() + a.nonZeros(), matrix.valuePtr());
      } else {
        matrix = a;
        matrix.makeCompressed();
      }
    }
    factorized = true;
  }

  // A one-shot factor (no analysis copy kept, so Refactor() can only factor anew) solved by the
  // tree: the tree solve holds its own, renumbered copy of the row indices and nothing reads
  // CHOLMOD's again (no cholmod_solve2, no update, no conversion; FreeFactor() frees a null
  // array), so they are freed: 4 bytes per factor entry, the largest array of a large run after
  // the factor's values (armadillo-bend-692k, classic: peak 1374 -> 1250 MB).
  void ReleaseRowsOfOneShotFactor() {
    if (!use_tree_solve || symbolic != nullptr || super != nullptr || keeps_copies() ||
        keeps_super() || factor == nullptr || factor->is_super || factor->i == nullptr) {
      return;
    }
    const size_t in_use = common.memory_inuse;
    factor->i = cholmod_free(factor->nzmax, sizeof(int), factor->i, &common);
    // CHOLMOD's workspace (Flag, Head, Iwork, Xwork: O(n)) too; any later call reallocates it.
    cholmod_free_work(&common);
    info.released_bytes = static_cast<double>(in_use - common.memory_inuse);
    tree_view.row = nullptr;  // same_arrays never matches a factor without rows
  }
  // Whether ReleaseRowsOfOneShotFactor() freed the rows of the current numeric factor (a
  // numeric simplicial factor has them otherwise).
  bool rows_released() const {
    return factor != nullptr && !factor->is_super && factor->xtype != CHOLMOD_PATTERN &&
           factor->i == nullptr;
  }

  // Throws for every failure status of the last CHOLMOD call; warnings other than NOT_POSDEF
  // (e.g. DSMALL) are left to the pivot check.
  void ThrowOnFailure(std::string_view stage, const SparseMatrix& a) const {
    switch (common.status) {
      case CHOLMOD_OK:
      case CHOLMOD_DSMALL:
        return;
      case CHOLMOD_OUT_OF_MEMORY:
        throw NumericalError(OutOfMemoryMessage(stage, common, a, options.ordering));
      case CHOLMOD_TOO_LARGE:
        throw NumericalError(fmt::format(
            "cholmod: the factor of the {}×{} matrix is too large for 32-bit indices (nnz(L) ≈ "
            "{:.3g}). {} or ordering = \"metis\".",
            a.rows(), a.cols(), common.lnz, solver_checks::kOutOfMemoryAdvice));
      case CHOLMOD_NOT_POSDEF: {
        const size_t minor = factor ? factor->minor : 0;
        const int row = factor && factor->Perm && minor < factor->n
                            ? static_cast<const int*>(factor->Perm)[minor]
                            : -1;
        throw NumericalError(fmt::format(
            "cholmod: the matrix is not positive definite: the {} factorization hit a "
            "non-positive pivot at column {} of the factor (row {} of the {}×{} matrix). {}",
            factor && factor->is_super ? "supernodal" : "simplicial", minor, row, a.rows(),
            a.cols(), solver_checks::kNotPositiveDefiniteAdvice));
      }
      default:
        throw InternalError(fmt::format("cholmod: {} failed with status {}", stage, common.status));
    }
  }

  // CHOLMOD's simplicial LDLᵀ accepts negative pivots (it handles some indefinite matrices) and
  // no factorization notices a pivot that is roundoff of a zero one (a singular matrix), so
  // check each pivot against the matching diagonal entry of A.
  void CheckPivots(const SparseMatrix& a, const Eigen::VectorXd& diagonal) const {
    const auto* perm = static_cast<const int*>(factor->Perm);
    int bad_column = -1;
    double bad_pivot = 0.0;
    ForEachPivot(*factor, [&](int column, double pivot) {
      if (bad_column >= 0) return;
      const int row = perm ? perm[column] : column;
      if (!solver_checks::AcceptablePivot(pivot, diagonal[row], options.pivot_tolerance)) {
        bad_column = column;
        bad_pivot = pivot;
      }
    });
    if (bad_column < 0) return;
    const int row = perm ? perm[bad_column] : bad_column;
    solver_checks::ThrowBadPivot("cholmod", a.rows(), bad_column, row, bad_pivot, diagonal[row],
                                 options.pivot_tolerance);
  }

  // Measures a solution's residual if asked to (LinearSolver::Solve() checks and times it).
  SolveSummary FinishSolve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                           const Eigen::Ref<Eigen::MatrixXd>& x) {
    SolveSummary summary;
    if (options.check_residual && x.allFinite()) {
      summary.relative_residual = solver_checks::MaxRelativeResidual(matrix, b, x, residual);
      summary.outcome = SolveOutcome::kSolvedChecked;
    }
    return summary;
  }

  Options options;
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // With keeps_copies(): the analysis of the last Factorize() (a symbolic factor), which
  // Refactor() factors anew.
  cholmod_factor* symbolic = nullptr;
  // Analyze()'s analysis, until the Factorize() of the same matrix takes it.
  cholmod_factor* analysis = nullptr;
  std::vector<int> analysis_outer, analysis_inner;  // its pattern, compressed (no values)
  struct {
    double lnz = 0.0, fl = 0.0, seconds = 0.0;
  } analysis_of;
  // With keeps_super(): the numeric supernodal LLᵀ factor `factor` was made from (current: no
  // update modified `factor` since), and the partial refactorization's structure and last
  // measured speed.
  cholmod_factor* super = nullptr;
  bool super_current = false;
  PartialSupernodalFactor partial;
  double partial_seconds_per_flop = kDefaultPartialSecondsPerFlop;
  // Seconds per factor entry touched by the deletions (cholmod_updown) and the additions
  // (cholmod_rowadd), as the last update measured them (see Refactor()).
  double delete_seconds_per_entry = kDefaultDeleteSecondsPerEntry;
  double add_seconds_per_entry = kDefaultAddSecondsPerEntry;
  // Wall time of the last full set-up of the parallel solve's plan, which additions cause.
  double plan_seconds = 0.0;
  // Solve workspaces, kept so that Solve() allocates only on its first call (per column count).
  cholmod_dense* x = nullptr;
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;
  // With parallel_solve and a simplicial factor: solves with `factor` in place.
  EliminationTreeSolve tree_solve;
  LdltFactorView tree_view;  // the arrays tree_solve was set up with
  bool use_tree_solve = false;
  int rows = 0;
  bool factorized = false;
  FactorInfo info;
  // The last factored matrix: with check_residual (for the residual) or keeps_copies() (for
  // Refactor(): the pattern check and the changed rows' old values).
  SparseMatrix matrix;
  Eigen::MatrixXd residual;
  // Refactor() workspaces (factor order): path costs, the inverse permutation, marks, and the
  // row handed to cholmod_rowadd / cholmod_rowdel.
  std::vector<double> path_cost;
  std::vector<int> inverse_permutation, mark, row_index;
  std::vector<double> row_value;
  std::vector<int> update_start, update_row;  // the columns of the deletions' update
  std::vector<double> update_value;
};

namespace {

// The option names, for FromConfig() and ToString().
constexpr EnumNames<CholmodSolver::Mode, 3> kModeNames = {{
    {CholmodSolver::Mode::kAuto, "auto"},
    {CholmodSolver::Mode::kSimplicial, "simplicial"},
    {CholmodSolver::Mode::kSupernodal, "supernodal"},
}};
constexpr EnumNames<CholmodSolver::Ordering, 3> kOrderingNames = {{
    {CholmodSolver::Ordering::kMetis, "metis"},
    {CholmodSolver::Ordering::kAmd, "amd"},
    {CholmodSolver::Ordering::kBest, "best"},
}};
constexpr EnumNames<CholmodSolver::Numeric, 2> kNumericNames = {{
    {CholmodSolver::Numeric::kParallel, "parallel"},
    {CholmodSolver::Numeric::kCholmod, "cholmod"},
}};
constexpr EnumNames<CholmodSolver::RefactorChoice, 5> kRefactorNames = {{
    {CholmodSolver::RefactorChoice::kAuto, "auto"},
    {CholmodSolver::RefactorChoice::kFull, "full"},
    {CholmodSolver::RefactorChoice::kNumeric, "numeric"},
    {CholmodSolver::RefactorChoice::kUpdate, "update"},
    {CholmodSolver::RefactorChoice::kPartial, "partial"},
}};

}  // namespace

CholmodSolver::Options CholmodSolver::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.mode = node.GetEnum("mode", options.mode, kModeNames,
                              "simplicial = up-looking LDLᵀ, supernodal = BLAS LLᵀ (fastest "
                              "factorization, slower 3-column solves), auto = supernodal "
                              "factorization converted to simplicial form for the solves (both "
                              "fast)");
  options.ordering = node.GetEnum("ordering", options.ordering, kOrderingNames,
                                  "fill-reducing ordering; best = CHOLMOD's default (AMD, then "
                                  "METIS if AMD fills a lot)");
  options.parallel_solve =
      node.Get("parallel_solve", options.parallel_solve,
               "solve with a simplicial factor by substitution over independent subtrees of the "
               "elimination tree on all threads (false = CHOLMOD's sequential cholmod_solve2)");
  solver_checks::ReadFactorizationOptions(node, options.pivot_tolerance, options.check_residual);
  options.refactor = node.GetEnum(
      "refactor", options.refactor, kRefactorNames,
      "how Refactor() (handle edits of a session) updates the factor: numeric = reuse the "
      "analysis, factor the values; update = modify the factor row by row (cholmod_rowdel/rowadd; "
      "not with mode supernodal); partial = refactor only the supernodes the changed rows reach "
      "(mode auto; keeps the supernodal factor); auto = the cheapest of these by estimates from "
      "the factor's elimination tree and measured times; full = factor from scratch (keeps no "
      "copies)");
  options.numeric = node.GetEnum(
      "numeric", options.numeric, kNumericNames,
      "who computes a supernodal numeric factorization: parallel = harap's left-looking "
      "factorization (CHOLMOD's algorithm and values, independent subtrees on the run's threads, "
      "no permuted copies of A); cholmod = cholmod_factorize");
  options.native_threads = node.Get(
      "native_threads", options.native_threads,
      "threads for CHOLMOD's OpenMP loops and its BLAS (0: as the environment sets them; harap's "
      "own parallelism is TBB's, which native threads compete with)");
  node.RejectUnknownKeys();
  if (options.refactor == RefactorChoice::kUpdate && options.mode == Mode::kSupernodal) {
    throw ConfigError(fmt::format(
        "{}: refactor = \"update\" modifies a simplicial LDLᵀ factor, but mode = \"supernodal\" "
        "keeps a supernodal one; use mode = \"auto\" or \"simplicial\", or refactor = "
        "\"numeric\"",
        node.Where("refactor")));
  }
  if (options.native_threads < 0) {
    throw ConfigError(fmt::format("{}: native_threads must be >= 0, got {}",
                                  node.Where("native_threads"), options.native_threads));
  }
  return options;
}

CholmodSolver::CholmodSolver(const Options& options)
    : LinearSolver(kName), impl_(std::make_unique<Impl>(options)) {
  // Early, while memory is likely still free (see EnsureBlasWorkBuffer); Factorize checks again.
  if (options.mode != Mode::kSimplicial) EnsureBlasWorkBuffer();
}

CholmodSolver::~CholmodSolver() = default;

const CholmodSolver::Options& CholmodSolver::options() const { return impl_->options; }

const CholmodSolver::FactorInfo& CholmodSolver::factor_info() const { return impl_->info; }

void CholmodSolver::PrepareForRefactor() { impl_->prepared_for_refactor = true; }

void CholmodSolver::set_refactor(RefactorChoice choice) {
  HARAP_CHECK(choice != RefactorChoice::kUpdate || impl_->options.mode != Mode::kSupernodal,
              "refactor = \"update\" needs a simplicial factor (mode auto or simplicial)");
  impl_->options.refactor = choice;
}

std::string_view CholmodSolver::ToString(Mode mode) { return NameOf(kModeNames, mode); }

std::string_view CholmodSolver::ToString(Ordering ordering) {
  return NameOf(kOrderingNames, ordering);
}

std::string_view CholmodSolver::ToString(RefactorChoice choice) {
  return NameOf(kRefactorNames, choice);
}

void CholmodSolver::FactorizeImpl(const SparseMatrix& a, const Context& context) {
  Impl& impl = *impl_;
  impl.factorized = false;
  impl.use_tree_solve = false;
  impl.FreeFactor();
  impl.FreeSymbolic();
  impl.FreeSuper();
  impl.partial = PartialSupernodalFactor();
  impl.info = FactorInfo{};
  impl.matrix = SparseMatrix();
  impl.rows = static_cast<int>(a.rows());
  if (impl.rows == 0) {
    impl.factorized = true;
    return;
  }

  // A diagonal entry ≤ 0 already rules out positive definiteness; the entries also scale the
  // pivot check.
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "cholmod");

  if (impl.options.mode != Mode::kSimplicial && !EnsureBlasWorkBuffer()) {
    throw NumericalError(fmt::format(
        "cholmod: out of memory before the supernodal factorization of a {}×{} matrix: less "
        "than {} MiB of address space is left for BLAS's work buffer. Try mode = \"simplicial\" "
        "(no BLAS), or {}.",
        a.rows(), a.cols(), kBlasBufferProbeBytes >> 20,
        solver_checks::kOutOfMemoryAdvice.substr(4)));  // "an iterative solver ..."
  }
  const ScopedNativeThreads native_threads(impl.options.native_threads);
  cholmod_sparse view = LowerTriangleView(a);
  impl.factor = impl.TakeOrMakeAnalysis(a);
  if (impl.keeps_copies()) {
    const Stopwatch copy_clock;  // the copy for Refactor() counts as analysis too
    const size_t in_use = impl.common.memory_inuse;
    impl.symbolic = cholmod_copy_factor(impl.factor, &impl.common);
    impl.ThrowOnFailure("copy of the analysis", a);
    impl.info.refactor_bytes = static_cast<double>(impl.common.memory_inuse - in_use) +
                               static_cast<double>(a.nonZeros()) * (sizeof(double) + sizeof(int)) +
                               static_cast<double>(a.cols() + 1) * sizeof(int);
    impl.info.analysis_seconds += copy_clock.Seconds();
  }
  if (impl.keeps_super() && impl.factor->is_super) {
    impl.FactorNumericKeepingSuper(view, a, context);
    impl.info.refactor_bytes += static_cast<double>(impl.super->xsize) * sizeof(double);
  } else {
    impl.FactorNumeric(view, a, context);
  }
  impl.FinishFactor(a, diagonal, context);
}

CholmodSolver::Estimate CholmodSolver::Analyze(const SparseMatrix& a) {
  HARAP_CHECK(a.rows() == a.cols(), "matrix is {}×{}, not square", a.rows(), a.cols());
  Impl& impl = *impl_;
  impl.FreeAnalysis();
  Estimate estimate;
  if (a.rows() == 0) return estimate;
  const ScopedNativeThreads native_threads(impl.options.native_threads);
  cholmod_sparse view = PatternView(a);
  const Stopwatch clock;
  impl.analysis = cholmod_analyze(&view, &impl.common);
  impl.ThrowOnFailure("analysis (ordering)", a);
  HARAP_CHECK(impl.analysis != nullptr, "cholmod_analyze returned no factor (status {})",
              impl.common.status);
  estimate.analysis_seconds = clock.Seconds();
  estimate.nnz_l = impl.common.lnz;
  estimate.flops = impl.common.fl;
  // A simplicial factor stores a value and a row index per entry plus O(n) column data; the
  // supernodal factor of modes auto and supernodal pads relaxed supernodes, which CHOLMOD's
  // analysis sizes exactly (xsize entries, ssize row indices).
  const cholmod_factor& f = *impl.analysis;
  const double entries =
      f.is_super ? std::max(static_cast<double>(f.xsize), estimate.nnz_l) : estimate.nnz_l;
  estimate.factor_bytes =
      entries * sizeof(double) +
      (f.is_super ? static_cast<double>(f.ssize) : estimate.nnz_l) * sizeof(int) +
      static_cast<double>(a.rows()) * 4 * sizeof(int);
  impl.analysis_of = {impl.common.lnz, impl.common.fl, estimate.analysis_seconds};
  // The pattern, to recognize the matrix (or a copy of it) in Factorize(); without the values
  // (a third of a copy of `a`).
  SparseMatrix compressed;
  const SparseMatrix* pattern = &a;
  if (!a.isCompressed()) {
    compressed = a;
    compressed.makeCompressed();
    pattern = &compressed;
  }
  impl.analysis_outer.assign(pattern->outerIndexPtr(),
                             pattern->outerIndexPtr() + pattern->outerSize() + 1);
  impl.analysis_inner.assign(pattern->innerIndexPtr(),
                             pattern->innerIndexPtr() + pattern->nonZeros());
  return estimate;
}

LinearSolver::RefactorSummary CholmodSolver::RefactorImpl(const SparseMatrix& a,
                                                          const std::vector<Index>& changed_rows,
                                                          const Context& context) {
  const Stopwatch clock;
  Impl& impl = *impl_;
  RefactorSummary summary;
  summary.changed_rows = static_cast<Index>(changed_rows.size());
  const auto full = [&] {
    Factorize(a, context);
    summary.route = RefactorRoute::kFull;
    summary.seconds = clock.Seconds();
    return summary;
  };
  // Without a factorization of the same pattern to start from, there is nothing to reuse.
  if (!impl.factorized || impl.symbolic == nullptr || impl.rows == 0 ||
      impl.options.refactor == RefactorChoice::kFull || !SamePattern(impl.matrix, a)) {
    return full();
  }
  const Index n = impl.rows;
  for (size_t k = 0; k < changed_rows.size(); ++k) {
    HARAP_CHECK(changed_rows[k] >= 0 && changed_rows[k] < n &&
                    (k == 0 || changed_rows[k] > changed_rows[k - 1]),
                "Refactor: changed_rows must be sorted, unique and in [0, {}); entry {} is {}", n,
                k, changed_rows[k]);
  }
  // The contract: values differ only in the changed rows and columns. The update route relies
  // on it, so a caller's mistake is an error, not a wrong factor.
  std::vector<int>& changed = impl.mark;
  changed.assign(n, 0);
  for (Index r : changed_rows) changed[r] = 1;
  for (Index j = 0; j < n; ++j) {
    if (changed[j]) continue;
    const auto [begin, end] = ColumnRange(a, j);
    const auto [old_begin, old_end] = ColumnRange(impl.matrix, j);
    for (Index e = begin, o = old_begin; e < end; ++e, ++o) {
      const Index i = a.innerIndexPtr()[e];
      HARAP_CHECK(changed[i] || a.valuePtr()[e] == impl.matrix.valuePtr()[o],
                  "Refactor: entry ({}, {}) changed from {} to {}, but neither row {} nor row {} "
                  "is in changed_rows",
                  i, j, impl.matrix.valuePtr()[o], a.valuePtr()[e], i, j);
    }
  }
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "cholmod");

  // What an update would touch (see the header for the rule).
  const bool can_update = !impl.factor->is_super && !impl.factor->is_ll;
  const bool can_partial = impl.super != nullptr && impl.super_current && impl.keeps_super();
  RefactorChoice route = impl.options.refactor;
  if (route == RefactorChoice::kUpdate && !can_update) route = RefactorChoice::kNumeric;
  if (route == RefactorChoice::kPartial && !can_partial) route = RefactorChoice::kNumeric;
  impl.info.estimated_update_seconds = 0.0;
  impl.info.estimated_partial_seconds = 0.0;
  impl.info.estimated_numeric_seconds = impl.info.numeric_seconds;
  const cholmod_factor& f = *impl.factor;
  const auto* lp = static_cast<const int*>(f.p);
  const auto* lnz = static_cast<const int*>(f.nz);
  const auto* li = static_cast<const int*>(f.i);
  const auto* perm = static_cast<const int*>(f.Perm);
  const auto parent = [&](int j) { return lnz[j] > 1 ? li[lp[j] + 1] : -1; };
  impl.inverse_permutation.resize(n);
  for (Index j = 0; j < n; ++j) impl.inverse_permutation[perm ? perm[j] : j] = static_cast<int>(j);
  // The partial refactorization's share of the work (PartialSupernodalFactor::Mark) and time:
  // its flops at the speed of the last partial refactorization (before any: the default).
  double partial_fraction = 0.0;
  if (can_partial && (route == RefactorChoice::kPartial || route == RefactorChoice::kAuto)) {
    std::vector<int>& columns = impl.row_index;
    columns.clear();
    for (Index r : changed_rows) columns.push_back(impl.inverse_permutation[r]);
    partial_fraction = impl.partial.Mark(impl.SuperView(), columns);
    impl.info.partial_work_fraction = partial_fraction;
    impl.info.partial_supernodes = impl.partial.marked_supernodes();
    impl.info.estimated_partial_seconds =
        impl.partial.marked_work() * impl.partial_seconds_per_flop;
  }
  // Entries the deletions and the additions would touch (see the header for the rule).
  double delete_entries = 0.0, add_entries = 0.0;
  if (can_update) {
    // path_cost[j]: the factor entries in the columns from j up to the root (parents have
    // larger indices, so one descending sweep).
    impl.path_cost.resize(n);
    for (Index j = n; j-- > 0;) {
      const int p = parent(static_cast<int>(j));
      impl.path_cost[j] = lnz[j] + (p >= 0 ? impl.path_cost[p] : 0.0);
    }
    // A deletion's column of the update starts at its first row that is not deleted too.
    std::vector<int>& deleted = impl.mark;  // `changed` is no longer needed
    std::fill(deleted.begin(), deleted.end(), 0);
    for (Index r : changed_rows) {
      if (!IsIdentityRow(impl.matrix, r)) deleted[impl.inverse_permutation[r]] = 1;
    }
    for (Index r : changed_rows) {
      const int k = impl.inverse_permutation[r];
      if (deleted[k]) {
        for (int e = lp[k] + 1; e < lp[k] + lnz[k]; ++e) {
          if (deleted[li[e]]) continue;
          delete_entries += impl.path_cost[li[e]];
          break;
        }
      }
      if (!IsIdentityRow(a, r)) {
        double forward = 0.0;
        const auto [begin, end] = ColumnRange(a, r);
        for (Index e = begin; e < end; ++e) {
          const int i = impl.inverse_permutation[a.innerIndexPtr()[e]];
          if (i < k) forward = std::max(forward, impl.path_cost[i] - impl.path_cost[k]);
        }
        add_entries += forward + impl.path_cost[k];
      }
    }
    // Additions move columns of a packed factor, so the parallel solve's plan is set up again.
    const double plan = add_entries > 0.0 && impl.use_tree_solve ? impl.plan_seconds : 0.0;
    impl.info.estimated_update_seconds = delete_entries * impl.delete_seconds_per_entry +
                                         add_entries * impl.add_seconds_per_entry + plan;
  }
  if (route == RefactorChoice::kAuto) {
    // The lowest estimate of the routes this factor allows (see the header).
    route = RefactorChoice::kNumeric;
    double best = impl.info.estimated_numeric_seconds;
    if (can_partial && impl.info.estimated_partial_seconds < best) {
      route = RefactorChoice::kPartial;
      best = impl.info.estimated_partial_seconds;
    }
    if (can_update && impl.info.estimated_update_seconds < best) route = RefactorChoice::kUpdate;
  }

  // From here on the old factor is being replaced: a throw leaves the solver unfactored.
  impl.factorized = false;
  impl.use_tree_solve = false;
  if (route == RefactorChoice::kPartial) {
    if (!EnsureBlasWorkBuffer()) return full();
    const ScopedNativeThreads native_threads(impl.options.native_threads);
    const Stopwatch partial_clock;
    const int bad_column = impl.partial.Refactor(impl.SuperView(), a, impl.inverse_permutation);
    // A non-positive pivot (`a` is not positive definite): Factorize() says so in detail.
    if (bad_column >= 0 || !impl.CopySuperToSimplicial(/*all=*/false)) {
      impl.FreeSuper();
      return full();
    }
    // Calibrate on refactorizations large enough to time.
    constexpr double kCalibrationFlops = 1e7;
    if (impl.partial.marked_work() >= kCalibrationFlops) {
      impl.partial_seconds_per_flop = partial_clock.Seconds() / impl.partial.marked_work();
    }
    impl.FinishFactor(a, diagonal, context, /*same_arrays=*/true);
    summary.route = RefactorRoute::kPartial;
    summary.seconds = clock.Seconds();
    return summary;
  }
  if (route == RefactorChoice::kNumeric) {
    if (impl.options.mode != Mode::kSimplicial && !EnsureBlasWorkBuffer()) return full();
    const ScopedNativeThreads native_threads(impl.options.native_threads);
    cholmod_sparse view = LowerTriangleView(a);
    if (impl.FactorNumericInPlace(view, a, context)) {
      impl.FinishFactor(a, diagonal, context, /*same_arrays=*/true);
    } else {
      // E.g. a factor whose pattern updates changed: factored from a copy of the analysis
      // (keeping the supernodal factor again if kept at all).
      impl.FreeFactor();
      impl.factor = cholmod_copy_factor(impl.symbolic, &impl.common);
      impl.ThrowOnFailure("copy of the analysis", a);
      if (impl.keeps_super()) {
        impl.FactorNumericKeepingSuper(view, a, context);
      } else {
        impl.FreeSuper();
        impl.FactorNumeric(view, a, context);
      }
      impl.FinishFactor(a, diagonal, context, /*same_arrays=*/false, /*same_pattern=*/true);
    }
    summary.route = RefactorRoute::kNumeric;
    summary.seconds = clock.Seconds();
    return summary;
  }

  // kUpdate. First every changed row k that is not already the identity's becomes it, all at
  // once: with F the other rows, the old P A Pᵀ restricted to F is
  //   Σ_j d_j L(F,j) L(F,j)ᵀ = L̃ D̃ L̃ᵀ (F,F) + Σ_k d_k L(F,k) L(F,k)ᵀ,
  // where L̃, D̃ are L, D with the deleted rows and columns replaced by the identity's. So
  // setting those rows and columns to the identity's and updating with the columns
  // sqrt(d_k) L(F,k) (cholmod_updown, up to 8 columns per sweep along the elimination tree)
  // gives the factor of `a` with all changed rows and columns replaced by the identity's, since
  // `a` and the old matrix differ only there. Then each changed row that is not the
  // identity's in `a` is added (cholmod_rowadd) with its entries in the rows already added,
  // which keeps that invariant.
  impl.super_current = false;  // the kept supernodal factor no longer matches
  const double reallocations_before = impl.common.nrealloc_col;
  const auto fail = [&](std::string_view stage) {
    impl.ThrowOnFailure(stage, a);
    throw InternalError(
        fmt::format("cholmod: {} failed with status {}", stage, impl.common.status));
  };
  Stopwatch phase_clock;
  std::vector<int>& deleted = impl.mark;  // `changed` is no longer needed
  std::fill(deleted.begin(), deleted.end(), 0);
  std::vector<int>& deletions = impl.row_index;
  deletions.clear();
  for (Index r : changed_rows) {
    if (IsIdentityRow(impl.matrix, r)) continue;
    deletions.push_back(impl.inverse_permutation[r]);
    deleted[impl.inverse_permutation[r]] = 1;
  }
  if (!deletions.empty()) {
    auto* lx = static_cast<double*>(impl.factor->x);
    std::vector<int>& cp = impl.update_start;
    std::vector<int>& ci = impl.update_row;
    std::vector<double>& cx = impl.update_value;
    cp.assign(1, 0);
    ci.clear();
    cx.clear();
    for (int k : deletions) {
      const double scale = std::sqrt(lx[lp[k]]);  // d_k > 0: the old factor passed the checks
      for (int e = lp[k] + 1; e < lp[k] + lnz[k]; ++e) {
        if (deleted[li[e]]) continue;
        ci.push_back(li[e]);
        cx.push_back(lx[e] * scale);
      }
      if (static_cast<int>(ci.size()) > cp.back()) cp.push_back(static_cast<int>(ci.size()));
    }
    // L̃, D̃: one pass over the factor (cheaper than searching each deleted row's columns).
    for (Index j = 0; j < n; ++j) {
      if (deleted[j]) {
        lx[lp[j]] = 1.0;
        std::fill(lx + lp[j] + 1, lx + lp[j] + lnz[j], 0.0);
        continue;
      }
      for (int e = lp[j] + 1; e < lp[j] + lnz[j]; ++e) {
        if (deleted[li[e]]) lx[e] = 0.0;
      }
    }
    if (cp.size() > 1) {
      // The factor's columns are sorted.
      cholmod_sparse c = ColumnsView(n, cp.size() - 1, cp.data(), ci.data(), cx.data(), ci.size(),
                                     /*sorted=*/true);
      if (!cholmod_updown(1, &c, impl.factor, &impl.common)) fail("update (cholmod_updown)");
    }
  }
  const double delete_seconds = phase_clock.Seconds();
  phase_clock.Restart();

  std::vector<int>& pending = impl.mark;
  std::fill(pending.begin(), pending.end(), 0);
  for (Index r : changed_rows) pending[r] = 1;
  std::vector<int>& rows = impl.row_index;
  std::vector<double>& values = impl.row_value;
  int column_start[2] = {0, 0};
  for (Index r : changed_rows) {
    pending[r] = 0;
    if (IsIdentityRow(a, r)) continue;
    rows.clear();
    values.clear();
    const auto [begin, end] = ColumnRange(a, r);
    for (Index e = begin; e < end; ++e) {
      const Index i = a.innerIndexPtr()[e];
      if (pending[i]) continue;
      rows.push_back(impl.inverse_permutation[i]);
      values.push_back(a.valuePtr()[e]);
    }
    column_start[1] = static_cast<int>(rows.size());
    cholmod_sparse column = ColumnsView(n, 1, column_start, rows.data(), values.data(),
                                        std::max<size_t>(rows.size(), 1), /*sorted=*/false);
    if (!cholmod_rowadd(static_cast<size_t>(impl.inverse_permutation[r]), &column, impl.factor,
                        &impl.common)) {
      fail("row addition (cholmod_rowadd)");
    }
  }
  const double add_seconds = phase_clock.Seconds();
  // Calibrate on modifications large enough to time (a few milliseconds at least).
  constexpr double kCalibrationEntries = 1e6;
  if (delete_entries >= kCalibrationEntries) {
    impl.delete_seconds_per_entry = delete_seconds / delete_entries;
  }
  if (add_entries >= kCalibrationEntries) impl.add_seconds_per_entry = add_seconds / add_entries;
  // The pattern holds every entry a row can need, but cholmod_rowadd makes room for one more
  // in every column of its forward solve that has no slack (all of them in a packed factor),
  // moving it to the end of the factor's arrays: its solve plan must then be set up anew.
  // Moved columns stay below the tail L->p[n], which is all EliminationTreeSolve reads; if
  // a CHOLMOD version did otherwise, pack the factor first.
  const bool moved = impl.common.nrealloc_col != reallocations_before || !impl.factor->is_monotonic;
  if (moved) {
    const auto* start = static_cast<const int*>(impl.factor->p);
    const auto* count = static_cast<const int*>(impl.factor->nz);
    bool below_tail = true;
    for (Index j = 0; j < n && below_tail; ++j) below_tail = start[j] + count[j] <= start[n];
    if (!below_tail && !cholmod_change_factor(CHOLMOD_REAL, impl.factor->is_ll, 0, 1, 1,
                                              impl.factor, &impl.common)) {
      fail("packing of the modified factor");
    }
  }
  impl.FinishFactor(a, diagonal, context, /*same_arrays=*/!moved);
  summary.route = RefactorRoute::kUpdate;
  summary.seconds = clock.Seconds();
  return summary;
}

SolveSummary CholmodSolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                      Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  Impl& impl = *impl_;
  // A Refactor() that failed midway leaves no factor (LinearSolver only knows the last call
  // threw).
  HARAP_CHECK(impl.factorized, "cholmod: Solve() needs a successful Factorize() first");
  if (impl.use_tree_solve) {
    impl.tree_solve.Solve(b, x, context);
    return impl.FinishSolve(b, x);
  }

  HARAP_CHECK(!impl.rows_released(), "cholmod: the factor's rows were released for the tree solve");
  // B wraps b's memory; cholmod_solve2 only reads it (permuting it into the Y workspace).
  cholmod_dense rhs{};
  rhs.nrow = static_cast<size_t>(b.rows());
  rhs.ncol = static_cast<size_t>(b.cols());
  rhs.d = static_cast<size_t>(b.outerStride());
  rhs.nzmax = rhs.d * rhs.ncol;
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  RestoreSimplicialWorkspaceShape(impl.factor, b.cols(), impl.y);
  if (!cholmod_solve2(CHOLMOD_A, impl.factor, &rhs, nullptr, &impl.x, nullptr, &impl.y, &impl.e,
                      &impl.common)) {
    if (impl.common.status == CHOLMOD_OUT_OF_MEMORY) {
      throw NumericalError(
          fmt::format("cholmod: out of memory allocating the {}×{} solve workspaces. {}.", b.rows(),
                      b.cols(), solver_checks::kOutOfMemoryAdvice));
    }
    throw InternalError(fmt::format("cholmod: solve failed with status {}", impl.common.status));
  }
  x = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(
      static_cast<const double*>(impl.x->x), b.rows(), b.cols(),
      Eigen::OuterStride<>(static_cast<Eigen::Index>(impl.x->d)));
  return impl.FinishSolve(b, x);
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
