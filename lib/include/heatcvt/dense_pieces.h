#pragma once
/// \file dense_pieces.h
/// Dense pieces of a cloud: separate parts that hold a large share of its points on a small share
/// of its area (a small object scanned closely beside a large one, a close-up merged into a room
/// scan). The CVT spreads its sites by area, so such a part gets a few sites, too few for a mesh
/// of its own, and the mesher drops it as a small piece (SurfaceMesherOptions::
/// min_piece_vertex_fraction): a large part of the data is left out. reconstruct_surface() meshes
/// each dense piece on its own sites, enough for a closed piece with the shape targets, and the
/// rest of the cloud on the sites left.
///
/// The pieces are the connected components of the CVT points' triangles (the point Laplacian's
/// local triangulations: points in different pieces share no kNN neighbourhood). A component c
/// with area A_c gets about sites · A_c / A sites from the CVT; it is dense when that is below
/// split_below × its floor m = max(min_sites, ⌈2 · min_piece_vertex_fraction · sites⌉) (it is
/// then meshed on m sites), it holds at least
/// min_point_fraction of the cloud's points and at least min_points_per_site · m of them, and its
/// share of the points is at least min_density_ratio times its share of the area. The
/// component of the largest area is the rest and never a dense piece. Where the joined meshes fail
/// the checks (parts about a spacing apart whose faces cross) and the cloud meshed as one passes
/// them, that one is taken instead.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace heatcvt {

/// Options of the dense-piece rule (see the file comment).
struct DensePieceOptions {
  /// A component is dense only when it holds at least this fraction of the cloud's points: parts
  /// holding fewer are clutter the mesher may drop (its smallest piece is 1 % of the vertices).
  /// 0 turns the rule off. Default 0.05.
  double min_point_fraction = 0.05;
  /// A dense piece's share of the points is at least this times its share of the area: it is
  /// sampled that much more densely than the cloud on average (the mirror of the stray rule's
  /// sparse_density_ratio): parts of an RGB-D frame nearer the camera than the rest are sampled
  /// a few times more densely and get their share of the sites by area already. Default 4.
  double min_density_ratio = 4;
  /// A component is dense only where its share of the area gives it fewer than this times the
  /// floor m of sites: with about half of it (12 of 24) the mesher keeps the piece as it is (its
  /// smallest piece has 20 faces), and a split only moves a few sites and changes the rest's
  /// run (pcl_five_people at 500 sites: its nearest person, 4.2 times as dense as the scene and
  /// 20 sites by area, split off on 24 gave φm 51.8° against 52.4° and 80.3 % of the points
  /// covered against 82.9 %). Default 0.5.
  double split_below = 0.5;
  /// The fewest sites a dense piece is meshed on (a closed piece of 24 vertices has 44 triangles,
  /// enough for the angle targets on a sphere-like part). Default 24.
  int min_sites = 24;
  /// A dense piece needs at least this many of its points per site, as the CVT points do
  /// (ReconstructionOptions::cvt_points_per_site). Default 10.
  double min_points_per_site = 10;
  /// The dense pieces together take at most this fraction of the sites, those with the most points
  /// first; the rest of the cloud keeps the others. Default 0.5.
  double max_site_fraction = 0.5;
  bool enabled() const { return min_point_fraction > 0; }
};

/// \throw InvalidInputError on min_point_fraction or max_site_fraction outside [0, 1], min_sites
/// < 4, split_below outside (0, 1], or a negative or non-finite min_points_per_site or
/// min_density_ratio.
void check_dense_piece_options(const DensePieceOptions& options);

/// The floor m of the file comment: the sites each dense piece is meshed on.
int dense_piece_sites(int sites, double min_piece_vertex_fraction, const DensePieceOptions& options);

/// Whether any set of pieces could hold a dense one, from the weights alone: a dense piece has
/// less than split_below · m / sites of the area, so where every point has the same area, it
/// holds at most ⌈#points · split_below · m / sites⌉ points and at least min_point_fraction of the
/// weight; false when even the heaviest points that many cannot (a cheap test before the
/// components are built).
bool dense_piece_possible(const std::vector<int>& weight, int sites, double min_piece_vertex_fraction,
                          const DensePieceOptions& options);

/// The dense pieces found: a piece index per point (−1 for the rest) and each piece's sites.
struct DensePieces {
  std::vector<int> piece;  ///< per point of the triangles, its piece or −1
  std::vector<int> sites;  ///< per piece, the sites to mesh it on (its floor m)
  int count() const { return static_cast<int>(sites.size()); }
};

/// Dense pieces of the triangles T over the points PC, where point i stands for weight[i] points
/// of the cloud (a voxel's points, or 1), for a reconstruction on `sites` sites whose mesher drops
/// pieces below min_piece_vertex_fraction of the vertices. No piece where the rule is off.
/// Deterministic: pieces are ordered by their first point.
/// \throw InvalidInputError on bad options, a weight per point missing or an index of T out of range.
DensePieces dense_pieces(const Eigen::MatrixX3d& PC, const Eigen::MatrixX3i& T, const std::vector<int>& weight,
                         int sites, double min_piece_vertex_fraction, const DensePieceOptions& options);

/// The same rule on pieces given by a label per point (component[i] ≥ 0, or −1 for a point on
/// none, which belongs to the rest), each point carrying area[i] of the surface and weight[i]
/// points of the cloud. dense_pieces() calls it with the triangles' components and lumped areas;
/// the streamed path with the 26-connected components of its voxels.
/// \throw InvalidInputError on bad options or inputs of different lengths.
DensePieces dense_pieces_of_components(const std::vector<int>& component, const std::vector<double>& area,
                                       const std::vector<int>& weight, int sites, double min_piece_vertex_fraction,
                                       const DensePieceOptions& options);

/// Labels of the 26-connected components of the voxel cells (#cells by 3 integer cells, distinct),
/// numbered from 0 in the order of their first cell.
std::vector<int> voxel_components(const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3>& cells);

}  // namespace heatcvt
