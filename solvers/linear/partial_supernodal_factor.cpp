// SPDX-License-Identifier: MIT
// Used by CholmodSolver; compiled, and linked with BLAS and LAPACK, only with CHOLMOD
// (solvers/CMakeLists.txt).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/partial_supernodal_factor.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <utility>

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
  ResetLists();
  above_pieces_.clear();
  for (int s = 0; s < num_supernodes_; ++s) {
    const int bad =
        FactorSupernode(s, marked_[s] != 0, f, a, inverse_permutation, workspace_, nullptr);
    if (bad >= 0) return bad;
  }
  return -1;
}

void PartialSupernodalFactor::ResetLists() {
  head_.assign(num_supernodes_, -1);
  next_.resize(num_supernodes_);
  position_.resize(num_supernodes_);
  workspace_.map.resize(n_);
}

void PartialSupernodalFactor::Link(int d, int ancestor, Piece* piece) {
  if (piece != nullptr && above_pieces_[ancestor]) {
    // Replayed in this order when the piece is spliced in (FactorAll): the same pushes, so the
    // same list, as if made now.
    piece->links.emplace_back(ancestor, d);
  } else {
    next_[d] = head_[ancestor];
    head_[ancestor] = d;
  }
}

int PartialSupernodalFactor::FactorSupernode(int s, bool recompute, const SupernodalFactorView& f,
                                             const SparseMatrix& a,
                                             const std::vector<int>& inverse_permutation,
                                             Workspace& workspace, Piece* piece) {
  const int* first = f.first;
  const int* row_start = f.row_start;
  const int* value_start = f.value_start;
  const int* row = f.row;
  double* value = f.value;
  std::vector<int>& map = workspace.map;
  std::vector<double>& update = workspace.update;
  const char lower = 'L', no = 'N', transposed = 'T', right = 'R';
  const double one = 1.0, zero = 0.0;
  const int k1 = first[s], k2 = first[s + 1];
  const int columns = k2 - k1;
  const int rows = row_start[s + 1] - row_start[s];
  const int* s_row = row + row_start[s];
  double* block = value + value_start[s];
  if (recompute) {
    for (int q = 0; q < rows; ++q) map[s_row[q]] = q;
    std::fill(block, block + static_cast<size_t>(rows) * columns, 0.0);
    // Column k of P A Pᵀ on and below the diagonal: column permutation[k] of A (both
    // triangles stored), rows mapped to the factor's order. An entry outside the supernode's
    // rows can only come from a matrix that is not symmetric in its pattern (the analysis saw
    // the lower triangle): rejected, not written out of bounds (CHOLMOD skips such entries).
    for (int k = k1; k < k2; ++k) {
      const Index column = f.permutation ? f.permutation[k] : k;
      double* target = block + static_cast<size_t>(k - k1) * rows;
      for (SparseMatrix::InnerIterator it(a, column); it; ++it) {
        const int i = inverse_permutation[it.row()];
        if (i < k) continue;
        const int q = map[i];
        HARAP_CHECK(q >= 0 && q < rows && s_row[q] == i,
                    "entry ({}, {}) of the matrix is not in its factor's pattern: the matrix "
                    "must be symmetric, stored in both triangles",
                    it.row(), column);
        target[q] += it.value();
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
      update.resize(static_cast<size_t>(m2) * m1);
      const double* ld = value + value_start[d];
      dsyrk_(&lower, &no, &m1, &d_columns, &one, ld + p1, &d_rows, &zero, update.data(), &m2);
      if (m2 > m1) {
        const int below = m2 - m1;
        dgemm_(&no, &transposed, &below, &m1, &d_columns, &one, ld + p2, &d_rows, ld + p1, &d_rows,
               &zero, update.data() + m1, &m2);
      }
      for (int j = 0; j < m1; ++j) {
        double* target = block + static_cast<size_t>(d_row[p1 + j] - k1) * rows;
        const double* c = update.data() + static_cast<size_t>(j) * m2;
        for (int i = j; i < m2; ++i) target[map[d_row[p1 + i]]] -= c[i];
      }
    }
    position_[d] = p2;
    if (p2 < d_rows) Link(d, supernode_of_[d_row[p2]], piece);
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
  if (rows > columns) Link(s, supernode_of_[s_row[columns]], piece);
  return -1;
}

std::vector<PartialSupernodalFactor::Piece> PartialSupernodalFactor::SplitIntoPieces(int threads) {
  above_pieces_.clear();
  if (threads <= 1 || num_supernodes_ < 2) return {};
  // Subtree work and size (children come before their parent: the tree is postordered).
  std::vector<double> subtree_work(work_);
  std::vector<int> subtree_size(num_supernodes_, 1);
  std::vector<int> first_descendant(num_supernodes_);
  std::iota(first_descendant.begin(), first_descendant.end(), 0);
  std::vector<int> child_start(num_supernodes_ + 1, 0), children(num_supernodes_);
  for (int s = 0; s < num_supernodes_; ++s) {
    const int p = parent_[s];  // > s: the parent is the supernode of a later row
    if (p < 0) continue;
    subtree_work[p] += subtree_work[s];
    subtree_size[p] += subtree_size[s];
    first_descendant[p] = std::min(first_descendant[p], first_descendant[s]);
    ++child_start[p + 1];
  }
  // A piece is the range [r − size + 1, r] of its root r: the tree must be postordered (CHOLMOD
  // postorders its analysis; common.postorder = 1), else no pieces (factored in order).
  for (int s = 0; s < num_supernodes_; ++s) {
    if (first_descendant[s] != s - subtree_size[s] + 1) return {};
  }
  for (int s = 0; s < num_supernodes_; ++s) child_start[s + 1] += child_start[s];
  {
    std::vector<int> fill(child_start.begin(), child_start.end() - 1);
    for (int s = 0; s < num_supernodes_; ++s) {
      if (parent_[s] >= 0) children[fill[parent_[s]]++] = s;
    }
  }
  // From the roots down: split the heaviest subtree (its root goes above the pieces, its
  // children become candidates) until none has more than a quarter of a thread's share. The
  // number of splits is capped (each puts a supernode in the sequential part), not the number
  // of candidates: a mesh in many pieces (dragon-lift: 151 components, one of them almost all
  // of the work) has many roots and still needs its large tree split.
  const double limit = total_work_ / (4.0 * threads);
  const auto lighter = [&](int x, int y) { return subtree_work[x] < subtree_work[y]; };
  std::vector<int> candidates;
  for (int s = 0; s < num_supernodes_; ++s) {
    if (parent_[s] < 0) candidates.push_back(s);
  }
  std::make_heap(candidates.begin(), candidates.end(), lighter);
  std::vector<char> above(num_supernodes_, 0);
  std::vector<int> unsplittable;  // heavy leaves: pieces as they are
  int splits = 0;
  const int max_splits = 64 * threads;
  while (!candidates.empty() && splits < max_splits) {
    const int r = candidates.front();
    if (subtree_work[r] <= limit) break;
    std::pop_heap(candidates.begin(), candidates.end(), lighter);
    candidates.pop_back();
    if (child_start[r] == child_start[r + 1]) {
      unsplittable.push_back(r);
      continue;
    }
    above[r] = 1;
    ++splits;
    for (int c = child_start[r]; c < child_start[r + 1]; ++c) {
      candidates.push_back(children[c]);
      std::push_heap(candidates.begin(), candidates.end(), lighter);
    }
  }
  candidates.insert(candidates.end(), unsplittable.begin(), unsplittable.end());
  if (candidates.size() < 2) return {};
  above_pieces_ = std::move(above);
  std::vector<Piece> pieces(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    pieces[k].end = candidates[k] + 1;
    pieces[k].begin = pieces[k].end - subtree_size[candidates[k]];
    pieces[k].work = subtree_work[candidates[k]];
  }
  std::sort(pieces.begin(), pieces.end(),
            [](const Piece& x, const Piece& y) { return x.begin < y.begin; });
  return pieces;
}

int PartialSupernodalFactor::FactorAll(const SupernodalFactorView& f, const SparseMatrix& a,
                                       const std::vector<int>& inverse_permutation, int threads,
                                       bool (*thread_ready)()) {
  Setup(f);
  std::fill(marked_.begin(), marked_.end(), 1);
  marked_count_ = num_supernodes_;
  marked_work_ = total_work_;
  ResetLists();
  std::vector<Piece> pieces = SplitIntoPieces(threads);
  subtrees_ = static_cast<int>(pieces.size());
  subtree_work_fraction_ = 0.0;
  largest_subtree_fraction_ = 0.0;
  for (const Piece& piece : pieces) {
    subtree_work_fraction_ += piece.work;
    largest_subtree_fraction_ = std::max(largest_subtree_fraction_, piece.work);
  }
  if (total_work_ > 0.0) {
    subtree_work_fraction_ /= total_work_;
    largest_subtree_fraction_ /= total_work_;
  }
  if (!pieces.empty()) {
    // The pieces, heaviest first, on the arena's threads (each thread its own workspace).
    std::vector<std::pair<double, size_t>> by_work;
    for (size_t k = 0; k < pieces.size(); ++k) {
      by_work.emplace_back(-pieces[k].work, k);
    }
    std::sort(by_work.begin(), by_work.end());
    tbb::enumerable_thread_specific<Workspace> workspaces([&] {
      Workspace workspace;
      workspace.map.resize(n_);
      return workspace;
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, by_work.size(), 1),
                      [&](const tbb::blocked_range<size_t>& range) {
                        if (thread_ready != nullptr && !thread_ready()) return;
                        Workspace& workspace = workspaces.local();
                        for (size_t k = range.begin(); k != range.end(); ++k) {
                          Piece& piece = pieces[by_work[k].second];
                          piece.factored = true;
                          for (int s = piece.begin; s < piece.end; ++s) {
                            const int bad = FactorSupernode(s, true, f, a, inverse_permutation,
                                                            workspace, &piece);
                            if (bad >= 0) {
                              piece.failed_column = bad;
                              break;
                            }
                          }
                        }
                      });
  }
  // In postorder: each piece's links spliced in where the sequential loop made them, the
  // supernodes above the pieces factored in between.
  size_t next_piece = 0;
  for (int s = 0; s < num_supernodes_;) {
    if (next_piece < pieces.size() && pieces[next_piece].begin == s &&
        pieces[next_piece].factored) {
      const Piece& piece = pieces[next_piece++];
      if (piece.failed_column >= 0) return piece.failed_column;
      for (const auto& [ancestor, d] : piece.links) Link(d, ancestor, nullptr);
      s = piece.end;
      continue;
    }
    // A supernode above the pieces, or one of a piece no thread took: in order, as the
    // sequential loop factors it.
    if (next_piece < pieces.size() && pieces[next_piece].begin == s) ++next_piece;
    const int bad = FactorSupernode(s, true, f, a, inverse_permutation, workspace_, nullptr);
    if (bad >= 0) return bad;
    ++s;
  }
  return -1;
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
