#include "delta/ib/grid_vtk.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "io/vtk_read.h"

namespace delta::ib {
namespace {

GridOptions smallGrid(bool signedDistance) {
  GridOptions options;
  options.levels = 4;
  options.signedDistance = signedDistance;
  return options;
}

/// The point data array named `name`, or null.
const io::VtkArray* pointArray(const io::VtkVoxelGrid& vtk, const std::string& name) {
  for (const io::VtkArray& array : vtk.pointData)
    if (array.name == name) return &array;
  return nullptr;
}

TEST(GridVtk, LeavesAreVoxelsAndVerticesArePoints) {
  const AdaptiveGrid grid(QueryMesh(primitives::icosphere(2)), smallGrid(true));
  const io::VtkVoxelGrid vtk = toVtk(grid);
  ASSERT_EQ(vtk.voxels.size(), grid.leafCount());
  ASSERT_EQ(vtk.points.size(), grid.vertexCount());
  for (std::uint32_t v = 0; v < grid.vertexCount(); ++v)
    ASSERT_EQ(vtk.points[v], grid.position(v));

  const io::VtkArray* distance = pointArray(vtk, "signed_distance");
  ASSERT_NE(distance, nullptr);
  EXPECT_EQ(distance->components, 1);
  ASSERT_EQ(distance->values.size(), grid.vertexCount());
  for (std::size_t v = 0; v < grid.vertexCount(); ++v)
    EXPECT_EQ(distance->values[v], grid.distances()[v]);
  const io::VtkArray* bound = pointArray(vtk, "error_bound");
  ASSERT_NE(bound, nullptr);
  EXPECT_EQ(bound->values, grid.errorBounds());
  EXPECT_EQ(pointArray(vtk, "distance"), nullptr);

  ASSERT_EQ(vtk.cellData.size(), 1u);
  EXPECT_EQ(vtk.cellData[0].name, "level");
  ASSERT_EQ(vtk.cellData[0].values.size(), grid.leafCount());
  // Leaves per level as the grid counts them, and every voxel a box in VTK's voxel order.
  const std::vector<std::size_t> perLevel = grid.leavesPerLevel();
  std::vector<std::size_t> counted(perLevel.size(), 0);
  const Vec3 domain = grid.domain().extent();
  for (std::size_t i = 0; i < vtk.voxels.size(); ++i) {
    const int level = static_cast<int>(vtk.cellData[0].values[i]);
    ASSERT_GE(level, 0);
    ASSERT_LE(level, grid.levels());
    ++counted[static_cast<std::size_t>(level)];
    const Vec3 side = domain * (1.0 / double(1u << level));
    const Vec3 lowest = vtk.points[vtk.voxels[i][0]];
    for (std::uint32_t c = 0; c < 8; ++c) {
      const Vec3 offset = vtk.points[vtk.voxels[i][c]] - lowest;
      const Vec3 expected{(c & 1) * side.x, ((c >> 1) & 1) * side.y, ((c >> 2) & 1) * side.z};
      EXPECT_NEAR(offset.x, expected.x, 1e-12 * domain.x) << "voxel " << i << " corner " << c;
      EXPECT_NEAR(offset.y, expected.y, 1e-12 * domain.y) << "voxel " << i << " corner " << c;
      EXPECT_NEAR(offset.z, expected.z, 1e-12 * domain.z) << "voxel " << i << " corner " << c;
    }
  }
  EXPECT_EQ(counted, perLevel);
  EXPECT_GT(perLevel.back(), 0u) << "the boundary is refined to the finest level";

  // Each vertex's level is the finest of the leaves it is a corner of.
  const io::VtkArray* vertexLevel = pointArray(vtk, "finest_level");
  ASSERT_NE(vertexLevel, nullptr);
  std::vector<double> finest(grid.vertexCount(), -1.0);
  for (std::size_t i = 0; i < vtk.voxels.size(); ++i)
    for (std::uint32_t v : vtk.voxels[i])
      finest[v] = std::max(finest[v], vtk.cellData[0].values[i]);
  EXPECT_EQ(vertexLevel->values, finest);
}

TEST(GridVtk, UnsignedGridsNameTheirDistanceAndMovedGridsKeepTheirBounds) {
  AdaptiveGrid grid(QueryMesh(primitives::box({1, 2, 1})), smallGrid(false));
  grid.moveBoundary(RigidTransform::translationBy({0.05, 0, 0}));
  const io::VtkVoxelGrid vtk = toVtk(grid);
  EXPECT_EQ(vtk.voxels.size(), grid.leafCount());
  const io::VtkArray* distance = pointArray(vtk, "distance");
  ASSERT_NE(distance, nullptr);
  ASSERT_EQ(distance->values.size(), grid.vertexCount());
  for (double d : distance->values)
    EXPECT_GE(d, 0.0);
  EXPECT_EQ(pointArray(vtk, "signed_distance"), nullptr);
  const io::VtkArray* bound = pointArray(vtk, "error_bound");
  ASSERT_NE(bound, nullptr);
  EXPECT_EQ(bound->values, grid.errorBounds());
}

TEST(GridVtk, AWrittenGridReadsBack) {
  const AdaptiveGrid grid(QueryMesh(primitives::icosphere(1)), smallGrid(true));
  const io::VtkVoxelGrid vtk = toVtk(grid);
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("delta_grid_vtk_" + std::to_string(::getpid()) + ".vtu");
  io::writeVtu(vtk, path);
  const std::string file = test::readFile(path);
  std::filesystem::remove(path);
  EXPECT_NE(file.find("NumberOfPoints=\"" + std::to_string(grid.vertexCount()) +
                      "\" NumberOfCells=\"" + std::to_string(grid.leafCount()) + "\""),
            std::string::npos);
  EXPECT_EQ(test::readVtkArray<double>(file, "signed_distance"), vtk.pointData[0].values);
  const std::vector<std::uint8_t> levels = test::readVtkArray<std::uint8_t>(file, "level");
  EXPECT_EQ(std::vector<double>(levels.begin(), levels.end()), vtk.cellData[0].values);
  const std::vector<std::uint8_t> finest = test::readVtkArray<std::uint8_t>(file, "finest_level");
  EXPECT_EQ(std::vector<double>(finest.begin(), finest.end()), vtk.pointData[2].values);
  EXPECT_EQ(vtk.cellData[0].type, io::VtkType::UInt8);
  EXPECT_EQ(test::readVtkArray<std::int32_t>(file, "connectivity").size(), 8 * grid.leafCount());
  EXPECT_EQ(test::readVtkArray<std::uint8_t>(file, "types"),
            std::vector<std::uint8_t>(grid.leafCount(), 11));
}

}  // namespace
}  // namespace delta::ib
