/// Fuzz target: read_pcd (ascii, binary and binary_compressed; any fields, sizes, types and
/// counts). A cloud that reads is written back and must read again to the same size.
#include "fuzz_util.hpp"

#include <duet/runtime/io/cloud_io.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = duet::fuzz::put("in.pcd", {reinterpret_cast<const char*>(data), size});
  try {
    const duet::PointCloud cloud = duet::read_pcd(path);
    const auto out = duet::fuzz::scratch() / "out.pcd";
    duet::write_pcd(out, cloud);
    if (duet::read_pcd(out).size() != cloud.size()) std::abort();  // our own file must round-trip
    duet::fuzz::accepted("pcd");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
