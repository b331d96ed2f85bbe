// nncoords: natural-neighbour coordinates by area stealing on heat Voronoi diagrams (paper §7.2):
// interpolate values given at sites to every vertex, or export per-vertex skinning weights.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli_common.h"
#include "heatcvt/atomic_file.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/natural_neighbour.h"
#include "heatcvt/normalize.h"
#include "report_json.h"
#include "sites.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

namespace {

// Mesh with per-vertex values as ASCII PLY: x y z value_0 .. value_{k-1} [red green blue].
void write_values_ply(const std::string& path, const TriangleMesh& mesh, const Eigen::MatrixXd& X, bool colour) {
  write_atomically(path, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\ncomment nncoords: natural-neighbour interpolation (heatcvt)\n";
    out << "element vertex " << mesh.V.rows() << "\nproperty double x\nproperty double y\nproperty double z\n";
    for (int c = 0; c < X.cols(); ++c) out << "property double value_" << c << "\n";
    if (colour) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << "element face " << mesh.F.rows() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int v = 0; v < mesh.V.rows(); ++v) {
      out << format_double(mesh.V(v, 0)) << ' ' << format_double(mesh.V(v, 1)) << ' ' << format_double(mesh.V(v, 2));
      for (int c = 0; c < X.cols(); ++c) out << ' ' << format_double(X(v, c));
      if (colour)
        for (int c = 0; c < 3; ++c) out << ' ' << static_cast<int>(std::lround(255.0 * std::clamp(X(v, c), 0.0, 1.0)));
      out << '\n';
    }
    for (int f = 0; f < mesh.F.rows(); ++f) out << "3 " << mesh.F(f, 0) << ' ' << mesh.F(f, 1) << ' ' << mesh.F(f, 2) << '\n';
  });
}

// Per vertex: "v count site weight site weight ...".
void write_weights(const std::string& path, const VertexWeights& W) {
  write_atomically(path, [&](std::ostream& out) {
    out << "# nncoords: natural-neighbour coordinates (area stealing on heat Voronoi cells), "
        << W.rows() << " vertices, " << W.cols() << " sites\n"
        << "# per line: vertex count site weight [site weight ...] (0-based; weights >= 0, sum 1)\n";
    for (int v = 0; v < W.rows(); ++v) {
      out << v << ' ' << W.row(v).nonZeros();
      for (VertexWeights::InnerIterator it(W, v); it; ++it) out << ' ' << it.col() << ' ' << format_double(it.value());
      out << '\n';
    }
  });
}

// The command line of nncoords.
struct Settings {
  std::string mesh_path, sites_path, values_path, out_path, weights_path, report_path;
  double t_coef = NaturalNeighbourOptions{}.time_coefficient, snap = cli::kDefaultSnapTolerance;
  int threads = NaturalNeighbourOptions{}.threads, samples = NaturalNeighbourOptions{}.samples;
  bool quiet = false, exact = false;
};

