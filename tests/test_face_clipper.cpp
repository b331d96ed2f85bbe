// The face clipper alone (face_clipper.h): the cells of one triangle under linear functions
// (paper eq. 19–20) with two and three labels, ties on a vertex and on the whole face, and
// degenerate faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "heatcvt/face_clipper.h"

using namespace heatcvt;

namespace {

FaceFunction fn(int label, double u0, double u1, double u2) {
  FaceFunction f;
  f.label = label;
  f.value = {u0, u1, u2};
  return f;
}

double value_at(const FaceFunction& f, const Eigen::Vector3d& bary) {
  return f.value[0] * bary[0] + f.value[1] * bary[1] + f.value[2] * bary[2];
}

std::vector<FacePiece> pieces_of(const std::vector<FaceFunction>& fns) {
  std::vector<FacePiece> out;
  FaceClipScratch scratch;
  clip_face(fns, out, scratch);
  return out;
}

double fraction_of(const std::vector<FacePiece>& pieces, int label) {
  double total = 0;
  for (const FacePiece& p : pieces)
    if (p.label == label) total += p.moments.fraction;
  return total;
}

}  // namespace

TEST(FaceClipper, TwoLabelsSplitAlongTheBisector) {
  // u_a − u_b = λ0 − λ1 (λ = barycentric coordinates): the bisector runs from corner 2 to the
  // midpoint of edge 01, so each label owns exactly half the face.
  const std::vector<FaceFunction> fns = {fn(3, 1.0, 0.0, 0.5), fn(7, 0.0, 1.0, 0.5)};
  const std::vector<FacePiece> pieces = pieces_of(fns);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_NEAR(fraction_of(pieces, 3), 0.5, 1e-15);
  EXPECT_NEAR(fraction_of(pieces, 7), 0.5, 1e-15);
  // first moments: the half owned by label 3 is the triangle (corner 0, corner 2, midpoint of 01),
  // centroid λ = (1/2, 1/6, 1/3); weight = fraction × centroid
  const FacePiece& a = pieces[0].label == 3 ? pieces[0] : pieces[1];
  EXPECT_NEAR(a.moments.weight[0], 0.5 * 0.5, 1e-15);
  EXPECT_NEAR(a.moments.weight[1], 0.5 / 6.0, 1e-15);
  EXPECT_NEAR(a.moments.weight[2], 0.5 / 3.0, 1e-15);
}

TEST(FaceClipper, ThreeLabelsMeetAtTheTriplePoint) {
  // u_i = λ_i: each label wins where its own coordinate is the largest, a third of the face,
  // and the three regions meet at the centroid.
  const std::vector<FaceFunction> fns = {fn(0, 1, 0, 0), fn(1, 0, 1, 0), fn(2, 0, 0, 1)};
  const std::vector<FacePiece> pieces = pieces_of(fns);
  ASSERT_EQ(pieces.size(), 3u);
  for (int l = 0; l < 3; ++l) EXPECT_NEAR(fraction_of(pieces, l), 1.0 / 3.0, 1e-14) << l;
  std::vector<ClipVertex> region, scratch;
  const std::vector<int> all = {0, 1, 2};
  ASSERT_TRUE(clip_face_region(fns, all, 0, region, scratch));
  // the region of label 0 is a quadrilateral: corner 0, midpoint of 01, centroid, midpoint of 20
  ASSERT_EQ(region.size(), 4u);
  int interior = 0;
  for (const ClipVertex& v : region)
    if (v.line_a >= 0 && v.line_b >= 0) {  // on two bisectors: the triple point
      ++interior;
      EXPECT_NEAR((v.bary - Eigen::Vector3d::Constant(1.0 / 3)).norm(), 0.0, 1e-15);
    }
  EXPECT_EQ(interior, 1);
}

TEST(FaceClipper, PiecesTileTheFaceAndEachPointGoesToItsLargestFunction) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int m = 2 + trial % 5;
    std::vector<FaceFunction> fns;
    for (int i = 0; i < m; ++i) fns.push_back(fn(10 * i + trial % 7, u(rng), u(rng), u(rng)));
    const std::vector<FacePiece> pieces = pieces_of(fns);
    double total = 0;
    for (const FacePiece& p : pieces) {
      total += p.moments.fraction;
      const double sum = p.moments.weight[0] + p.moments.weight[1] + p.moments.weight[2];
      EXPECT_NEAR(sum, p.moments.fraction, 1e-12);
      // the piece's centroid lies where its function is the largest
      const Eigen::Vector3d c(p.moments.weight[0] / sum, p.moments.weight[1] / sum, p.moments.weight[2] / sum);
      const FaceFunction& own = *std::find_if(fns.begin(), fns.end(), [&](const FaceFunction& f) { return f.label == p.label; });
      for (const FaceFunction& other : fns) EXPECT_GE(value_at(own, c), value_at(other, c) - 1e-12) << trial;
    }
    EXPECT_NEAR(total, 1.0, 1e-12) << trial;
  }
}

