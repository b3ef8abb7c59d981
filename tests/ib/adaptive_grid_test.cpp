#include "delta/ib/adaptive_grid.h"

#include <gtest/gtest.h>
#include <omp.h>
#include <pthread.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "delta/core/cancel.h"
#include "delta/core/error.h"
#include "delta/core/parallel.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/winding_number.h"

#include "kernels/triangle_pairs.h"

namespace delta::ib {
namespace {

const std::filesystem::path kMeshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";

/// The brute-force checks visit every vertex, or every sixteenth in the (slower) sanitizer build.
constexpr std::size_t kEveryVertex = test::kSlowBuild ? 16 : 1;

/// The brute-force reference at a point: the exact minimum of closestPointOnTriangle over all
/// triangles, signed by the generalized winding number.
struct Reference {
  double distance = std::numeric_limits<double>::infinity();
  bool inside = false;
};

Reference reference(const TriangleSoA& triangles, const Vec3& p) {
  Reference answer;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    answer.distance = std::min(
        answer.distance,
        std::sqrt(kernels::closestPointOnTriangle(p, triangles.triangle(t)).distanceSquared));
  answer.inside = inside(triangles, p);
  return answer;
}

/// Checks every `stride`-th vertex of `grid` (in the boundary's prepared frame) against the
/// brute-force reference: distances to 1e-12 of the diagonal (or within their error bound, after
/// a move), and no sign mismatch for vertices further than 1e-9 of the diagonal from the surface.
/// Returns how many vertices it checked.
std::size_t expectMatchesBruteForce(const AdaptiveGrid& grid, std::size_t stride) {
  const TriangleSoA& triangles = grid.boundary().triangles();
  const double diagonal = grid.boundary().bounds().diagonal();
  std::vector<std::uint32_t> checked;
  for (std::uint32_t v = 0; v < grid.vertexCount(); v += static_cast<std::uint32_t>(stride))
    checked.push_back(v);
  std::vector<Reference> expected(checked.size());
  parallelFor(0, checked.size(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      expected[i] =
          reference(triangles, grid.boundary().inversePose().apply(grid.position(checked[i])));
  });
  const std::vector<double> bounds = grid.errorBounds();
  std::size_t signMismatches = 0, distanceMismatches = 0;
  for (std::size_t i = 0; i < checked.size(); ++i) {
    const double got = grid.distances()[checked[i]];
    if (std::abs(std::abs(got) - expected[i].distance) > 1e-12 * diagonal + bounds[checked[i]])
      ++distanceMismatches;
    if (expected[i].distance > 1e-9 * diagonal &&
        (got < 0.0) != (grid.options().signedDistance && expected[i].inside))
      ++signMismatches;
  }
  EXPECT_EQ(distanceMismatches, 0u);
  EXPECT_EQ(signMismatches, 0u);
  return checked.size();
}

/// Every inner cell is refined because a corner is closer than refineFactor × its diagonal, and
/// every leaf above the finest level is not; level-L leaves are where the surface is.
void expectRefinementRule(const AdaptiveGrid& grid) {
  const auto distances = grid.distances();
  for (int level = 0; level < grid.levels(); ++level) {
    const double threshold = grid.options().refineFactor * grid.cellDiagonal(level);
    for (const Cell& cell : grid.cells(level)) {
      double lowest = std::numeric_limits<double>::infinity();
      for (std::uint32_t v : cell.corners)
        lowest = std::min(lowest, std::abs(distances[v]));
      EXPECT_EQ(cell.leaf(), lowest >= threshold) << "level " << level;
    }
  }
}

TEST(AdaptiveGrid, FandiskMatchesBruteForceAndWindingNumbers) {
  const QueryMesh fandisk(io::load(kMeshes / "fandisk.off"));
  const AdaptiveGrid grid(fandisk, {.levels = 4});
  const std::vector<std::size_t> leaves = grid.leavesPerLevel();
  ASSERT_EQ(leaves.size(), 5u);
  EXPECT_GT(leaves[4], 1000u);
  EXPECT_EQ(grid.statistics().queries, grid.vertexCount());  // each vertex asked once
  std::size_t cells = 0;
  for (int level = 0; level <= 4; ++level)
    cells += grid.cells(level).size();
  EXPECT_EQ(grid.statistics().cellsCreated, cells);
  EXPECT_GT(expectMatchesBruteForce(grid, kEveryVertex), 4000u / kEveryVertex);
  expectRefinementRule(grid);
}

TEST(AdaptiveGrid, ArmadilloMatchesBruteForceAndWindingNumbers) {
  const QueryMesh armadillo(io::load(kMeshes / "armadillo.off"));
  const AdaptiveGrid grid(armadillo, {.levels = 4});
  EXPECT_GT(expectMatchesBruteForce(grid, kEveryVertex), 4000u / kEveryVertex);
  expectRefinementRule(grid);
}

TEST(AdaptiveGrid, SphereFieldMatchesTheAnalyticDistance) {
  const double radius = 1.0;
  const Mesh sphere = primitives::icosphere(4, radius);
  // The mesh lies between the sphere and the sphere of its smallest face distance from the
  // centre: the field can differ from |x| − r by at most that gap.
  double inner = radius;
  const TriangleSoA triangles(sphere);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    inner = std::min(
        inner,
        std::sqrt(kernels::closestPointOnTriangle({}, triangles.triangle(t)).distanceSquared));
  const double gap = radius - inner;
  ASSERT_GT(gap, 0.0);
  ASSERT_LT(gap, 0.01);
  const AdaptiveGrid grid(QueryMesh(sphere), {.levels = 6});
  double worst = 0.0;
  for (std::uint32_t v = 0; v < grid.vertexCount(); ++v)
    worst = std::max(worst, std::abs(grid.distances()[v] - (length(grid.position(v)) - radius)));
  EXPECT_LE(worst, gap * (1 + 1e-9));
  EXPECT_GT(worst, 0.5 * gap);  // the discretisation is what is seen, not noise
}

TEST(AdaptiveGrid, OpenBoundaryNeedsUnsignedDistances) {
  const Mesh open = primitives::quad(1.0, 1.0);
  try {
    AdaptiveGrid grid{QueryMesh(open), {.levels = 3}};
    ADD_FAILURE() << "an open boundary gave signed distances";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("not"), std::string::npos) << message;
    EXPECT_NE(message.find("closed"), std::string::npos) << message;
    EXPECT_NE(message.find("4 boundary"), std::string::npos) << message;
    EXPECT_NE(message.find("unsigned"), std::string::npos) << message;
  }
  const AdaptiveGrid grid(QueryMesh(open), {.levels = 5, .signedDistance = false});
  for (double d : grid.distances())
    EXPECT_GE(d, 0.0);
  expectMatchesBruteForce(grid, 1);
  expectRefinementRule(grid);
}

TEST(AdaptiveGrid, RejectsBadOptions) {
  const QueryMesh sphere(primitives::icosphere(1));
  EXPECT_THROW(AdaptiveGrid(sphere, {.levels = 0}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.levels = 21}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.refineFactor = 0.0}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.refineFactor = std::nan("")}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.refineFactor = INFINITY}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.padding = -0.1}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.exactBand = -1.0}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.domain = Aabb{{0, 0, 0}, {1, 0, 1}}}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.domain = Aabb{{0, 0, 0}, {1, NAN, 1}}}), Error);
  EXPECT_THROW(AdaptiveGrid(sphere, {.domain = Aabb{{0, 0, 0}, {1, INFINITY, 1}}}), Error);
  // A domain beyond the queries' range: named as the domain, not as "point 0" of a query.
  for (const GridOptions& huge :
       {GridOptions{.padding = 1e100},
        GridOptions{.domain = Aabb{{-1e308, -1e308, -1e308}, {1e308, 1e308, 1e308}}}}) {
    try {
      AdaptiveGrid grid(sphere, huge);
      ADD_FAILURE() << "a domain beyond the range was taken";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("GridOptions: the", 0), 0u) << e.what();
    }
  }
  AdaptiveGrid grid(sphere, {.levels = 2});
  EXPECT_THROW(grid.cells(3), Error);
  EXPECT_THROW(grid.moveBoundary(RigidTransform::translationBy({NAN, 0, 0})), Error);
}

