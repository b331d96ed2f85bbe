// Lloyd iteration with heat Voronoi cells and heat centroids (paper §7.1), localized solves
// (paper §6): the driver over the start (cvt/start.h), the Lloyd state (cvt/lloyd.h) and the
// quality control (cvt/quality.h). See cvt.h.
#include "heatcvt/cvt.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <string>
#include <thread>

#include "heatcvt/cvt/anisotropic_lift.h"
#include "heatcvt/cvt/lloyd.h"
#include "heatcvt/cvt/quality.h"
#include "heatcvt/cvt/start.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/localized_solve.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// \throw InvalidInputError on bad sizes or options (see centroidal_voronoi()).
void validate_cvt_inputs(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Laplacian& laplacian,
                         const CvtOptions& options, const std::vector<SurfacePoint>& given_sites,
                         const Eigen::VectorXd& face_metric_area, const Eigen::VectorXd& vertex_density) {
  const int n = static_cast<int>(V.rows());
  validate_mesh(V, F, "centroidal_voronoi: mesh");
  if (laplacian.num_vertices() != n)
    throw InvalidInputError("centroidal_voronoi: the Laplacian has " + std::to_string(laplacian.num_vertices()) +
                            " vertices but the mesh has " + std::to_string(n));
  if (options.iterations < 0) throw InvalidInputError("centroidal_voronoi: iterations must be >= 0");
  if (!(options.tolerance >= 0) || !(options.mean_move_tolerance >= 0))
    throw InvalidInputError("centroidal_voronoi: tolerance and mean_move_tolerance must be >= 0");
  if (options.voronoi_rings < 0 || options.centroid_rings < 0 || options.voronoi_rings_settled < 0)
    throw InvalidInputError("centroidal_voronoi: ring counts must be >= 0");
  if (options.quality_every < 0) throw InvalidInputError("centroidal_voronoi: quality_every must be >= 0");
  if (options.keep_sites_per_vertex < 1) throw InvalidInputError("centroidal_voronoi: keep_sites_per_vertex must be >= 1");
  if (face_metric_area.size() != 0 && face_metric_area.size() != F.rows())
    throw InvalidInputError("centroidal_voronoi: face_metric_area has " + std::to_string(face_metric_area.size()) +
                            " entries but the mesh has " + std::to_string(F.rows()) + " faces");
  if (vertex_density.size() != 0 && (vertex_density.size() != n || !vertex_density.allFinite() || !(vertex_density.minCoeff() > 0)))
    throw InvalidInputError("centroidal_voronoi: vertex_density must have one positive finite value per vertex (" +
                            std::to_string(n) + "), got " + std::to_string(vertex_density.size()) + " values");
  if (!(options.relaxation >= 1.0 && options.relaxation < 2.0))
    throw InvalidInputError("centroidal_voronoi: relaxation must be in [1, 2), got " + std::to_string(options.relaxation));
  if (options.graph_lloyd_iterations < 0 || options.anderson_depth < 0 || options.quality_patience < 0 || options.quality_start < 0 || !(options.max_inserted_fraction >= 0))
    throw InvalidInputError("centroidal_voronoi: graph_lloyd_iterations, quality_start and max_inserted_fraction must be >= 0");
  if (options.surface_lloyd_iterations < 0 || options.surface_lloyd_split_rounds < 0 || !(options.surface_lloyd_tolerance >= 0) ||
      !(options.surface_lloyd_mean_tolerance >= 0))
    throw InvalidInputError("centroidal_voronoi: surface_lloyd_iterations, surface_lloyd_split_rounds and the surface Lloyd tolerances must be >= 0");
  if (!(options.surface_lloyd_relaxation >= 1.0 && options.surface_lloyd_relaxation < 2.0))
    throw InvalidInputError("centroidal_voronoi: surface_lloyd_relaxation must be in [1, 2), got " +
                            std::to_string(options.surface_lloyd_relaxation));
  const CvtTuning& t = options.tuning;
  auto need = [](bool ok, const char* what) {
    if (!ok) throw InvalidInputError(std::string("centroidal_voronoi: tuning.") + what);
  };
  need(t.settled_move >= 0 && t.max_extra_step >= 0, "settled_move and max_extra_step must be >= 0");
  need(t.relaxation_decay >= 0 && t.relaxation_decay < 1 && t.relaxation_floor >= 0,
       "relaxation_decay must be in [0, 1) and relaxation_floor >= 0");
  need(t.empty_cell_radius > 0, "empty_cell_radius must be > 0");
  need(t.spot_growth_factor >= 1 && t.spot_growth_slack >= 0, "spot_growth_factor must be >= 1 and spot_growth_slack >= 0");
  need(t.patience_gain_deg >= 0 && t.refine_fraction_per_round >= 0 && t.split_min_distance >= 0,
       "patience_gain_deg, refine_fraction_per_round and split_min_distance must be >= 0");
  need(t.walk_max_steps >= 0 && t.walk_min_gain >= 0 && t.face_blocks_per_thread >= 1,
       "walk_max_steps and walk_min_gain must be >= 0 and face_blocks_per_thread >= 1");
  const std::vector<SurfacePoint>& sites = given_sites;
  if (sites.empty()) {
    if (options.sites < 1 || options.sites > n)
      throw InvalidInputError("centroidal_voronoi: the number of sites must be in [1, #V = " + std::to_string(n) +
                              "], got " + std::to_string(options.sites));
  }
  for (size_t s = 0; s < sites.size(); ++s)
    if (sites[s].face < 0 || sites[s].face >= F.rows() || !sites[s].bary.allFinite())
      throw InvalidInputError("centroidal_voronoi: initial site " + std::to_string(s) + " is not on a face of the mesh");
}

