// Scale benchmark of the streamed, voxel-first front end (reconstruct_stream.h): clouds of 1e5,
// 1e6, 1e7 (and 1e8 with --huge) points sampled from armadillo (noise 0.1 % of the bbox diagonal
// by default, --noise F for F of it,
// no normals) are written as binary little-endian PLY (float x y z) to a temporary directory in
// chunks of 1e6 points (never the whole cloud in memory), then reconstructed through
// reconstruct_surface_streamed at -n 3000 and at a fixed density (points / 50 sites, capped at
// 200,000; only for clouds up to --density-max points). Each reconstruction runs in a child
// process (this program re-executed) so that its peak memory (getrusage ru_maxrss) is its own.
// The peer, PCL Poisson (depth 8) + CGAL isotropic remeshing to the same vertex count on the
// whole cloud in memory (normals by PCA + MST), runs the same way on clouds up to --peer-max
// points. Prints a markdown table: time, the time spent reading, peak memory, the points the
// reconstruction ran on, vertices, the mesh checks (closed, genus, φmin, φm) and the distances to
// armadillo.obj. Below the table: heatcvt's time over the peer's for each row the peer ran, and
// heatcvt's milliseconds per site on the fixed-density rows with their spread (± % around the
// midpoint of their range; the issue asks for ±30 %).
//
// Usage: bench_scale [--sizes 100000,1000000,10000000] [--huge] [--density-max 1000000]
//                    [--peer-max 1000000] [--sites 3000] [--keep-dir DIR] [--fine F] [--plain-means]
//                    [--plain-fit] [--glibc-allocator] [--noise F] [--stream-per-site P]
//                    [--points-per-site M]
// (--fine: StreamOptions::fine_voxel_factor; --plain-means: project_to_surface = false;
//  --plain-fit: the 3×3×3 voxel plane fit only, VoxelSurfaceFit max_levels = shift_steps = 0;
//  --stream-per-site P: StreamOptions::max_raw_points_per_site = P, 0 = no limit per site;
//  --points-per-site M: StreamOptions::voxel.points_per_site = M (voxel means per site);
//  --glibc-allocator: both children keep glibc's allocator defaults instead of the tools' setting)
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "cli_common.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/validate.h"
#include "peer_pipelines.h"

using namespace heatcvt;
namespace fs = std::filesystem;

namespace {

constexpr std::int64_t kWriteChunk = 1000000;  // points sampled and written at a time
constexpr double kNoiseFraction = 0.001;       // default noise σ (--noise) as a fraction of the bbox diagonal

// Writes `count` points sampled from (V, F) plus noise as a float binary little-endian PLY.
// Written to `path`.part and renamed at the end, so an interrupted write leaves no file that a
// later run with --keep-dir would take for a finished cloud.
void write_sampled_ply(const std::string& path, const TriangleMesh& mesh, std::int64_t count, double sigma) {
  const std::string part = path + ".part";
  std::ofstream out(part, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << count
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  std::vector<float> buf;
  std::uint32_t seed = 101;
  for (std::int64_t done = 0; done < count; done += kWriteChunk) {
    const int n = static_cast<int>(std::min(kWriteChunk, count - done));
    const Eigen::MatrixX3d P = sample_surface(mesh.V, mesh.F, n, seed++, sigma);
    buf.resize(static_cast<std::size_t>(n) * 3);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) buf[static_cast<std::size_t>(i) * 3 + k] = static_cast<float>(P(i, k));
    out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() * sizeof(float)));
  }
  out.close();
  if (!out) throw std::runtime_error("cannot write " + part);
  fs::rename(part, path);
}

// "mean=… hausdorff=…": two-sided distances between `m` and the source mesh, in ‰ of its diagonal.
// The child's system time and minor page faults (getrusage), as "sys=… faults=…".
std::string fault_keys(const rusage& ru) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "sys=%.2f faults=%ld", ru.ru_stime.tv_sec + 1e-6 * ru.ru_stime.tv_usec, ru.ru_minflt);
  return buf;
}

std::string distance_keys(const TriangleMesh& m) {
  const TriangleMesh source = read_mesh(std::string(HEATCVT_DATA_DIR) + "/meshes/armadillo.obj");
  const double diag = (source.V.colwise().maxCoeff() - source.V.colwise().minCoeff()).norm();
  const SurfaceDistance d = surface_distance(source.V, source.F, m.V, m.F, 20000);
  char buf[96];
  std::snprintf(buf, sizeof buf, "mean=%.3f hausdorff=%.2f", 1000 * d.mean / diag, 1000 * d.hausdorff / diag);
  return buf;
}