TEST(AdaptiveGrid, InvalidValuesAreRefusedNotReplacedByDefaults) {
  // An inverted domain (lower > upper) is an empty box, and a NaN band was the "default"
  // sentinel: both used to be silently replaced by the defaults.
  const QueryMesh sphere(primitives::icosphere(1));
  try {
    AdaptiveGrid(sphere, {.levels = 2, .domain = Aabb{{1, 1, 1}, {-1, -1, -1}}});
    ADD_FAILURE() << "an inverted domain was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("lower < upper"), std::string::npos) << error.what();
  }
  try {
    AdaptiveGrid(sphere, {.levels = 2, .exactBand = std::nan("")});
    ADD_FAILURE() << "a NaN exact band was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("exactBand nan"), std::string::npos) << error.what();
  }
  // Unset: the defaults, resolved in options().
  const AdaptiveGrid grid(sphere, {.levels = 2});
  EXPECT_EQ(grid.exactBand(), grid.cellDiagonal(2));
  ASSERT_TRUE(grid.options().domain.has_value());
  EXPECT_EQ(grid.options().domain->lower, grid.domain().lower);
  EXPECT_FALSE(grid.options().exactBand.has_value());
}

TEST(AdaptiveGrid, BuildStopsWhenItsCancelScopeAsks) {
  const QueryMesh sphere(primitives::icosphere(4));
  const GridOptions options{.levels = test::kSlowBuild ? 6 : 7};
  const AdaptiveGrid reference(sphere, options);
  // A scope that never stops: the same grid, polled several times, on this thread only.
  const pthread_t owner = pthread_self();
  std::size_t polls = 0;
  bool wrongPlace = false;
  {
    const CancelScope scope([&] {
      wrongPlace = wrongPlace || !pthread_equal(pthread_self(), owner);
      ++polls;
      return false;
    });
    const AdaptiveGrid polled(sphere, options);
    EXPECT_EQ(polled.leavesPerLevel(), reference.leavesPerLevel());
    EXPECT_TRUE(std::equal(polled.distances().begin(), polled.distances().end(),
                           reference.distances().begin(), reference.distances().end()));
  }
  EXPECT_GT(polls, 7u);
  EXPECT_FALSE(wrongPlace);
  // Stopped at the first poll, or at one a good way in (how many polls a build makes varies a
  // little with the chunks the calling thread takes): Cancelled, no grid.
  for (std::size_t stopAt : {std::size_t{1}, polls / 4}) {
    std::size_t calls = 0;
    const CancelScope scope([&] { return ++calls >= stopAt; });
    EXPECT_THROW(AdaptiveGrid(sphere, options), Cancelled) << "stop at poll " << stopAt;
    EXPECT_EQ(calls, stopAt);
  }
  // A poll's own exception propagates unchanged.
  {
    const CancelScope scope([]() -> bool { throw std::logic_error("interrupted"); });
    EXPECT_THROW(AdaptiveGrid(sphere, options), std::logic_error);
  }
  // Moves never poll: a scope that would stop at once lets them finish.
  AdaptiveGrid moving(sphere, options);
  {
    std::size_t calls = 0;
    const CancelScope scope([&] { return ++calls > 0; });
    moving.moveBoundary(RigidTransform::translationBy({0.05, 0, 0}));
    EXPECT_EQ(calls, 0u);
  }
  expectRefinementRule(moving);
}

