#pragma once
/// \file face_clipper.h
/// The cells of one triangle under a set of functions that are linear on it (paper §4, eq. 19–20).
///
/// Inside one face every heat function u_s is linear (its corner values interpolated with
/// barycentric coordinates), so the part of the face where u_s is the largest is convex: the
/// triangle clipped by the half-planes u_s − u_r ≥ 0 (the bisector lines of eq. 20). This gives
/// exactly the pieces of the recursive cut of Fig. 2 and terminates by construction. The same
/// clipper serves the exact tessellation (voronoi.h), the cells of a Lloyd iteration (heat) and
/// the restricted cells of the surface Lloyd (Euclidean: u_s = −|x − p_s|², also linear on a face
/// up to a term common to all sites).
///
/// Tie rule (eq. 19), used everywhere: the larger value wins; where two functions are equal the
/// one that is larger just inside the face wins (corner_winner()), and where they are equal on
/// the whole face the smaller label wins. Inside the clipper only the last case changes an area
/// (a point on a bisector of two different functions has measure zero): a point with
/// u_s = u_r belongs to the region of s when label_s < label_r.
#include <Eigen/Core>
#include <array>
#include <vector>

namespace heatcvt {

/// A function that is linear on one face: its values at the face's corners 0, 1, 2, and the
/// label (site index) that breaks ties.
struct FaceFunction {
  int label = -1;
  std::array<double, 3> value{};
};

/// A corner of a clipped region, in barycentric coordinates of the face. Lines are coded as
/// −1−k for face edge k (from corner k to corner k+1) and as i ≥ 0 for the bisector u_s = u_i with
/// function i of the list passed to clip_face_region(). A corner lies on `line_a` and `line_b`;
/// the region's side from this corner to the next one lies on `line_out`.
struct ClipVertex {
  Eigen::Vector3d bary;
  int line_a, line_b, line_out;
};

/// True when function a beats function b at a point where a − b = `difference` (tie rule above).
inline bool wins_at(double difference, const FaceFunction& a, const FaceFunction& b) {
  return difference > 0 || (difference == 0 && a.label < b.label);
}

/// The function that wins at corner c (eq. 19): the largest value; on a tie the largest sum of
/// the values at the face's other two corners (a perturbation towards the face interior), then
/// the smaller label. Returns an index into `functions`, −1 if it is empty.
int corner_winner(const std::vector<FaceFunction>& functions, int c);

/// Indices of the functions that can win somewhere in the face, in their given order: drops a
/// function equal at the three corners to one with a smaller label (it loses every tie to it)
/// and a function strictly below another one at the three corners (linear interpolation: it is
/// below it on the whole face, and its bisectors never bound a winner's region).
void face_candidates(const std::vector<FaceFunction>& functions, std::vector<int>& alive);

/// Region of function `s` (an index into `functions`): the face clipped by the half-planes
/// u_s ≥ u_r of every other r in `others` (indices into `functions`, clipped in that order, ties
/// by the rule above). `region` receives its corners counter-clockwise in barycentric
/// coordinates; `scratch` is work space. Returns false (and an empty region) when fewer than
/// three corners remain.
bool clip_face_region(const std::vector<FaceFunction>& functions, const std::vector<int>& others, int s,
                      std::vector<ClipVertex>& region, std::vector<ClipVertex>& scratch);

/// Area and first moment of a region in barycentric coordinates: `fraction` = its area / the
/// face's area, `weight[k]` = ∫_region λ_k / area(face) (λ_k = barycentric coordinate k), so that
/// Σ_k weight[k] = fraction, and for a face of area A with corners x_k the region's area is
/// A · fraction and its first moment A · Σ_k weight[k] x_k. Fan triangulation from corner 0.
struct RegionMoments {
  double fraction = 0;
  std::array<double, 3> weight{};
};
RegionMoments region_moments(const std::vector<ClipVertex>& region);

/// One non-empty cell of a face: the label of its function and the moments of its region.
struct FacePiece {
  int label = -1;
  RegionMoments moments;
};

/// Work space of clip_face() (reuse it across faces of one thread).
struct FaceClipScratch {
  std::vector<int> alive;
  std::vector<ClipVertex> region, next;
};

/// All cells of one face: face_candidates(), then clip_face_region() for each candidate against
/// the others, appending one FacePiece per region of positive area to `out` (in candidate order).
/// The pieces tile the face: their fractions sum to 1 up to rounding.
void clip_face(const std::vector<FaceFunction>& functions, std::vector<FacePiece>& out, FaceClipScratch& scratch);

}  // namespace heatcvt