// Declares the options; either --values with -o or --weights is required.
void add_options(CLI::App& app, Settings& s) {
  app.add_option("MESH", s.mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("--sites", s.sites_path, "sites (handles), one 'x y z' per line, on the surface")->required();
  auto* values_opt = app.add_option("--values", s.values_path, "values at the sites: one row per site (k columns)");
  auto* out_opt = app.add_option("-o,--output", s.out_path, "output with --values: mesh with interpolated per-vertex values (.ply; colour when k = 3 in [0,1])");
  auto* weights_opt = app.add_option("--weights", s.weights_path, "output: per vertex the non-zero (site, weight) pairs (.txt)");
  values_opt->needs(out_opt);
  out_opt->needs(values_opt);
  weights_opt->excludes(values_opt);
  values_opt->excludes(weights_opt);
  cli::add_time_coefficient_option(app, s.t_coef);
  app.add_option("--samples", s.samples, "vertices computed exactly before propagation (0 = max(500, #V/20))")
      ->capture_default_str();
  app.add_flag("--exact", s.exact, "exact coordinates at every vertex (one diffusion per vertex; slow)");
  cli::add_snap_tolerance_option(app, s.snap);
  cli::add_threads_option(app, s.threads);
  app.add_option("--report", s.report_path, "write a JSON report");
  app.add_flag("-q,--quiet", s.quiet, "no progress output on stderr");
  app.callback([&s]() {
    if (s.values_path.empty() && s.weights_path.empty())
      throw CLI::RequiredError("one of --values VALUES -o OUT.ply or --weights WEIGHTS.txt");
  });
}

// Option checks before any work, naming the option at fault; then the output paths.
void check_settings(const Settings& s) {
  cli::check_time_coefficient(s.t_coef);
  cli::check_threads(s.threads);
  if (s.samples < 0) throw InvalidInputError("--samples must be >= 0");
  cli::check_snap_tolerance(s.snap);
  cli::check_output_path(s.out_path, {".ply"});
  cli::check_output_path(s.weights_path, {".txt"});
  cli::check_output_path(s.report_path, {".json"});
  cli::check_distinct_outputs({{"-o", s.out_path}, {"--weights", s.weights_path}, {"--report", s.report_path}},
                              {s.mesh_path, s.sites_path, s.values_path});
}

// Reads and checks the input mesh and notes its size on stderr.
TriangleMesh read_input(const Settings& s) {
  TriangleMesh mesh = read_mesh(s.mesh_path);
  validate_mesh(mesh.V, mesh.F, s.mesh_path);
  cli::log_line(s.quiet, "read " + s.mesh_path + ": " + std::to_string(mesh.V.rows()) + " vertices, " +
                             std::to_string(mesh.F.rows()) + " faces");
  return mesh;
}

// The --values file as a matrix with one row per site; its row count must match `sites`.
Eigen::MatrixXd read_site_values(const std::string& path, int sites) {
  const auto rows = cli::read_number_rows(path, 0, "values");
  if (static_cast<int>(rows.size()) != sites)
    throw InvalidInputError(path + ": " + std::to_string(rows.size()) + " rows of values for " +
                            std::to_string(sites) + " sites");
  Eigen::MatrixXd values(sites, static_cast<Eigen::Index>(rows[0].size()));
  for (int i = 0; i < sites; ++i)
    for (size_t c = 0; c < rows[i].size(); ++c) values(i, static_cast<Eigen::Index>(c)) = rows[i][c];
  return values;
}

// The coordinates of every vertex and what computing them took.
struct Coordinates {
  VertexWeights W;
  std::vector<int> exact_vertices;  // the vertices computed exactly (all of them with --exact)
  double setup_s = 0, coords_s = 0;
};

// The library's options of the coordinates that the settings ask for.
NaturalNeighbourOptions coordinate_options(const Settings& s) {
  NaturalNeighbourOptions opt;
  opt.time_coefficient = s.t_coef;
  opt.threads = s.threads;
  opt.samples = s.samples;
  return opt;
}

// Coordinates are undefined on a component without sites (its rows would be empty): an input error.
void require_a_site_per_component(const VoronoiDiagram& diagram, const Settings& s) {
  if (!diagram.unreached_components.empty())
    throw InvalidInputError(s.sites_path + ": connected component " +
                            std::to_string(diagram.unreached_components.front()) + " of " + s.mesh_path +
                            " has no site (natural-neighbour coordinates are undefined there; give every component "
                            "a site)");
}

// Sets up the coordinates of the sites (factorisation, one diffusion per site, tessellation) and
// computes those of every vertex (exactly with --exact, else propagated from exact samples).
Coordinates compute_coordinates(const TriangleMesh& unit, const std::vector<SurfacePoint>& sites, const Settings& s,
                                const NormalizationFrame& frame) {
  Coordinates c;
  auto t0 = Clock::now();
  const NaturalNeighbourOptions opt = coordinate_options(s);
  NaturalNeighbourCoordinates nn =
      cli::on_file(s.mesh_path, [&] { return NaturalNeighbourCoordinates(unit.V, unit.F, sites, opt); });
  c.setup_s = cli::seconds_since(t0);
  require_a_site_per_component(nn.diagram(), s);
  cli::log_line(s.quiet, "factored M - tL (t = " + format_double(nn.solver().time_step() * frame.scale * frame.scale) +
                             "), " + std::to_string(sites.size()) + " diffusions and the tessellation in " +
                             std::to_string(c.setup_s) + " s");
  t0 = Clock::now();
  {
    // progress in per mille of the work (the total is only known once the work has started)
    cli::Progress bar(s.exact ? "exact coordinates" : "coordinates", 1000, s.quiet);
    auto report = [&](long done, long total) { bar.update(total > 0 ? 1000 * done / total : 0); };
    c.W = cli::on_file(s.mesh_path, [&] {
      return s.exact ? nn.vertex_weights_direct(report) : nn.vertex_weights(report, &c.exact_vertices);
    });
    bar.finish();
  }
  if (s.exact) c.exact_vertices.resize(unit.V.rows());
  c.coords_s = cli::seconds_since(t0);
  return c;
}

// Checks of the result (exit status 3 when one fails, cli_common.h): rows are partitions of unity.
std::vector<cli::CheckRecord> weight_checks(const VertexWeights& W) {
  constexpr double sum_tolerance = 1e-9;
  long empty_rows = 0, bad_sums = 0, negative = 0;
  for (int v = 0; v < W.rows(); ++v) {
    double sum = 0;
    for (VertexWeights::InnerIterator it(W, v); it; ++it) {
      sum += it.value();
      negative += it.value() < 0 ? 1 : 0;
    }
    if (W.row(v).nonZeros() == 0) ++empty_rows;
    else if (!(std::abs(sum - 1) <= sum_tolerance)) ++bad_sums;
  }
  return {{"every_vertex_weighted", empty_rows == 0, true,
           empty_rows == 0 ? "ok" : std::to_string(empty_rows) + " vertices without weights"},
          {"weights_sum_to_one", bad_sums == 0, true,
           bad_sums == 0 ? "ok" : std::to_string(bad_sums) + " vertices whose weights do not sum to 1"},
          {"weights_non_negative", negative == 0, true,
           negative == 0 ? "ok" : std::to_string(negative) + " negative weights"}};
}

// The --report of a run (schema: report_json.h), without the common tail.
cli::Json make_report(const Settings& s, const TriangleMesh& mesh, int sites, const Coordinates& c, double total_s) {
  cli::Json rep = cli::report_head("nncoords", s.mesh_path, {s.out_path, s.weights_path, s.report_path});
  rep["sites_file"] = s.sites_path;
  rep["vertices"] = static_cast<int>(mesh.V.rows());
  rep["faces"] = mesh.F.rows();
  rep["sites"] = sites;
  rep["exact"] = s.exact;
  rep["exact_vertices"] = c.exact_vertices.size();
  rep["nonzero_weights"] = c.W.nonZeros();
  rep["total_s"] = total_s;
  return rep;
}

// Writes the interpolated values (with --values) or the weights, and the report: all or none.
// Returns the note on the values output (" (as colour)" when they are written as colour).
std::string write_outputs(const Settings& s, const TriangleMesh& mesh, const Eigen::MatrixXd& values,
                          const VertexWeights& W, const cli::Json& rep) {
  std::string colour_note;
  OutputTransaction outputs;  // all outputs or none (atomic_file.h)
  if (!s.values_path.empty()) {
    const Eigen::MatrixXd X = interpolate_site_values(W, values);
    const bool colour = values.cols() == 3 && values.minCoeff() >= 0 && values.maxCoeff() <= 1;
    colour_note = colour ? " (as colour)" : "";
    write_values_ply(s.out_path, mesh, X, colour);
  } else {
    write_weights(s.weights_path, W);
  }
  if (!s.report_path.empty()) cli::write_json(s.report_path, rep);
  outputs.commit();
  return colour_note;
}

// Prints the summary of a run on stdout: sizes, weights per vertex, times, the output and the checks.
void print_summary(const Settings& s, const TriangleMesh& mesh, int sites, const Coordinates& c, double total_s,
                   const std::string& colour_note, const std::vector<cli::CheckRecord>& checks) {
  const int nv = static_cast<int>(mesh.V.rows());
  long nonzeros = c.W.nonZeros();
  std::printf("nncoords: %d sites on %d vertices / %ld faces: %.2f non-zero weights per vertex on average\n", sites, nv,
              static_cast<long>(mesh.F.rows()), static_cast<double>(nonzeros) / nv);
  std::printf("  %s: %zu vertices computed exactly%s\n", s.exact ? "exact" : "propagated", c.exact_vertices.size(),
              s.exact ? "" : ", the others propagated biharmonically");
  std::printf("  time: setup %.3f s, coordinates %.3f s (%.3f ms / vertex), total %.3f s\n", c.setup_s, c.coords_s,
              1e3 * c.coords_s / nv, total_s);
  std::printf("  wrote %s%s\n", (s.values_path.empty() ? s.weights_path : s.out_path).c_str(), colour_note.c_str());
  cli::print_checks(checks);
}

// The whole run after parsing: checks, inputs, coordinates, report, outputs, summary; the exit status.
int run(const Settings& s) {
  check_settings(s);
  const auto t_start = Clock::now();
  const TriangleMesh mesh = read_input(s);
  // Everything below runs on the mesh in its unit bounding-box frame (normalize.h); the
  // coordinates do not depend on the units, and the output keeps the input's positions.
  TriangleMesh unit = mesh;
  const NormalizationFrame frame = cli::on_file(s.mesh_path, [&] { return normalize_positions(unit.V); });
  // sites: snapped to the surface; off-surface and duplicate sites are errors
  const std::vector<SurfacePoint> sites = cli::read_snapped_sites(s.sites_path, unit.V, unit.F, frame, s.snap);
  const int ns = static_cast<int>(sites.size());
  if (ns < 2) throw InvalidInputError(s.sites_path + ": " + std::to_string(ns) + " site given, at least 2 are needed");
  const Eigen::MatrixXd values = s.values_path.empty() ? Eigen::MatrixXd() : read_site_values(s.values_path, ns);
  const Coordinates c = compute_coordinates(unit, sites, s, frame);
  const std::vector<cli::CheckRecord> checks = weight_checks(c.W);
  const double total_s = cli::seconds_since(t_start);
  cli::Json rep = make_report(s, mesh, ns, c, total_s);
  const int status = cli::finish_report(rep, {{"setup", c.setup_s}, {"coordinates", c.coords_s}}, checks);
  const std::string colour_note = write_outputs(s, mesh, values, c.W, rep);
  if (!s.quiet) print_summary(s, mesh, ns, c, total_s, colour_note, checks);
  if (status != cli::exit_ok) cli::log_line(s.quiet, "warning: the coordinates failed some checks (exit status 3)");
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"nncoords: natural-neighbour coordinates by area stealing on heat Voronoi cells "
               "(Herholz et al. 2017, §7.2): interpolate site values or export skinning weights"};
  Settings settings;
  add_options(app, settings);
  return cli::parse_and_run(app, argc, argv, "nncoords", [&] { return run(settings); });
}