TEST(AdaptiveGrid, TouchingAndTinyBoundaries) {
  // A boundary whose faces lie on grid planes (vertices exactly on the surface, distance 0), and
  // one far smaller than the finest cell.
  const AdaptiveGrid box(QueryMesh(primitives::box({1, 1, 1})),
                         {.levels = 4, .domain = Aabb{{-1, -1, -1}, {1, 1, 1}}});
  std::size_t onSurface = 0;
  for (double d : box.distances())
    onSurface += d == 0.0;
  EXPECT_GT(onSurface, 0u);
  expectMatchesBruteForce(box, 1);
  expectRefinementRule(box);

  const AdaptiveGrid tiny(QueryMesh(primitives::icosphere(2, 1e-9, {0.3, 0.1, 0.2})),
                          {.levels = 6, .domain = Aabb{{-1, -1, -1}, {1, 1, 1}}});
  EXPECT_GT(tiny.leavesPerLevel()[6], 0u);
  expectMatchesBruteForce(tiny, 1);
  expectRefinementRule(tiny);
}

/// Vertex positions → distance, to compare grids whose vertices were made in different orders.
std::map<std::tuple<double, double, double>, double> fieldOf(const AdaptiveGrid& grid) {
  std::map<std::tuple<double, double, double>, double> field;
  for (std::uint32_t v = 0; v < grid.vertexCount(); ++v) {
    const Vec3 p = grid.position(v);
    field[{p.x, p.y, p.z}] = grid.distances()[v];
  }
  return field;
}

