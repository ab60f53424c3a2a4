// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (see cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_views.h"

namespace harap::cholmod_views {

cholmod_sparse LowerTriangleView(const SparseMatrix& a) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(a.rows());
  view.ncol = static_cast<size_t>(a.cols());
  view.nzmax = static_cast<size_t>(a.data().allocatedSize());
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

cholmod_sparse PatternView(const SparseMatrix& a) {
  cholmod_sparse view = LowerTriangleView(a);
  view.x = nullptr;
  view.xtype = CHOLMOD_PATTERN;
  return view;
}

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

cholmod_dense DenseView(const Eigen::Ref<const Eigen::MatrixXd>& b) {
  cholmod_dense view{};
  view.nrow = static_cast<size_t>(b.rows());
  view.ncol = static_cast<size_t>(b.cols());
  view.d = static_cast<size_t>(b.outerStride());
  view.nzmax = view.d * view.ncol;
  view.x = const_cast<double*>(b.data());
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  return view;
}

SupernodalFactorView SupernodalView(const cholmod_factor& f) {
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

LdltFactorView SimplicialView(const cholmod_factor& f) {
  LdltFactorView view;
  view.n = static_cast<Index>(f.n);
  view.column_start = static_cast<const int*>(f.p);
  view.column_count = static_cast<const int*>(f.nz);
  view.row = static_cast<const int*>(f.i);
  view.value = static_cast<const double*>(f.x);
  view.permutation = static_cast<const int*>(f.Perm);
  return view;
}

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

}  // namespace harap::cholmod_views

#endif  // HARAP_HAVE_CHOLMOD
