#include "heatcvt/mesh_orientation.h"

#include <algorithm>
#include <array>
#include <vector>

namespace heatcvt {

namespace {

// One side of an edge: the face, and whether the face runs along the edge from its smaller
// vertex to its larger one.
struct EdgeSide {
  int lo, hi, face;
  bool forward;
};

}  // namespace

int orient_faces_consistently(Eigen::MatrixX3i& F) {
  const int nf = static_cast<int>(F.rows());
  std::vector<EdgeSide> sides;
  sides.reserve(static_cast<std::size_t>(3 * nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      sides.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  std::sort(sides.begin(), sides.end(), [](const EdgeSide& x, const EdgeSide& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.face < y.face;
  });
  // Neighbours across interior edges, each with whether the two faces agree (run the edge in
  // opposite directions).
  struct Link {
    int face;
    bool agree;
  };
  std::vector<std::vector<Link>> links(static_cast<std::size_t>(nf));
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
    if (j - i > 2) return -1;  // a non-manifold edge
    if (j - i == 2 && sides[i].face != sides[i + 1].face) {
      const bool agree = sides[i].forward != sides[i + 1].forward;
      links[static_cast<std::size_t>(sides[i].face)].push_back({sides[i + 1].face, agree});
      links[static_cast<std::size_t>(sides[i + 1].face)].push_back({sides[i].face, agree});
    }
    i = j;
  }
  // Breadth-first over each piece: flip[f] says whether f must turn to agree with the piece's
  // first face.
  std::vector<int> flip(static_cast<std::size_t>(nf), -1);
  std::vector<int> queue;
  std::vector<char> reverse(static_cast<std::size_t>(nf), 0);
  for (int start = 0; start < nf; ++start) {
    if (flip[static_cast<std::size_t>(start)] >= 0) continue;
    queue.assign(1, start);
    flip[static_cast<std::size_t>(start)] = 0;
    int flipped = 0;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int f = queue[q];
      for (const Link& l : links[static_cast<std::size_t>(f)]) {
        const int want = flip[static_cast<std::size_t>(f)] ^ (l.agree ? 0 : 1);
        int& g = flip[static_cast<std::size_t>(l.face)];
        if (g < 0) {
          g = want;
          flipped += want;
          queue.push_back(l.face);
        } else if (g != want) {
          return -1;  // no consistent orientation
        }
      }
    }
    // Keep the orientation most of the piece's faces already have.
    const bool turn_first = 2 * flipped > static_cast<int>(queue.size());
    for (const int f : queue) reverse[static_cast<std::size_t>(f)] = (flip[static_cast<std::size_t>(f)] != 0) != turn_first;
  }
  int reversed = 0;
  for (int f = 0; f < nf; ++f)
    if (reverse[static_cast<std::size_t>(f)]) std::swap(F(f, 1), F(f, 2)), ++reversed;
  return reversed;
}

}  // namespace heatcvt
