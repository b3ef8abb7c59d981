// delta.ib: AdaptiveGrid. Builds and moves run without the GIL; `distances` is a view of the
// grid's storage, kept valid by copy on write.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/ib/adaptive_grid.h"
#include "delta/ib/grid_vtk.h"
#include "delta/io/vtk.h"

#include "arrays.h"
#include "bindings.h"
#include "handles.h"
#include "interrupt.h"
#include "records.h"
#include "transforms.h"

namespace delta::python {
namespace {

using namespace pybind11::literals;

constexpr const char* kGrid = "delta.ib.AdaptiveGrid";

static_assert(std::is_trivially_copyable_v<ib::Cell>);

/// The grid behind a Python `delta.ib.AdaptiveGrid`: copy on write, like PyMesh. Views of the
/// distances hold a snapshot; a move transforms the grid in place when nothing else holds it,
/// otherwise a copy (so a view keeps showing the distances it was taken of).
///
/// Threading: used with the GIL held; a move works without it, holding the busy flag, and every
/// other use checks the flag (RuntimeError while another thread moves the grid).
class PyGrid {
 public:
  explicit PyGrid(ib::AdaptiveGrid grid)
      : grid_(std::make_shared<ib::AdaptiveGrid>(std::move(grid))) {}

  const ib::AdaptiveGrid& read() const {
    busy_.check(kGrid);
    return *grid_;
  }
  std::shared_ptr<const ib::AdaptiveGrid> snapshot() const {
    busy_.check(kGrid);
    return grid_;
  }

  /// Moves the boundary by `motion` (or to `motion` as a pose) and updates the grid.
  ib::GridStatistics move(const RigidTransform& motion, bool toPose) {
    const BusyFlag::Hold hold(busy_, kGrid);
    const bool shared = grid_.use_count() > 1;
    std::shared_ptr<ib::AdaptiveGrid> target = grid_;
    ib::GridStatistics statistics;
    {
      py::gil_scoped_release release;
      if (shared) target = std::make_shared<ib::AdaptiveGrid>(*grid_);
      statistics = toPose ? target->moveBoundaryTo(motion) : target->moveBoundary(motion);
    }
    grid_ = std::move(target);
    return statistics;
  }

