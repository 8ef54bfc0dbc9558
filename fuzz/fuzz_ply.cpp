/// Fuzz target: read_ply (ascii and binary little / big endian; any elements and properties).
/// A cloud that reads is written back and must read again to the same size.
#include "fuzz_util.hpp"

#include <duet/runtime/io/cloud_io.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = duet::fuzz::put("in.ply", {reinterpret_cast<const char*>(data), size});
  try {
    const duet::PointCloud cloud = duet::read_ply(path);
    const auto out = duet::fuzz::scratch() / "out.ply";
    duet::write_ply(out, cloud);
    if (duet::read_ply(out).size() != cloud.size()) std::abort();
    duet::fuzz::accepted("ply");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
