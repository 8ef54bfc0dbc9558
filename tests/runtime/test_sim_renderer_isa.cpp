// Simulated RGB-D sensors: the same bytes on other machines. A lockstep run repeats on another
// machine only if every frame does. Embree chooses its kernels by the CPU (SSE, AVX2, AVX-512),
// and their hits differ in the last bits of the distance (an approximate reciprocal: rcpps with a
// Newton step, rcp14 on AVX-512) and so, rarely, in which surface a ray meets first. AVX-512's
// rcp14 gives the same bits on Intel and AMD CPUs; SSE's and AVX2's rcpps do not. So a frame is
// the same bytes on every CPU with AVX-512, and on CPUs of one vendor without it
// (duet/kernels/embree_device.hpp). These tests render the lab with each kernel family this CPU
// has and compare with the hashes taken on the machines named below.
#include "sim_renderer_test_util.hpp"

#include "embree_config.hpp"

#include <duet/kernels/embree_device.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace test_sim_renderer_isa {

using namespace duet_test::render;

std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

// Depth (with the Kinect noise) and colour of 48 frames over the lab, 160 x 120, hashed frame
// by frame.
std::uint64_t lab_hash() {
  const World w = duet::sim::builtin_world("lab");
  const RgbdRenderer r(w, RenderSettings{});
  const auto s = kinect(160, 120);
  std::uint64_t h = 0xcbf29ce484222325ull;
  std::size_t valid = 0;
  RgbdImage img;  // reused: render() keeps its buffers
  for (int iy = 0; iy < 6; ++iy)
    for (int ix = 0; ix < 8; ++ix) {
      const float fx = (static_cast<float>(ix) + 0.5f) / 8.0f, fy = (static_cast<float>(iy) + 0.5f) / 6.0f;
      const Eigen::Vector2f p = w.floor.min + Eigen::Vector2f(fx, fy).cwiseProduct(w.floor.max - w.floor.min);
      const float yaw = 0.37f * static_cast<float>(ix + 8 * iy);
      r.render(s, camera({p.x(), p.y(), 0.45f}, yaw, 0.05f), static_cast<std::uint64_t>(ix + 8 * iy), img);
      h = fnv1a(h, img.depth.data(), img.depth.size() * sizeof(img.depth[0]));
      h = fnv1a(h, img.rgb.data(), img.rgb.size());
      for (const auto z : img.depth) valid += z > 0 ? 1 : 0;
    }
  EXPECT_GT(valid, 48u * 160u * 120u / 4u);  // most pixels see a surface
  return h;
}

bool has_avx512() {  // what Embree's AVX-512 (SKX) kernels need
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512cd") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
}

// Hashes taken on: AMD EPYC Zen 5 (family 26; AVX-512 and AVX2 kernels), AMD EPYC Zen 3
// (family 25, AVX2 only: its runs repeated the Zen 5 machine's AVX2 runs byte for byte) and an
// Intel Xeon with AVX-512 (AVX-512 and AVX2 kernels).
constexpr std::uint64_t kAvx512Hash = 0x3d9050a81e879709ull;    // Intel and AMD alike
constexpr std::uint64_t kAvx2AmdHash = 0xc97310c32e7e7f18ull;   // AMD
constexpr std::uint64_t kAvx2IntelHash = 0xeeacf7567c560a17ull; // Intel

TEST(SimRendererIsa, TheLabRendersTheBytesOfOtherMachinesWithTheSameKernels) {
  __builtin_cpu_init();
  const bool amd = __builtin_cpu_is("amd"), intel = __builtin_cpu_is("intel");
  int checked = 0;
  if (has_avx512()) {
    const std::uint64_t h = duet_test::with_embree_config("max_isa=avx512", lab_hash);
    EXPECT_EQ(h, kAvx512Hash) << std::hex << "AVX-512 kernels: hash 0x" << h;
    ++checked;
  }
  if (__builtin_cpu_supports("avx2") && (amd || intel)) {
    const std::uint64_t h = duet_test::with_embree_config("max_isa=avx2", lab_hash);
    EXPECT_EQ(h, amd ? kAvx2AmdHash : kAvx2IntelHash) << std::hex << (amd ? "AMD" : "Intel") << " AVX2 kernels: hash 0x" << h;
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "no reference hash for this CPU's Embree kernels (SSE only, or neither Intel nor AMD)";
}

// The default configuration uses the widest kernels the CPU has: on a CPU with AVX-512, the
// AVX-512 frames (a cap on the ISA would give the AVX2 frames, which differ between vendors).
TEST(SimRendererIsa, TheDefaultUsesTheWidestKernels) {
  if (!has_avx512()) GTEST_SKIP() << "this CPU has no AVX-512: the default is its widest kernels, AVX2 or SSE";
  const std::uint64_t h = duet_test::with_embree_config(duet::kEmbreeDeviceConfig, lab_hash);
  EXPECT_EQ(h, kAvx512Hash) << std::hex << "hash 0x" << h;
}

}  // namespace test_sim_renderer_isa
