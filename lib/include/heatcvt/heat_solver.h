#pragma once
/// \file heat_solver.h
/// The heat solver: factors `A = M − t L` once (CHOLMOD) and answers many implicit Euler
/// diffusions `A u = M h` (paper §2, eq. 7). Thread-safe for concurrent const queries.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"

namespace heatcvt {

/// Fill-reducing ordering of the Cholesky factorisation.
enum class FillOrdering {
  automatic,  ///< CHOLMOD's default: AMD, METIS tried too when AMD's fill is poor
  amd,        ///< approximate minimum degree: fastest analysis
  metis,      ///< METIS nested dissection: slower analysis, less fill (cheaper solves, less memory)
};

/// Options of HeatSolver.
struct HeatSolverOptions {
  /// t = time_coefficient · h̄² when `time_step` is not set (Crane et al. 2013). Default 1.
  double time_coefficient = 1.0;
  /// Absolute time step; used instead of the coefficient when > 0. Default 0 (unset).
  double time_step = 0.0;
  /// Threads for batched solves; 0 = all hardware threads. Default 0.
  int threads = 0;
  /// Threads of the BLAS inside CHOLMOD's supernodal factorisation, set for its duration and
  /// restored afterwards (OpenBLAS only, found at run time; other BLAS libraries are left alone).
  /// 0 = leave the BLAS library's own setting. Default 1: the factorisation usually overlaps
  /// other work (meshcvt's surface Lloyd), and idle OpenBLAS threads spin-wait on the cores our
  /// OpenMP loops need (docs/benchmarks.md).
  int blas_threads = 1;
  /// Fill-reducing ordering. Default automatic (CHOLMOD picks AMD on meshes). METIS usually gives
  /// less fill (a smaller factor and cheaper solves) for a slower analysis (docs/benchmarks.md,
  /// bench_cvt with CVT_ORDERING).
  FillOrdering ordering = FillOrdering::automatic;
  /// Systems with fewer unknowns than this are factored by CHOLMOD's simplicial method, which
  /// calls no BLAS: the factor has the same bits on every machine. A supernodal factor's last
  /// bits depend on the BLAS kernel OpenBLAS picks for the CPU, and a CVT, and the mesh after it,
  /// can follow them. Up to about this size the simplicial method is as fast and smaller
  /// (docs/benchmarks.md, bench_heat); at and above it the supernodal one (BLAS) is used.
  /// Default 100,000.
  int simplicial_max_vertices = 100000;
};

/// Name and thread count of the BLAS that CHOLMOD calls, e.g. "OpenBLAS 0.3.21 (2 threads)", or
/// "reference or unknown BLAS" when no OpenBLAS is loaded (its supernodal factorisation is then
/// 3–4× slower: install an optimised BLAS, on Debian libopenblas0-pthread).
std::string blas_description();

/// How HeatSolver factors a system of `unknowns` with `options`: "simplicial, no BLAS" below
/// options.simplicial_max_vertices, else "supernodal, " followed by blas_description().
std::string factorization_description(int unknowns, const HeatSolverOptions& options = {});

/// Sparse Cholesky factor `P A Pᵀ = L Lᵀ`, lower triangular, compressed columns with sorted
/// row indices and the diagonal first in each column. Exposed for localized solves
/// (paper §6, localized_solve.h).
struct CholeskyFactor {
  int n = 0;
  std::vector<int64_t> col_ptr;  ///< n+1
  std::vector<int> row;          ///< row index per entry (sorted per column, diagonal first)
  std::vector<double> value;     ///< entry values
  std::vector<int> perm;         ///< perm[k] = original index of elimination position k
  std::vector<int> inverse_perm; ///< inverse_perm[i] = elimination position of original index i
  std::vector<int> parent;       ///< elimination tree: parent of column j, −1 at roots
  size_t nonzeros() const { return value.size(); }
  size_t memory_bytes() const;
  /// Solves L y = y in place (elimination order).
  void forward(double* y) const;
  /// Solves Lᵀ y = y in place (elimination order).
  void backward(double* y) const;
};

/// Factors `M − t L` once; every diffusion afterwards is a forward + back substitution.
class HeatSolver {
 public:
  /// \throw SolverError if the matrix is not positive definite (e.g. t ≤ 0).
  explicit HeatSolver(const Laplacian& laplacian, const HeatSolverOptions& options = {});
  ~HeatSolver();
  HeatSolver(HeatSolver&&) noexcept;
  HeatSolver& operator=(HeatSolver&&) noexcept;

  int num_vertices() const { return factor_.n; }
  double time_step() const { return t_; }
  const Eigen::VectorXd& mass() const { return mass_; }
  const CholeskyFactor& factor() const { return factor_; }
  double factor_seconds() const { return factor_seconds_; }
  int threads() const { return threads_; }

  /// Solves `(M − t L) u = rhs` (rhs = M h, a load vector).
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  /// Solves for every column of `rhs` (#V by k), in parallel over columns.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& rhs) const;
  /// Sparse right-hand side given as (vertex, value) pairs.
  Eigen::VectorXd solve_sparse(const std::vector<std::pair<int, double>>& rhs) const;

  /// Heat after one step from a unit point source at vertex v: rhs = e_v (h = M⁻¹ e_v, eq. 8).
  Eigen::VectorXd diffuse_from_vertex(int v) const;
  /// Heat from a unit point source inside a face: rhs = b(p) (eq. 8).
  Eigen::VectorXd diffuse_from_point(const Eigen::MatrixX3i& F, const SurfacePoint& p) const;
  /// Heat from a uniform area source on the given faces (eq. 10–11): rhs_i = Σ area(f)/3.
  Eigen::VectorXd diffuse_from_faces(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                     const std::vector<int>& faces) const;
  /// `steps` implicit steps (h ← u, repeated) from a load vector; steps = 1 is solve().
  /// Mimics a large t with well-conditioned steps (paper §5, Fig. 4).
  Eigen::VectorXd diffuse_steps(const Eigen::VectorXd& rhs, int steps) const;

 private:
  CholeskyFactor factor_;
  Eigen::VectorXd mass_;
  double t_ = 0;
  double factor_seconds_ = 0;
  int threads_ = 1;
};

}  // namespace heatcvt
