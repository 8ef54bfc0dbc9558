// Every reader takes only a regular file within its size limit (input_limits.hpp): a FIFO would
// block forever, /dev/zero never ends, a huge file exhausts memory. Each must be refused at once
// with the file named, what it is and the limit.
#include <duet/kernels/error.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/io/cloud_io.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/input_limits.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace fs = std::filesystem;

namespace {

using duet_test::TempDir;

void expect_refused(const std::function<void()>& read, const std::string& path, const std::string& words) {
  try {
    read();
    ADD_FAILURE() << "no error reading " << path;
  } catch (const duet::Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.code(), duet::ErrorCode::kIo) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(words), std::string::npos) << m;
  }
}

}  // namespace

TEST(InputLimits, EveryReaderRefusesAFifoAtOnce) {
  const TempDir tmp;
  const fs::path& d = tmp.path();
  for (const char* name : {"a.pcd", "a.ply", "map.yaml", "world.yaml", "profile.yaml"})
    ASSERT_EQ(::mkfifo((d / name).c_str(), 0600), 0) << name;  // nobody writes: reading would block forever
  const std::string fifo = "a FIFO (named pipe), not a regular file";
  expect_refused([&] { (void)duet::read_pcd(d / "a.pcd"); }, (d / "a.pcd").string(), "the PCD file is " + fifo);
  expect_refused([&] { (void)duet::read_ply(d / "a.ply"); }, (d / "a.ply").string(), "the PLY file is " + fifo);
  expect_refused([&] { (void)duet::read_cloud(d / "a.pcd"); }, (d / "a.pcd").string(), fifo);
  expect_refused([&] { (void)duet::read_map_server(d / "map.yaml"); }, (d / "map.yaml").string(), "the map YAML is " + fifo);
  expect_refused([&] { (void)duet::sim::load_world(d / "world.yaml"); }, (d / "world.yaml").string(), "the world file is " + fifo);
  expect_refused([&] { (void)duet::load_profile(d / "profile.yaml"); }, (d / "profile.yaml").string(), "the profile is " + fifo);
  expect_refused([&] { (void)duet::file_overlay(d / "profile.yaml"); }, (d / "profile.yaml").string(), "the overlay file is " + fifo);
}

TEST(InputLimits, DevicesAreRefusedWhereverTheyAreNamed) {
  // `duet profile /dev/zero` and `image: /dev/zero` in a map YAML read gigabytes until killed
  // before; /dev/null is a device too.
  expect_refused([] { (void)duet::load_profile("/dev/zero"); }, "/dev/zero", "the profile is a character device");
  expect_refused([] { (void)duet::read_pcd("/dev/null"); }, "/dev/null", "a character device, not a regular file");
  const TempDir tmp;
  const fs::path& d = tmp.path();
  std::ofstream(d / "map.yaml") << "image: /dev/zero\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                   "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  expect_refused([&] { (void)duet::read_map_server(d / "map.yaml"); }, "/dev/zero", "the map image is a character device");
  expect_refused([&] { (void)duet::read_pcd(d); }, d.string(), "the PCD file is a directory");
}

TEST(InputLimits, FilesOverTheLimitAreRefusedBeforeTheyAreRead) {
  const TempDir tmp;
  const fs::path& d = tmp.path();
  // Sparse files: the size is there, the disk space is not.
  auto sparse = [&](const char* name, std::uintmax_t bytes) {
    std::ofstream(d / name) << "x";
    fs::resize_file(d / name, bytes);
    return d / name;
  };
  const fs::path yaml = sparse("big.yaml", duet::input_limits::kYamlBytes + 1);
  expect_refused([&] { (void)duet::load_profile(yaml); }, yaml.string(), "the limit is 16.0 MiB");
  expect_refused([&] { (void)duet::sim::load_world(yaml); }, yaml.string(), "the world file is 16.0 MiB; the limit is 16.0 MiB");
  const fs::path pcd = sparse("big.pcd", duet::input_limits::kCloudBytes + 1);
  expect_refused([&] { (void)duet::read_pcd(pcd); }, pcd.string(), "the limit is 4096.0 MiB");
  // At the limit is fine as far as the size goes (then parsed: here it is no YAML map).
  const fs::path ok = sparse("ok.yaml", 1024);
  try {
    (void)duet::load_profile(ok);
  } catch (const duet::Error& e) {
    EXPECT_EQ(std::string(e.what()).find("the limit"), std::string::npos) << e.what();
  }
}

TEST(InputLimits, RgbdFoldersNameAFifoListOrFrame) {
  // A slambook2 folder whose pose list is a FIFO, and one whose depth frame is a device.
  const TempDir tmp;
  const fs::path& d = tmp.path();
  fs::create_directories(d / "color");
  fs::create_directories(d / "depth");
  ASSERT_EQ(::mkfifo((d / "pose.txt").c_str(), 0600), 0);
  duet::RgbdDatasetOptions o;
  o.layout = "slambook2";
  expect_refused([&] { (void)duet::RgbdDataset::open(d, o); }, (d / "pose.txt").string(), "the pose list is a FIFO (named pipe)");
  fs::remove(d / "pose.txt");
  std::ofstream(d / "pose.txt") << "0 0 0 0 0 0 1\n";
  std::ofstream(d / "color" / "1.png") << "x";
  fs::create_symlink("/dev/zero", d / "depth" / "1.pgm");
  // open() reads the first depth frame (its size): refused there, before any read.
  expect_refused([&] { (void)duet::RgbdDataset::open(d, o); }, (d / "depth" / "1.pgm").string(),
                 "the depth image is a character device");
}
