// Streaming cloud readers (cloud_stream.h): for every format, the chunks concatenated are the
// points read_cloud reads (same order; read_cloud's clean-up applied to both), whatever the chunk
// size; a truncated file gives one IOError naming the file, the same error read_cloud gives.
#include <gtest/gtest.h>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "heatcvt/cloud_io.h"
#include "heatcvt/cloud_stream.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "test_support.h"

using namespace heatcvt;
namespace fs = std::filesystem;

namespace {

// Streams a whole file with the given chunk size into one PointCloud; checks that every chunk
// but the last is full and that the counters add up.
PointCloud stream_all(const std::string& path, std::int64_t chunk_points, bool* normals_complete = nullptr) {
  StreamReaderOptions options;
  options.chunk_points = chunk_points;
  std::int64_t last_bytes = -1, last_points = -1, calls = 0;
  options.progress = [&](const StreamProgress& p) {
    EXPECT_GE(p.bytes_read, last_bytes);
    EXPECT_GE(p.points_read, last_points);
    EXPECT_LE(p.bytes_read, p.bytes_total);
    last_bytes = p.bytes_read;
    last_points = p.points_read;
    ++calls;
  };
  CloudChunkReader reader(path, options);
  std::vector<double> p, n, c;
  CloudChunk chunk;
  bool short_chunk_seen = false;
  std::int64_t chunks = 0;
  while (reader.next(chunk)) {
    EXPECT_FALSE(short_chunk_seen) << path << ": a short chunk before the end";
    EXPECT_LE(chunk.rows(), chunk_points);
    EXPECT_EQ(chunk.has_normals(), reader.has_normals());
    EXPECT_EQ(chunk.has_colours(), reader.has_colours());
    if (chunk.rows() < chunk_points) short_chunk_seen = true;
    for (Eigen::Index i = 0; i < chunk.rows(); ++i)
      for (int k = 0; k < 3; ++k) {
        p.push_back(chunk.P(i, k));
        if (chunk.has_normals()) n.push_back(chunk.N(i, k));
        if (chunk.has_colours()) c.push_back(chunk.C(i, k));
      }
    ++chunks;
  }
  EXPECT_EQ(calls, chunks + 1);  // one call per chunk and one at the end
  EXPECT_EQ(last_points, static_cast<std::int64_t>(p.size() / 3));
  if (reader.points_in_file() >= 0) EXPECT_EQ(reader.points_in_file(), last_points);
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const Eigen::Index rows = static_cast<Eigen::Index>(p.size() / 3);
  PointCloud cloud;
  cloud.P = Eigen::Map<RowMajor>(p.data(), rows, 3);
  if (!n.empty()) cloud.N = Eigen::Map<RowMajor>(n.data(), rows, 3);
  if (!c.empty()) cloud.C = Eigen::Map<RowMajor>(c.data(), rows, 3);
  if (normals_complete) *normals_complete = reader.all_points_had_normals();
  if (reader.has_normals() && !reader.all_points_had_normals()) cloud.N.resize(0, 3);
  return cloud;
}

bool identical(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return a.rows() == b.rows() && (a.array() == b.array()).all();
}

// The property: streaming with chunk sizes 1, 7 and 1000, then read_cloud's clean-up, gives
// exactly read_cloud's cloud (positions, normals, colours, order).
// The reader hands out every point of the file as it is: read_cloud without its flying-pixel rule
// and its refit of quantised depth (test_flying_pixels.cpp compares the filtered stream with
// read_cloud, test_depth_steps.cpp the refit).
void expect_stream_matches_read_cloud(const std::string& path) {
  CloudReadReport rep;
  CloudReadOptions every_pixel;
  every_pixel.flying_pixels.neighbour_distance_ratio = 0;
  every_pixel.depth_steps.max_distinct_fraction = 0;
  const PointCloud whole = read_cloud(path, &rep, every_pixel);
  for (std::int64_t chunk : {1, 7, 1000}) {
    PointCloud streamed = stream_all(path, chunk);
    EXPECT_EQ(streamed.P.rows(), rep.points_in_file) << path << " chunk " << chunk;
    clean_cloud(streamed);
    EXPECT_TRUE(identical(streamed.P, whole.P)) << path << " chunk " << chunk;
    EXPECT_TRUE(identical(streamed.N, whole.N)) << path << " chunk " << chunk << " normals";
    EXPECT_TRUE(identical(streamed.C, whole.C)) << path << " chunk " << chunk << " colours";
  }
}

// A noisy torus sample with normals and colours (2,000 points).
PointCloud torus_cloud() {
  const TriangleMesh torus = test::torus(40, 20);
  PointCloud cloud;
  cloud.P = sample_surface(torus.V, torus.F, 2000, 3, 0.01);
  cloud.N = cloud.P.rowwise().normalized();
  cloud.C = ((cloud.P.array() + 1.5) / 3.0).min(1.0).max(0.0).matrix();
  cloud.C = (cloud.C * 255.0).array().round().matrix() / 255.0;  // exactly representable as uchar
  return cloud;
}

void write_ply(const std::string& path, const PointCloud& cloud, PlyEncoding encoding) {
  MeshAttributes attr;
  attr.vertex_normal = cloud.N;
  attr.vertex_color = cloud.C;
  MeshWriteOptions options;
  options.ply_encoding = encoding;
  write_mesh(path, cloud.P, Eigen::MatrixX3i(0, 3), attr, options);
}

void write_pcd(const std::string& path, const PointCloud& cloud, int kind) {
  pcl::PointCloud<pcl::PointXYZRGBNormal> pc;
  for (Eigen::Index i = 0; i < cloud.P.rows(); ++i) {
    pcl::PointXYZRGBNormal q;
    q.x = static_cast<float>(cloud.P(i, 0));
    q.y = static_cast<float>(cloud.P(i, 1));
    q.z = static_cast<float>(cloud.P(i, 2));
    q.normal_x = static_cast<float>(cloud.N(i, 0));
    q.normal_y = static_cast<float>(cloud.N(i, 1));
    q.normal_z = static_cast<float>(cloud.N(i, 2));
    q.r = static_cast<std::uint8_t>(std::lround(cloud.C(i, 0) * 255));
    q.g = static_cast<std::uint8_t>(std::lround(cloud.C(i, 1) * 255));
    q.b = static_cast<std::uint8_t>(std::lround(cloud.C(i, 2) * 255));
    pc.push_back(q);
  }
  int status = -1;
  if (kind == 0) status = pcl::io::savePCDFileASCII(path, pc);
  else if (kind == 1) status = pcl::io::savePCDFileBinary(path, pc);
  else status = pcl::io::savePCDFileBinaryCompressed(path, pc);
  ASSERT_EQ(status, 0) << path;
}

// The files of every format, written from the torus cloud.
std::vector<std::string> write_every_format(const test::ScratchDir& dir) {
  const PointCloud cloud = torus_cloud();
  std::vector<std::string> paths = {dir.path("le.ply"), dir.path("be.ply"), dir.path("ascii.ply"),
                                    dir.path("ascii.pcd"), dir.path("binary.pcd"), dir.path("compressed.pcd"),
                                    dir.path("cloud.xyz")};
  write_ply(paths[0], cloud, PlyEncoding::binary_little_endian);
  write_ply(paths[1], cloud, PlyEncoding::binary_big_endian);
  write_ply(paths[2], cloud, PlyEncoding::ascii);
  for (int kind = 0; kind < 3; ++kind) write_pcd(paths[3 + kind], cloud, kind);
  write_cloud_xyz(paths[6], cloud);
  return paths;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const IOError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CloudStream, EveryFormatBuiltInCodeMatchesReadCloud) {
  test::ScratchDir dir("cloud_stream_formats");
  for (const auto& path : write_every_format(dir)) {
    SCOPED_TRACE(path);
    const PointCloud whole = read_cloud(path);
    ASSERT_EQ(whole.P.rows(), 2000);
    ASSERT_TRUE(whole.has_normals());
    expect_stream_matches_read_cloud(path);
  }
  // Colours travel through PLY and PCD (XYZ has none).
  for (const char* name : {"le.ply", "be.ply", "ascii.ply", "ascii.pcd", "binary.pcd", "compressed.pcd"}) {
    CloudChunkReader reader(dir.path(name));
    EXPECT_TRUE(reader.has_colours()) << name;
    EXPECT_EQ(reader.points_in_file(), 2000) << name;
  }
}

TEST(CloudStream, EveryRealCloudFileMatchesReadCloud) {
  const fs::path dir = fs::path(test::data_path("clouds/kitten.xyz")).parent_path();
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 30u);
  for (const auto& path : files) {
    SCOPED_TRACE(path);
    expect_stream_matches_read_cloud(path);
  }
}