TEST(FaceClipper, TieOnAVertexIsBrokenByTheHeatInsideTheFace) {
  // At corner 0 both functions are 1; label 9 is larger at the other corners, so eq. 19 gives
  // corner 0 to label 9 although label 2 is the smaller label.
  const std::vector<FaceFunction> fns = {fn(2, 1.0, 0.2, 0.2), fn(9, 1.0, 0.6, 0.6)};
  EXPECT_EQ(fns[corner_winner(fns, 0)].label, 9);
  EXPECT_EQ(fns[corner_winner(fns, 1)].label, 9);
  // label 9 is at least as large everywhere (equal only at corner 0): it owns the whole face,
  // label 2 gets no piece of positive area
  const std::vector<FacePiece> pieces = pieces_of(fns);
  EXPECT_NEAR(fraction_of(pieces, 9), 1.0, 1e-15);
  EXPECT_EQ(fraction_of(pieces, 2), 0.0);
  // a full tie at a corner (same values at all three corners) goes to the smaller label
  const std::vector<FaceFunction> same = {fn(9, 0.3, 0.2, 0.1), fn(2, 0.3, 0.2, 0.1)};
  EXPECT_EQ(same[corner_winner(same, 0)].label, 2);
}

TEST(FaceClipper, IdenticalFunctionsGoToTheSmallerLabel) {
  // coincident sites: the same heat everywhere on the face; one of them must own all of it
  const std::vector<FaceFunction> fns = {fn(5, 0.4, 0.3, 0.2), fn(1, 0.4, 0.3, 0.2), fn(8, 0.1, 0.1, 0.1)};
  std::vector<int> alive;
  face_candidates(fns, alive);
  ASSERT_EQ(alive.size(), 1u);  // label 5 ties with label 1 and loses; label 8 is below everywhere
  EXPECT_EQ(fns[alive[0]].label, 1);
  const std::vector<FacePiece> pieces = pieces_of(fns);
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0].label, 1);
  EXPECT_DOUBLE_EQ(pieces[0].moments.fraction, 1.0);
  // the tie rule inside the clipper agrees: clipped against each other alone, label 5 is empty
  std::vector<ClipVertex> region, scratch;
  EXPECT_FALSE(clip_face_region(fns, {0, 1}, 0, region, scratch));
  EXPECT_TRUE(region.empty());
  EXPECT_TRUE(clip_face_region(fns, {0, 1}, 1, region, scratch));
  EXPECT_EQ(region.size(), 3u);
}

TEST(FaceClipper, DegenerateFaces) {
  // no function: no piece
  EXPECT_TRUE(pieces_of({}).empty());
  // one function: the whole face
  const std::vector<FacePiece> one = pieces_of({fn(4, 0.0, 0.0, 0.0)});
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].label, 4);
  EXPECT_DOUBLE_EQ(one[0].moments.fraction, 1.0);
  // a bisector through a corner only (the other label touches the face in one point): no
  // zero-area piece is reported
  const std::vector<FacePiece> touch = pieces_of({fn(0, 1.0, 1.0, 1.0), fn(1, 1.0, 0.0, 0.0)});
  ASSERT_EQ(touch.size(), 1u);
  EXPECT_EQ(touch[0].label, 0);
  EXPECT_NEAR(touch[0].moments.fraction, 1.0, 1e-15);
  // a bisector along a face edge: u_0 − u_1 = λ2 vanishes on edge 01, label 0 owns the face
  const std::vector<FacePiece> edge = pieces_of({fn(1, 0.5, 0.5, 0.5), fn(0, 0.5, 0.5, 1.5)});
  ASSERT_EQ(edge.size(), 1u);
  EXPECT_EQ(edge[0].label, 0);
  EXPECT_NEAR(edge[0].moments.fraction, 1.0, 1e-15);
}
