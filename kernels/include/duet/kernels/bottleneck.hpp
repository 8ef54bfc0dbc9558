#pragma once
/// @file bottleneck.hpp
/// Widest passage to every cell: for each cell of an InflatedGrid, the largest clearance c such
/// that a path of known-free cells (state kFree), each with clearance_m >= c, joins it to the
/// start cell (8-connected, diagonal steps allowed only where both side cells are free too, as
/// the path search). The narrowest point of the best such path: a frontier whose value is at most
/// the robot's radius lies behind a passage the robot does not fit through, and 2 * value is the
/// passage's width to within one cell. Used once, when exploration stops, to say why what is
/// left was left (navigation/unexplored.hpp); not on a control path.
///
/// Semantics: out[start] = clearance_m[start] when the start cell is kFree; cells that are not
/// kFree, or that no such path reaches, get 0; a start outside the grid or not kFree leaves every
/// cell 0. Clearances of +inf (no blocked cell in the grid) stay +inf along the path.
/// Complexity: O(N log N) (a max-heap over the reached cells). Reentrant; single-threaded.
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <vector>

namespace duet {

/// Fills `out` (resized to g.cell_count()) as described in the file comment. `start_xy` is a
/// world point [m]; a non-finite one leaves every cell 0. Throws duet::Error(kInvalidArgument)
/// if g's buffers do not match its size.
void widest_passage(const InflatedGrid& g, const Eigen::Vector2f& start_xy, std::vector<float>& out);

}  // namespace duet
