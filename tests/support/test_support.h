#pragma once
// Shared helpers for the tests: shapes built in code and access to ../shared/data.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"

namespace heatcvt::test {

/// The thread counts every determinism test compares: results must be bit-identical for each.
constexpr std::array<int, 3> kThreadCounts{1, 2, 4};

/// Path of a file under ../shared/data (e.g. "meshes/torus.obj"); fails the test with a clear
/// message (via ADD_FAILURE + throw) when the data directory or the file is missing.
std::string data_path(const std::string& relative);

/// Icosphere with `subdivisions` Loop-style midpoint subdivisions of an icosahedron, radius 1.
TriangleMesh icosphere(int subdivisions);

/// icosphere(subdivisions) with its vertex 0 moved out to `tip_radius` along its own direction:
/// a thin cone on the sphere whose end (vertex 0) is the tip of a thin part.
TriangleMesh spiked_sphere(int subdivisions, double tip_radius);

/// Regular grid triangulation of [x0,x1]×[y0,y1] in the z = 0 plane with n×n quads, each split
/// into two triangles (alternating diagonals when `alternate` is set).
TriangleMesh grid(int n, double x0 = 0, double x1 = 1, double y0 = 0, double y1 = 1, bool alternate = true);

/// Torus with radii R, r and n×m vertices.
TriangleMesh torus(int n, int m, double R = 1.0, double r = 0.4);

/// `n` points uniformly on the sphere of radius r about c (normalised Gaussian vectors,
/// std::mt19937 seeded with `seed`).
Eigen::MatrixX3d sphere_points(int n, double r, const Eigen::Vector3d& c, unsigned seed);

/// Scales V so the surface area is exactly `area`.
void scale_to_area(TriangleMesh& mesh, double area);

/// The shape on which the CVT tests compare configurations: icosphere(subdivisions) scaled to
/// unit area, with its cotan Laplacian.
struct UnitSphere {
  TriangleMesh mesh;
  Laplacian laplacian;
};
UnitSphere unit_area_sphere(int subdivisions);

/// The mesher's working mesh of `m`: its vertices with their area-weighted vertex normals, no
/// projection anchors, and its faces.
WorkingMesh working_mesh(const TriangleMesh& m);

}  // namespace heatcvt::test

namespace heatcvt::test {

/// A fresh temporary directory, removed with its content when the object dies.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string path(const std::string& name) const;
  /// Number of entries (files, including hidden temporaries) in the directory.
  int entries() const;

 private:
  std::string dir_;
};

/// Result of running a command through the shell.
struct CommandResult {
  int exit_code = -1;
  std::string out, err;
};

/// Runs `bin/<tool> <args>` from the build tree (args are passed to the shell as written),
/// capturing stdout and stderr.
CommandResult run_tool(const std::string& tool, const std::string& args);

/// Writes a text file.
void write_text_file(const std::string& path, const std::string& text);

/// The bytes of a file ("" when it cannot be read).
std::string read_file(const std::string& path);

/// The number after `"key":` in a JSON text (the first occurrence); fails the test and returns NaN
/// when there is none.
double json_number(const std::string& json, const std::string& key);

/// The names of the checks a tool's `--report` JSON text lists as failed or not run ("passed" not
/// true), in the report's order; fails the test and returns {"<no checks>"} when it lists none.
std::vector<std::string> failed_checks(const std::string& json);

/// The contract of a tool on bad input: a non-zero exit, exactly one line mentioning "error" on
/// stderr, which starts with "<tool>: error: " and contains every needle, and `dir` holding
/// `expected_entries` entries afterwards (no output or temporary left behind).
void expect_tool_failure(const std::string& tool, const CommandResult& r, const std::vector<std::string>& needles,
                         const ScratchDir& dir, int expected_entries);

}  // namespace heatcvt::test