// Child: reconstruct one file, print one line "key=value ...".
int run_child(const std::string& path, int sites, double fine_factor, bool project, bool plain_fit, double per_site,
              double means_per_site) {
  ReconstructionOptions options;
  options.sites = sites;
  StreamOptions stream;
  stream.voxel.points_per_site = means_per_site;
  stream.fine_voxel_factor = fine_factor;
  stream.project_to_surface = project;
  if (plain_fit) stream.surface_fit.max_levels = stream.surface_fit.shift_steps = 0;
  stream.max_raw_points_per_site = per_site;
  const double t0 = bench::now_seconds();
  double t_stream = -1;
  const auto progress = [&](const std::string&, double) {
    if (t_stream < 0) t_stream = bench::now_seconds() - t0;
  };
  const StreamedReconstruction r = reconstruct_surface_streamed(path, options, stream, progress);
  const double total = bench::now_seconds() - t0;
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);  // before the distance below, which is not part of the run
  const auto& v = r.result.validation;
  std::printf("%s time=%.2f stream=%.2f peak_mb=%.0f used=%lld summarised=%d voxel=%.6g vertices=%ld boundary=%d genus=%d "
              "phimin=%.1f phim=%.1f %s\n",
              fault_keys(ru).c_str(), total, t_stream, static_cast<double>(ru.ru_maxrss) / 1024.0, static_cast<long long>(r.cloud.P.rows()),
              r.summarised ? 1 : 0, r.voxel_size, static_cast<long>(r.result.mesh.V.rows()), v.boundary_loops, v.genus,
              r.result.min_angle_deg, r.result.mean_min_angle_deg, distance_keys(r.result.mesh).c_str());
  return 0;
}

// Peer child: the whole cloud read into memory, normals (peer_normals), PCL Poisson (depth 8)
// and CGAL isotropic remeshing to `sites` vertices; prints the same keys as run_child.
int run_peer_child(const std::string& path, int sites) {
  const double t0 = bench::now_seconds();
  const PointCloud cloud = read_cloud(path);
  const double t_read = bench::now_seconds() - t0;
  const Eigen::MatrixX3d N = test::peer_normals(cloud.P);
  const TriangleMesh poisson = test::pcl_poisson(cloud.P, N, 8);
  // The remeshing counts with its last run alone (remesh_to() searches the edge length that
  // gives the count; a user who knew it would run once).
  const double before_remesh = bench::now_seconds() - t0;
  double last_run = 0;
  const TriangleMesh m = test::remesh_to(poisson, sites, &last_run);
  const double total = before_remesh + last_run;
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  ValidationOptions vo;
  vo.require_closed = false;
  vo.check_self_intersections = false;
  const ValidationReport rep = validate_triangle_mesh(m.V, m.F, vo);
  const TriangleQuality q = triangle_quality(m.V, m.F);
  std::printf("%s time=%.2f stream=%.2f peak_mb=%.0f used=%lld summarised=0 voxel=- vertices=%ld boundary=%d genus=%d "
              "phimin=%.1f phim=%.1f %s\n",
              fault_keys(ru).c_str(), total, t_read, static_cast<double>(ru.ru_maxrss) / 1024.0, static_cast<long long>(cloud.P.rows()),
              static_cast<long>(m.V.rows()), rep.boundary_loops, rep.genus, q.min_angle_deg, q.mean_min_angle_deg,
              distance_keys(m).c_str());
  return 0;
}

std::string value_of(const std::string& line, const std::string& key) {
  const auto p = line.find(key + "=");
  if (p == std::string::npos) return "?";
  const auto e = line.find_first_of(" \n", p);
  return line.substr(p + key.size() + 1, e == std::string::npos ? std::string::npos : e - p - key.size() - 1);
}

std::vector<std::int64_t> parse_sizes(const std::string& s) {
  std::vector<std::int64_t> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(static_cast<std::int64_t>(std::stod(item)));
  return out;
}

// Runs `command`; returns its "time=..." line, or "failed: <all output>".
std::string run_command(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  std::string line, all;
  char buf[4096];
  while (pipe && std::fgets(buf, sizeof buf, pipe)) {
    all += buf;
    if (std::strncmp(buf, "sys=", 4) == 0) line = buf;
  }
  const int status = pipe ? pclose(pipe) : -1;
  return status != 0 || line.empty() ? "failed: " + all : line;
}

