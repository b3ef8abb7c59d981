#include "delta/ib/grid_vtk.h"

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace delta::ib {

io::VtkVoxelGrid toVtk(const AdaptiveGrid& grid) {
  io::VtkVoxelGrid vtk;
  vtk.points = grid.positions();
  const std::span<const double> distances = grid.distances();
  vtk.pointData.push_back({grid.options().signedDistance ? "signed_distance" : "distance", 1,
                           std::vector<double>(distances.begin(), distances.end())});
  vtk.pointData.push_back({"error_bound", 1, grid.errorBounds()});

  io::VtkArray level{"level", 1, {}, io::VtkType::UInt8};  // levels are 0 to 20
  io::VtkArray vertexLevel{"finest_level", 1, std::vector<double>(grid.vertexCount(), 0.0),
                           io::VtkType::UInt8};
  vtk.voxels.reserve(grid.leafCount());
  level.values.reserve(grid.leafCount());
  for (int l = 0; l <= grid.levels(); ++l)
    for (const Cell& cell : grid.cells(l)) {
      if (!cell.leaf()) continue;
      vtk.voxels.push_back(cell.corners);
      level.values.push_back(cell.level);
      for (std::uint32_t v : cell.corners)  // levels ascend: the finest leaf is the last
        vertexLevel.values[v] = cell.level;
    }
  vtk.cellData.push_back(std::move(level));
  vtk.pointData.push_back(std::move(vertexLevel));
  return vtk;
}

}  // namespace delta::ib
