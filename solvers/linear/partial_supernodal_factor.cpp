// SPDX-License-Identifier: MIT
// Used by CholmodSolver; compiled, and linked with BLAS and LAPACK, only with CHOLMOD
// (solvers/CMakeLists.txt).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/partial_supernodal_factor.h"

#include <algorithm>

#include "framework/error.h"

// BLAS and LAPACK (the libraries CHOLMOD's supernodal factorization calls).
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* a, const int* lda, double* b,
            const int* ldb);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc);
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc);
}

namespace harap {

void PartialSupernodalFactor::Setup(const SupernodalFactorView& f) {
  n_ = f.n;
  num_supernodes_ = f.num_supernodes;
  supernode_of_.resize(n_);
  parent_.assign(num_supernodes_, -1);
  work_.assign(num_supernodes_, 0.0);
  for (int s = 0; s < num_supernodes_; ++s) {
    for (int j = f.first[s]; j < f.first[s + 1]; ++j) supernode_of_[j] = s;
  }
  total_work_ = 0.0;
  for (int s = 0; s < num_supernodes_; ++s) {
    const int columns = f.first[s + 1] - f.first[s];
    const int rows = f.row_start[s + 1] - f.row_start[s];
    const int* row = f.row + f.row_start[s];
    if (rows > columns) parent_[s] = supernode_of_[row[columns]];
    // Its own Cholesky and triangular solve, then its update of each ancestor it has rows in
    // (counted for the ancestor, which does that work when it is recomputed).
    const double k = columns;
    work_[s] += k * k * k / 3.0 + k * k * (rows - columns);
    for (int r = columns; r < rows;) {
      const int target = supernode_of_[row[r]];
      int end = r;
      while (end < rows && supernode_of_[row[end]] == target) ++end;
      work_[target] += static_cast<double>(end - r) * (rows - r) * k;
      r = end;
    }
  }
  for (double w : work_) total_work_ += w;
  marked_.assign(num_supernodes_, 0);
  marked_count_ = 0;
}

double PartialSupernodalFactor::Mark(const SupernodalFactorView& f,
                                     const std::vector<int>& changed) {
  HARAP_CHECK(f.n == n_ && f.num_supernodes == num_supernodes_,
              "the factor's structure changed since Setup()");
  std::fill(marked_.begin(), marked_.end(), 0);
  // The columns the change reaches: the changed ones and their ancestors.
  for (int c : changed) {
    HARAP_CHECK(c >= 0 && c < n_, "changed column {} out of range [0, {})", c, n_);
    for (int s = supernode_of_[c]; s >= 0 && !marked_[s]; s = parent_[s]) marked_[s] = 1;
  }
  // The other supernodes with a changed row: only those rows change, but recomputing the whole
  // supernode is simpler and cheap (few of them: 18 besides the paths' 254 for a ball of 1,729
  // vertices on armadillo-bend).
  map_.assign(n_, 0);
  for (int c : changed) map_[c] = 1;
  for (int s = 0; s < num_supernodes_; ++s) {
    if (marked_[s]) continue;
    const int columns = f.first[s + 1] - f.first[s];
    for (int q = f.row_start[s] + columns; q < f.row_start[s + 1]; ++q) {
      if (map_[f.row[q]]) {
        marked_[s] = 1;
        break;
      }
    }
  }
  marked_count_ = 0;
  double work = 0.0;
  for (int s = 0; s < num_supernodes_; ++s) {
    if (!marked_[s]) continue;
    ++marked_count_;
    work += work_[s];
  }
  marked_work_ = work;
  return total_work_ > 0.0 ? work / total_work_ : 0.0;
}

int PartialSupernodalFactor::Refactor(const SupernodalFactorView& f, const SparseMatrix& a,
                                      const std::vector<int>& inverse_permutation) {
  HARAP_CHECK(f.n == n_ && f.num_supernodes == num_supernodes_,
              "the factor's structure changed since Setup()");
  const int* first = f.first;
  const int* row_start = f.row_start;
  const int* value_start = f.value_start;
  const int* row = f.row;
  double* value = f.value;
  head_.assign(num_supernodes_, -1);
  next_.resize(num_supernodes_);
  position_.resize(num_supernodes_);
  map_.resize(n_);
  const char lower = 'L', no = 'N', transposed = 'T', right = 'R';
  const double one = 1.0, zero = 0.0;
  for (int s = 0; s < num_supernodes_; ++s) {
    const int k1 = first[s], k2 = first[s + 1];
    const int columns = k2 - k1;
    const int rows = row_start[s + 1] - row_start[s];
    const int* s_row = row + row_start[s];
    double* block = value + value_start[s];
    const bool recompute = marked_[s] != 0;
    if (recompute) {
      for (int q = 0; q < rows; ++q) map_[s_row[q]] = q;
      std::fill(block, block + static_cast<size_t>(rows) * columns, 0.0);
      // Column k of P A Pᵀ on and below the diagonal: column permutation[k] of A (both
      // triangles stored), rows mapped to the factor's order.
      for (int k = k1; k < k2; ++k) {
        const Index column = f.permutation ? f.permutation[k] : k;
        double* target = block + static_cast<size_t>(k - k1) * rows;
        for (SparseMatrix::InnerIterator it(a, column); it; ++it) {
          const int i = inverse_permutation[it.row()];
          if (i >= k) target[map_[i]] += it.value();
        }
      }
    }
    // Every descendant with rows in this supernode's columns: its update (if recomputing), then
    // it moves on to the next ancestor it has rows in (CHOLMOD's left-looking lists).
    for (int d = head_[s]; d != -1;) {
      const int d_next = next_[d];
      const int d_columns = first[d + 1] - first[d];
      const int d_rows = row_start[d + 1] - row_start[d];
      const int* d_row = row + row_start[d];
      const int p1 = position_[d];
      int p2 = p1;
      while (p2 < d_rows && d_row[p2] < k2) ++p2;
      if (recompute) {
        // C = L_d(p1:end, :) · L_d(p1:p2, :)ᵀ, lower part of the top square by dsyrk.
        const int m1 = p2 - p1, m2 = d_rows - p1;
        update_.resize(static_cast<size_t>(m2) * m1);
        const double* ld = value + value_start[d];
        dsyrk_(&lower, &no, &m1, &d_columns, &one, ld + p1, &d_rows, &zero, update_.data(), &m2);
        if (m2 > m1) {
          const int below = m2 - m1;
          dgemm_(&no, &transposed, &below, &m1, &d_columns, &one, ld + p2, &d_rows, ld + p1,
                 &d_rows, &zero, update_.data() + m1, &m2);
        }
        for (int j = 0; j < m1; ++j) {
          double* target = block + static_cast<size_t>(d_row[p1 + j] - k1) * rows;
          const double* c = update_.data() + static_cast<size_t>(j) * m2;
          for (int i = j; i < m2; ++i) target[map_[d_row[p1 + i]]] -= c[i];
        }
      }
      position_[d] = p2;
      if (p2 < d_rows) {
        const int ancestor = supernode_of_[d_row[p2]];
        next_[d] = head_[ancestor];
        head_[ancestor] = d;
      }
      d = d_next;
    }
    if (recompute) {
      int info = 0;
      dpotrf_(&lower, &columns, block, &rows, &info);
      if (info != 0) return k1 + info - 1;
      if (rows > columns) {
        const int below = rows - columns;
        dtrsm_(&right, &lower, &transposed, &no, &below, &columns, &one, block, &rows,
               block + columns, &rows);
      }
    }
    position_[s] = columns;
    if (rows > columns) {
      const int ancestor = supernode_of_[s_row[columns]];
      next_[s] = head_[ancestor];
      head_[ancestor] = s;
    }
  }
  return -1;
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
