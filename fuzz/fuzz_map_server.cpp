/// Fuzz target: a map_server map (part 0: the YAML, part 1: the image it names as map.pgm)
/// through read_map_server and, when it reads, world_from_map (the world duet explore builds
/// from it: walls, the start pose search) and the truth grid.
#include "fuzz_util.hpp"

#include <duet/runtime/io/grid_io.hpp>
#include <duet/sim/world.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  duet::fuzz::clear_scratch();
  const auto parts = duet::fuzz::split_parts(data, size, 2);
  const auto yaml = duet::fuzz::put("map.yaml", parts[0]);
  duet::fuzz::put("map.pgm", parts[1]);
  try {
    const duet::OccupancyGrid grid = duet::read_map_server(yaml);
    (void)grid;
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
    return 0;
  }
  try {
    const duet::sim::World world = duet::sim::world_from_map(yaml);
    (void)duet::sim::rasterize(world, duet::fuzz::raster_resolution(world.floor.min, world.floor.max));
    duet::fuzz::accepted("map_server grid and world");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