/// After moves, `moved` has exactly the cells of a grid made around the boundary where it is
/// now, the same distances (bit for bit) in the exact band, and elsewhere the same sign and a
/// distance within its error bound.
void expectSameAsNewGrid(const AdaptiveGrid& moved) {
  GridOptions options = moved.options();
  const AdaptiveGrid fresh(moved.boundary(), options);
  for (int level = 0; level <= moved.levels(); ++level) {
    const auto a = moved.cells(level), b = fresh.cells(level);
    ASSERT_EQ(a.size(), b.size()) << "level " << level;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].origin, b[i].origin);
      ASSERT_EQ(a[i].leaf(), b[i].leaf());
      for (int c = 0; c < 8; ++c)
        ASSERT_EQ(moved.position(a[i].corners[c]), fresh.position(b[i].corners[c]));
    }
  }
  ASSERT_EQ(moved.vertexCount(), fresh.vertexCount());
  const auto exact = fieldOf(fresh);
  const std::vector<double> bounds = moved.errorBounds();
  std::size_t stale = 0;
  for (std::uint32_t v = 0; v < moved.vertexCount(); ++v) {
    const Vec3 p = moved.position(v);
    const double want = exact.at({p.x, p.y, p.z}), got = moved.distances()[v];
    if (bounds[v] == 0.0) {
      ASSERT_EQ(got, want);
    } else {
      ++stale;
      ASSERT_GT(std::abs(got) - bounds[v], moved.exactBand());
      ASSERT_EQ(got < 0.0, want < 0.0);
      ASSERT_LE(std::abs(got - want), bounds[v]);
    }
  }
  if (std::isfinite(moved.exactBand())) {
    EXPECT_GT(stale, 0u);  // far vertices were left alone
  } else {
    EXPECT_EQ(stale, 0u);
  }
}

TEST(AdaptiveGrid, MovingBoundaryGivesTheGridOfItsNewPosition) {
  const QueryMesh fandisk(io::load(kMeshes / "fandisk.off"));
  // Under the sanitizers a level fewer (an eighth of the cells: it took 80 s at five levels).
  const int levels = test::kSlowBuild ? 4 : 5;
  for (std::optional<double> band : {std::optional<double>{}, std::optional<double>{0.0}}) {
    AdaptiveGrid grid(fandisk, {.levels = levels, .exactBand = band});
    // A time step's motion: about a fifth of the finest cell.
    const double h = grid.cellDiagonal(levels);
    const RigidTransform step =
        RigidTransform::translationBy(Vec3{0.5, 0.3, 0.1} * (0.2 * h)) *
        RigidTransform::rotationAbout(Quaternion::fromAxisAngle({0.2, 0.3, 1.0}, 0.2 * h),
                                      fandisk.bounds().center());
    GridStatistics total;
    std::size_t queries = 0;
    for (int t = 0; t < 6; ++t) {
      const GridStatistics& statistics = grid.moveBoundary(step);
      total += statistics;
      queries += statistics.queries;
      // Only what could have changed is asked again.
      EXPECT_LT(double(statistics.queries), double(grid.vertexCount()) * (band ? 0.35 : 0.6));
      EXPECT_GT(statistics.cellsCreated + statistics.cellsRemoved, 0u);
      // A new grid to compare with after every step; under the sanitizers (where each costs
      // seconds) after the first and the last, which still sees the five updates in between.
      if (!test::kSlowBuild || t == 0 || t == 5) expectSameAsNewGrid(grid);
    }
    EXPECT_EQ(total.queries, queries);
    EXPECT_GE(total.seconds, total.querySeconds);
    expectMatchesBruteForce(grid, 7);  // the moved boundary, in its own frame
    expectRefinementRule(grid);

    // Back where it started: the first grid again.
    grid.moveBoundaryTo(fandisk.pose());
    expectSameAsNewGrid(grid);
  }
}

