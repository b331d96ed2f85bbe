#include "heatcvt/heat_solver.h"

#include <cholmod.h>
#include <dlfcn.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

// OpenBLAS's thread controls, looked up at run time: CHOLMOD links the generic libblas.so.3,
// which Debian's alternatives may point at OpenBLAS, the reference BLAS or another library.
struct OpenBlasControls {
  void (*set_threads)(int) = nullptr;
  int (*get_threads)() = nullptr;
  char* (*get_config)() = nullptr;
  OpenBlasControls() {
    set_threads = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    get_threads = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    get_config = reinterpret_cast<char* (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_config"));
  }
};

const OpenBlasControls& openblas() {
  static const OpenBlasControls controls;
  return controls;
}

// Sets the OpenBLAS thread count for its lifetime (no-op for 0 or without OpenBLAS).
class ScopedBlasThreads {
 public:
  explicit ScopedBlasThreads(int threads) {
    const auto& ob = openblas();
    if (threads <= 0 || !ob.set_threads || !ob.get_threads) return;
    previous_ = ob.get_threads();
    if (previous_ != threads) ob.set_threads(threads);
    else previous_ = 0;
  }
  ~ScopedBlasThreads() {
    if (previous_ > 0) openblas().set_threads(previous_);
  }
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

 private:
  int previous_ = 0;
};

}  // namespace

std::string blas_description() {
  const auto& ob = openblas();
  if (!ob.get_config) return "reference or unknown BLAS";
  std::string config = ob.get_config();
  const size_t cut = config.find(' ', config.find(' ') + 1);  // "OpenBLAS 0.3.21 DYNAMIC_ARCH ..."
  std::string name = cut == std::string::npos ? config : config.substr(0, cut);
  if (ob.get_threads) name += " (" + std::to_string(ob.get_threads()) + " threads)";
  return name;
}

namespace {
// Whether a system of `unknowns` is factored by the simplicial method (HeatSolverOptions::simplicial_max_vertices).
bool factored_simplicial(Eigen::Index unknowns, const HeatSolverOptions& options) {
  return unknowns < options.simplicial_max_vertices;
}
}  // namespace

std::string factorization_description(int unknowns, const HeatSolverOptions& options) {
  return factored_simplicial(unknowns, options) ? "simplicial, no BLAS" : "supernodal, " + blas_description();
}

size_t CholeskyFactor::memory_bytes() const {
  return value.size() * (sizeof(double) + sizeof(int)) + col_ptr.size() * sizeof(int64_t) +
         (perm.size() + inverse_perm.size() + parent.size()) * sizeof(int);
}

void CholeskyFactor::forward(double* y) const {
  for (int j = 0; j < n; ++j) {
    const int64_t begin = col_ptr[j], end = col_ptr[j + 1];
    const double yj = (y[j] /= value[begin]);
    if (yj == 0.0) continue;
    for (int64_t p = begin + 1; p < end; ++p) y[row[p]] -= value[p] * yj;
  }
}

void CholeskyFactor::backward(double* y) const {
  for (int j = n - 1; j >= 0; --j) {
    const int64_t begin = col_ptr[j], end = col_ptr[j + 1];
    double s = y[j];
    for (int64_t p = begin + 1; p < end; ++p) s -= value[p] * y[row[p]];
    y[j] = s / value[begin];
  }
}

namespace {

// Block variants: B right-hand sides interleaved (y[k*B + b]); one pass over the factor
// serves all B columns, which is what makes batches cheaper than B single solves.
template <int B>
void forward_block(const CholeskyFactor& L, double* y) {
  for (int j = 0; j < L.n; ++j) {
    const int64_t begin = L.col_ptr[j], end = L.col_ptr[j + 1];
    const double d = 1.0 / L.value[begin];
    double yj[B];
    bool any = false;
    for (int b = 0; b < B; ++b) {
      yj[b] = (y[j * B + b] *= d);
      any |= yj[b] != 0.0;
    }
    if (!any) continue;
    for (int64_t p = begin + 1; p < end; ++p) {
      double* target = y + static_cast<int64_t>(L.row[p]) * B;
      const double v = L.value[p];
      for (int b = 0; b < B; ++b) target[b] -= v * yj[b];
    }
  }
}

template <int B>
void backward_block(const CholeskyFactor& L, double* y) {
  for (int j = L.n - 1; j >= 0; --j) {
    const int64_t begin = L.col_ptr[j], end = L.col_ptr[j + 1];
    double s[B];
    for (int b = 0; b < B; ++b) s[b] = y[j * B + b];
    for (int64_t p = begin + 1; p < end; ++p) {
      const double* src = y + static_cast<int64_t>(L.row[p]) * B;
      const double v = L.value[p];
      for (int b = 0; b < B; ++b) s[b] -= v * src[b];
    }
    const double d = 1.0 / L.value[begin];
    for (int b = 0; b < B; ++b) y[j * B + b] = s[b] * d;
  }
}

constexpr int kBlock = 8;

}  // namespace

