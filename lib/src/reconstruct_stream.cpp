// Streamed, voxel-first front end of the surface reconstruction (reconstruct_stream.h).
#include "heatcvt/reconstruct_stream.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "heatcvt/dense_pieces.h"
#include "heatcvt/errors.h"

namespace heatcvt {

namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The raw points of a cloud while it is small enough to keep (row-major triples).
struct RawBuffer {
  std::vector<double> p, n, c;
  bool normals = true, colours = true;
  bool kept = true;  // false once the cloud outgrew max_raw_points

  void add(const CloudChunk& chunk) {
    normals = normals && chunk.has_normals();
    colours = colours && chunk.has_colours();
    for (Eigen::Index i = 0; i < chunk.rows(); ++i)
      for (int k = 0; k < 3; ++k) {
        p.push_back(chunk.P(i, k));
        if (normals) n.push_back(chunk.N(i, k));
        if (colours) c.push_back(chunk.C(i, k));
      }
  }
  void drop() {
    kept = false;
    std::vector<double>().swap(p);
    std::vector<double>().swap(n);
    std::vector<double>().swap(c);
  }
  PointCloud cloud() const {
    const Eigen::Index rows = static_cast<Eigen::Index>(p.size() / 3);
    PointCloud cloud;
    cloud.P = Eigen::Map<const RowMajor>(p.data(), rows, 3);
    if (normals && n.size() == p.size()) cloud.N = Eigen::Map<const RowMajor>(n.data(), rows, 3);
    if (colours && c.size() == p.size()) cloud.C = Eigen::Map<const RowMajor>(c.data(), rows, 3);
    return cloud;
  }
};

// Uniform sample of the finite points seen so far (reservoir sampling, algorithm R), point by
// point so that chunk boundaries do not matter.
class Reservoir {
 public:
  Reservoir(std::int64_t size, std::uint64_t seed) : size_(std::max<std::int64_t>(size, 10)), rng_(seed) {}
  void add(const CloudChunk& chunk) {
    for (Eigen::Index i = 0; i < chunk.rows(); ++i) {
      if (!chunk.P.row(i).allFinite()) continue;
      if (seen_ < size_) {
        sample_.push_back(chunk.P.row(i));
      } else {
        const std::uint64_t j = rng_() % static_cast<std::uint64_t>(seen_ + 1);
        if (j < static_cast<std::uint64_t>(size_)) sample_[static_cast<std::size_t>(j)] = chunk.P.row(i);
      }
      ++seen_;
    }
  }
  std::int64_t seen() const { return seen_; }
  void clear() { std::vector<Eigen::RowVector3d>().swap(sample_); }
  Eigen::MatrixX3d sample() const {
    Eigen::MatrixX3d S(static_cast<Eigen::Index>(sample_.size()), 3);
    for (std::size_t i = 0; i < sample_.size(); ++i) S.row(static_cast<Eigen::Index>(i)) = sample_[i];
    return S;
  }