// Weight of a face's area in the centroids' area sources: metric area / Euclidean area (the
// anisotropic lift) times the face's density (a CVT with density); empty without either.
Eigen::VectorXd face_scale_of(const CvtSurface& surface, const Eigen::VectorXd& face_metric_area) {
  const Eigen::VectorXd& face_area = surface.face_area;
  Eigen::VectorXd face_scale;
  if (face_metric_area.size() == 0 && !surface.has_density()) return face_scale;
  face_scale.resize(face_area.size());
  for (Eigen::Index f = 0; f < face_area.size(); ++f) {
    const double metric = face_metric_area.size() ? face_metric_area[f] : face_area[f];
    face_scale[f] = face_area[f] > 0 ? metric * surface.face_mass[f] / (face_area[f] * face_area[f]) : 0.0;
  }
  return face_scale;
}

// The start step concurrently with the factorisation of the heat matrix (threads ≥ 2: the start
// runs on one core while CHOLMOD factors on the other, then on all threads; results do not depend
// on it). Returns the solver.
std::unique_ptr<HeatSolver> factor_during_start(const CvtSurface& surface, const Laplacian& laplacian,
                                                const CvtOptions& options, bool run_start, bool surface_on,
                                                int threads, std::vector<SurfacePoint>& sites,
                                                CvtStartReport& report) {
  std::exception_ptr start_error;
  std::atomic<bool> factor_done{threads < 2};
  auto start_job = [&]() {
    try {
      report = cvt_start(surface, options, surface_on, sites, [&]() { return factor_done.load() ? threads : 1; });
    } catch (...) {
      start_error = std::current_exception();
    }
  };
  std::thread start_thread;
  if (run_start) {
    if (threads >= 2) start_thread = std::thread(start_job);
    else start_job();
  }
  HeatSolverOptions so;
  so.time_coefficient = options.time_coefficient;
  so.ordering = options.ordering;
  so.threads = threads;
  std::unique_ptr<HeatSolver> solver;
  try {
    solver = std::make_unique<HeatSolver>(laplacian, so);
    factor_done = true;
  } catch (...) {
    if (start_thread.joinable()) start_thread.join();
    throw;
  }
  if (start_thread.joinable()) start_thread.join();
  if (start_error) std::rethrow_exception(start_error);
  return solver;
}

// quality_at_start: evaluates the start sites; while cells were split (or, with
// refine_small_angles, only φmin missed and sites were inserted), relaxes all sites with a few
// surface-Lloyd iterations and evaluates again (surface_lloyd_split_rounds). True when the
// targets were met.
bool start_rounds(const CvtSurface& surface, const CvtOptions& options, bool surface_on, double spacing,
                  int threads, LloydState& lloyd, CvtQualityControl& quality, CvtResult& result) {
  for (int round = 0;; ++round) {
    CvtIterationStats st0;
    const auto tr = Clock::now();
    const bool met = quality.evaluate(lloyd, st0, 0, result);
    result.start_phi_min_deg = st0.phi_min_deg;
    result.start_phi_mean_deg = st0.phi_mean_deg;
    result.start_quality_seconds += since(tr);
    result.start_spots = st0.nonmanifold_spots;
    if (met) return true;
    if (!surface_on || round >= options.surface_lloyd_split_rounds) return false;
    if (quality.only_phi_min_missed(st0)) {
      if (quality.refine_small_angles(lloyd, result) == 0) return false;
    } else if (st0.inserted_sites == 0) {
      return false;
    }
    // Sites were added: relax them with the cheap surface Lloyd (instead of heat iterations).
    int done = 0;
    std::vector<int> labels;
    const auto ts = Clock::now();
    std::vector<SurfacePoint> sites = surface_lloyd(
        surface, lloyd.sites(), surface_lloyd_options(options, std::max(1, options.surface_lloyd_split_iterations), spacing),
        &done, &labels, [&]() { return threads; });
    result.surface_lloyd_iterations += done;
    result.surface_lloyd_seconds += since(ts);
    const int ns = static_cast<int>(sites.size());
    lloyd.reset_sites(std::move(sites), cells_from_labels(surface.graph, labels, ns),
                      std::min(options.voronoi_rings, options.voronoi_rings_settled));
    ++result.start_rounds;
  }
}

