#pragma once
// A mesh written as a triangle soup: every face with its own three vertices (as exporters that
// split vertices at seams write it), for the tests of welding (weld.h) and of meshcvt on soups.
#include "heatcvt/mesh.h"

namespace heatcvt::test {

inline TriangleMesh triangle_soup(const TriangleMesh& m) {
  TriangleMesh s;
  s.V.resize(3 * m.F.rows(), 3);
  s.F.resize(m.F.rows(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      s.V.row(3 * f + k) = m.V.row(m.F(f, k));
      s.F(f, k) = static_cast<int>(3 * f + k);
    }
  return s;
}

}  // namespace heatcvt::test
