#pragma once
// Runs code with duet's Embree devices created under another configuration (DUET_EMBREE_CONFIG,
// duet/kernels/embree_device.hpp): the ISA tests render and observe with each of Embree's kernels.
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

namespace duet_test {

/// Embree configurations with each of its x86 kernel families. Embree lowers a max_isa the CPU
/// lacks to the widest one it has, so on a CPU without AVX-512 the last two are the same kernels.
inline constexpr const char* kEmbreeIsaConfigs[] = {"max_isa=sse2", "max_isa=sse4.2", "max_isa=avx2", "max_isa=avx512"};

/// fn() with DUET_EMBREE_CONFIG set to `config` (the previous value, or none, restored after).
/// Only the devices created inside fn() see it. Not thread-safe (setenv): tests call it from the
/// test's own thread only.
template <class Fn>
auto with_embree_config(const char* config, Fn&& fn) {
  const char* old = std::getenv("DUET_EMBREE_CONFIG");
  const std::optional<std::string> saved = old ? std::optional<std::string>(old) : std::nullopt;
  ::setenv("DUET_EMBREE_CONFIG", config, 1);
  struct Restore {
    const std::optional<std::string>& saved;
    ~Restore() {
      if (saved)
        ::setenv("DUET_EMBREE_CONFIG", saved->c_str(), 1);
      else
        ::unsetenv("DUET_EMBREE_CONFIG");
    }
  } restore{saved};
  return std::forward<Fn>(fn)();
}

}  // namespace duet_test
