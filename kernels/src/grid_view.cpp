#include <duet/kernels/error.hpp>
#include <duet/kernels/grid_view.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <string>

namespace duet {

void validate(const GridView& grid, const char* what) {
  const std::string name = what ? what : "grid";
  if (grid.width < 0 || grid.height < 0)
    fail(ErrorCode::kInvalidArgument, name + ": negative size " + std::to_string(grid.width) + " x " +
                                          std::to_string(grid.height));
  if (grid.logodds.size() != grid.cell_count())
    fail(ErrorCode::kInvalidArgument, name + ": " + std::to_string(grid.logodds.size()) +
                                          " log-odds values for " + std::to_string(grid.width) + " x " +
                                          std::to_string(grid.height) + " cells");
  // The map frame's limits (grid.hpp): a ray of the longest sensor range walks at most
  // 2 * kMaxSensorRangeM / kMinGridResolutionM cells (a resolution of 1e-30 overflowed the ray
  // buffers' size: found by fuzz_capi); the origin leaves room for a grid's growth margin.
  if (!(grid.resolution_m >= kMinGridResolutionM && grid.resolution_m <= kMaxGridResolutionM))
    fail(ErrorCode::kInvalidArgument, name + ": resolution_m must be in [" + std::to_string(kMinGridResolutionM) + ", " +
                                          std::to_string(kMaxGridResolutionM) + "] m, got " + std::to_string(grid.resolution_m));
  if (!(std::fabs(grid.origin.x()) <= 2.0f * kMaxCoordinateM) || !(std::fabs(grid.origin.y()) <= 2.0f * kMaxCoordinateM))
    fail(ErrorCode::kOutOfRange, name + ": origin must be finite and within +-" + std::to_string(2.0f * kMaxCoordinateM) +
                                     " m, got (" + std::to_string(grid.origin.x()) + ", " + std::to_string(grid.origin.y()) + ")");
}

void validate(const CellThresholds& t) {
  if (!std::isfinite(t.occupied_logodds) || !std::isfinite(t.free_logodds) ||
      !(t.free_logodds < t.occupied_logodds))
    fail(ErrorCode::kInvalidArgument,
         "CellThresholds: need finite free_logodds < occupied_logodds, got free_logodds=" +
             std::to_string(t.free_logodds) + " occupied_logodds=" + std::to_string(t.occupied_logodds));
}

void classify_grid(const GridView& grid, const CellThresholds& t, std::span<CellState> out) {
  validate(grid);
  validate(t);
  if (out.size() != grid.cell_count())
    fail(ErrorCode::kInvalidArgument, "classify_grid: output has " + std::to_string(out.size()) +
                                          " cells, grid has " + std::to_string(grid.cell_count()));
  const float* in = grid.logodds.data();
  CellState* o = out.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.cell_count(), 1 << 14),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) o[i] = classify(in[i], t);
                    });
}

}  // namespace duet