TEST(CloudStream, XyzNormalsOnlyWhenEveryLineHasThem) {
  test::ScratchDir dir("cloud_stream_xyz");
  const std::string path = dir.path("mixed.xyz");
  {
    std::ofstream out(path);
    out << "3\n# comment\n0 0 0 0 0 1\n\n1 0 0\n0 1 0 0 0 1\n";
  }
  bool complete = true;
  PointCloud streamed = stream_all(path, 2, &complete);
  EXPECT_FALSE(complete);
  const PointCloud whole = read_cloud(path);
  EXPECT_FALSE(whole.has_normals());
  clean_cloud(streamed);
  EXPECT_TRUE(identical(streamed.P, whole.P));
  EXPECT_FALSE(streamed.has_normals());
}

TEST(CloudStream, TruncatedFileGivesOneIOErrorNamingTheFile) {
  test::ScratchDir dir("cloud_stream_truncated");
  for (const auto& path : write_every_format(dir)) {
    SCOPED_TRACE(path);
    const auto size = fs::file_size(path);
    // Cut inside the data: XYZ files carry no count, so the cut leaves a line of two numbers.
    std::string data;
    {
      std::ifstream in(path, std::ios::binary);
      data.assign(std::istreambuf_iterator<char>(in), {});
    }
    std::size_t cut = size * 6 / 10;
    if (path.size() > 4 && path.substr(path.size() - 4) == ".xyz") {
      cut = data.find('\n', cut) + 1;
      cut = data.find(' ', data.find(' ', cut) + 1);
    }
    const std::string truncated = path + ".cut" + fs::path(path).extension().string();
    {
      std::ofstream out(truncated, std::ios::binary);
      out.write(data.data(), static_cast<std::streamsize>(cut));
    }
    for (std::int64_t chunk : {1, 7, 1000}) {
      int errors = 0;
      std::string message;
      std::int64_t points = 0;
      try {
        StreamReaderOptions options;
        options.chunk_points = chunk;
        CloudChunkReader reader(truncated, options);
        CloudChunk c;
        while (reader.next(c)) points += c.rows();
      } catch (const IOError& e) {
        ++errors;
        message = e.what();
      }
      EXPECT_EQ(errors, 1);
      EXPECT_EQ(message.rfind(truncated + ": ", 0), 0u) << message;
      EXPECT_LT(points, 2000);
      // The same error read_cloud gives.
      EXPECT_EQ(message, error_of([&] { read_cloud(truncated); }));
    }
  }
}