/// Everything a grid answers, to compare a grid before and after a refused move.
struct GridSnapshot {
  std::vector<std::vector<std::tuple<std::array<std::uint32_t, 3>, bool>>> cells;
  std::vector<Vec3> positions;
  std::vector<double> distances, bounds;
  std::vector<double> pose;

  explicit GridSnapshot(const AdaptiveGrid& grid)
      : positions(grid.positions()),
        distances(grid.distances().begin(), grid.distances().end()),
        bounds(grid.errorBounds()) {
    for (int level = 0; level <= grid.levels(); ++level) {
      cells.emplace_back();
      for (const Cell& cell : grid.cells(level))
        cells.back().emplace_back(cell.origin, cell.leaf());
    }
    const RigidTransform& p = grid.boundary().pose();
    pose = {p.rotation.w,    p.rotation.x,    p.rotation.y,   p.rotation.z,
            p.translation.x, p.translation.y, p.translation.z};
  }
  bool operator==(const GridSnapshot&) const = default;
};

TEST(AdaptiveGrid, AMoveThatLeavesThePoseAsItIsQueriesNothing) {
  // It asked the band again (every vertex within the exact band: the same answers).
  const QueryMesh sphere(primitives::icosphere(3, 0.4));
  for (std::optional<double> band : {std::optional<double>{}, std::optional<double>{0.0}}) {
    AdaptiveGrid grid(sphere, {.levels = 5, .exactBand = band});
    grid.moveBoundary(RigidTransform::translationBy({1e-3, 0, 0}));
    const GridSnapshot before(grid);
    for (int how = 0; how < 2; ++how) {
      const GridStatistics& statistics = how == 0 ? grid.moveBoundary(RigidTransform{})
                                                  : grid.moveBoundaryTo(grid.boundary().pose());
      EXPECT_EQ(statistics.queries, 0u) << how;
      EXPECT_EQ(statistics.cellsCreated + statistics.cellsRemoved, 0u) << how;
      EXPECT_TRUE(GridSnapshot(grid) == before) << how;
    }
  }
}

