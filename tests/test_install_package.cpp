// The installed package works on its own: `cmake --install` of the build tree into a temporary
// prefix, then the standalone example examples/pcl_reconstruct is configured with only that
// prefix (find_package(heatcvt) + find_package(PCL)), built, run on a real PCD cloud, and its
// PLY output is compared with the same reconstruction done in this process.
#include <gtest/gtest.h>
#include <pcl/io/ply_io.h>
#include <pcl/io/pcd_io.h>
#include <pcl/conversions.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include "heatcvt/pcl/heat_cvt_reconstruction.h"
#include "test_support.h"

namespace {

struct Shell {
  int code = -1;
  std::string output;  // stdout and stderr
};

Shell sh(const std::string& command) {
  Shell r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

std::string quote(const std::string& s) { return "'" + s + "'"; }

TEST(InstallPackage, ExampleBuildsAgainstTheInstalledPackageAloneAndReproducesTheLibrary) {
  const std::string cmake = HEATCVT_CMAKE_COMMAND;
  const std::string source = HEATCVT_SOURCE_DIR, build_tree = HEATCVT_BUILD_DIR;
  heatcvt::test::ScratchDir dir("install_package");
  const std::string prefix = dir.path("prefix"), build = dir.path("example-build"), out = dir.path("bun0.ply");

  // 1. Install the library component (headers, libraries, package files) into the prefix.
  const Shell install = sh(quote(cmake) + " --install " + quote(build_tree) + " --prefix " + quote(prefix) +
                           " --component heatcvt_library");
  ASSERT_EQ(install.code, 0) << install.output;
  for (const char* f : {"include/heatcvt/heatcvt.h", "include/heatcvt/reconstruct.h",
                        "include/heatcvt/pcl/heat_cvt_reconstruction.h",
                        "include/heatcvt/pcl/impl/heat_cvt_reconstruction.hpp",
                        "include/heatcvt/pcl/heat_voronoi_segmentation.h", "lib/libheatcvt.so", "lib/libheatcvt_pcl.so",
                        "lib/cmake/heatcvt/heatcvtConfig.cmake", "lib/cmake/heatcvt/heatcvtConfigVersion.cmake",
                        "lib/cmake/heatcvt/heatcvtTargets.cmake", "lib/cmake/heatcvt/heatcvtFindPCL.cmake"})
    EXPECT_TRUE(exists(prefix + "/" + f)) << f << " not installed";
  // Relocatable: the exported targets mention neither the source nor the build tree.
  const std::string targets = slurp(prefix + "/lib/cmake/heatcvt/heatcvtTargets.cmake");
  EXPECT_NE(targets.find("heatcvt::pcl"), std::string::npos);
  EXPECT_EQ(targets.find(source + "/lib"), std::string::npos);
  EXPECT_EQ(targets.find(build_tree), std::string::npos);

  // 2. Configure the example against the prefix only (no package registry).
  const Shell configure = sh(quote(cmake) + " -S " + quote(source + "/examples/pcl_reconstruct") + " -B " +
                             quote(build) + " -DCMAKE_PREFIX_PATH=" + quote(prefix) +
                             " -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_EXPORT_COMPILE_COMMANDS=ON");
  ASSERT_EQ(configure.code, 0) << configure.output;
  EXPECT_NE(slurp(build + "/CMakeCache.txt").find("heatcvt_DIR:PATH=" + prefix + "/lib/cmake/heatcvt"),
            std::string::npos);
  const std::string commands = slurp(build + "/compile_commands.json");
  EXPECT_NE(commands.find(prefix + "/include"), std::string::npos) << commands;
  EXPECT_EQ(commands.find(source + "/lib/include"), std::string::npos) << commands;

  // 3. Build it.
  const Shell make = sh(quote(cmake) + " --build " + quote(build) + " -j 2");
  ASSERT_EQ(make.code, 0) << make.output;
  const std::string exe = build + "/pcl_reconstruct";
  const Shell ldd = sh("ldd " + quote(exe));
  // Both libraries resolve into the prefix (libheatcvt through libheatcvt_pcl's $ORIGIN RUNPATH).
  for (const std::string lib : {"libheatcvt_pcl.so => ", "libheatcvt.so => "}) {
    const std::size_t at = ldd.output.find(lib);
    ASSERT_NE(at, std::string::npos) << lib << "not linked:\n" << ldd.output;
    EXPECT_EQ(ldd.output.compare(at + lib.size(), prefix.size() + 5, prefix + "/lib/"), 0) << ldd.output;
  }

  // 4. Run it on a real scan: 120 sites, 8 iterations, seed 7.
  const std::string cloud_path = heatcvt::test::data_path("clouds/pcl_bun0.pcd");
  const Shell run = sh(quote(exe) + " " + quote(cloud_path) + " " + quote(out) + " 120 8 7");
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_NE(run.output.find("saved"), std::string::npos) << run.output;

  // 5. Same mesh as the library in this process.
  pcl::PolygonMesh from_file;
  ASSERT_GE(pcl::io::loadPLYFile(out, from_file), 0);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  ASSERT_EQ(pcl::io::loadPCDFile(cloud_path, *cloud), 0);
  heatcvt::HeatCVTReconstruction<pcl::PointXYZ> rec;
  rec.setInputCloud(cloud);
  rec.setNumberOfSites(120);
  rec.setMaximumIterations(8);
  rec.setSeed(7);
  pcl::PolygonMesh here;
  rec.reconstruct(here);
  ASSERT_GT(here.polygons.size(), 100u);
  ASSERT_EQ(from_file.polygons.size(), here.polygons.size());
  for (std::size_t f = 0; f < here.polygons.size(); ++f)
    ASSERT_EQ(from_file.polygons[f].vertices, here.polygons[f].vertices) << "face " << f;
  pcl::PointCloud<pcl::PointXYZ> a, b;
  pcl::fromPCLPointCloud2(from_file.cloud, a);
  pcl::fromPCLPointCloud2(here.cloud, b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t v = 0; v < a.size(); ++v) {
    EXPECT_EQ(a[v].x, b[v].x);
    EXPECT_EQ(a[v].y, b[v].y);
    EXPECT_EQ(a[v].z, b[v].z);
  }

  // 6. A bad input reaches the example as PCL_ERROR + empty mesh → exit code 1.
  const Shell bad = sh(quote(exe) + " " + quote(cloud_path) + " " + quote(dir.path("bad.ply")) + " 100000");
  EXPECT_EQ(bad.code, 1) << bad.output;
  EXPECT_NE(bad.output.find("[heatcvt::HeatCVTReconstruction::reconstruct] Too many sites"), std::string::npos)
      << bad.output;
  EXPECT_FALSE(exists(dir.path("bad.ply")));
}

}  // namespace
