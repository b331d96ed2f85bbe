// nncoords: natural-neighbour coordinates by area stealing on heat Voronoi diagrams (paper §7.2):
// interpolate values given at sites to every vertex, or export per-vertex skinning weights.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"nncoords: natural-neighbour coordinates by area stealing on heat Voronoi cells "
               "(Herholz et al. 2017, §7.2): interpolate site values or export skinning weights"};
  NaturalNeighbourOptions defaults;
  std::string mesh_path, sites_path, values_path, out_path, weights_path, report_path;
  double t_coef = defaults.time_coefficient, snap = 1e-3;
  int threads = defaults.threads, samples = defaults.samples;
  bool quiet = false, exact = false;
  app.add_option("MESH", mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("--sites", sites_path, "sites (handles), one 'x y z' per line, on the surface")->required();
  auto* values_opt = app.add_option("--values", values_path, "values at the sites: one row per site (k columns)");
  auto* out_opt = app.add_option("-o,--output", out_path, "output with --values: mesh with interpolated per-vertex values (.ply; colour when k = 3 in [0,1])");
  auto* weights_opt = app.add_option("--weights", weights_path, "output: per vertex the non-zero (site, weight) pairs (.txt)");
  values_opt->needs(out_opt);
  out_opt->needs(values_opt);
  weights_opt->excludes(values_opt);
  values_opt->excludes(weights_opt);
  app.add_option("--t-coef", t_coef, "time step t = C * (mean edge length)^2")->capture_default_str();
  app.add_option("--samples", samples, "vertices computed exactly before propagation (0 = max(500, #V/20))")
      ->capture_default_str();
  app.add_flag("--exact", exact, "exact coordinates at every vertex (one diffusion per vertex; slow)");
  app.add_option("--snap-tolerance", snap, "sites farther than this fraction of the bounding-box diagonal from the surface are an error")
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (0 = all cores)")->capture_default_str();
  app.add_option("--report", report_path, "write a JSON report");
  app.add_flag("-q,--quiet", quiet, "no progress output on stderr");
  app.callback([&]() {
    if (values_path.empty() && weights_path.empty())
      throw CLI::RequiredError("one of --values VALUES -o OUT.ply or --weights WEIGHTS.txt");
  });
  if (const int status = cli::parse_command_line(app, argc, argv, "nncoords"); status >= 0) return status;

  return cli::run_tool("nncoords", [&]() -> int {
    if (!(t_coef > 0) || !std::isfinite(t_coef)) throw InvalidInputError("--t-coef must be a positive number");
    if (threads < 0) throw InvalidInputError("--threads must be >= 0");
    if (samples < 0) throw InvalidInputError("--samples must be >= 0");
    if (!(snap > 0) || !std::isfinite(snap)) throw InvalidInputError("--snap-tolerance must be a positive number");
    cli::check_output_path(out_path, {".ply"});
    cli::check_output_path(weights_path, {".txt"});
    cli::check_output_path(report_path, {".json"});
    cli::check_distinct_outputs({{"-o", out_path}, {"--weights", weights_path}, {"--report", report_path}}, {mesh_path});
    auto log = [&](const std::string& s) {
      if (!quiet) std::cerr << s << std::endl;
    };
    const auto t_start = Clock::now();
    TriangleMesh mesh = read_mesh(mesh_path);
    validate_mesh(mesh.V, mesh.F, mesh_path);
    const int nv = static_cast<int>(mesh.V.rows());
    log("read " + mesh_path + ": " + std::to_string(nv) + " vertices, " + std::to_string(mesh.F.rows()) + " faces");

    // Everything below runs on the mesh in its unit bounding-box frame (normalize.h); the
    // coordinates do not depend on the units, and the output keeps the input's positions.
    TriangleMesh unit = mesh;
    const NormalizationFrame frame = cli::on_file(mesh_path, [&] { return normalize_positions(unit.V); });
    // sites: snapped to the surface; off-surface and duplicate sites are errors
    const std::vector<SurfacePoint> sites = cli::read_snapped_sites(sites_path, unit.V, unit.F, frame, snap);
    const int ns = static_cast<int>(sites.size());
    if (ns < 2) throw InvalidInputError(sites_path + ": " + std::to_string(ns) + " site given, at least 2 are needed");
    Eigen::MatrixXd values;
    if (!values_path.empty()) {
      const auto rows = cli::read_number_rows(values_path, 0, "values");
      if (static_cast<int>(rows.size()) != ns)
        throw InvalidInputError(values_path + ": " + std::to_string(rows.size()) + " rows of values for " +
                                std::to_string(ns) + " sites");
      values.resize(ns, static_cast<Eigen::Index>(rows[0].size()));
      for (int i = 0; i < ns; ++i)
        for (size_t c = 0; c < rows[i].size(); ++c) values(i, static_cast<Eigen::Index>(c)) = rows[i][c];
    }

    auto t0 = Clock::now();
    NaturalNeighbourOptions opt;
    opt.time_coefficient = t_coef;
    opt.threads = threads;
    opt.samples = samples;
    NaturalNeighbourCoordinates nn =
        cli::on_file(mesh_path, [&] { return NaturalNeighbourCoordinates(unit.V, unit.F, sites, opt); });
    const double setup_s = cli::seconds_since(t0);
    // Coordinates are undefined on a component without sites (its rows would be empty).
    if (!nn.diagram().unreached_components.empty())
      throw InvalidInputError(sites_path + ": connected component " +
                              std::to_string(nn.diagram().unreached_components.front()) + " of " + mesh_path +
                              " has no site (natural-neighbour coordinates are undefined there; give every component "
                              "a site)");
    log("factored M - tL (t = " + format_double(nn.solver().time_step() * frame.scale * frame.scale) + "), " + std::to_string(ns) +
        " diffusions and the tessellation in " + std::to_string(setup_s) + " s");

    t0 = Clock::now();
    VertexWeights W;
    std::vector<int> exact_vertices;
    {
      // progress in per mille of the work (the total is only known once the work has started)
      cli::Progress bar(exact ? "exact coordinates" : "coordinates", 1000, quiet);
      auto report = [&](long done, long total) { bar.update(total > 0 ? 1000 * done / total : 0); };
      W = cli::on_file(mesh_path, [&] {
        return exact ? nn.vertex_weights_direct(report) : nn.vertex_weights(report, &exact_vertices);
      });
      bar.finish();
    }
    if (exact) exact_vertices.resize(nv);
    const double coords_s = cli::seconds_since(t0);

    // Checks of the result (exit status 3 when one fails, cli_common.h): rows are partitions of unity.
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
    const std::vector<cli::CheckRecord> checks = {
        {"every_vertex_weighted", empty_rows == 0, true,
         empty_rows == 0 ? "ok" : std::to_string(empty_rows) + " vertices without weights"},
        {"weights_sum_to_one", bad_sums == 0, true,
         bad_sums == 0 ? "ok" : std::to_string(bad_sums) + " vertices whose weights do not sum to 1"},
        {"weights_non_negative", negative == 0, true,
         negative == 0 ? "ok" : std::to_string(negative) + " negative weights"}};
    const double total_s = cli::seconds_since(t_start);
    cli::Json rep = cli::report_head("nncoords", mesh_path, {out_path, weights_path, report_path});
    rep["sites_file"] = sites_path;
    rep["vertices"] = nv;
    rep["faces"] = mesh.F.rows();
    rep["sites"] = ns;
    rep["exact"] = exact;
    rep["exact_vertices"] = exact_vertices.size();
    rep["nonzero_weights"] = W.nonZeros();
    rep["total_s"] = total_s;
    const int status = cli::finish_report(rep, {{"setup", setup_s}, {"coordinates", coords_s}}, checks);

    std::string colour_note;
    {
      OutputTransaction outputs;  // all outputs or none (atomic_file.h)
      if (!values_path.empty()) {
        const Eigen::MatrixXd X = interpolate_site_values(W, values);
        const bool colour = values.cols() == 3 && values.minCoeff() >= 0 && values.maxCoeff() <= 1;
        colour_note = colour ? " (as colour)" : "";
        write_values_ply(out_path, mesh, X, colour);
      } else {
        write_weights(weights_path, W);
      }
      if (!report_path.empty()) cli::write_json(report_path, rep);
      outputs.commit();
    }
    if (!quiet) {
      long nonzeros = W.nonZeros();
      std::printf("nncoords: %d sites on %d vertices / %ld faces: %.2f non-zero weights per vertex on average\n", ns, nv,
                  static_cast<long>(mesh.F.rows()), static_cast<double>(nonzeros) / nv);
      std::printf("  %s: %zu vertices computed exactly%s\n", exact ? "exact" : "propagated", exact_vertices.size(),
                  exact ? "" : ", the others propagated biharmonically");
      std::printf("  time: setup %.3f s, coordinates %.3f s (%.3f ms / vertex), total %.3f s\n", setup_s, coords_s,
                  1e3 * coords_s / nv, total_s);
      std::printf("  wrote %s%s\n", (values_path.empty() ? weights_path : out_path).c_str(), colour_note.c_str());
      cli::print_checks(checks);
    }
    if (status != cli::exit_ok) log("warning: the coordinates failed some checks (exit status 3)");
    return status;
  });
}