 private:
  std::shared_ptr<ib::AdaptiveGrid> grid_;
  BusyFlag busy_;
};

py::dict statisticsDict(const ib::GridStatistics& s) {
  return py::dict("queries"_a = s.queries, "cells_created"_a = s.cellsCreated,
                  "cells_removed"_a = s.cellsRemoved, "query_seconds"_a = s.querySeconds,
                  "seconds"_a = s.seconds);
}

py::dtype cellDtype() {
  using ib::Cell;
  return recordDtype({{"origin", "(3,)u4", offsetof(Cell, origin)},
                      {"corners", "(8,)u4", offsetof(Cell, corners)},
                      {"first_child", "u4", offsetof(Cell, firstChild)},
                      {"level", "u1", offsetof(Cell, level)}},
                     sizeof(Cell));
}

std::optional<Aabb> domainFrom(const std::optional<ArrayLike>& given) {
  if (!given) return std::nullopt;
  // Its own shape asked for where pointArray would ask for (n, 3); pointArray's checks of the
  // values (integers float64 would round) come before the count of rows.
  const auto refuseShape = [](const std::string& shape) {
    throw Error("domain must have shape (2, 3): lower, upper corner; not " + shape);
  };
  if (const RealArray real = realArray(given->object);
      real.problem.empty() && !(real.array.ndim() == 2 && real.array.shape(1) == 3))
    refuseShape(shapeOf(real.array));
  const DoubleArray corners = pointArray(*given, "domain", true);
  if (corners.shape(0) != 2) refuseShape(shapeOf(corners));
  const std::span<const Vec3> box = asVec3(corners);
  return Aabb{box[0], box[1]};
}

/// Builds without the GIL; Ctrl-C stops the build (KeyboardInterrupt, no grid made).
PyGrid makeGrid(const Geometry& mesh, int levels, double refineFactor, Flag signedDistance,
                std::optional<double> exactBand, double padding,
                const std::optional<ArrayLike>& domain, const std::string& sign) {
  ib::GridOptions options;
  options.sign = signNamed(sign);
  options.levels = levels;
  options.refineFactor = refineFactor;
  options.signedDistance = signedDistance.value;
  options.exactBand = exactBand;
  options.padding = padding;
  options.domain = domainFrom(domain);
  const SignalScope interruptible;
  py::gil_scoped_release release;
  return PyGrid(ib::AdaptiveGrid(mesh.prepare(), options));
}

}  // namespace

void bindIb(py::module_& ib) {
  ib.attr("cell_dtype") = cellDtype();
  py::class_<PyGrid>(ib, "AdaptiveGrid", R"(An octree Cartesian grid refined around a boundary mesh.

AdaptiveGrid(boundary, levels=7, refine_factor=1.0, signed=True, exact_band=None, padding=0.1,
domain=None, sign="pseudonormal"): `boundary` a Mesh or QueryMesh (signed distances by
pseudonormals need one that bounds a solid, QueryMesh.bounds_solid, delta.Error otherwise; sign="winding"
signs by the generalized winding number any boundary, open or self-intersecting, and then
queries every vertex again after a move; another string raises ValueError). The domain
(default: the boundary's box made a cube and grown by padding times its longest side) is the root
cell; a cell of level l < levels is split while the smallest |distance|
at its corners is below refine_factor times its diagonal. Every grid vertex holds the boundary's
exact distance (negative inside when signed), computed level by level by Delta's point queries
without the GIL. `move_boundary(motion)` / `move_boundary_to(pose)` move the boundary rigidly and
update the grid, querying again only what could have changed: within `exact_band` (default: a
finest cell's diagonal; inf: everywhere) distances stay exact, farther ones within
`error_bounds`. As `delta ib MESH`. Invalid values raise delta.Error, never a silent default:
levels outside 1-20, refine_factor not finite and positive, padding negative or not finite,
exact_band NaN or negative, a domain that is not finite with lower < upper on every axis. Ctrl-C
stops a build within some tens of milliseconds (KeyboardInterrupt; no grid is made); moves run
to the end.

`distances` is a read-only view of the grid's storage (no copy); a move writes new storage when a
view is alive, so a view keeps showing the distances it was taken of.

Threading: one Python thread at a time moves a grid; other threads' calls on it meanwhile raise
RuntimeError.)")
      .def(py::init(&makeGrid), "boundary"_a, "levels"_a = 7, "refine_factor"_a = 1.0,
           "signed"_a = true, "exact_band"_a = py::none(), "padding"_a = 0.1,
           "domain"_a = py::none(), "sign"_a = "pseudonormal",
           "Builds the grid around `boundary` (see the class); `domain`: (2, 3) lower and upper "
           "corner, or None.")
      .def(
          "move_boundary",
          [](PyGrid& grid, const Motion& motion) {
            return statisticsDict(grid.move(motion.value, false));
          },
          "motion"_a,
          "Moves the boundary by `motion` (a RigidTransform or a 4×4 matrix; its pose becomes "
          "motion * pose) and updates the grid; "
          "returns what the move did (statistics).")
      .def(
          "move_boundary_to",
          [](PyGrid& grid, const Motion& pose) {
            return statisticsDict(grid.move(pose.value, true));
          },
          "pose"_a,
          "Puts the boundary at `pose` (a RigidTransform or a 4×4 matrix, from the frame it was "
          "prepared in) and updates the grid.")
      .def_property_readonly(
          "distances",
          [](const PyGrid& grid) {
            const std::shared_ptr<const ib::AdaptiveGrid> snapshot = grid.snapshot();
            const std::span<const double> values = snapshot->distances();
            return view(snapshot, values.data(), py::dtype::of<double>(),
                        {static_cast<py::ssize_t>(values.size())}, {py::ssize_t{sizeof(double)}});
          },
          "The boundary's distance at every vertex (negative inside when signed), in vertex "
          "order: a read-only float64 view, no copy.")
      .def_property_readonly(
          "positions",
          [](const PyGrid& grid) {
            std::vector<Vec3> points = grid.read().positions();
            const auto count = static_cast<py::ssize_t>(points.size());
            return adopt(std::move(points), py::dtype::of<double>(), {count, 3});
          },
          "Where the vertices are, (n, 3) float64, in vertex order.")
      .def_property_readonly(
          "error_bounds",
          [](const PyGrid& grid) {
            std::vector<double> bounds = grid.read().errorBounds();
            const auto count = static_cast<py::ssize_t>(bounds.size());
            return adopt(std::move(bounds), py::dtype::of<double>(), {count});
          },
          "How far each vertex's distance may be from the exact one (0 within exact_band and "
          "after a build), float64.")
      .def_property_readonly(
          "leaves_per_level",
          [](const PyGrid& grid) {
            std::vector<std::size_t> leaves = grid.read().leavesPerLevel();
            const auto count = static_cast<py::ssize_t>(leaves.size());
            return adopt(std::move(leaves), py::dtype::of<std::size_t>(), {count});
          },
          "Leaf cells of each level 0 ... levels.")
      .def_property_readonly(
          "leaf_count", [](const PyGrid& grid) { return grid.read().leafCount(); },
          "Leaf cells of all levels.")
      .def_property_readonly(
          "vertex_count", [](const PyGrid& grid) { return grid.read().vertexCount(); },
          "Grid vertices.")
      .def_property_readonly(
          "levels", [](const PyGrid& grid) { return grid.read().levels(); }, "The finest level.")
      .def_property_readonly(
          "exact_band", [](const PyGrid& grid) { return grid.read().exactBand(); },
          "The band within which distances are exact after a move.")
      .def_property_readonly(
          "domain",
          [](const PyGrid& grid) {
            const Aabb& box = grid.read().domain();
            return vec3Array(std::vector<Vec3>{box.lower, box.upper});
          },
          "The box of the root cell, (2, 3).")
      .def_property_readonly(
          "boundary", [](const PyGrid& grid) { return grid.read().boundary(); },
          "The boundary where it is now (a QueryMesh copy).")
      .def_property_readonly(
          "statistics", [](const PyGrid& grid) { return statisticsDict(grid.read().statistics()); },
          "What the last build or move did: queries, cells_created, cells_removed, "
          "query_seconds, seconds.")
      .def(
          "cell_diagonal",
          [](const PyGrid& grid, int level) {
            const ib::AdaptiveGrid& g = grid.read();
            if (level < 0 || level > g.levels())
              throw Error("cell_diagonal: level " + std::to_string(level) + " is not 0 to " +
                          std::to_string(g.levels()));
            return g.cellDiagonal(level);
          },
          "level"_a, "The diagonal of a cell of this level (0 to levels; delta.Error otherwise).")
      .def(
          "cells",
          [](const PyGrid& grid, int level) {
            const std::span<const ib::Cell> cells = grid.read().cells(level);
            py::array array(cellDtype(),
                            std::vector<py::ssize_t>{static_cast<py::ssize_t>(cells.size())});
            if (!cells.empty()) std::memcpy(array.mutable_data(), cells.data(), cells.size_bytes());
            return array;
          },
          "level"_a,
          "The cells of a level (inner cells and leaves), a structured array of "
          "delta.ib.cell_dtype (a copy): origin (in finest-cell units), the eight corner vertex "
          "indices in VTK voxel order, first_child (index into the next level; 4294967295 for a "
          "leaf), level.")
      .def(
          "write_vtu",
          [](const PyGrid& grid, const std::filesystem::path& path) {
            const std::shared_ptr<const ib::AdaptiveGrid> snapshot = grid.snapshot();
            py::gil_scoped_release release;
            io::writeVtu(ib::toVtk(*snapshot), path);
          },
          "path"_a,
          "Writes the leaves as VTK voxels for ParaView (.vtu): point data signed_distance (or "
          "distance) and error_bound (Float64) and finest_level (UInt8), cell data level (UInt8), "
          "zlib-compressed; as `delta ib --out --compression 1`.")
      .def("__repr__", [](const PyGrid& grid) {
        const ib::AdaptiveGrid& g = grid.read();
        return "<delta.ib.AdaptiveGrid: " + std::to_string(g.levels()) + " levels, " +
               std::to_string(g.leafCount()) + " leaves, " + std::to_string(g.vertexCount()) +
               " vertices>";
      });
}

}  // namespace delta::python
