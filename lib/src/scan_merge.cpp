#include "heatcvt/scan_merge.h"

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "heatcvt/errors.h"
#include "heatcvt/input_file.h"

namespace heatcvt {
namespace {

std::string read_text(const std::string& path, const char* what) {
  require_regular_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IOError(path + ": cannot open the " + what);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Parses one number, rejecting anything strtod does not consume entirely.
bool parse_number(const std::string& tok, double& out) {
  if (tok.empty()) return false;
  char* end = nullptr;
  out = std::strtod(tok.c_str(), &end);
  return end == tok.c_str() + tok.size();
}

Eigen::Isometry3d rigid_pose(const std::string& path, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  if (!R.allFinite() || !t.allFinite()) throw InvalidInputError(path + ": the pose has a NaN or infinite entry");
  const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (orthogonality > kPoseRigidityTolerance || std::abs(det - 1.0) > kPoseRigidityTolerance)
    throw InvalidInputError(path + ": the pose is not rigid (its 3x3 block is not a rotation: |R^T R - I| = " +
                            std::to_string(orthogonality) + ", det R = " + std::to_string(det) + ")");
  // Nearest rotation (polar decomposition through the SVD) removes the rounding of the file.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = svd.matrixU() * svd.matrixV().transpose();
  pose.translation() = t;
  return pose;
}

}  // namespace

Eigen::Isometry3d read_pose_file(const std::string& path) {
  const std::string text = read_text(path, "pose file");
  std::vector<double> v;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::string tok;
    while (tokens >> tok) {
      double x = 0;
      if (!parse_number(tok, x)) throw IOError(path + ": not a number in the pose matrix: '" + tok.substr(0, 32) + "'");
      v.push_back(x);
    }
  }
  if (v.size() != 16 && v.size() != 12)
    throw IOError(path + ": a pose file holds a 4x4 or 3x4 matrix (16 or 12 numbers), found " + std::to_string(v.size()));
  if (v.size() == 16) {
    const bool last_row_ok = v[12] == 0 && v[13] == 0 && v[14] == 0 && v[15] == 1;
    if (!last_row_ok) throw InvalidInputError(path + ": the last row of the 4x4 pose must be 0 0 0 1");
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = v[static_cast<size_t>(4 * r + c)];
    t[r] = v[static_cast<size_t>(4 * r + 3)];
  }
  return rigid_pose(path, R, t);
}

std::vector<ScanInput> read_stanford_conf(const std::string& path) {
  const std::string text = read_text(path, ".conf file");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<ScanInput> scans;
  std::istringstream lines(text);
  std::string line;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::string key, file;
    if (!(tokens >> key) || key == "camera") continue;
    const std::string where = path + ": line " + std::to_string(line_no);
    if (key != "bmesh" && key != "mesh") throw IOError(where + ": unknown entry '" + key.substr(0, 32) + "' (expected bmesh, mesh or camera)");
    double x[7];
    std::string tok;
    if (!(tokens >> file)) throw IOError(where + ": missing file name");
    for (double& xi : x)
      if (!(tokens >> tok) || !parse_number(tok, xi)) throw IOError(where + ": expected 7 numbers (tx ty tz qx qy qz qw)");
    const Eigen::Quaterniond q(x[6], x[3], x[4], x[5]);
    if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > 1e-3)
      throw InvalidInputError(where + ": the quaternion is not of unit length");
    ScanInput scan;
    const std::filesystem::path p(file);
    scan.path = p.is_absolute() ? file : (folder / p).string();
    std::error_code ec;
    if (!std::filesystem::exists(scan.path, ec)) throw IOError(where + ": the scan " + scan.path + " does not exist");
    scan.pose = rigid_pose(where, q.normalized().toRotationMatrix(), Eigen::Vector3d(x[0], x[1], x[2]));
    scans.push_back(scan);
  }
  if (scans.empty()) throw IOError(path + ": the .conf file lists no scan (no bmesh line)");
  return scans;
}

void transform_cloud(PointCloud& cloud, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d R = pose.linear();
  const Eigen::RowVector3d t = pose.translation().transpose();
  cloud.P = ((cloud.P * R.transpose()).rowwise() + t).eval();
  if (cloud.has_normals()) cloud.N = (cloud.N * R.transpose()).eval();
}

namespace {

// The depth-step figures of several scans: quantised where one is, moves added up (the axis,
// levels and step of the first quantised scan).
void add_depth_steps(DepthStepReport& total, const DepthStepReport& r) {
  const std::int64_t moved = total.points_moved + r.points_moved;
  if (moved > 0)
    total.mean_move_steps = (total.mean_move_steps * static_cast<double>(total.points_moved) +
                             r.mean_move_steps * static_cast<double>(r.points_moved)) / static_cast<double>(moved);
  total.points_moved = moved;
  total.seconds += r.seconds;
  if (!total.quantised && r.quantised) {
    total.quantised = true;
    total.axis = r.axis;
    total.levels = r.levels;
    total.distinct_fraction = r.distinct_fraction;
    total.median_step = r.median_step;
  }
}

}  // namespace

PointCloud read_scans(const std::vector<ScanInput>& scans, CloudReadReport* report, const CloudReadOptions& options) {
  if (scans.empty()) throw InvalidInputError("read_scans: no scan given");
  std::vector<PointCloud> clouds;
  CloudReadReport total;
  Eigen::Index n = 0;
  bool normals = true, colours = true;
  for (const ScanInput& scan : scans) {
    CloudReadReport r;
    clouds.push_back(read_cloud(scan.path, &r, options));
    if (clouds.size() == 1) total = r;
    else {
      total.points_in_file += r.points_in_file;
      total.width += r.width;
      total.non_finite_dropped += r.non_finite_dropped;
      total.duplicates_merged += r.duplicates_merged;
      total.invalid_normals_zeroed += r.invalid_normals_zeroed;
      total.flying_pixels_removed += r.flying_pixels_removed;
      add_depth_steps(total.depth_steps, r.depth_steps);
    }
    transform_cloud(clouds.back(), scan.pose);
    n += clouds.back().P.rows();
    normals = normals && clouds.back().has_normals();
    colours = colours && clouds.back().has_colours();
  }
  PointCloud out;
  out.P.resize(n, 3);
  if (normals) out.N.resize(n, 3);
  if (colours) out.C.resize(n, 3);
  Eigen::Index at = 0;
  for (const PointCloud& c : clouds) {
    out.P.middleRows(at, c.P.rows()) = c.P;
    if (normals) out.N.middleRows(at, c.P.rows()) = c.N;
    if (colours) out.C.middleRows(at, c.P.rows()) = c.C;
    at += c.P.rows();
  }
  total.height = 1;
  total.has_normals = normals;
  total.has_colours = colours;
  if (report) *report = total;
  return out;
}

}  // namespace heatcvt