HeatSolver::HeatSolver(const Laplacian& laplacian, const HeatSolverOptions& options) {
  const int n = laplacian.num_vertices();
  if (n == 0) throw InvalidInputError("HeatSolver: empty Laplacian");
  if (laplacian.L.rows() != n || laplacian.L.cols() != n)
    throw InvalidInputError("HeatSolver: L and M sizes differ");
  t_ = options.time_step > 0 ? options.time_step
                             : options.time_coefficient * laplacian.mean_edge_length * laplacian.mean_edge_length;
  if (!(t_ > 0) || !std::isfinite(t_))
    throw InvalidInputError("HeatSolver: the time step must be positive and finite (got " + std::to_string(t_) + ")");
  threads_ = resolve_threads(options.threads);
  mass_ = laplacian.M;

  const auto start = std::chrono::steady_clock::now();
  // A = M − t L, lower triangle only (CHOLMOD stype = −1).
  Eigen::SparseMatrix<double> A = -t_ * laplacian.L;
  for (int i = 0; i < n; ++i) A.coeffRef(i, i) += mass_[i];
  Eigen::SparseMatrix<double> lower = A.triangularView<Eigen::Lower>();
  lower.makeCompressed();

  cholmod_common common;
  cholmod_l_start(&common);
  common.print = 0;
  common.error_handler = nullptr;
  // Simplicial (no BLAS, the same factor on every machine) on small systems, supernodal (BLAS,
  // fastest on large ones) above; either is converted below.
  common.supernodal = factored_simplicial(n, options) ? CHOLMOD_SIMPLICIAL : CHOLMOD_SUPERNODAL;
  if (options.ordering != FillOrdering::automatic) {
    common.nmethods = 1;
    common.method[0].ordering = options.ordering == FillOrdering::amd ? CHOLMOD_AMD : CHOLMOD_METIS;
    common.postorder = 1;
  }
  cholmod_sparse* cA = cholmod_l_allocate_sparse(n, n, lower.nonZeros(), 1, 1, -1, CHOLMOD_REAL, &common);
  auto* Ap = static_cast<SuiteSparse_long*>(cA->p);
  auto* Ai = static_cast<SuiteSparse_long*>(cA->i);
  auto* Ax = static_cast<double*>(cA->x);
  for (int j = 0; j <= n; ++j) Ap[j] = lower.outerIndexPtr()[j];
  for (Eigen::Index k = 0; k < lower.nonZeros(); ++k) {
    Ai[k] = lower.innerIndexPtr()[k];
    Ax[k] = lower.valuePtr()[k];
  }
  cholmod_factor* cL = cholmod_l_analyze(cA, &common);
  bool ok = false;
  {
    const ScopedBlasThreads blas(options.blas_threads);
    ok = cL != nullptr && cholmod_l_factorize(cA, cL, &common);
  }
  if (!ok || common.status == CHOLMOD_NOT_POSDEF || (cL && static_cast<int>(cL->minor) < n)) {
    if (cL) cholmod_l_free_factor(&cL, &common);
    cholmod_l_free_sparse(&cA, &common);
    cholmod_l_finish(&common);
    throw SolverError("HeatSolver: M - tL is not positive definite (check the mesh and the time step)");
  }
  // Simplicial, packed, monotonic LLᵀ: plain CSC columns that our (localized) solves walk.
  cholmod_l_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, cL, &common);
  factor_.n = n;
  const auto* Lp = static_cast<const SuiteSparse_long*>(cL->p);
  const auto* Li = static_cast<const SuiteSparse_long*>(cL->i);
  const auto* Lx = static_cast<const double*>(cL->x);
  const auto* Perm = static_cast<const SuiteSparse_long*>(cL->Perm);
  factor_.col_ptr.assign(Lp, Lp + n + 1);
  const int64_t nnz = factor_.col_ptr[n];
  factor_.row.resize(nnz);
  factor_.value.assign(Lx, Lx + nnz);
  for (int64_t k = 0; k < nnz; ++k) factor_.row[k] = static_cast<int>(Li[k]);
  factor_.perm.resize(n);
  factor_.inverse_perm.resize(n);
  for (int k = 0; k < n; ++k) {
    factor_.perm[k] = static_cast<int>(Perm[k]);
    factor_.inverse_perm[Perm[k]] = k;
  }
  cholmod_l_free_factor(&cL, &common);
  cholmod_l_free_sparse(&cA, &common);
  cholmod_l_finish(&common);

  // Sort rows per column (diagonal first) and derive the elimination tree.
  factor_.parent.assign(n, -1);
  std::vector<std::pair<int, double>> tmp;
  for (int j = 0; j < n; ++j) {
    const int64_t b = factor_.col_ptr[j], e = factor_.col_ptr[j + 1];
    bool sorted = true;
    for (int64_t p = b + 1; p < e; ++p) sorted &= factor_.row[p - 1] < factor_.row[p];
    if (!sorted) {
      tmp.clear();
      for (int64_t p = b; p < e; ++p) tmp.emplace_back(factor_.row[p], factor_.value[p]);
      std::sort(tmp.begin(), tmp.end());
      for (int64_t p = b; p < e; ++p) {
        factor_.row[p] = tmp[p - b].first;
        factor_.value[p] = tmp[p - b].second;
      }
    }
    if (e - b < 1 || factor_.row[b] != j || !(factor_.value[b] > 0))
      throw SolverError("HeatSolver: M - tL is not positive definite to rounding (pivot " + std::to_string(j) +
                        " of its Cholesky factor is not positive; check the mesh and the time step)");
    if (e - b > 1) factor_.parent[j] = factor_.row[b + 1];
  }
  factor_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

