/// Fuzz target: a duet recording (runtime/io/recording.hpp) as `duet replay` reads it. Parts:
/// profile.yaml, recording.yaml, odometry.txt, s/depth.txt, s/rgb.txt, s/depth/000000.png,
/// s/rgb/000000.png (the seeds: a one-sensor profile with 8x6 images, folder "s"). A recording
/// that reads is delivered through a ReplaySource to its end (every listed image decoded).
#include "fuzz_util.hpp"

#include <duet/runtime/io/recording.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  duet::fuzz::clear_scratch();
  const auto p = duet::fuzz::split_parts(data, size, 7);
  const char* names[] = {"rec/profile.yaml", "rec/recording.yaml", "rec/odometry.txt", "rec/s/depth.txt",
                         "rec/s/rgb.txt",    "rec/s/depth/000000.png", "rec/s/rgb/000000.png"};
  for (std::size_t i = 0; i < 7; ++i) duet::fuzz::put(names[i], p[i]);
  try {
    const duet::Recording rec = duet::read_recording(duet::fuzz::scratch() / "rec");
    duet::ReplaySource src(rec);
    const double end = std::min(rec.end_s(), 1e4);
    for (int k = 0; k < 64 && !src.finished(); ++k) {
      src.advance(end * (k + 1) / 64.0);
      (void)src.chassis().take_odometry();
      for (auto* s : src.sensors()) (void)s->take_frames();
    }
    duet::fuzz::accepted("recording");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
