#pragma once
// The line rules of XYZ / PWN / TXT point clouds, shared by read_cloud()'s text reader and the
// streaming decoder (cloud_stream.cpp). Not installed.
#include <string>
#include <string_view>

namespace heatcvt::detail {

/// What one line of a text cloud holds.
enum class XyzLineKind {
  blank,   ///< nothing (empty, white space, or a comment)
  header,  ///< the first non-blank line, holding names only ("x y z", "//X,Y,Z,R,G,B")
  count,   ///< the first non-blank line, a single non-negative integer: the point count
  values   ///< numbers: `cols` of them, the first 6 in `vals`
};

/// Reads one line of a text cloud. Comments start at '#' or "//" and run to the end of the line.
/// Numbers are separated by white space, or by commas or semicolons (CSV exports: "1.5, 2, 3"),
/// where each field between two separators holds exactly one number. `first`: no non-blank line
/// came before (only then may the line be a header or a count). A line that is neither gives an
/// IOError naming `path`, the line number and the token.
XyzLineKind read_xyz_line(std::string_view line, bool first, const std::string& path, long line_no, double vals[6],
                          int& cols);

}  // namespace heatcvt::detail