// The heat Lloyd iterations with their quality evaluations and stopping rules.
void heat_iterations(const CvtOptions& options, double spacing, LloydState& lloyd, CvtQualityControl& quality,
                     const CvtCallback& callback, CvtResult& result) {
  quality.reset_patience();  // the patience counts the evaluations of the heat iterations
  for (int it = 1; it <= options.iterations; ++it) {
    const auto t0 = Clock::now();
    CvtIterationStats st;
    st.iteration = it;
    HeatField field;
    double carried = 0;  // solve time spent during the previous evaluation, charged to this iteration
    if (!quality.take_field(field, carried, st.mean_index_set)) field = lloyd.heat_field(&st.mean_index_set);
    st.voronoi_solve_seconds = since(t0) + carried;
    lloyd.step(field, st);
    st.voronoi_seconds = st.voronoi_solve_seconds + st.tessellate_seconds;
    st.seconds = since(t0) + carried;
    bool stop_for_quality = false;
    if (options.quality_every > 0 && it >= options.quality_start && it % options.quality_every == 0)
      stop_for_quality = quality.evaluate(lloyd, st, it, result);
    result.iterations.push_back(st);
    if (stop_for_quality) {
      if (callback) callback(st);
      return;
    }
    const bool go_on = callback ? callback(st) : true;
    // The stall ends the run only right after an evaluation that added no site, so that the
    // result's dual is an evaluated one. Where the evaluation split cells, the splitting stops
    // instead and the next evaluation ends the run: splits that go on while φm does not improve
    // are at spots the CVT cannot resolve (a hole or a piece of the input smaller than a cell),
    // which later stages take over (the remesh's closed-ball repair, the mesher's extraction).
    if (quality.patience_exhausted() && st.phi_mean_deg >= 0) {
      if (st.inserted_sites == 0) {
        result.stalled = true;
        return;
      }
      quality.stop_splitting();
    }
    const bool small_max = options.tolerance > 0 && st.max_move < options.tolerance * spacing;
    const bool small_mean = options.mean_move_tolerance > 0 && st.mean_move < options.mean_move_tolerance * spacing;
    if ((small_max || small_mean) && st.inserted_sites == 0) {
      result.converged = true;
      return;
    }
    if (!go_on) return;
  }
}

}  // namespace

double cell_area_variance(const VoronoiDiagram& diagram) { return population_variance(diagram.cell_area); }

Laplacian anisotropic_laplacian(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double lambda,
                                Eigen::VectorXd* face_metric_area) {
  validate_mesh(V, F, "anisotropic_laplacian: mesh");
  if (!(lambda >= 0) || !std::isfinite(lambda))
    throw InvalidInputError("anisotropic_laplacian: lambda must be finite and >= 0, got " + std::to_string(lambda));
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0)) throw InvalidInputError("anisotropic_laplacian: the mesh has an empty bounding box");
  const Eigen::MatrixX3d unit = (V.rowwise() - lo) / extent;  // unit bounding box (largest side 1)
  return lifted_laplacian(unit, vertex_normals(V, F), F, lambda, face_metric_area);
}

