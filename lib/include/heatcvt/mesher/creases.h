#pragma once
/// \file creases.h
/// Sharp creases of an input mesh kept as feature lines of a remesh: the crease lines are found
/// on the input (edges whose two faces meet at a dihedral angle above a threshold), resampled at
/// the output's spacing (a uniform 1D sampling of each line between its corners, which is the 1D
/// centroidal Voronoi tessellation of the line), the nearest output vertices moved onto the
/// samples and joined by edges along the line, and the rest of the mesh relaxed around them.
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/mesh.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of detect_creases() and recover_creases().
struct CreaseOptions {
  bool enabled = true;  ///< Default true (`meshcvt --no-features` turns it off).
  /// An edge of two faces whose normals differ by more than this is a crease. Default 60°.
  double min_dihedral_deg = 60;
  /// A crease vertex where its line turns by more than this, or where other than two crease
  /// edges meet, is a corner: lines are resampled between corners, which keep their place. Default 60°.
  double corner_turn_deg = 60;
  /// The border of an open input is kept like a crease where it has corners: a boundary vertex
  /// where the border turns by more than corner_turn_deg (the corner of a square sheet or
  /// hole), or where a crease line ends, is a corner, and the boundary between two corners is a
  /// line. A border corner takes the nearest border vertex of the output within
  /// border_snap_spacings; the output's border between two corners is spread along the input's.
  /// A border loop without corners is left to the border stages. Defaults true and 1.
  bool border_corners = true;
  double border_snap_spacings = 1;
  /// Lines shorter than this many output spacings (the mean edge length) are not recovered: the
  /// output cannot resolve them. Default 1.
  double min_line_spacings = 1;
  /// A sample takes the nearest output vertex within this many spacings that no other sample
  /// took. Default 0.75.
  double max_snap_spacings = 0.75;
  /// Rounds of tangential relaxation, max-min-angle flips and angle polish after the snap, of
  /// the vertices off the lines within polish_rings rings of one on a line. Defaults 4 and 2.
  int polish_rounds = 4;
  int polish_rings = 2;
  /// In each polish round, a vertex of a recovered line slides along it to the best of
  /// slide_steps + 1 evenly spaced places in the middle slide_range of the stretch between its
  /// two neighbours on the line (the place where the smallest angle of its faces is largest).
  /// Defaults 8 and 0.6; slide_steps = 0 keeps the line's vertices evenly spread.
  int slide_steps = 8;
  double slide_range = 0.6;
  /// The recovery is undone where a face falls below the lower of the mesh's smallest angle
  /// before and this (after `retries` runs without the lines next to such faces), unless it
  /// keeps half of it and that smallest angle is at a corner between two line edges (two
  /// crease lines meeting at that angle bound every triangle between them) or the face's three
  /// corners are on lines (two lines closer than the spacing). Faces below it are also where the
  /// polish flips edges at a line vertex. Default 25°.
  double min_angle_deg = 25;
  /// The border lines' pass must keep the lower of the mesh's smallest angle before it and this
  /// (a border corner is worth less than a crease). Default 30°.
  double border_min_angle_deg = 30;
  /// Times a pass (the crease lines', the border lines') is run again without the lines next to
  /// faces below its floor before it is undone. Default 2.
  int retries = 2;
  int threads = 0;  ///< 0 = all cores; the result does not depend on it.
};

/// Crease lines of a mesh: each a polyline of input vertices from corner to corner (or a closed
/// loop without corners, first vertex repeated at the end).
struct CreaseLines {
  std::vector<std::vector<int>> lines;  ///< input vertex indices along each line
  std::vector<char> border;             ///< per line: it runs along the input's boundary
  std::vector<char> corner;             ///< per input vertex: a corner of the crease graph or of the border
  std::vector<char> on_border;          ///< per input vertex: on a boundary edge
  std::vector<int> border_loop;         ///< per input vertex: its border loop (connected boundary edges), −1 off it
  std::vector<std::pair<int, int>> border_edges;  ///< the input's boundary edges
  double length(const Eigen::MatrixX3d& V, int line) const;
};

/// The crease lines of (V, F): edges with exactly two faces whose normals differ by more than
/// options.min_dihedral_deg, chained between corners; with options.border_corners also the
/// boundary edges chained between border corners. `spacing` is the output's: the border turns
/// at a vertex are measured between the chords to the border points half of it behind and ahead
/// (0: its two border edges), and of the vertices within that distance turning by more than
/// corner_turn_deg only the one turning most is a corner (a ragged scan border has none).
CreaseLines detect_creases(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const CreaseOptions& options = {},
                           double spacing = 0);

/// What recover_creases() did.
struct CreaseStats {
  int lines = 0;          ///< lines recovered (long enough, and their snap made no faces cross)
  int skipped_lines = 0;  ///< lines long enough whose snap made faces cross: left out (a part thinner than the spacing)
  int dropped_crease_lines = 0;  ///< crease lines left out: faces next to them fell below min_angle_deg
  int corners = 0;        ///< corners of those lines
  int snapped = 0;        ///< output vertices moved onto a line
  int line_edges = 0;     ///< consecutive samples joined by an output edge (after flips)
  int missing_edges = 0;  ///< consecutive samples not joined (no vertex near, or no flip joins them)
  int flips = 0;          ///< flips that made a line edge
  /// The result made faces cross that did not before, or lowered the smallest angle (see
  /// CreaseOptions::min_angle_deg): the mesh was restored.
  bool undone = false;
  std::string undone_reason;  ///< why, in words (empty when kept)
  // The border lines' pass (the fields above count the crease lines).
  int border_lines = 0;    ///< border lines recovered
  int border_corners = 0;  ///< their corners kept
  int dropped_lines = 0;   ///< border lines left out: faces next to them fell below border_min_angle_deg
  std::string border_undone_reason;  ///< why no border line was kept (empty when kept or none)
};

/// Moves output vertices onto the crease lines of the input `lines` (input positions `V`): each
/// line resampled at the output's mean edge length between its corners, every sample (corners
/// first) takes the nearest output vertex within max_snap_spacings, consecutive samples are
/// joined by an edge (an existing one, one flip of the edge between them, or through a common
/// neighbour moved onto the line); a line whose snap makes faces cross is left out; then the
/// vertices off the lines are relaxed, flipped (no edge along a line) and polished around them.
/// Where faces fall below the smallest angle (CreaseOptions::min_angle_deg) the lines next to them
/// are left out and the rest recovered again (`retries` times); undone as a whole where it makes
/// more face pairs cross than before or still lowers the smallest angle.
/// Then, in a pass of their own, the border lines: corners onto the output's border, the border
/// between them spread along the input's, the same polish; where faces fall below
/// border_min_angle_deg next to them those lines are left out and the rest recovered again
/// (`retries` times) before the pass is undone.
CreaseStats recover_creases(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                            const CreaseLines& lines, const CreaseOptions& options = {});

}  // namespace heatcvt
