#pragma once
// Shared helpers for the tests: shapes built in code and access to ../shared/data.
#include <Eigen/Core>
#include <string>

#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"

namespace heatcvt::test {

/// Path of a file under ../shared/data (e.g. "meshes/torus.obj"); fails the test with a clear
/// message (via ADD_FAILURE + throw) when the data directory or the file is missing.
std::string data_path(const std::string& relative);

/// Icosphere with `subdivisions` Loop-style midpoint subdivisions of an icosahedron, radius 1.
TriangleMesh icosphere(int subdivisions);

/// Regular grid triangulation of [x0,x1]×[y0,y1] in the z = 0 plane with n×n quads, each split
/// into two triangles (alternating diagonals when `alternate` is set).
TriangleMesh grid(int n, double x0 = 0, double x1 = 1, double y0 = 0, double y1 = 1, bool alternate = true);

/// Torus with radii R, r and n×m vertices.
TriangleMesh torus(int n, int m, double R = 1.0, double r = 0.4);

/// Scales V so the surface area is exactly `area`.
void scale_to_area(TriangleMesh& mesh, double area);

/// The shape on which the CVT tests compare configurations: icosphere(subdivisions) scaled to
/// unit area, with its cotan Laplacian.
struct UnitSphere {
  TriangleMesh mesh;
  Laplacian laplacian;
};
UnitSphere unit_area_sphere(int subdivisions);

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

}  // namespace heatcvt::test