// Prints one table row; returns the run's time in seconds (-1 where it failed).
double print_row(std::int64_t points, int n, const char* method, const std::string& line) {
  if (line.rfind("failed", 0) == 0) {
    std::printf("| %lld | %d | %s | %s |\n", static_cast<long long>(points), n, method, line.c_str());
    return -1;
  }
  const double seconds = std::stod(value_of(line, "time"));
  const long vertices = std::stol(value_of(line, "vertices"));
  const bool closed = value_of(line, "boundary") == "0";
  std::printf("| %lld | %d | %s | %s | %.2f | %s | %s | %s | %.0f | %s%s | %s | %ld | %+.1f %% | %s | %s | %s | %s | %s | %s |\n",
              static_cast<long long>(points), n, method, value_of(line, "time").c_str(), 1000.0 * seconds / n,
              value_of(line, "stream").c_str(),
              value_of(line, "peak_mb").c_str(), value_of(line, "sys").c_str(),
              std::stod(value_of(line, "faults")) / 1000.0, value_of(line, "used").c_str(),
              value_of(line, "summarised") == "1" ? " means" : " raw", value_of(line, "voxel").c_str(), vertices,
              100.0 * (static_cast<double>(vertices) - n) / n, closed ? "yes" : "no", value_of(line, "genus").c_str(),
              value_of(line, "phimin").c_str(), value_of(line, "phim").c_str(), value_of(line, "mean").c_str(),
              value_of(line, "hausdorff").c_str());
  std::fflush(stdout);
  return seconds;
}

}  // namespace

// Set by --glibc-allocator for the children: they keep glibc's allocator defaults.
constexpr const char* kGlibcAllocatorEnv = "HEATCVT_BENCH_GLIBC_ALLOCATOR";

