// The cells of one face under linear functions: tie rule of eq. 19, clipping along the bisectors
// of eq. 20. See face_clipper.h.
#include "heatcvt/face_clipper.h"

#include <cmath>

namespace heatcvt {

int corner_winner(const std::vector<FaceFunction>& functions, int c) {
  int best = -1;
  for (int i = 0; i < static_cast<int>(functions.size()); ++i) {
    if (best < 0) {
      best = i;
      continue;
    }
    const auto &ui = functions[i].value, &ub = functions[best].value;
    if (ui[c] > ub[c]) {
      best = i;
    } else if (ui[c] == ub[c]) {
      const double pi = ui[(c + 1) % 3] + ui[(c + 2) % 3];
      const double pb = ub[(c + 1) % 3] + ub[(c + 2) % 3];
      if (pi > pb || (pi == pb && functions[i].label < functions[best].label)) best = i;
    }
  }
  return best;
}

void face_candidates(const std::vector<FaceFunction>& functions, std::vector<int>& alive) {
  alive.clear();
  const int m = static_cast<int>(functions.size());
  for (int r = 0; r < m; ++r) {
    const auto& ur = functions[r].value;
    bool drop = false;
    for (int q = 0; q < m && !drop; ++q) {
      if (q == r) continue;
      const auto& uq = functions[q].value;
      const bool equal = uq[0] == ur[0] && uq[1] == ur[1] && uq[2] == ur[2];
      drop = (equal && functions[q].label < functions[r].label) || (uq[0] > ur[0] && uq[1] > ur[1] && uq[2] > ur[2]);
    }
    if (!drop) alive.push_back(r);
  }
}

bool clip_face_region(const std::vector<FaceFunction>& functions, const std::vector<int>& others, int s,
                      std::vector<ClipVertex>& region, std::vector<ClipVertex>& scratch) {
  // the triangle: corner c lies on edges c−1 and c; the side from corner c to c+1 is edge c
  region.clear();
  for (int c = 0; c < 3; ++c) region.push_back({Eigen::Vector3d::Unit(c), -1 - (c + 2) % 3, -1 - c, -1 - c});
  const FaceFunction& fs = functions[s];
  constexpr size_t kStack = 64;  // corners kept on the stack (a region has at most 3 + #others)
  double g_stack[kStack];
  unsigned char in_stack[kStack];
  std::vector<double> g_heap;
  std::vector<unsigned char> in_heap;
  for (int r : others) {
    if (r == s) continue;
    const FaceFunction& fr = functions[r];
    const double d0 = fs.value[0] - fr.value[0], d1 = fs.value[1] - fr.value[1], d2 = fs.value[2] - fr.value[2];
    const size_t np = region.size();
    double* g = g_stack;
    unsigned char* in = in_stack;
    if (np > kStack) {
      g_heap.resize(np);
      in_heap.resize(np);
      g = g_heap.data();
      in = in_heap.data();
    }
    bool all_in = true, all_out = true;
    for (size_t i = 0; i < np; ++i) {
      const Eigen::Vector3d& x = region[i].bary;
      g[i] = x[0] * d0 + x[1] * d1 + x[2] * d2;
      in[i] = wins_at(g[i], fs, fr);
      all_out = all_out && !in[i];
      all_in = all_in && in[i];
    }
    if (all_in) continue;
    if (all_out) {
      region.clear();
      return false;
    }
    scratch.clear();
    for (size_t i = 0; i < np; ++i) {
      const size_t j = i + 1 == np ? 0 : i + 1;
      const int L = region[i].line_out;
      if (in[i]) scratch.push_back(region[i]);
      if (in[i] != in[j]) {
        const double lambda = g[i] / (g[i] - g[j]);
        const Eigen::Vector3d x = region[i].bary + lambda * (region[j].bary - region[i].bary);
        // leaving the region: the new side runs along the bisector; entering: along L again
        scratch.push_back({x, L, r, in[i] ? r : L});
      }
    }
    region.swap(scratch);
    if (region.size() < 3) {
      region.clear();
      return false;
    }
  }
  return true;
}

RegionMoments region_moments(const std::vector<ClipVertex>& region) {
  RegionMoments m;
  for (size_t p = 1; p + 1 < region.size(); ++p) {
    const Eigen::Vector3d &a = region[0].bary, &b = region[p].bary, &d = region[p + 1].bary;
    // twice the area of (a, b, d) in the (λ1, λ2) plane = its area as a fraction of the face
    const double frac = std::abs((b[1] - a[1]) * (d[2] - a[2]) - (b[2] - a[2]) * (d[1] - a[1]));
    m.fraction += frac;
    for (int k = 0; k < 3; ++k) m.weight[k] += frac * (a[k] + b[k] + d[k]) / 3.0;
  }
  return m;
}

void clip_face(const std::vector<FaceFunction>& functions, std::vector<FacePiece>& out, FaceClipScratch& scratch) {
  face_candidates(functions, scratch.alive);
  for (int s : scratch.alive) {
    if (!clip_face_region(functions, scratch.alive, s, scratch.region, scratch.next)) continue;
    const RegionMoments m = region_moments(scratch.region);
    if (m.fraction > 0) out.push_back({functions[s].label, m});
  }
}

}  // namespace heatcvt
