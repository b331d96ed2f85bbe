#pragma once
/// \file normals.h
/// k-nearest-neighbour queries and normals of point clouds: PCA estimation (unoriented) and a
/// consistent orientation by propagation along a minimum spanning tree of the kNN graph
/// (Hoppe et al. 1992). Used by point_laplacian() and by cloud2mesh to orient its output.
#include <Eigen/Core>

namespace heatcvt {

/// Exact k nearest neighbours of every point (kd-tree, exact search in double precision).
///   P  #P by 3 positions. Returns #P by k indices, row i sorted by increasing distance to
///   P.row(i), the point itself EXCLUDED (a duplicate of P.row(i) at distance 0 may appear).
///   Deterministic: the same input gives the same output for any `threads`.
/// \param threads  0 = all hardware threads (default).
/// \throw InvalidInputError if k < 1, #P < k + 1, or a coordinate is NaN / infinite.
Eigen::MatrixXi k_nearest_neighbors(const Eigen::MatrixX3d& P, int k, int threads = 0);

/// Exact k nearest points of P to every query point (kd-tree over P, exact search in double
/// precision). Returns #Q by k indices into P, row i sorted by increasing distance to Q.row(i)
/// (ties by index); a point of P equal to Q.row(i) is included. Deterministic for any `threads`.
/// \throw InvalidInputError if k < 1, #P < k, or a coordinate of P or Q is NaN / infinite.
Eigen::MatrixXi nearest_neighbors_of(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& Q, int k, int threads = 0);

/// PCA normal of every point: the eigenvector of the smallest eigenvalue of the covariance of
/// the point and its k nearest neighbours. Unit length, UNORIENTED (sign arbitrary but
/// deterministic).
///   P  #P by 3. Returns #P by 3. Default k = 30 (the point Laplacian's default).
/// \throw InvalidInputError if k < 2, #P < k + 1, or a coordinate is NaN / infinite.
Eigen::MatrixX3d estimate_normals(const Eigen::MatrixX3d& P, int k = 30, int threads = 0);

/// Same from precomputed neighbours (`neighbors` as returned by k_nearest_neighbors()).
Eigen::MatrixX3d estimate_normals(const Eigen::MatrixX3d& P, const Eigen::MatrixXi& neighbors,
                                  int threads = 0);

/// Flips normals in place so that they are consistently oriented: on every connected
/// component of the symmetrised kNN graph, start at the point of largest z (its normal is
/// made to point to +z, i.e. n_z ≥ 0), build the minimum spanning tree with edge weight
/// 1 − |n_i · n_j| (Prim) and flip each child so that n_parent · n_child ≥ 0.
/// On a closed, well-sampled surface the result points consistently outward or inward;
/// started at the topmost point with +z, it points outward for convex shapes.
///   P  #P by 3, N  #P by 3 (unit normals, any signs; modified in place). Default k = 10.
/// offset_penalty > 0 adds offset_penalty · |n_i · (p_j − p_i)| / |p_j − p_i| to the edge weight:
/// edges leaving the tangent plane (across a part thinner than the neighbourhood, whose two sides
/// are parallel) are taken last, so the two sides get opposite orientations. Default 0.
/// Deterministic (ties broken by index).
/// \throw InvalidInputError if the shapes differ, k < 1, #P < k + 1, or non-finite input.
void orient_normals_mst(const Eigen::MatrixX3d& P, Eigen::MatrixX3d& N, int k = 10, int threads = 0,
                        double offset_penalty = 0.0);

}  // namespace heatcvt
