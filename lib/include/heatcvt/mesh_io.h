#pragma once
/// \file mesh_io.h
/// Reading and writing triangle meshes: OBJ, OFF, PLY (ascii / binary little / big endian) and
/// STL (ascii / binary), chosen by the file extension (case-insensitive).
///
/// Readers return a clean triangle mesh: polygons are triangulated (ear clipping in the
/// polygon's best-fit (Newell) plane; a fan for polygons of more than 256 corners or when clipping
/// fails), faces with a repeated vertex index are dropped,
/// unreferenced vertices are removed (indices are renumbered preserving vertex order), STL
/// vertices are welded by exact position. What was changed is counted in MeshReadReport.
///
/// Error classes (every message is one line "<path>: <problem>"):
///   IOError            missing/unreadable file, unknown extension or format, truncated file
///                      (fewer vertices/faces than the header says, binary data too short),
///                      malformed numbers or header, face index out of range.
///   InvalidInputError  the file is well-formed but unusable: NaN/inf coordinates, no faces.
/// Header counts are checked against the file size before anything is allocated, so corrupt
/// headers cannot trigger huge allocations.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// What read_mesh saw and changed.
struct MeshReadReport {
  std::string format;                  ///< "obj", "off", "ply-ascii", "ply-binary_little_endian", "stl-binary", ...
  int vertices_in_file = 0;            ///< vertices stored in the file (STL: corners before welding)
  int polygons_in_file = 0;            ///< faces stored in the file (any arity)
  int polygons_triangulated = 0;       ///< faces with more than three corners that were split
  int triangles_from_polygons = 0;     ///< triangles those faces produced
  int degenerate_faces_dropped = 0;    ///< faces with < 3 distinct corners (repeated index) dropped
  int zero_area_triangles = 0;         ///< kept triangles with exactly zero area (informational)
  int unreferenced_vertices_dropped = 0;
  int welded_vertices = 0;             ///< STL corners merged into an existing vertex
  bool has_vertex_normals = false;     ///< the file had per-vertex normals (ignored by read_mesh)
};

/// Reads a triangle mesh (format by extension: .obj .off .ply .stl, case-insensitive).
///   returns V #V by 3, F #F by 3 (zero-based), every vertex referenced, no repeated corner.
/// \throw IOError, InvalidInputError as described in the file comment.
TriangleMesh read_mesh(const std::string& path, MeshReadReport* report = nullptr);

/// The raw content of a mesh file before triangulation and clean-up: all vertices as stored,
/// optional per-vertex normals (PLY nx/ny/nz, empty otherwise) and polygons as index lists in
/// CSR form (`polygon_start` has #polygons+1 entries). Indices are validated (in range).
/// Used by read_mesh and by the PLY point-cloud reader; NaN coordinates are NOT rejected here.
struct PolygonSoup {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3d N;                  ///< #V by 3 or empty
  Eigen::MatrixX3d C;                  ///< #V by 3 vertex colours in [0,1] or empty (PLY red/green/blue)
  std::vector<int> polygon_start{0};
  std::vector<int> polygon_index;
  int num_polygons() const { return static_cast<int>(polygon_start.size()) - 1; }
};

/// Parses a mesh file into a PolygonSoup without any clean-up. A file without faces is fine here.
/// \throw IOError for missing/unknown/truncated/malformed files and out-of-range indices.
PolygonSoup read_polygon_soup(const std::string& path, MeshReadReport* report = nullptr);

/// Optional per-face / per-vertex data for write_mesh.
struct MeshAttributes {
  Eigen::VectorXi face_int;            ///< #F labels (e.g. Voronoi cell id) or empty; PLY only
  std::string face_int_name = "cell";  ///< PLY property name of face_int
  Eigen::MatrixX3d face_color;         ///< #F by 3 in [0,1] or empty; PLY (uchar red/green/blue), OFF
  Eigen::MatrixX3d vertex_color;       ///< #V by 3 in [0,1] or empty; PLY (uchar), OBJ ("v x y z r g b")
  Eigen::MatrixX3d vertex_normal;      ///< #V by 3 or empty; PLY (float nx ny nz), OBJ ("vn" lines, "f a//a ...")
};

/// Encoding used by write_mesh for .ply files.
enum class PlyEncoding { binary_little_endian, binary_big_endian, ascii };

/// Writer options. Defaults: binary little-endian PLY.
struct MeshWriteOptions {
  PlyEncoding ply_encoding = PlyEncoding::binary_little_endian;
};

/// Writes a triangle mesh by extension: .ply (double coordinates, `list uchar int vertex_indices`,
/// optional face int property, face and vertex colours), .obj, .off (face colours as floats),
/// .stl (binary, float32, per-face normals). Atomic (see atomic_file.h).
///   V #V by 3, F #F by 3 zero-based; attribute sizes must match (#F resp. #V rows).
/// \throw InvalidInputError on size mismatches or indices out of range; IOError on unknown
///        extension or write failure (no file is left behind).
void write_mesh(const std::string& path, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                const MeshAttributes& attr = {}, const MeshWriteOptions& options = {});

/// Writes polylines as OBJ `v` and `l` lines (1-based indices into `points`). Atomic.
///   points #P by 3; each polyline is a list of row indices into points (at least 2).
/// \throw InvalidInputError on out-of-range indices; IOError on write failure.
void write_polylines_obj(const std::string& path, const Eigen::MatrixX3d& points,
                         const std::vector<std::vector<int>>& polylines);

/// Writes points (and optional normals, #P by 3 or empty) as text lines "x y z [nx ny nz]". Atomic.
/// \throw InvalidInputError when N is non-empty with a different row count; IOError on write failure.
void write_points_xyz(const std::string& path, const Eigen::MatrixX3d& P,
                      const Eigen::MatrixX3d& N = Eigen::MatrixX3d());

}  // namespace heatcvt
