#pragma once
/// @file world.hpp
/// Simulated worlds (issue 4): what the simulator renders, drives in and scores against.
///
/// A world is a floor rectangle plus vertical prisms ("solids"): a simple polygon in the xy
/// plane extruded from z_min_m to z_max_m. Walls, boxes, cabinets and the paper's 1.5 m baffle
/// plates are all solids. Every surface has a colour and a procedural texture, so rendered
/// colour images carry enough corners for ORB features.
///
/// Sources:
///  - a YAML world file (schema in profiles/worlds/lab.yaml, the built-in replica of the
///    paper's lab, Fig. 9): `walls` (polylines with a thickness), `boxes` (centre, size, yaw)
///    and `polygons` (explicit vertices), each with an optional height range and surface;
///  - a ROS map_server map (YAML + PGM): every occupied cell is extruded into a wall of
///    `wall_height_m` (runs of occupied cells in a row are merged into one box).
///
/// Frames: the world frame is z up, the floor at z = 0, SI units (DESIGN.md §6).
///
/// Errors: duet::Error naming the file, the key path and what was expected
/// ("lab.yaml: key 'boxes[3].size': expected a sequence of 2 or 3 numbers") with code kParse
/// for malformed content, kIo for a file that cannot be read, kInvalidArgument for a value out
/// of range (a self-intersecting polygon, z_max <= z_min, ...).
///
/// Thread safety: World is a value type; every function here is reentrant, and the const
/// queries (collides(), rasterize()) may run concurrently on one World.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/motion_model.hpp>
#include <duet/kernels/types.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace duet::sim {

/// Procedural textures (colour modulation of the surface colour), all deterministic in
/// world coordinates so that the same point looks the same from every view.
enum class Texture : std::uint8_t {
  kPlain = 0,    ///< flat colour (few features; use for tests only)
  kNoise = 1,    ///< value noise at two scales: blotches with corners (default)
  kChecker = 2,  ///< checkerboard of texture_scale_m squares
  kBricks = 3,   ///< staggered bricks with mortar lines
  kPosters = 4,  ///< random rectangles of random colour (notice boards, colour blocks)
};

struct Surface {
  Rgb8 colour{180, 180, 180};
  Texture texture = Texture::kNoise;
  float texture_scale_m = 0.10f;  ///< feature size of the texture [m], (0.001, 10]
};

/// A vertical prism. `polygon` is simple (no self-intersection), counter-clockwise after
/// loading (loaders reverse clockwise input), at least 3 vertices, no repeated closing vertex.
struct Solid {
  std::string name;                       ///< for messages ("walls[2]", "boxes[0] 'cabinet'")
  std::vector<Eigen::Vector2f> polygon;   ///< footprint in the world xy plane [m]
  float z_min_m = 0.0f;                   ///< bottom [m]
  float z_max_m = 2.5f;                   ///< top [m], > z_min_m
  Surface surface;
  /// A door: it opens (the solid is gone) at opens_at_s of simulated time, or when the caller
  /// opens it (SimRobot::open_door). Coverage counts the area behind a door as reachable.
  bool door = false;
  double opens_at_s = std::numeric_limits<double>::infinity();  ///< [s], >= 0; +inf: only when opened by the caller
};

/// An axis-aligned rectangle of the floor (start and target regions of the paper, Fig. 9).
struct Region {
  Eigen::Vector2f min{0.0f, 0.0f};  ///< [m]
  Eigen::Vector2f max{0.0f, 0.0f};  ///< [m]
  [[nodiscard]] bool contains(const Eigen::Vector2f& p) const noexcept {
    return p.x() >= min.x() && p.y() >= min.y() && p.x() <= max.x() && p.y() <= max.y();
  }
  [[nodiscard]] Eigen::Vector2f centre() const noexcept { return 0.5f * (min + max); }
  [[nodiscard]] float area_m2() const noexcept { return (max - min).prod(); }
};

struct World {
  std::string name;                  ///< e.g. "lab"
  std::string source;                ///< the file it came from (for messages), or "builtin:lab"
  Region floor;                      ///< the floor rectangle; the world's extent [m]
  Surface floor_surface{{150, 140, 120}, Texture::kNoise, 0.15f};
  /// Ceiling height [m]; 0 = no ceiling (rays that miss everything return no depth).
  float ceiling_height_m = 0.0f;
  Surface ceiling_surface{{235, 235, 230}, Texture::kPlain, 0.5f};
  std::vector<Solid> solids;
  Pose2 start{0.0f, 0.0f, 0.0f};     ///< the robot's start pose (world frame)
  std::optional<Region> start_region;
  /// The paper's end of task: the robot entering this region (Fig. 9, "target region").
  std::optional<Region> target_region;
};

/// The world with the named doors open (their solids removed); an empty `names` opens every door.
/// Solids that are not doors are kept whatever their name.
[[nodiscard]] World with_doors_open(const World& world, std::span<const std::string> names = {});

/// Parses a YAML world; `source_name` stands for the file in messages.
[[nodiscard]] World parse_world(std::string_view yaml_text, std::string_view source_name);