CvtResult centroidal_voronoi(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Laplacian& laplacian,
                             const CvtOptions& options, const std::vector<SurfacePoint>& given_sites,
                             const CvtCallback& callback, const Eigen::VectorXd& face_metric_area,
                             const Eigen::VectorXd& vertex_density) {
  const auto start = Clock::now();
  validate_cvt_inputs(V, F, laplacian, options, given_sites, face_metric_area, vertex_density);
  std::vector<SurfacePoint> sites = given_sites;
  const bool generate = sites.empty();
  const int ns = generate ? options.sites : static_cast<int>(sites.size());
  const int threads = resolve_threads(options.threads);
  CvtResult result;
  const CvtSurface surface(V, F, vertex_density);

  // 1. Start: initial sites, graph and surface Lloyd (not in the anisotropic metric, where
  //    Euclidean cells would pull towards isotropic ones), during the factorisation.
  const bool surface_on = options.surface_lloyd_iterations > 0 && face_metric_area.size() == 0;
  const bool run_start = options.graph_lloyd_iterations > 0 || surface_on;
  if (generate && !run_start) sites = generated_sites(V, F, options, vertex_density);
  CvtStartReport report;
  const std::unique_ptr<HeatSolver> solver =
      factor_during_start(surface, laplacian, options, run_start, surface_on, threads, sites, report);
  result.graph_lloyd_iterations = report.graph_lloyd_iterations;
  result.graph_lloyd_seconds = report.graph_lloyd_seconds;
  result.surface_lloyd_iterations = report.surface_lloyd_iterations;
  result.surface_lloyd_seconds = report.surface_lloyd_seconds;
  result.factor_seconds = solver->factor_seconds();
  result.factor_bytes = solver->factor().memory_bytes();
  LocalizedSolveOptions lo;
  lo.drop_tolerance = options.drop_tolerance;
  const LocalizedSolver local(*solver, lo);

  // Initial neighbourhoods: the surface Lloyd's restricted cells, else graph Voronoi cells.
  CellNeighbourhoods cells;
  if (!report.labels.empty()) {
    cells = cells_from_labels(surface.graph, report.labels, ns);
  } else {
    std::vector<int> sources(ns);
    for (int s = 0; s < ns; ++s) sources[s] = nearest_corner(F, sites[s]);
    cells = cells_from_labels(surface.graph, graph_voronoi(surface.graph, sources), ns);
  }
  result.setup_seconds = since(start);
  const double spacing = std::sqrt(surface_area(V, F) / ns);
  // Sites already relaxed by the surface Lloyd are settled: the settled index sets from the start.
  const int rings = result.surface_lloyd_iterations > 0 ? std::min(options.voronoi_rings, options.voronoi_rings_settled)
                                                        : options.voronoi_rings;
  LloydState lloyd(surface, local, options, face_scale_of(surface, face_metric_area), spacing, threads,
                   std::move(sites), std::move(cells), rings);
  CvtQualityControl quality(surface, options, ns, spacing, threads);

  // 2. Quality of the start sites, 3. heat Lloyd iterations.
  const bool met_at_start = options.quality_every > 0 && options.quality_at_start &&
                            start_rounds(surface, options, surface_on, spacing, threads, lloyd, quality, result);
  if (!met_at_start) heat_iterations(options, spacing, lloyd, quality, callback, result);

  // 4. Final exact diagram of the final sites (voronoi.h's conforming tessellation) and its dual.
  if (!result.reached_quality) {
    VoronoiOptions vo;
    vo.exact = true;
    vo.keep_sites_per_vertex = options.keep_sites_per_vertex;
    vo.threads = threads;
    HeatField field;
    double unused_seconds = 0, unused_index = 0;
    const bool ready = lloyd.full_rings_field_ready();
    if (!(ready && quality.take_field(field, unused_seconds, unused_index))) field = lloyd.heat_field(nullptr);
    result.diagram = tessellate(V, F, field, vo);
  }
  result.final_area_variance = population_variance(result.diagram.cell_area);
  result.sites = lloyd.sites();
  result.positions = lloyd.positions();
  if (options.build_dual && !result.reached_quality) result.dual = dual_mesh(result.diagram, result.positions);
  result.total_seconds = since(start);
  return result;
}

CvtOptions fast_cvt_options(int sites) {
  CvtOptions o;
  o.sites = sites;
  o.initialization = CvtInitialization::farthest_point;
  o.graph_lloyd_iterations = 0;
  o.surface_lloyd_iterations = 60;
  o.surface_lloyd_relaxation = 1.5;
  o.quality_at_start = true;
  o.surface_lloyd_split_rounds = 12;
  o.surface_lloyd_split_iterations = 3;
  o.refine_small_angles = true;
  o.relaxation = 1.5;
  o.quality_every = 2;  // an evaluation (exact tessellation + dual) costs about half an iteration
  o.quality_start = 2;
  o.target_phi_mean_deg = 51.0;
  o.target_phi_min_deg = 25.0;
  o.split_nonmanifold_cells = true;
  o.quality_patience = 10;
  // less fill makes the heat iterations and evaluations cheaper; the slower analysis overlaps
  // the surface Lloyd
  o.ordering = FillOrdering::metis;
  return o;
}

}  // namespace heatcvt