 private:
  std::int64_t size_, seen_ = 0;
  std::mt19937_64 rng_;
  std::vector<Eigen::RowVector3d> sample_;
};

void check_stream_options(const StreamOptions& s) {
  if (s.max_raw_points < 0) throw InvalidInputError("reconstruct_surface_streamed: max_raw_points must be >= 0");
  if (!(s.max_raw_points_per_site >= 0 && std::isfinite(s.max_raw_points_per_site)))
    throw InvalidInputError("reconstruct_surface_streamed: max_raw_points_per_site must be finite and >= 0");
  if (!(s.voxel_size >= 0 && std::isfinite(s.voxel_size)))
    throw InvalidInputError("reconstruct_surface_streamed: voxel_size must be finite and >= 0");
  if (!(s.fine_voxel_factor >= 1 && std::isfinite(s.fine_voxel_factor)))
    throw InvalidInputError("reconstruct_surface_streamed: fine_voxel_factor must be finite and >= 1");
  if (!(s.min_points_per_fine_voxel > 0 && std::isfinite(s.min_points_per_fine_voxel)))
    throw InvalidInputError("reconstruct_surface_streamed: min_points_per_fine_voxel must be finite and > 0");
  if (s.sample_points < 10) throw InvalidInputError("reconstruct_surface_streamed: sample_points must be >= 10");
  if (!(s.max_noise_spacings >= 0 && std::isfinite(s.max_noise_spacings)) ||
      !(s.max_noise_reduction >= 1 && std::isfinite(s.max_noise_reduction)) || s.noise_sample_points_per_site < 0)
    throw InvalidInputError("reconstruct_surface_streamed: max_noise_spacings must be finite and >= 0, "
                            "max_noise_reduction finite and >= 1, noise_sample_points_per_site >= 0");
  check_flying_pixel_options(s.flying_pixels);
}

// The exact path: read_cloud's clean-up, then the whole-cloud reconstruction.
StreamedReconstruction reconstruct_raw(const CloudChunkSource& source, PointCloud cloud, const ReconstructionOptions& options,
                                       const ReconstructionCallback& progress) {
  const auto* filter = dynamic_cast<const FlyingPixelFilter*>(&source);
  const auto* reader = dynamic_cast<const CloudChunkReader*>(filter ? &filter->source() : &source);
  if (reader && reader->has_normals() && !reader->all_points_had_normals()) cloud.N.resize(0, 3);  // as read_cloud
  const Eigen::Index in_source = cloud.P.rows();
  if (in_source == 0) throw InvalidInputError(source.name() + ": no points in the file");
  clean_cloud(cloud);
  if (cloud.P.rows() == 0)
    throw InvalidInputError(source.name() + ": no finite points (all " + std::to_string(in_source) + " points are NaN/inf)");
  StreamedReconstruction out;
  out.result = reconstruct_surface(cloud.P, options, progress);
  out.cloud = std::move(cloud);
  out.points_read = in_source;
  out.passes = 1;
  out.cvt_sites = options.sites;
  return out;
}

}  // namespace

namespace {

// The points a summary is reconstructed from (StreamOptions::project_to_surface: its surface
// points, else its plain means with their normals) with their mean colours.
PointCloud summary_cloud(const VoxelSummary& summary, const ReconstructionOptions& options, const StreamOptions& stream) {
  PointCloud cloud;
  if (stream.project_to_surface) {
    const double target = static_cast<double>(options.sites) * stream.voxel.points_per_site;
    cloud.P = summary.surface_points(static_cast<Eigen::Index>(std::ceil(target)), nullptr, &cloud.C, stream.surface_fit);
  } else {
    cloud.P = summary.points();
    cloud.N = summary.normals();
    cloud.C = summary.colours();
  }
  return cloud;
}

// The reconstruction's options on a summary's points.
ReconstructionOptions summary_options(const ReconstructionOptions& options, const StreamOptions& stream) {
  ReconstructionOptions subset = options;
  subset.cvt_points_per_site = 0;  // the voxel means already are the uniform subset
  subset.spatial_site_order = true;  // large site counts: keep each cell's data close in memory
  subset.surface_lloyd_mean_tolerance = stream.surface_lloyd_mean_tolerance;
  return subset;
}

}  // namespace

