/// Fuzz target: an RGB-D folder as duet map reads it. The first byte picks the layout (bit 0)
/// and whether intrinsics for 8x6 images replace the layout's (bit 1: slambook2 has none of its
/// own, and 640x480 images are too large to fuzz); the parts are the layout's files for two
/// frames:
///   slambook2: pose.txt, color/1.png, depth/1.pgm, color/2.png, depth/2.png
///   3dmatch:   camera-intrinsics.txt, frame-000000.{color.png, depth.png, pose.txt},
///              frame-000001.{color.png, depth.png, pose.txt}
/// With bit 2 set, the TUM RGB-D layout instead: rgb.txt, depth.txt, groundtruth.txt,
/// camera-intrinsics.txt, 1.png, 1_depth.png, 2.png, 2_depth.png.
/// Every frame that opens is loaded and back-projected.
#include "fuzz_util.hpp"

#include <duet/kernels/back_projection.hpp>
#include <duet/runtime/io/rgbd_dataset.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  duet::fuzz::clear_scratch();
  const bool threedmatch = data[0] & 1, tum = data[0] & 4;
  const auto root = duet::fuzz::scratch() / "seq";
  if (tum) {
    const auto p = duet::fuzz::split_parts(data + 1, size - 1, 8);
    const char* names[] = {"rgb.txt", "depth.txt", "groundtruth.txt", "camera-intrinsics.txt", "1.png", "1_depth.png", "2.png", "2_depth.png"};
    for (std::size_t i = 0; i < 8; ++i) duet::fuzz::put(std::string("seq/") + names[i], p[i]);
  } else if (!threedmatch) {
    const auto p = duet::fuzz::split_parts(data + 1, size - 1, 5);
    duet::fuzz::put("seq/pose.txt", p[0]);
    duet::fuzz::put("seq/color/1.png", p[1]);
    duet::fuzz::put("seq/depth/1.pgm", p[2]);
    duet::fuzz::put("seq/color/2.png", p[3]);
    duet::fuzz::put("seq/depth/2.png", p[4]);
  } else {
    const auto p = duet::fuzz::split_parts(data + 1, size - 1, 7);
    duet::fuzz::put("seq/camera-intrinsics.txt", p[0]);
    duet::fuzz::put("seq/frame-000000.color.png", p[1]);
    duet::fuzz::put("seq/frame-000000.depth.png", p[2]);
    duet::fuzz::put("seq/frame-000000.pose.txt", p[3]);
    duet::fuzz::put("seq/frame-000001.color.png", p[4]);
    duet::fuzz::put("seq/frame-000001.depth.png", p[5]);
    duet::fuzz::put("seq/frame-000001.pose.txt", p[6]);
  }
  try {
    duet::RgbdDatasetOptions opt;
    if (data[0] & 2) opt.intrinsics = duet::PinholeIntrinsics{8, 6, 5.0f, 5.0f, 3.5f, 2.5f};
    const duet::RgbdDataset ds = duet::RgbdDataset::open(root, opt);
    for (std::size_t i = 0; i < ds.size(); ++i) {
      const duet::RgbdFrame f = ds.load(i);
      const duet::SensorFrame sf = f.sensor_frame(f.T_world_camera);
      duet::PointCloud cloud;
      duet::back_project(std::span<const duet::SensorFrame>(&sf, 1), {}, cloud);
    }
    duet::fuzz::accepted(ds.layout().c_str());
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
