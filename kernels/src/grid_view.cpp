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
  if (!std::isfinite(grid.resolution_m) || !(grid.resolution_m > 0.0f))
    fail(ErrorCode::kInvalidArgument, name + ": resolution_m must be finite and > 0, got " +
                                          std::to_string(grid.resolution_m));
  if (!std::isfinite(grid.origin.x()) || !std::isfinite(grid.origin.y()))
    fail(ErrorCode::kInvalidArgument, name + ": origin must be finite");
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