int main(int argc, char** argv) {
  // Both children run with the allocator setting of the tools (cli::keep_freed_memory()), so
  // the library is timed as cloud2mesh runs it and the peer under the same conditions; with
  // --glibc-allocator (passed to the children in kGlibcAllocatorEnv) both keep glibc's defaults.
  if (argc >= 2 && (std::string(argv[1]) == "--child" || std::string(argv[1]) == "--peer-child") &&
      !std::getenv(kGlibcAllocatorEnv))
    heatcvt::cli::keep_freed_memory();
  if (argc == 9 && std::string(argv[1]) == "--child")
    return run_child(argv[2], std::atoi(argv[3]), std::atof(argv[4]), std::atoi(argv[5]) != 0, std::atoi(argv[6]) != 0,
                     std::atof(argv[7]), std::atof(argv[8]));
  if (argc == 4 && std::string(argv[1]) == "--peer-child") return run_peer_child(argv[2], std::atoi(argv[3]));
  const StreamOptions defaults;
  double fine_factor = defaults.fine_voxel_factor;
  bool project = defaults.project_to_surface, plain_fit = false;
  double raw_per_site = defaults.max_raw_points_per_site;
  double means_per_site = defaults.voxel.points_per_site;
  std::vector<std::int64_t> sizes = {100000, 1000000, 10000000};
  std::int64_t density_max = 1000000;
  std::int64_t peer_max = 1000000;
  int sites = 3000;
  double noise = kNoiseFraction;
  std::string keep_dir;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    try {
      if (a == "--sizes" && i + 1 < argc) sizes = parse_sizes(argv[++i]);
      else if (a == "--huge") sizes.push_back(100000000);
      else if (a == "--density-max" && i + 1 < argc) density_max = static_cast<std::int64_t>(std::stod(argv[++i]));
      else if (a == "--sites" && i + 1 < argc) sites = std::stoi(argv[++i]);
      else if (a == "--peer-max" && i + 1 < argc) peer_max = static_cast<std::int64_t>(std::stod(argv[++i]));
      else if (a == "--keep-dir" && i + 1 < argc) keep_dir = argv[++i];
      else if (a == "--fine" && i + 1 < argc) fine_factor = std::stod(argv[++i]);
      else if (a == "--plain-means") project = false;
      else if (a == "--plain-fit") plain_fit = true;
      else if (a == "--stream-per-site" && i + 1 < argc) raw_per_site = std::stod(argv[++i]);
      else if (a == "--points-per-site" && i + 1 < argc) means_per_site = std::stod(argv[++i]);
      else if (a == "--glibc-allocator") setenv(kGlibcAllocatorEnv, "1", 1);
      else if (a == "--noise" && i + 1 < argc) noise = std::stod(argv[++i]);
      else {
        std::fprintf(stderr, "bench_scale: error: %s: unknown option\n", a.c_str());
        return 2;
      }
    } catch (const std::exception&) {
      std::fprintf(stderr, "bench_scale: error: %s %s: not a number\n", a.c_str(), argv[i]);
      return 2;
    }
  }
  if (sites < 1) {
    std::fprintf(stderr, "bench_scale: error: --sites %d: must be at least 1\n", sites);
    return 2;
  }
  if (!(noise >= 0) || !std::isfinite(noise)) {
    std::fprintf(stderr, "bench_scale: error: --noise %g: must be a finite fraction >= 0\n", noise);
    return 2;
  }
  if (!(means_per_site > 0) || !std::isfinite(means_per_site)) {
    std::fprintf(stderr, "bench_scale: error: --points-per-site %g: must be a finite number > 0\n", means_per_site);
    return 2;
  }
  const TriangleMesh mesh = read_mesh(std::string(HEATCVT_DATA_DIR) + "/meshes/armadillo.obj");
  const double diag = (mesh.V.colwise().maxCoeff() - mesh.V.colwise().minCoeff()).norm();
  const fs::path dir = keep_dir.empty() ? fs::temp_directory_path() / ("heatcvt_bench_scale_" + std::to_string(::getpid())) : fs::path(keep_dir);
  fs::create_directories(dir);
  std::printf("| points | -n | method | time s | ms per site | read s | peak MB | sys s | page faults k | points reconstructed | voxel | V | "
              "V vs -n | closed | genus | phi_min | phi_m | mean dist ‰ | Hausdorff ‰ |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  struct Figure {
    std::int64_t points;
    int sites;
    double value;
  };
  std::vector<Figure> per_site;  // heatcvt's ms per site on the fixed-density rows
  std::vector<Figure> ratios;    // heatcvt's time over the peer's, same cloud and count
  // popen runs through the shell: /proc/self/exe would be the shell, so name this binary.
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  for (const std::int64_t points : sizes) {
    const std::string tag = noise == kNoiseFraction ? "" : "_noise" + std::to_string(noise);
    const fs::path file = dir / ("armadillo_" + std::to_string(points) + tag + ".ply");
    if (!fs::exists(file)) {
      const double t0 = bench::now_seconds();
      write_sampled_ply(file.string(), mesh, points, noise * diag);
      std::fprintf(stderr, "wrote %s (%.1f s)\n", file.c_str(), bench::now_seconds() - t0);
    }
    std::vector<int> runs = {sites};
    if (points <= density_max) runs.push_back(static_cast<int>(std::min<std::int64_t>(points / 50, 200000)));
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const int n = runs[r];
      double ours = -1;
      for (const bool peer : {false, true}) {
        if (peer && points > peer_max) continue;
        const std::string command =
            "'" + self + "' " +
            (peer ? "--peer-child '" + file.string() + "' " + std::to_string(n)
                  : "--child '" + file.string() + "' " + std::to_string(n) + " " + std::to_string(fine_factor) + " " +
                        (project ? "1" : "0") + (plain_fit ? " 1 " : " 0 ") + std::to_string(raw_per_site) + " " +
                        std::to_string(means_per_site)) +
            " 2>&1";
        const double t = print_row(points, n, peer ? "PCL Poisson + CGAL remesh" : "heatcvt", run_command(command));
        if (!peer) ours = t;
        if (peer && ours > 0 && t > 0) ratios.push_back({points, n, ours / t});
      }
      if (r == 1 && ours > 0) per_site.push_back({points, n, 1000.0 * ours / n});
    }
  }
  if (keep_dir.empty()) fs::remove_all(dir);
  for (const Figure& f : ratios)
    std::printf("\n%lld points -> %d vertices: heatcvt's time is %.3f x the peer's", static_cast<long long>(f.points),
                f.sites, f.value);
  if (!per_site.empty()) {
    double lo = per_site[0].value, hi = lo;
    std::printf("\nfixed density (points / 50 sites):");
    for (const Figure& f : per_site) {
      std::printf(" %d sites %.2f ms per site;", f.sites, f.value);
      lo = std::min(lo, f.value), hi = std::max(hi, f.value);
    }
    // Constant within ±x % means every figure within x % of one value: the midpoint of the range.
    std::printf(" spread +/-%.0f %% around %.2f ms", 100.0 * (hi - lo) / (hi + lo), 0.5 * (hi + lo));
  }
  std::printf("\n");
  std::printf("\nArmadillo (genus 0), noise σ = %.2f %% of the bbox diagonal, float binary PLY written in chunks of %lld "
              "points; time = wall time of the child process's work (heatcvt: reconstruct_surface_streamed, both read passes "
              "included; peer: read_cloud, PCA/MST normals, PCL Poisson depth 8, CGAL isotropic remeshing to -n), read = "
              "until the first reconstruction stage (heatcvt) or until the cloud is in memory (peer); peak MB = "
              "ru_maxrss of the child process (taken before the distances); sys s and page faults: its system time and minor page faults (ru_stime, ru_minflt); mean dist and Hausdorff: two-sided, "
              "between the output and armadillo.obj (20,000 samples each way), in ‰ of its bbox diagonal. The peer runs on clouds up to --peer-max points.\n",
              100 * noise, static_cast<long long>(kWriteChunk));
  return 0;
}
