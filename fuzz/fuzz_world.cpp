/// Fuzz target: a YAML world file through load_world (which also routes map_server keys to
/// world_from_map; a map image, if named, is part 1 as map.pgm), then the scoring grid.
#include "fuzz_util.hpp"

#include <duet/sim/world.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  duet::fuzz::clear_scratch();
  const auto parts = duet::fuzz::split_parts(data, size, 2);
  const auto path = duet::fuzz::put("world.yaml", parts[0]);
  duet::fuzz::put("map.pgm", parts[1]);
  try {
    const duet::sim::World world = duet::sim::load_world(path);
    (void)duet::sim::rasterize(world, duet::fuzz::raster_resolution(world.floor.min, world.floor.max));
    duet::fuzz::accepted("world");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
