// What an immersed-boundary code asks of Δ: an adaptive Cartesian grid refined around a boundary
// mesh, the boundary's signed distance at every grid vertex, and the grid following the boundary
// as it turns and moves — written as a ParaView series. Copy it as the start of your own.
//
//   immersed_boundary [MESH [OUT_DIR]]
//
// MESH: any closed mesh assimp reads (default: an icosphere); OUT_DIR (default ib_example/):
// grid.pvd and boundary.pvd, one .vtu and .vtp a step.
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "delta/delta.h"

namespace {

/// Writes step `step`'s grid and boundary and rewrites the two series that list them.
struct SeriesWriter {
  std::filesystem::path folder;
  std::vector<delta::io::VtkSeriesEntry> grids, boundaries;

  void write(const delta::ib::AdaptiveGrid& grid, const delta::Mesh& mesh, int step) {
    const std::string gridFile = "grid_" + std::to_string(step) + ".vtu";
    const std::string boundaryFile = "boundary_" + std::to_string(step) + ".vtp";
    delta::io::writeVtu(delta::ib::toVtk(grid), folder / gridFile);
    delta::Mesh moved = mesh;
    moved.transform(grid.boundary().pose());
    delta::io::writeVtp(delta::io::VtkPolyData::fromMesh(moved), folder / boundaryFile);
    grids.push_back({double(step), gridFile});
    boundaries.push_back({double(step), boundaryFile});
    delta::io::writePvd(grids, folder / "grid.pvd");
    delta::io::writePvd(boundaries, folder / "boundary.pvd");
  }
};

}  // namespace

int main(int argc, char** argv) try {
  const delta::Mesh mesh = argc > 1 ? delta::io::load(argv[1]) : delta::primitives::icosphere(4);
  SeriesWriter out{argc > 2 ? argv[2] : "ib_example", {}, {}};
  std::filesystem::create_directories(out.folder);

  // The grid: 2^6 finest cells per axis over the mesh's box (made a cube, grown by 10%).
  const delta::QueryMesh boundary(mesh);
  delta::ib::AdaptiveGrid grid(boundary, {.levels = 6});
  out.write(grid, mesh, 0);
  std::printf("build: %zu leaf cells, %zu vertices, %zu queries in %.3f s\n", grid.leafCount(),
              grid.vertexCount(), grid.statistics().queries, grid.statistics().seconds);

  // Ten time steps: the boundary turns about its centre and drifts along x; each step the grid
  // refines toward it and coarsens behind it, and only what could have changed is asked again.
  const delta::Vec3 centre = mesh.bounds().center();
  const double size = mesh.bounds().diagonal();
  for (int step = 1; step <= 10; ++step) {
    const delta::RigidTransform pose =
        delta::RigidTransform::translationBy({0.01 * size * step, 0.0, 0.0}) *
        delta::RigidTransform::rotationAbout(
            delta::Quaternion::fromAxisAngle({0, 0, 1}, std::numbers::pi / 90 * step), centre);
    const delta::ib::GridStatistics& moved = grid.moveBoundaryTo(pose);

    // A solver's use of the field: the vertices inside the body (negative distance) are solid.
    std::size_t solid = 0;
    for (double d : grid.distances())
      solid += d < 0.0;
    std::printf("step %2d: %zu leaf cells, %zu vertices (%zu solid), %zu queries in %.3f s\n", step,
                grid.leafCount(), grid.vertexCount(), solid, moved.queries, moved.seconds);
    out.write(grid, mesh, step);
    if (solid == 0) return 1;  // a closed boundary inside the grid has solid vertices
  }
  std::printf("open %s in ParaView\n", (out.folder / "grid.pvd").string().c_str());
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "immersed_boundary: %s\n", error.what());
  return 1;
}
