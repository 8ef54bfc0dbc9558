#pragma once
/// @file grid_io.hpp
/// 2D occupancy grid files (DESIGN.md §5): the ROS map_server format (a YAML file beside an
/// 8-bit image) in and out, and a PNG picture of the grid for people, with optional overlays.
///
/// map_server conventions: the image's row 0 is the grid's highest y (the image is the grid
/// flipped vertically); `origin` is the world position [m] of the lower-left corner of cell
/// (0, 0); a pixel of value v (after `negate`) has occupancy p = (255 - v) / 255, occupied when
/// p > occupied_thresh, free when p < free_thresh, unknown otherwise (mode trinary). duet
/// writes trinary images: 0 occupied, 254 free, 205 unknown.
///
/// Errors: duet::Error naming the file and the key or position ("map.yaml: key 'resolution':
/// must be > 0, got -1"); ErrorCode kIo when a file cannot be opened, read or written, kParse
/// for malformed content, kUnsupported for a rotated map (origin yaw != 0), kInvalidArgument
/// for an empty grid or options out of range. Written files go to a temporary sibling first
/// and are renamed into place, so an existing map is never left half-written.
///
/// Thread safety: every function is reentrant; calls on different files may run
/// concurrently.
#include <duet/kernels/grid.hpp>
#include <duet/kernels/types.hpp>

#include <filesystem>
#include <vector>

namespace duet {

struct MapServerOptions {
  /// A cell whose log-odds give p(occupied) >= this is written occupied (0) [probability].
  /// Default: one hit (p = 0.70) marks a cell occupied.
  float classify_occupied_p = 0.65f;
  /// A cell whose log-odds give p(occupied) <= this is written free (254) [probability].
  /// Default: one miss (p = 0.40) marks a cell free; a hit then a miss (p = 0.61) is unknown.
  float classify_free_p = 0.45f;
  /// Written to the YAML for map_server's reading of the PGM pixel values (not the cells'):
  /// must be in (50/255, 1) so that the unknown value 205 reads back unknown [probability].
  float occupied_thresh = 0.65f;
  /// Written to the YAML: must be in (1/255, 50/255) so that 254 reads back free and 205
  /// unknown [probability].
  float free_thresh = 0.196f;
};

struct MapServerReadOptions {
  float occupied_logodds = 3.5f;  ///< log-odds of occupied cells (GridUpdateSettings::max_logodds)
  float free_logodds = -2.0f;     ///< log-odds of free cells (GridUpdateSettings::min_logodds)
};

/// Writes `<stem of yaml_path>.pgm` (P5, 8-bit, trinary) beside `yaml_path`, then the YAML
/// (image, resolution, origin [x, y, 0.0], negate 0, occupied_thresh, free_thresh, mode
/// trinary). Throws kInvalidArgument for an empty grid or thresholds out of range.
void write_map_server(const OccupancyGrid& grid, const std::filesystem::path& yaml_path,
                      const MapServerOptions& options = {});

/// Reads a map_server YAML and its image (relative paths are relative to the YAML's folder):
/// PGM P5 or P2 (8 or 16 bit), or anything OpenCV decodes (PNG, ...; colour channels are
/// averaged, alpha 0 is unknown in mode scale), honouring negate, occupied_thresh,
/// free_thresh and mode (trinary, scale, raw). Keys negate, occupied_thresh, free_thresh and
/// mode are optional (defaults 0, 0.65, 0.196, trinary); any other key is an error.
/// Occupied cells get options.occupied_logodds, free cells options.free_logodds, unknown
/// cells NaN; in-between values (mode scale or raw) get the log-odds of their probability,
/// clamped to that range.
[[nodiscard]] OccupancyGrid read_map_server(const std::filesystem::path& yaml_path,
                                            const MapServerReadOptions& options = {});

struct GridPngOptions {
  int scale = 1;                 ///< pixels per cell edge, to enlarge small grids [1, 64]
  float occupied_thresh = 0.65f; ///< p(occupied) at or above which a cell is black [probability]
  float free_thresh = 0.45f;     ///< p(occupied) at or below which a cell is white (one miss) [probability]
  Rgb8 unknown_color{150, 160, 175};  ///< never-observed cells (a blue-grey, unlike any shade)
  /// World xy points [m] drawn as a connected line, e.g. the robot trajectory; a non-finite
  /// point breaks the line.
  std::vector<Eigen::Vector2f> polyline;
  Rgb8 polyline_color{220, 30, 30};
  int polyline_width_px = 2;     ///< line thickness [px, in the scaled image] [1, 64]
  /// World xy points [m] drawn as filled dots, e.g. frontier cells; non-finite ones skipped.
  std::vector<Eigen::Vector2f> dots;
  Rgb8 dot_color{20, 110, 230};
  int dot_radius_px = 2;         ///< [px, in the scaled image] [0, 64]
};

/// Writes a PNG picture of `grid` (north up: the image's row 0 is the highest y): unknown
/// cells in unknown_color, free white, occupied black, probabilities in between as greys,
/// then the polyline and the dots. Throws kInvalidArgument for an empty grid, options out of
/// range or an image above 2^28 pixels.
void write_grid_png(const OccupancyGrid& grid, const std::filesystem::path& path,
                    const GridPngOptions& options = {});

}  // namespace duet
