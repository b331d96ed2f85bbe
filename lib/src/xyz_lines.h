#pragma once
// The line rules of XYZ / PWN / TXT point clouds, shared by read_cloud()'s text reader and the
// streaming decoder (cloud_stream.cpp). Not installed.
#include <string>
#include <string_view>

namespace heatcvt::detail {

/// What one line of a text cloud holds.
enum class XyzLineKind {
  blank,   ///< nothing (empty, white space, or a comment)
  header,  ///< the first non-blank line, holding no number: column names ("x y z", "X (m);Y (m);Z (m)")
  count,   ///< the first non-blank line, a single non-negative integer: the point count
  values   ///< numbers: `cols` of them, the first 6 in `vals`
};

/// Reads one line of a text cloud. Comments start at '#' or "//" (CloudCompare's "//X,Y,Z" header)
/// and run to the end of the line. Numbers are separated by white space, or by the line's
/// separator: ';' where the line holds one (so "1,5;2,5;3,5" is refused, not read as six numbers),
/// else ',' ("1.5, 2, 3"); each field between two separators holds exactly one number. `first`:
/// no non-blank line came before (only then may the line be a header or a count; a UTF-8
/// byte-order mark at its start is skipped). Any other line gives an IOError naming `path`, the
/// line number and the field.
XyzLineKind read_xyz_line(std::string_view line, bool first, const std::string& path, long line_no, double vals[6],
                          int& cols);

}  // namespace heatcvt::detail
