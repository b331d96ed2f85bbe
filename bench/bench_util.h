#pragma once
// Small helpers shared by the benchmark programs (shapes built in code, subdivision, timing).
#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt::bench {

inline double now_seconds() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

/// Icosphere (radius 1) with `subdivisions` midpoint subdivisions: 10·4^k + 2 vertices.
inline TriangleMesh icosphere(int subdivisions) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                                    {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : v) x.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> nf;
    for (const auto& t : f) {
      int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      nf.push_back({t[0], a, c});
      nf.push_back({t[1], b, a});
      nf.push_back({t[2], c, b});
      nf.push_back({a, b, c});
    }
    f.swap(nf);
  }
  TriangleMesh m;
  m.V.resize(v.size(), 3);
  m.F.resize(f.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) m.V.row(i) = v[i];
  for (size_t i = 0; i < f.size(); ++i) m.F.row(i) = f[i];
  return m;
}

}  // namespace heatcvt::bench