StreamedReconstruction reconstruct_surface_from_summary(const VoxelSummary& summary, const ReconstructionOptions& options,
                                                        const StreamOptions& stream, const ReconstructionCallback& progress) {
  if (summary.voxels() == 0) throw InvalidInputError("reconstruct_surface_from_summary: the summary holds no point");
  StreamedReconstruction out;
  if (progress) progress("preprocess", 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  out.cloud = summary_cloud(summary, options, stream);
  const double summary_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.result = reconstruct_surface(out.cloud.P, summary_options(options, stream), progress);
  out.result.stage_seconds.insert(out.result.stage_seconds.begin(), {"voxel surface points", summary_seconds});
  out.summarised = true;
  out.voxel_size = summary.voxel_size();
  out.cvt_sites = options.sites;
  out.points_read = summary.points_added() + summary.non_finite_skipped();
  return out;
}

namespace {

// The options of a streamed cloud's reconstruction under the noise limit
// (StreamOptions::max_noise_spacings): where the noise σ measured on `sample` at the requested
// spacing is too wide for it, fewer CVT sites and the mesher's sizing to the requested count.
// `noise_spacings` receives σ in requested spacings.
ReconstructionOptions noise_limited_options(const Eigen::MatrixX3d& sample, const ReconstructionOptions& options,
                                            const StreamOptions& stream, double& noise_spacings) {
  ReconstructionOptions out = options;
  noise_spacings = 0;
  if (!(stream.max_noise_spacings > 0)) return out;
  VoxelSizeOptions voxel = stream.voxel;
  voxel.threads = options.threads;
  const double spacing = std::sqrt(estimate_surface_area(sample, voxel).area / options.sites);
  NoiseEstimateOptions noise_options = stream.noise;
  noise_options.threads = options.threads;
  const NoiseEstimate noise = estimate_noise(sample, spacing, noise_options);
  noise_spacings = noise.sigma / spacing;
  const int sites = noise_limited_sites(options.sites, spacing, noise.sigma, stream.max_noise_spacings,
                                        stream.max_noise_reduction);
  if (sites < options.sites) {
    out.sites = sites;
    if (out.mesher.sizing.target_vertices == 0) out.mesher.sizing.target_vertices = options.sites;
    if (out.mesher.split.max_vertices == 0) out.mesher.split.max_vertices = options.sites + options.sites / 50;
  }
  return out;
}

}  // namespace

namespace {

using Cell = std::array<std::int64_t, 3>;

struct CellHash {
  std::size_t operator()(const Cell& c) const {
    return static_cast<std::size_t>((static_cast<std::uint64_t>(c[0]) * 0x9E3779B97F4A7C15ULL) ^
                                    (static_cast<std::uint64_t>(c[1]) * 0xC2B2AE3D27D4EB4FULL) ^
                                    (static_cast<std::uint64_t>(c[2]) * 0x165667B19E3779F9ULL));
  }
};

Cell cell_of(const Eigen::Vector3d& x, double inv_h) {
  return {static_cast<std::int64_t>(std::floor(x[0] * inv_h)), static_cast<std::int64_t>(std::floor(x[1] * inv_h)),
          static_cast<std::int64_t>(std::floor(x[2] * inv_h))};
}

// The dense pieces of a summary (dense_pieces.h) as its voxels' pieces: the 26-connected
// components of its voxels, each voxel of the same area (a surface occupies about area / h²
// voxels) and weighted by its point count. The cell of each voxel of a piece maps to the piece.
std::unordered_map<Cell, int, CellHash> summary_dense_pieces(const VoxelSummary& summary,
                                                             const ReconstructionOptions& options, DensePieces& found) {
  std::unordered_map<Cell, int, CellHash> piece_of;
  if (!options.dense_pieces.enabled()) return piece_of;
  const Eigen::VectorXi counts = summary.counts();
  const std::vector<int> weight(counts.data(), counts.data() + counts.size());
  if (!dense_piece_possible(weight, options.sites, options.mesher.min_piece_vertex_fraction, options.dense_pieces))
    return piece_of;
  const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3> cells = summary.cells();
  found = dense_pieces_of_components(voxel_components(cells), std::vector<double>(weight.size(), 1.0), weight,
                                     options.sites, options.mesher.min_piece_vertex_fraction, options.dense_pieces);
  for (Eigen::Index v = 0; v < cells.rows(); ++v)
    if (found.piece[static_cast<std::size_t>(v)] >= 0)
      piece_of.emplace(Cell{cells(v, 0), cells(v, 1), cells(v, 2)}, found.piece[static_cast<std::size_t>(v)]);
  return piece_of;
}

// The piece of a point near the summary's voxels: that of its own cell, else of the first of the
// 26 around it that has one (a surface point moved onto its local plane may leave its voxel),
// else −1.
int piece_near(const std::unordered_map<Cell, int, CellHash>& piece_of, const Eigen::Vector3d& x, double inv_h) {
  const Cell c = cell_of(x, inv_h);
  if (const auto it = piece_of.find(c); it != piece_of.end()) return it->second;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (const auto it = piece_of.find(Cell{c[0] + dx, c[1] + dy, c[2] + dz}); it != piece_of.end()) return it->second;
  return -1;
}

// One more pass over the source: the points in each dense piece's voxels into a summary of their
// own, at a voxel size fine enough for stream.voxel.points_per_site voxel points per site of the
// piece (fine_voxel_factor² times that many voxels, as the first summary), then its points.
std::vector<PointCloud> dense_piece_clouds(CloudChunkSource& source, const VoxelSummary& summary,
                                           const std::unordered_map<Cell, int, CellHash>& piece_of,
                                           const DensePieces& found, const ReconstructionOptions& options,
                                           const StreamOptions& stream) {
  const double h = summary.voxel_size(), inv_h = 1.0 / h;
  std::vector<long> voxels(static_cast<std::size_t>(found.count()), 0);
  for (const auto& [cell, k] : piece_of) ++voxels[static_cast<std::size_t>(k)];
  std::vector<VoxelSummary> pieces;
  for (int k = 0; k < found.count(); ++k) {
    const double wanted = stream.fine_voxel_factor * stream.fine_voxel_factor * stream.voxel.points_per_site *
                          found.sites[static_cast<std::size_t>(k)];
    pieces.emplace_back(h * std::min(1.0, std::sqrt(voxels[static_cast<std::size_t>(k)] / wanted)), options.threads);
  }
  source.rewind();
  CloudChunk chunk;
  std::vector<std::vector<Eigen::Index>> rows(pieces.size());
  while (source.next(chunk)) {
    for (auto& r : rows) r.clear();
    for (Eigen::Index i = 0; i < chunk.rows(); ++i) {
      if (!chunk.P.row(i).allFinite()) continue;
      if (const auto it = piece_of.find(cell_of(chunk.P.row(i).transpose(), inv_h)); it != piece_of.end())
        rows[static_cast<std::size_t>(it->second)].push_back(i);
    }
    for (size_t k = 0; k < pieces.size(); ++k) {
      if (rows[k].empty()) continue;
      CloudChunk part;
      part.P = chunk.P(rows[k], Eigen::all);
      if (chunk.has_colours()) part.C = chunk.C(rows[k], Eigen::all);
      pieces[k].add(part);
    }
  }
  std::vector<PointCloud> clouds;
  for (int k = 0; k < found.count(); ++k) {
    ReconstructionOptions piece = options;
    piece.sites = found.sites[static_cast<std::size_t>(k)];
    clouds.push_back(summary_cloud(pieces[static_cast<std::size_t>(k)], piece, stream));
  }
  return clouds;
}

// The rows of `cloud` (points, normals and colours where present) where keep[i].
PointCloud rows_kept(const PointCloud& cloud, const std::vector<char>& keep) {
  std::vector<Eigen::Index> rows;
  for (size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) rows.push_back(static_cast<Eigen::Index>(i));
  PointCloud out;
  out.P = cloud.P(rows, Eigen::all);
  if (cloud.N.rows() == cloud.P.rows()) out.N = cloud.N(rows, Eigen::all);
  if (cloud.C.rows() == cloud.P.rows()) out.C = cloud.C(rows, Eigen::all);
  return out;
}

// A summary with dense pieces: the rest from its points outside the pieces' voxels, each piece
// from its own points read again (dense_piece_clouds()), joined by reconstruct_parts(). The
// cloud returned holds every part's points (colours where every part has them, no normals).
StreamedReconstruction reconstruct_summary_in_parts(CloudChunkSource& source, const VoxelSummary& summary,
                                                    const std::unordered_map<Cell, int, CellHash>& piece_of,
                                                    const DensePieces& found, const ReconstructionOptions& options,
                                                    const StreamOptions& stream, const ReconstructionCallback& progress) {
  if (progress) progress("preprocess", 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  const PointCloud whole = summary_cloud(summary, options, stream);
  const double inv_h = 1.0 / summary.voxel_size();
  std::vector<char> in_rest(static_cast<std::size_t>(whole.P.rows()));
  for (Eigen::Index i = 0; i < whole.P.rows(); ++i)
    in_rest[static_cast<std::size_t>(i)] = piece_near(piece_of, whole.P.row(i).transpose(), inv_h) < 0;
  const PointCloud rest = rows_kept(whole, in_rest);
  const std::vector<PointCloud> pieces = dense_piece_clouds(source, summary, piece_of, found, options, stream);
  const double summary_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<Eigen::MatrixX3d> piece_points;
  StreamedReconstruction out;
  out.cloud.P = rest.P;
  bool coloured = rest.C.rows() == rest.P.rows();
  for (const PointCloud& piece : pieces) {
    piece_points.push_back(piece.P);
    coloured = coloured && piece.C.rows() == piece.P.rows();
  }
  out.result = reconstruct_parts(rest.P, piece_points, found.sites, summary_options(options, stream), progress);
  out.result.stage_seconds.insert(out.result.stage_seconds.begin(), {"voxel surface points and dense pieces", summary_seconds});
  for (const PointCloud& piece : pieces) {
    const Eigen::Index r = out.cloud.P.rows();
    out.cloud.P.conservativeResize(r + piece.P.rows(), 3);
    out.cloud.P.bottomRows(piece.P.rows()) = piece.P;
  }
  if (coloured) {
    out.cloud.C = rest.C;
    for (const PointCloud& piece : pieces) {
      const Eigen::Index r = out.cloud.C.rows();
      out.cloud.C.conservativeResize(r + piece.C.rows(), 3);
      out.cloud.C.bottomRows(piece.C.rows()) = piece.C;
    }
  }
  out.summarised = true;
  out.voxel_size = summary.voxel_size();
  out.cvt_sites = options.sites;
  return out;
}

// reconstruct_surface_from_summary(), or where the summary has dense pieces, its reconstruction
// in parts (one more pass over the source: `passes` grows by one).
StreamedReconstruction from_summary(CloudChunkSource& source, const VoxelSummary& summary,
                                    const ReconstructionOptions& options, const StreamOptions& stream,
                                    const ReconstructionCallback& progress, int& passes) {
  const auto t0 = std::chrono::steady_clock::now();
  DensePieces found;
  const std::unordered_map<Cell, int, CellHash> piece_of = summary_dense_pieces(summary, options, found);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  StreamedReconstruction out;
  if (found.count() == 0) {
    out = reconstruct_surface_from_summary(summary, options, stream, progress);
  } else {
    ++passes;
    // As reconstruct_surface(): the summary as one where the rest gives no mesh on its sites or
    // the parts fail the checks joined.
    bool joined = true;
    try {
      out = reconstruct_summary_in_parts(source, summary, piece_of, found, options, stream, progress);
    } catch (const Error&) {
      joined = false;
    }
    if (!joined || !out.result.validation.ok()) {
      StreamedReconstruction whole = reconstruct_surface_from_summary(summary, options, stream, progress);
      if (!joined || whole.result.validation.ok()) out = std::move(whole);
    }
  }
  out.result.stage_seconds.insert(out.result.stage_seconds.begin(), {"dense pieces of the voxels", seconds});
  return out;
}

}  // namespace

std::int64_t raw_point_limit(const StreamOptions& stream, int sites) {
  if (!(stream.max_raw_points_per_site > 0) || sites <= 0) return stream.max_raw_points;
  const double per_site = std::floor(stream.max_raw_points_per_site * static_cast<double>(sites));
  return std::min<std::int64_t>(stream.max_raw_points, static_cast<std::int64_t>(std::min(per_site, 9e18)));
}

StreamedReconstruction reconstruct_surface_streamed(CloudChunkSource& source, const ReconstructionOptions& options,
                                                    const StreamOptions& stream, const ReconstructionCallback& progress) {
  check_stream_options(stream);
  RawBuffer raw;
  Reservoir reservoir(stream.sample_points, stream.sample_seed);
  // The noise sample: denser than the voxel-size sample at large site counts, drawn apart so that
  // the voxel size does not depend on it.
  const bool estimate = stream.voxel_size == 0 && stream.max_noise_spacings > 0;
  Reservoir noise_sample(estimate ? std::max<std::int64_t>(stream.sample_points,
                                                           stream.noise_sample_points_per_site * options.sites)
                                  : 10,
                         stream.sample_seed + 1);
  std::unique_ptr<VoxelSummary> summary;
  if (stream.voxel_size > 0) summary = std::make_unique<VoxelSummary>(stream.voxel_size, options.threads);
  std::int64_t points = 0;
  const std::int64_t raw_limit = raw_point_limit(stream, options.sites);
  CloudChunk chunk;
  // Pass 1: raw points while they fit, the reservoir sample, and the summary when its size is given.
  while (source.next(chunk)) {
    points += chunk.rows();
    if (raw.kept && points <= raw_limit) raw.add(chunk);
    else if (raw.kept) raw.drop();
    if (summary) {
      summary->add(chunk);
    } else {
      reservoir.add(chunk);
      if (estimate) noise_sample.add(chunk);
    }
  }
  if (raw.kept) return reconstruct_raw(source, raw.cloud(), options, progress);
  if (!summary) {
    if (reservoir.seen() < 10)
      throw InvalidInputError(source.name() + ": fewer than 10 finite points (" + std::to_string(points) + " points read)");
    double noise_spacings = 0;
    const auto t_noise = std::chrono::steady_clock::now();
    const ReconstructionOptions cvt = estimate ? noise_limited_options(noise_sample.sample(), options, stream, noise_spacings)
                                               : options;
    noise_sample.clear();
    const double noise_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_noise).count();
    VoxelSizeOptions voxel = stream.voxel;
    voxel.threads = options.threads;
    double h = choose_voxel_size(reservoir.sample(), cvt.sites, voxel);
    if (stream.project_to_surface) {
      const double per_voxel = static_cast<double>(reservoir.seen()) / (cvt.sites * stream.voxel.points_per_site);
      h /= std::min(stream.fine_voxel_factor, std::max(1.0, std::sqrt(per_voxel / stream.min_points_per_fine_voxel)));
    }
    summary = std::make_unique<VoxelSummary>(h, options.threads);
    source.rewind();  // pass 2: every point into the summary
    while (source.next(chunk)) summary->add(chunk);
    int passes = 2;
    StreamedReconstruction out = from_summary(source, *summary, cvt, stream, progress, passes);
    out.points_read = points;
    out.passes = passes;
    out.noise_spacings = noise_spacings;
    if (estimate) out.result.stage_seconds.insert(out.result.stage_seconds.begin(), {"noise estimate", noise_seconds});
    return out;
  }
  int passes = 1;
  StreamedReconstruction out = from_summary(source, *summary, options, stream, progress, passes);
  out.points_read = points;
  out.passes = passes;
  return out;
}

StreamedReconstruction reconstruct_surface_streamed(const std::string& path, const ReconstructionOptions& options,
                                                    const StreamOptions& stream, const ReconstructionCallback& progress) {
  check_stream_options(stream);
  StreamReaderOptions reader_options;
  reader_options.chunk_points = stream.chunk_points;
  const CloudChunkReader* reader_seen = nullptr;
  if (stream.progress)
    reader_options.progress = [&](const StreamProgress& p) { stream.progress(reader_seen ? reader_seen->passes() : 1, p); };
  CloudChunkReader reader(path, reader_options);
  reader_seen = &reader;
  if (reader.grid_height() > 1 && stream.depth_steps.enabled()) {
    // A depth frame: read whole, its quantised depth refitted, then streamed from memory.
    CloudReadOptions read;
    read.flying_pixels = stream.flying_pixels;
    read.depth_steps = stream.depth_steps;
    read.depth_steps.threads = options.threads;
    CloudReadReport report;
    const PointCloud cloud = read_cloud(path, &report, read);
    if (stream.progress) stream.progress(1, {reader.bytes_total(), reader.bytes_total(), report.points_in_file, report.points_in_file});
    MemoryChunkSource memory(cloud.P, cloud.N, cloud.C, path, stream.chunk_points);
    StreamedReconstruction out = reconstruct_surface_streamed(static_cast<CloudChunkSource&>(memory), options, stream, progress);
    out.points_read = report.points_in_file;
    out.flying_pixels_removed = report.flying_pixels_removed;
    out.depth_steps = report.depth_steps;
    return out;
  }
  if (reader.grid_height() < 2 || !stream.flying_pixels.enabled())
    return reconstruct_surface_streamed(static_cast<CloudChunkSource&>(reader), options, stream, progress);
  // An organised cloud: its flying pixels go (as read_cloud drops them).
  FlyingPixelFilter filter(reader, static_cast<int>(reader.grid_width()), static_cast<int>(reader.grid_height()),
                           reader.sensor_origin(), stream.flying_pixels);
  StreamedReconstruction out = reconstruct_surface_streamed(static_cast<CloudChunkSource&>(filter), options, stream, progress);
  out.flying_pixels_removed = filter.removed();
  return out;
}

}  // namespace heatcvt