TEST(AdaptiveGrid, AMoveBeyondTheCoordinateRangeIsRefusedAndChangesNothing) {
  // A move that puts the boundary, or the domain's points in the boundary's frame, beyond ±2²⁰⁰
  // was found out by the distance queries half-way through it: the grid was left with no cells,
  // the pose moved, and the next move read past the end of its levels (a crash from Python).
  const QueryMesh sphere(primitives::icosphere(1));
  AdaptiveGrid grid(sphere, {.levels = 3});
  grid.moveBoundary(RigidTransform::translationBy({0.05, 0.0, 0.0}));
  const GridSnapshot before(grid);
  ASSERT_GT(grid.leafCount(), 1u);
  for (const RigidTransform& far :
       {RigidTransform::translationBy({1e61, 0, 0}),
        RigidTransform::translationBy({0, -0x1p201, 0}),
        RigidTransform::rotationAbout(Quaternion::fromAxisAngle({0, 0, 1}, 1.0),
                                      {1e61, 1e61, 0})}) {
    EXPECT_THROW(grid.moveBoundary(far), Error);
    EXPECT_TRUE(GridSnapshot(grid) == before);
    EXPECT_THROW(grid.moveBoundaryTo(far), Error);
    EXPECT_TRUE(GridSnapshot(grid) == before);
  }
  try {
    grid.moveBoundaryTo(RigidTransform::translationBy({1e61, 0, 0}));
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("AdaptiveGrid: the boundary moved", 0), 0u) << e.what();
  }
  // The boundary within the range, but the domain's far corner carried beyond it.
  AdaptiveGrid wide(sphere,
                    {.levels = 2, .domain = Aabb{{-1e60, -1e60, -1e60}, {1e60, 1e60, 1e60}}});
  const GridSnapshot wideBefore(wide);
  try {
    wide.moveBoundary(RigidTransform::translationBy({1e60, 0, 0}));
    ADD_FAILURE() << "a move that carries the domain beyond the range was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the grid is unchanged"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(GridSnapshot(wide) == wideBefore);
  EXPECT_NO_THROW(wide.moveBoundary(RigidTransform::translationBy({1e59, 0, 0})));
  // And the grid goes on: the next moves give the grid of their pose.
  grid.moveBoundaryTo(RigidTransform::translationBy({-0.03, 0.02, 0.0}));
  expectSameAsNewGrid(grid);
  grid.moveBoundaryTo(RigidTransform{});
  expectSameAsNewGrid(grid);
  // Near the range, but within it, a move is taken: the boundary at 2¹⁹⁹, the domain's points
  // at −2¹⁹⁹ in its frame.
  EXPECT_NO_THROW(grid.moveBoundaryTo(RigidTransform::translationBy({0x1p199, 0, 0})));
  EXPECT_EQ(grid.boundary().pose().translation.x, 0x1p199);
}

TEST(AdaptiveGrid, InfiniteBandKeepsEveryDistanceExact) {
  const QueryMesh sphere(primitives::icosphere(3, 1.0));
  AdaptiveGrid grid(sphere, {.levels = 5, .exactBand = INFINITY});
  grid.moveBoundary(RigidTransform::translationBy({0.05, -0.02, 0.03}));
  EXPECT_EQ(grid.statistics().queries, grid.vertexCount());
  expectSameAsNewGrid(grid);
  // A boundary that leaves the domain: no cell refined around it, every sign outside.
  grid.moveBoundary(RigidTransform::translationBy({10, 0, 0}));
  expectSameAsNewGrid(grid);
  EXPECT_EQ(grid.leafCount(), 1u);
}

TEST(AdaptiveGrid, LongRunsForgetPosesNoVertexDatesFrom) {
  const QueryMesh sphere(primitives::icosphere(3, 1.0));
  AdaptiveGrid grid(sphere, {.levels = 3});
  EXPECT_EQ(grid.rememberedPoses(), 1u);
  const RigidTransform step =
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 1, 0}, 0.02), {0.3, 0, 0});
  for (int t = 0; t < 60; ++t)
    grid.moveBoundary(step);
  EXPECT_LT(grid.rememberedPoses(), 30u);
  expectSameAsNewGrid(grid);
}

TEST(AdaptiveGridThreads, AnswersDoNotDependOnTheThreadCount) {
  const QueryMesh fandisk(io::load(kMeshes / "fandisk.off"));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  AdaptiveGrid serial(fandisk, {.levels = 5});
  serial.moveBoundary(RigidTransform::translationBy({0.02, 0.0, -0.01}));
  omp_set_num_threads(2);
  AdaptiveGrid parallel(fandisk, {.levels = 5});
  parallel.moveBoundary(RigidTransform::translationBy({0.02, 0.0, -0.01}));
  omp_set_num_threads(threads);
  ASSERT_EQ(serial.vertexCount(), parallel.vertexCount());
  for (std::uint32_t v = 0; v < serial.vertexCount(); ++v) {
    ASSERT_EQ(serial.position(v), parallel.position(v));
    ASSERT_EQ(serial.distances()[v], parallel.distances()[v]);
  }
}

}  // namespace
}  // namespace delta::ib