HeatSolver::~HeatSolver() = default;
HeatSolver::HeatSolver(HeatSolver&&) noexcept = default;
HeatSolver& HeatSolver::operator=(HeatSolver&&) noexcept = default;

Eigen::VectorXd HeatSolver::solve(const Eigen::VectorXd& rhs) const {
  const int n = factor_.n;
  if (rhs.size() != n) throw InvalidInputError("HeatSolver::solve: right-hand side has the wrong size");
  std::vector<double> y(n);
  for (int k = 0; k < n; ++k) y[k] = rhs[factor_.perm[k]];
  factor_.forward(y.data());
  factor_.backward(y.data());
  Eigen::VectorXd u(n);
  for (int k = 0; k < n; ++k) u[factor_.perm[k]] = y[k];
  return u;
}

Eigen::MatrixXd HeatSolver::solve(const Eigen::MatrixXd& rhs) const {
  const int n = factor_.n;
  if (rhs.rows() != n) throw InvalidInputError("HeatSolver::solve: right-hand side has the wrong size");
  const int k = static_cast<int>(rhs.cols());
  Eigen::MatrixXd U(n, k);
  const int blocks = (k + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads_)
  for (int blk = 0; blk < blocks; ++blk) {
    const int c0 = blk * kBlock, width = std::min(kBlock, k - c0);
    std::vector<double> y(static_cast<size_t>(n) * kBlock, 0.0);
    for (int r = 0; r < n; ++r)
      for (int b = 0; b < width; ++b) y[static_cast<size_t>(r) * kBlock + b] = rhs(factor_.perm[r], c0 + b);
    forward_block<kBlock>(factor_, y.data());
    backward_block<kBlock>(factor_, y.data());
    for (int r = 0; r < n; ++r)
      for (int b = 0; b < width; ++b) U(factor_.perm[r], c0 + b) = y[static_cast<size_t>(r) * kBlock + b];
  }
  return U;
}

Eigen::VectorXd HeatSolver::solve_sparse(const std::vector<std::pair<int, double>>& rhs) const {
  Eigen::VectorXd b = Eigen::VectorXd::Zero(factor_.n);
  for (const auto& [i, v] : rhs) {
    if (i < 0 || i >= factor_.n) throw InvalidInputError("HeatSolver::solve_sparse: vertex index out of range");
    b[i] += v;
  }
  return solve(b);
}

Eigen::VectorXd HeatSolver::diffuse_from_vertex(int v) const { return solve_sparse({{v, 1.0}}); }

Eigen::VectorXd HeatSolver::diffuse_from_point(const Eigen::MatrixX3i& F, const SurfacePoint& p) const {
  if (p.face < 0 || p.face >= F.rows()) throw InvalidInputError("HeatSolver::diffuse_from_point: face index out of range");
  return solve_sparse({{F(p.face, 0), p.bary[0]}, {F(p.face, 1), p.bary[1]}, {F(p.face, 2), p.bary[2]}});
}

Eigen::VectorXd HeatSolver::diffuse_from_faces(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                               const std::vector<int>& faces) const {
  std::vector<std::pair<int, double>> rhs;
  rhs.reserve(faces.size() * 3);
  for (int f : faces) {
    if (f < 0 || f >= F.rows()) throw InvalidInputError("HeatSolver::diffuse_from_faces: face index out of range");
    Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    for (int k = 0; k < 3; ++k) rhs.emplace_back(F(f, k), area / 3.0);  // eq. 10–11: M h
  }
  return solve_sparse(rhs);
}

Eigen::VectorXd HeatSolver::diffuse_steps(const Eigen::VectorXd& rhs, int steps) const {
  if (steps < 1) throw InvalidInputError("HeatSolver::diffuse_steps: steps must be >= 1");
  Eigen::VectorXd u = solve(rhs);
  for (int s = 1; s < steps; ++s) u = solve(Eigen::VectorXd(mass_.cwiseProduct(u)));  // h ← u
  return u;
}

}  // namespace heatcvt