/// Reads a world file. A file whose top-level keys are those of a map_server YAML
/// (`image`, `resolution`, `origin`) is read as a map world with default MapWorldOptions;
/// anything else as a YAML world.
[[nodiscard]] World load_world(const std::filesystem::path& path);

struct MapWorldOptions {
  float wall_height_m = 2.5f;  ///< occupied cells become walls of this height [m]
  /// Where the robot starts; nullopt = the free cell nearest the centre of the largest
  /// connected free area that has room for a robot of `start_clearance_m` radius.
  std::optional<Pose2> start;
  /// With no `start`: the map's start file beside its YAML (`NAME.start`, read_start_file), when
  /// there is one - the real robot's first pose - before the computed start.
  bool start_file = true;
  float start_clearance_m = 0.35f;  ///< [m]
  Surface wall_surface{{200, 195, 185}, Texture::kNoise, 0.10f};
};

/// A world from a ROS map_server map (YAML + image): occupied cells extruded to walls,
/// unknown cells are treated as walls too (the map's outside is solid), free cells are floor.
[[nodiscard]] World world_from_map(const std::filesystem::path& map_yaml, const MapWorldOptions& options = {});

/// A start pose file: one line "x y theta" (m, m, rad; the map's frame), as the real robots'
/// first poses in ../shared/data/maps/*.start; blank lines and '#' comments allowed. Throws
/// kIo (unreadable) or kInvalidArgument naming the file, the line and what was wrong.
[[nodiscard]] Pose2 read_start_file(const std::filesystem::path& path);
/// "x,y,theta" (m, m, rad), as `duet explore --start` takes it. Throws kInvalidArgument naming
/// the text and what was wrong.
[[nodiscard]] Pose2 parse_start(std::string_view text);
/// Moves the world's start to `start` after checking that a robot of `radius_m` stands there: on
/// the floor and clear of every solid. Throws kInvalidArgument naming `what` (e.g. "--start"),
/// the pose and the solid it overlaps (or "off the floor"); the world is unchanged then.
/// radius_m = 0: only the centre is checked (the solid it is inside).
void set_start(World& world, const Pose2& start, float radius_m, std::string_view what);

/// The built-in worlds by name ("lab"); throws kInvalidArgument naming the known ones.
[[nodiscard]] World builtin_world(std::string_view name);
[[nodiscard]] std::vector<std::string> builtin_world_names();
/// `name_or_path`: a built-in world's name, else a file for load_world().
[[nodiscard]] World resolve_world(std::string_view name_or_path);

/// Checks a world built in code (the loaders call it): non-empty floor, valid polygons
/// (>= 3 finite vertices, non-zero area, simple), z ranges, texture scales, start pose inside
/// the floor, regions non-empty. Makes polygons counter-clockwise. Throws kInvalidArgument.
void validate(World& world, std::string_view source_name = "world");

/// True when a disc of `radius_m` centred at `centre` (world xy) overlaps any solid whose
/// height range overlaps [z_low_m, z_high_m] (the robot's body height), or leaves the floor.
[[nodiscard]] bool collides(const World& world, const Eigen::Vector2f& centre, float radius_m,
                            float z_low_m = 0.0f, float z_high_m = 0.6f);
/// The first solid such a disc overlaps (height range as collides()), nullptr if none; the
/// floor's edge is not checked. `centre` must be finite.
[[nodiscard]] const Solid* overlapping_solid(const World& world, const Eigen::Vector2f& centre, float radius_m,
                                             float z_low_m = 0.0f, float z_high_m = 0.6f);

/// Distance [m] from `p` to the nearest solid (height range as collides()) or the floor's
/// edge; 0 inside a solid or outside the floor.
[[nodiscard]] float clearance(const World& world, const Eigen::Vector2f& p, float z_low_m = 0.0f,
                              float z_high_m = 0.6f);

/// The world as a ground-truth grid of `resolution_m` cells covering the floor: a cell is
/// occupied when its square overlaps a solid in [z_low_m, z_high_m], free otherwise.
/// Cell values (row-major, y up): 1 occupied, 0 free.
struct TruthGrid {
  float resolution_m = 0.05f;
  Eigen::Vector2f origin{0.0f, 0.0f};  ///< world xy of the lower-left corner of cell (0, 0)
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> occupied;  ///< width * height
  [[nodiscard]] std::uint8_t at(int x, int y) const { return occupied[static_cast<std::size_t>(y) * width + x]; }
};
[[nodiscard]] TruthGrid rasterize(const World& world, float resolution_m, float z_low_m = 0.0f, float z_high_m = 0.6f);

/// The free area a robot of radius `robot_radius_m` can see from where it can go, starting at
/// world.start: cells reachable by the robot's centre (4-connected over cells whose centre is
/// at least robot_radius_m from every occupied cell's square, and from the floor's edge), plus
/// every free cell within `sensor_range_m` of a reachable cell measured through free cells
/// (8-connected path length: a stand-in for line of sight that needs no ray casting).
/// This is the denominator of coverage in the run summary. Returns a mask on `truth`'s cells.
[[nodiscard]] std::vector<std::uint8_t> reachable_free_mask(const TruthGrid& truth, const Pose2& start,
                                                            float robot_radius_m, float sensor_range_m);

}  // namespace duet::sim
