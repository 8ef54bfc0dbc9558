/// @file replay_main.cpp
/// The fuzz targets without libFuzzer (gcc; the Release and ASan + UBSan test builds):
///   fuzz_replay <target> <file or folder>...
/// runs the target on every file given and on every file under every folder given (sorted by
/// path), so each target's seeds and regression inputs run as a ctest (Fuzz.<target>). The
/// targets' entry points are renamed duet_fuzz_<target> in this build (fuzz/CMakeLists.txt).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#define DUET_FUZZ_TARGETS(X) X(pcd) X(ply) X(map_server) X(world) X(profile) X(rgbd) X(recording) X(capi) X(tum)
#define DUET_DECLARE(name) extern "C" int duet_fuzz_##name(const std::uint8_t* data, std::size_t size);
DUET_FUZZ_TARGETS(DUET_DECLARE)

int main(int argc, char** argv) {
  using Fn = int (*)(const std::uint8_t*, std::size_t);
  Fn fn = nullptr;
#define DUET_PICK(name) \
  if (argc > 1 && std::strcmp(argv[1], #name) == 0) fn = duet_fuzz_##name;
  DUET_FUZZ_TARGETS(DUET_PICK)
  if (!fn) {
    std::fprintf(stderr, "usage: fuzz_replay <target> <file or folder>...; targets:");
#define DUET_LIST(name) std::fprintf(stderr, " %s", #name);
    DUET_FUZZ_TARGETS(DUET_LIST)
    std::fprintf(stderr, "\n");
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (int i = 2; i < argc; ++i) {
    const std::filesystem::path p(argv[i]);
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
    } else {
      files.push_back(p);
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "replay: cannot read %s\n", f.c_str());
      return 2;
    }
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "replay: %s (%zu bytes)\n", f.c_str(), bytes.size());
    fn(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::fprintf(stderr, "replay %s: %zu inputs, no crash\n", argv[1], files.size());
  return files.empty() ? 3 : 0;  // an empty corpus is a broken test, not a pass
}