TEST(CloudStream, ACompressedPcdWithoutCompressedBytesIsRefused) {
  // A binary_compressed PCD whose compressed-size field is 0 while its data size is not: one
  // IOError naming the file, from the chunk reader and from read_cloud.
  test::ScratchDir dir("cloud_stream_compressed_zero");
  const std::string path = dir.path("compressed.pcd");
  write_pcd(path, torus_cloud(), 2);
  std::string data;
  {
    std::ifstream in(path, std::ios::binary);
    data.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string marker = "DATA binary_compressed\n";
  const std::size_t at = data.find(marker);
  ASSERT_NE(at, std::string::npos);
  std::uint32_t sizes[2];
  std::memcpy(sizes, data.data() + at + marker.size(), sizeof sizes);
  ASSERT_GT(sizes[0], 0u);
  ASSERT_GT(sizes[1], 0u);
  std::memset(&data[at + marker.size()], 0, 4);
  const std::string corrupt = dir.path("zero.pcd");
  {
    std::ofstream out(corrupt, std::ios::binary);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  }
  const std::string streamed = error_of([&] {
    CloudChunkReader r(corrupt);
    CloudChunk c;
    while (r.next(c)) {
    }
  });
  EXPECT_EQ(streamed.rfind(corrupt + ": ", 0), 0u) << streamed;
  EXPECT_NE(streamed.find("compressed"), std::string::npos) << streamed;
  const std::string whole = error_of([&] { read_cloud(corrupt); });
  EXPECT_EQ(whole.rfind(corrupt + ": ", 0), 0u) << whole;
}

TEST(CloudStream, AnAsciiPcdWithMorePointsThanItsHeaderSaysIsRefused) {
  // Header says 2 points, the body holds 3: the third would be dropped silently. Blank lines
  // after the last point are fine.
  test::ScratchDir dir("cloud_stream_extra_rows");
  const std::string head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n";
  const std::string extra = dir.path("extra.pcd"), blank = dir.path("blank.pcd");
  { std::ofstream(extra) << head << "0 0 0\n1 0 0\n0 1 0\n"; }
  { std::ofstream(blank) << head << "0 0 0\n1 0 0\n\n  \n"; }
  const std::string streamed = error_of([&] {
    CloudChunkReader r(extra);
    CloudChunk c;
    while (r.next(c)) {
    }
  });
  EXPECT_EQ(streamed.rfind(extra + ": line 13: data beyond the 2 points", 0), 0u) << streamed;
  EXPECT_EQ(streamed, error_of([&] { read_cloud(extra); }));
  EXPECT_EQ(read_cloud(blank).P.rows(), 2);
  CloudChunkReader r(blank);
  CloudChunk c;
  Eigen::Index rows = 0;
  while (r.next(c)) rows += c.P.rows();
  EXPECT_EQ(rows, 2);
}

TEST(CloudStream, BadInputsGiveReadCloudsErrors) {
  test::ScratchDir dir("cloud_stream_bad");
  const std::string missing = dir.path("missing.ply");
  EXPECT_EQ(error_of([&] { CloudChunkReader r(missing); }), error_of([&] { read_cloud(missing); }));
  const std::string unknown = dir.path("cloud.abc");
  { std::ofstream(unknown) << "0 0 0\n"; }
  EXPECT_EQ(error_of([&] { CloudChunkReader r(unknown); }), error_of([&] { read_cloud(unknown); }));
  const std::string bad_number = dir.path("bad.xyz");
  { std::ofstream(bad_number) << "0 0 0\n1 x 0\n"; }
  const std::string message = error_of([&] {
    CloudChunkReader r(bad_number);
    CloudChunk c;
    while (r.next(c)) {
    }
  });
  EXPECT_EQ(message, error_of([&] { read_cloud(bad_number); }));
  EXPECT_NE(message.find("line 2"), std::string::npos) << message;
  const std::string bad_index = dir.path("bad_face.ply");
  { std::ofstream(bad_index) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n"; }
  const std::string face_message = error_of([&] {
    CloudChunkReader r(bad_index);
    CloudChunk c;
    while (r.next(c)) {
    }
  });
  EXPECT_EQ(face_message, error_of([&] { read_cloud(bad_index); }));
  EXPECT_NE(face_message.find("out of range"), std::string::npos) << face_message;
}

// Text clouds as spreadsheets and other tools export them: comma or semicolon separators (with or
// without spaces), a first line of column names ("x y z", with units, after a byte-order mark;
// CloudCompare's "//X,Y,Z" is a comment), trailing separators. Both readers give the points of the
// plain file; decimal commas ("1,5 2,5 3,5", "1,5;2,5;3,5"), an empty field and names after the
// first line are refused with the line number.
TEST(CloudStream, CommaSeparatedTextAndHeaderLinesReadLikePlainXyz) {
  test::ScratchDir dir("cloud_stream_csv");
  const std::string plain = dir.path("plain.xyz");
  { std::ofstream(plain) << "0 0 0\n1.5 0 -2\n0 1e-3 4\n2 2 2\n"; }
  const PointCloud expected = read_cloud(plain);
  ASSERT_EQ(expected.P.rows(), 4);
  const std::vector<std::pair<std::string, std::string>> variants = {
      {"commas.xyz", "0,0,0\n1.5,0,-2\n0,1e-3,4\n2,2,2\n"},
      {"comma_space.txt", "0, 0, 0\n1.5, 0, -2\n0, 1e-3, 4\n2, 2, 2,\n"},
      {"semicolons.xyz", "x;y;z\n0;0;0\n1.5;0;-2\n0;1e-3;4\n2;2;2\n"},
      {"cloudcompare.xyz", "//X,Y,Z\n0,0,0\n1.5,0,-2\n0,1e-3,4\n2,2,2\n"},
      {"names.xyz", "x y z\n0 0 0 // origin\n1.5 0 -2\n0 1e-3 4\n2 2 2\n"},
      {"units.txt", "\xEF\xBB\xBFX (m); Y (m); Z (m)\n0;0;0\n1.5;0;-2\n0;1e-3;4\n2;2;2\n"},
  };
  for (const auto& [name, text] : variants) {
    SCOPED_TRACE(name);
    const std::string path = dir.path(name);
    { std::ofstream(path) << text; }
    const PointCloud whole = read_cloud(path);
    EXPECT_TRUE(identical(whole.P, expected.P));
    expect_stream_matches_read_cloud(path);
  }
  const std::vector<std::tuple<std::string, std::string, std::string>> bad = {
      {"decimal_comma.xyz", "0 0 0\n1,5 2,5 3,5\n", "line 2: a field holds more than one number"},
      {"decimal_comma.txt", "0;0;0\n1,5;2,5;3,5\n", "line 2: malformed number '1,5'"},
      {"empty_field.xyz", "0,0,0\n1,,3\n", "line 2: empty field"},
      {"late_names.xyz", "0 0 0\nx y z\n", "line 2: malformed number 'x'"},
  };
  for (const auto& [name, text, problem] : bad) {
    SCOPED_TRACE(name);
    const std::string path = dir.path(name);
    { std::ofstream(path) << text; }
    const std::string message = error_of([&] { read_cloud(path); });
    EXPECT_EQ(message.rfind(path + ": " + problem, 0), 0u) << message;
    EXPECT_EQ(message, error_of([&] {
                CloudChunkReader r(path);
                CloudChunk c;
                while (r.next(c)) {
                }
              }));
  }
}

// PCL's padding fields '_' (a point type's alignment bytes, often several per point: PCL-ROS
// lidar types) are skipped however many there are: the points are those of the same file without
// padding, in both encodings.
TEST(CloudStream, RepeatedPaddingFieldsOfAPcdAreSkipped) {
  test::ScratchDir dir("cloud_stream_pad");
  const PointCloud cloud = torus_cloud();
  const long n = static_cast<long>(cloud.P.rows());
  const std::string head = "# .PCD v0.7\nVERSION 0.7\nFIELDS x _ y z _ intensity _\nSIZE 4 1 4 4 1 4 1\n"
                           "TYPE F U F F U F U\nCOUNT 1 4 1 1 1 1 12\nWIDTH " + std::to_string(n) +
                           "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\n";
  const std::string binary = dir.path("padded_binary.pcd"), ascii = dir.path("padded_ascii.pcd");
  {
    std::ofstream out(binary, std::ios::binary);
    out << head << "DATA binary\n";
    const char pad[12] = {0};
    for (long i = 0; i < n; ++i) {
      const float x = static_cast<float>(cloud.P(i, 0)), y = static_cast<float>(cloud.P(i, 1)),
                  z = static_cast<float>(cloud.P(i, 2)), intensity = 0.5f;
      out.write(reinterpret_cast<const char*>(&x), 4);
      out.write(pad, 4);
      out.write(reinterpret_cast<const char*>(&y), 4);
      out.write(reinterpret_cast<const char*>(&z), 4);
      out.write(pad, 1);
      out.write(reinterpret_cast<const char*>(&intensity), 4);
      out.write(pad, 12);
    }
  }
  {
    std::ofstream out(ascii);
    out << head << "DATA ascii\n";
    out.precision(9);
    for (long i = 0; i < n; ++i)
      out << static_cast<float>(cloud.P(i, 0)) << " 0 0 0 0 " << static_cast<float>(cloud.P(i, 1)) << ' '
          << static_cast<float>(cloud.P(i, 2)) << " 0 0.5 0 0 0 0 0 0 0 0 0 0 0 0\n";
  }
  PointCloud expected;
  expected.P = cloud.P.cast<float>().cast<double>();
  clean_cloud(expected);
  for (const std::string& path : {binary, ascii}) {
    SCOPED_TRACE(path);
    EXPECT_TRUE(identical(read_cloud(path).P, expected.P));
    expect_stream_matches_read_cloud(path);
  }
}
