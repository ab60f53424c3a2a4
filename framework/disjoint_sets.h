// SPDX-License-Identifier: MIT
#pragma once

#include <algorithm>
#include <numeric>
#include <vector>

namespace harap {

/// Union–find with path halving over the integers 0..n−1. The root of a set is its smallest
/// member, so roots (and anything numbered by them) do not depend on the order of the unions.
template <class Integer>
struct DisjointSets {
  explicit DisjointSets(Integer n = 0) { Reset(n); }
  /// Makes 0..n−1 singletons again, keeping the storage (for reuse in a loop).
  void Reset(Integer n) {
    parent.resize(static_cast<size_t>(n));
    std::iota(parent.begin(), parent.end(), Integer{0});
  }
  Integer Find(Integer x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void Unite(Integer a, Integer b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<Integer> parent;
};

}  // namespace harap
