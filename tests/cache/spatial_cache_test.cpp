#include "delta/cache/spatial_cache.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/triangle_soa.h"

#include "kernels/triangle_pairs.h"

namespace delta {
namespace {

using delta::test::scaledCount;

const std::filesystem::path kMeshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";

/// Uniform in [0, 1) from the generator's raw bits (the same on every platform).
double unit(std::mt19937_64& random) {
  return static_cast<double>(random() >> 11) * 0x1p-53;
}

/// The reference: every triangle in id order, a strictly smaller squared distance replaces the
/// best (so ties go to the smallest id).
CachedNearest byAllTriangles(const TriangleSoA& triangles, const Vec3& p) {
  CachedNearest best;
  best.distanceSquared = std::numeric_limits<double>::infinity();
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const kernels::PointTriangleResult r =
        kernels::closestPointOnTriangle(p, triangles.triangle(t));
    if (r.distanceSquared < best.distanceSquared) {
      best.distanceSquared = r.distanceSquared;
      best.triangle = t;
      best.closest = r;
    }
  }
  return best;
}

/// Exact triangle–box overlap (CGAL's exact predicates), the oracle for "every triangle that
/// overlaps a cell is a candidate". A zero-area triangle is the union of its edges.
bool overlapsExactly(const Triangle& triangle, const Aabb& box) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  const auto point = [](const Vec3& v) { return Kernel::Point_3(v.x, v.y, v.z); };
  const Kernel::Iso_cuboid_3 cuboid(point(box.lower), point(box.upper));
  const Kernel::Point_3 a = point(triangle.a), b = point(triangle.b), c = point(triangle.c);
  if (!CGAL::collinear(a, b, c)) return CGAL::do_intersect(Kernel::Triangle_3(a, b, c), cuboid);
  for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    if (from == to ? !cuboid.has_on_unbounded_side(from)
                   : CGAL::do_intersect(Kernel::Segment_3(from, to), cuboid))
      return true;
  }
  return false;
}

bool boxesOverlap(const Aabb& a, const Aabb& b) {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (a.lower[axis] > b.upper[axis] || b.lower[axis] > a.upper[axis]) return false;
  return true;
}

/// Points where a cache is put to the test: uniform in the root cube; near the surface (random
/// points of random triangles moved along the normal by 0, ±1e-9, ±1e-6, ±1e-3 and ±0.1 of the
/// mesh's size); exactly on vertices and on edge midpoints; the root's centre and corners. Only
/// points inside the root cube are kept.
std::vector<Vec3> probes(const Mesh& mesh, const Aabb& root, std::size_t count,
                         std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const Vec3 extent = root.extent();
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < count; ++i)
    points.push_back(root.lower + Vec3{extent.x * unit(random), extent.y * unit(random),
                                       extent.z * unit(random)});
  const Vec3 meshExtent = mesh.bounds().extent();
  const double size = std::max({meshExtent.x, meshExtent.y, meshExtent.z});
  const double nudges[] = {0.0, 1e-9, -1e-9, 1e-6, -1e-6, 1e-3, -1e-3, 0.1, -0.1};
  for (std::size_t i = 0; i < count; ++i) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    double u = unit(random), v = unit(random);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const Vec3 on = t.a + (t.b - t.a) * u + (t.c - t.a) * v;
    points.push_back(on + normalized(t.areaVector()) * (nudges[i % std::size(nudges)] * size));
  }
  for (std::size_t i = 0; i < count / 4; ++i) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    points.push_back(t.a);
    points.push_back((t.b + t.c) * 0.5);
  }
  points.push_back(root.center());
  for (std::size_t corner = 0; corner < 8; ++corner)
    points.push_back({corner & 1u ? root.upper.x : root.lower.x,
                      corner & 2u ? root.upper.y : root.lower.y,
                      corner & 4u ? root.upper.z : root.lower.z});
  std::erase_if(points, [&](const Vec3& p) { return !root.contains(p); });
  return points;
}

/// The corners and centres of the cells that hold `points` (points on the cells' faces, where a
/// query must pick one side).
std::vector<Vec3> cellCorners(const SpatialCache& cache, const std::vector<Vec3>& points,
                              std::size_t count) {
  std::vector<Vec3> corners;
  for (std::size_t i = 0; i < std::min(count, points.size()); ++i) {
    const SpatialCache::Leaf leaf = cache.leafAt(points[i]);
    corners.push_back(leaf.box.lower);
    corners.push_back(leaf.box.upper);
    corners.push_back(leaf.box.center());
  }
  return corners;
}

std::vector<CachedNearest> byAllTriangles(const TriangleSoA& triangles,
                                          const std::vector<Vec3>& points) {
  std::vector<CachedNearest> nearest;
  for (const Vec3& p : points)
    nearest.push_back(byAllTriangles(triangles, p));
  return nearest;
}

/// The invariants at every point: the cached nearest is bitwise the brute force's, the leaf
/// holds the point, its bounds hold the exact distance, its candidates are ascending and
/// include the nearest triangle.
void expectExact(const SpatialCache& cache, const std::vector<Vec3>& points,
                 const std::vector<CachedNearest>& byAll, const std::string& name) {
  ASSERT_EQ(points.size(), byAll.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const CachedNearest& expected = byAll[i];
    const CachedNearest found = nearestTriangle(cache, p);
    const std::string where = name + ", point " + std::to_string(i) + " " + toString(p);
    ASSERT_EQ(found.distanceSquared, expected.distanceSquared) << where;
    ASSERT_EQ(found.triangle, expected.triangle) << where;
    ASSERT_EQ(found.closest.closest, expected.closest.closest) << where;
    const SpatialCache::Leaf leaf = cache.leafAt(p);
    ASSERT_TRUE(leaf.box.contains(p)) << where;
    const double distance = std::sqrt(expected.distanceSquared);
    ASSERT_LE(leaf.lowerBound, distance) << where;
    ASSERT_GE(leaf.upperBound, distance) << where;
    ASSERT_TRUE(std::ranges::adjacent_find(leaf.candidates, std::greater_equal<>()) ==
                leaf.candidates.end())
        << where << ": candidates not strictly ascending";
    ASSERT_TRUE(std::ranges::binary_search(leaf.candidates, expected.triangle)) << where;
  }
}

/// Every triangle that overlaps the leaf of a point is one of its candidates. Returns how many
/// overlapping (leaf, triangle) pairs had no vertex of the triangle inside the leaf: the pairs the
/// seed's octree missed.
std::size_t expectOverlapsAreCandidates(const SpatialCache& cache, const Mesh& mesh,
                                        const std::vector<Vec3>& points, const std::string& name) {
  std::size_t withoutVertexInside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SpatialCache::Leaf leaf = cache.leafAt(points[i]);
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const Triangle triangle = mesh.triangle(t);
      if (!boxesOverlap(triangle.bounds(), leaf.box) || !overlapsExactly(triangle, leaf.box))
        continue;
      EXPECT_TRUE(std::ranges::binary_search(leaf.candidates, t))
          << name << ": triangle " << t << " overlaps the leaf of point " << i << " "
          << toString(points[i]) << " (depth " << leaf.depth << ") but is no candidate";
      if (!leaf.box.contains(triangle.a) && !leaf.box.contains(triangle.b) &&
          !leaf.box.contains(triangle.c))
        ++withoutVertexInside;
    }
  }
  return withoutVertexInside;
}

Mesh concatenated(const Mesh& first, const Mesh& second) {
  std::vector<Vec3> vertices(first.vertices().begin(), first.vertices().end());
  std::vector<TriangleIndices> triangles(first.triangles().begin(), first.triangles().end());
  const auto offset = static_cast<std::uint32_t>(vertices.size());
  vertices.insert(vertices.end(), second.vertices().begin(), second.vertices().end());
  for (TriangleIndices t : second.triangles())
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return Mesh(std::move(vertices), std::move(triangles));
}

struct NamedMesh {
  std::string name;
  Mesh mesh;
};

std::vector<NamedMesh> primitiveMeshes() {
  Mesh far = primitives::granulate(5, {1, 0.5, 0.2});
  far.translate({1e6, -1e6, 3e5});
  std::vector<NamedMesh> meshes;
  meshes.push_back({"icosphere", primitives::icosphere(3)});
  meshes.push_back({"box (ties on every face)", primitives::box({1, 2, 3}, {0.5, -1, 2})});
  meshes.push_back({"cylinder", primitives::cylinder(0.5, 2, 17)});
  meshes.push_back({"quad (open, flat)", primitives::quad(2, 1)});
  meshes.push_back({"granulate at 1e6", far});
  meshes.push_back({"tiny icosphere", primitives::icosphere(2, 1e-9, {1, 1, 1})});
  // A zero-area triangle, a needle, a repeated triangle and a point among ordinary ones.
  meshes.push_back(
      {"degenerate",
       Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1, 1e-300, 0}, {0.5, 0.5, 1}},
            {{0, 1, 2}, {0, 1, 3}, {1, 3, 4}, {0, 1, 2}, {2, 1, 5}, {4, 4, 4}})});
  meshes.push_back({"one point", Mesh({{1, 2, 3}}, {{0, 0, 0}})});
  return meshes;
}

TEST(SpatialCache, RootCubeAroundTheMeshBox) {
  const TriangleSoA triangles(primitives::box({1, 2, 4}, {10, 20, 30}));
  const SpatialCache cache(triangles);  // largest extent 4, margin 0.25: side 6
  EXPECT_EQ(cache.bounds().lower, (Vec3{7, 17, 27}));
  EXPECT_EQ(cache.bounds().upper, (Vec3{13, 23, 33}));
  EXPECT_EQ(cache.cellCount(), 1u);
  EXPECT_EQ(&cache.triangles(), &triangles);
  EXPECT_TRUE(cache.contains({7, 23, 30}));
  EXPECT_FALSE(cache.contains({6.999, 20, 30}));
  EXPECT_FALSE(cache.contains({10, 20, std::nan("")}));
  const SpatialCache wide(triangles, {.margin = 1.0});  // side 12
  EXPECT_EQ(wide.bounds().lower, (Vec3{4, 14, 24}));
  EXPECT_EQ(wide.options().margin, 1.0);
  const SpatialCache tight(triangles, {.margin = 0.0});
  EXPECT_EQ(tight.bounds().lower, (Vec3{8, 18, 28}));

  // Small enough not to be split: the root is the leaf; the box's 12 triangles all candidates.
  const SpatialCache::Leaf root = cache.leafAt({10, 20, 30});
  EXPECT_EQ(root.depth, 0);
  EXPECT_EQ(root.candidates.size(), 12u);
  EXPECT_EQ(root.lowerBound, 0.0);  // the centre is inside the box, 0.5 from its nearest face
  EXPECT_NEAR(root.upperBound, 0.5 + 3.0 * std::sqrt(3.0), 1e-10);

  const TriangleSoA point(Mesh({{1, 2, 3}}, {{0, 0, 0}}));  // no extent: side 1 · 1.5
  const SpatialCache pointCache(point);
  EXPECT_EQ(pointCache.bounds().lower, (Vec3{0.25, 1.25, 2.25}));
  EXPECT_EQ(pointCache.bounds().upper, (Vec3{1.75, 2.75, 3.75}));
}

TEST(SpatialCache, NearestIsTheBruteForceOnPrimitives) {
  for (const auto& [name, mesh] : primitiveMeshes()) {
    const TriangleSoA triangles(mesh);
    std::vector<Vec3> points = probes(mesh, SpatialCache(triangles).bounds(), scaledCount(400), 7);
    ASSERT_GT(points.size(), scaledCount(400)) << name;
    const std::vector<Vec3> corners =
        cellCorners(SpatialCache(triangles, {.maxCandidates = 4}), points, 50);
    points.insert(points.end(), corners.begin(), corners.end());
    const std::vector<CachedNearest> byAll = byAllTriangles(triangles, points);
    // Refined on demand by the queries, and a priori (where the tree stays small: with 4
    // candidates a leaf, cells around vertices of degree ≥ 5 go down to maxDepth).
    for (const CacheOptions& options :
         {CacheOptions{}, CacheOptions{.maxCandidates = 8, .maxDepth = 7},
          CacheOptions{.maxCandidates = 4}}) {
      expectExact(SpatialCache(triangles, options), points, byAll, name);
      if (options.maxCandidates >= 8)
        expectExact(buildCache(triangles, options), points, byAll, name + " (a priori)");
    }
  }
}

TEST(SpatialCache, NearestIsTheBruteForceOnRealMeshes) {
  for (const char* file : {"fandisk.off", "elephant.off", "cube-meshed.off"}) {
    const Mesh mesh = io::load(kMeshes / file);
    const TriangleSoA triangles(mesh);
    const SpatialCache cache(triangles);
    std::vector<Vec3> points = probes(mesh, cache.bounds(), scaledCount(300), 11);
    const std::vector<Vec3> corners = cellCorners(cache, points, 30);
    points.insert(points.end(), corners.begin(), corners.end());
    expectExact(cache, points, byAllTriangles(triangles, points), file);
    EXPECT_GT(cache.statistics().depth, 3) << file;  // the cache was refined, not just a root
  }
}

TEST(SpatialCache, EveryTriangleThatOverlapsALeafIsACandidate) {
  std::size_t withoutVertexInside = 0;
  for (const auto& [name, mesh] : primitiveMeshes()) {
    const TriangleSoA triangles(mesh);
    const SpatialCache cache(triangles, {.maxCandidates = 4});
    withoutVertexInside += expectOverlapsAreCandidates(
        cache, mesh, probes(mesh, cache.bounds(), scaledCount(100), 13), name);
  }
  for (const char* file : {"fandisk.off", "elephant.off"}) {
    const Mesh mesh = io::load(kMeshes / file);
    const TriangleSoA triangles(mesh);
    const SpatialCache cache(triangles);
    withoutVertexInside += expectOverlapsAreCandidates(
        cache, mesh, probes(mesh, cache.bounds(), scaledCount(100), 17), file);
  }
  EXPECT_GT(withoutVertexInside, 100u);  // the case the seed's vertex-in-cell rule missed
}

TEST(SpatialCache, LargeTriangleCrossingASmallCellIsACandidate) {
  // A large triangle in the plane z = 0 under a small sphere: the sphere's triangles make the
  // cells near it split, so points of the large triangle far from its vertices land in small
  // leaves that the triangle crosses with no vertex inside.
  const Mesh ground({{-100, -100, 0}, {100, -100, 0}, {0, 100, 0}}, {{0, 1, 2}});
  const Mesh mesh = concatenated(ground, primitives::icosphere(2, 1.0, {0, 0, 1.01}));
  const TriangleSoA triangles(mesh);
  const SpatialCache cache(triangles, {.maxCandidates = 8});
  std::mt19937_64 random(3);
  int smallLeaves = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 p{4 * unit(random) - 2, 4 * unit(random) - 2, 0.0};  // on the large triangle
    const SpatialCache::Leaf leaf = cache.leafAt(p);
    const Triangle large = mesh.triangle(0);
    ASSERT_FALSE(leaf.box.contains(large.a) || leaf.box.contains(large.b) ||
                 leaf.box.contains(large.c));
    ASSERT_TRUE(overlapsExactly(large, leaf.box));
    ASSERT_TRUE(std::ranges::binary_search(leaf.candidates, 0u))
        << "point " << toString(p) << ", leaf at depth " << leaf.depth;
    const CachedNearest nearest = nearestTriangle(cache, p);
    ASSERT_EQ(nearest.distanceSquared, 0.0);
    ASSERT_EQ(nearest.triangle, 0u);
    if (leaf.box.extent().x < 1.0) ++smallLeaves;  // 1/200 of the triangle's size
  }
  EXPECT_GT(smallLeaves, 100);
}

TEST(SpatialCache, OnDemandAndAprioriAreTheSameTree) {
  for (const char* file : {"fandisk.off", "elephant.off"}) {
    const Mesh mesh = io::load(kMeshes / file);
    const TriangleSoA triangles(mesh);
    const CacheOptions options{.maxCandidates = 24, .maxDepth = 7};
    const SpatialCache built = buildCache(triangles, options);
    const std::size_t builtCells = built.cellCount();
    const SpatialCache::Statistics statistics = built.statistics();
    EXPECT_EQ(statistics.cells, builtCells) << file;
    EXPECT_EQ(statistics.leaves, 1 + (builtCells - 1) / 8 * 7) << file;
    EXPECT_GT(statistics.depth, 4) << file;
    EXPECT_GT(built.memoryBytes(), builtCells * 64) << file;

    SpatialCache onDemand(triangles, options);
    const std::vector<Vec3> points = probes(mesh, built.bounds(), scaledCount(400), 19);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const SpatialCache::Leaf a = onDemand.leafAt(points[i]), b = built.leafAt(points[i]);
      ASSERT_EQ(a.box.lower, b.box.lower) << file << ", point " << i;
      ASSERT_EQ(a.box.upper, b.box.upper) << file << ", point " << i;
      ASSERT_EQ(a.depth, b.depth);
      ASSERT_EQ(a.lowerBound, b.lowerBound);
      ASSERT_EQ(a.upperBound, b.upperBound);
      ASSERT_TRUE(std::ranges::equal(a.candidates, b.candidates));
      // A priori, every leaf meets the criterion: few candidates, the deepest level, or away
      // from the surface (lowerBound > 0: such cells are not split).
      ASSERT_TRUE(b.candidates.size() <= options.maxCandidates || b.depth == options.maxDepth ||
                  b.lowerBound > 0.0)
          << file << ", point " << i << ": " << b.candidates.size() << " candidates at depth "
          << b.depth;
      const CachedNearest x = nearestTriangle(onDemand, points[i]),
                          y = nearestTriangle(built, points[i]);
      ASSERT_EQ(x.distanceSquared, y.distanceSquared);
      ASSERT_EQ(x.triangle, y.triangle);
    }
    EXPECT_EQ(built.cellCount(), builtCells) << file << ": a priori, queries refine nothing";
    EXPECT_LT(onDemand.cellCount(), builtCells) << file;  // only the visited cells
    onDemand.refineAll();
    EXPECT_EQ(onDemand.cellCount(), builtCells) << file;
  }
}

TEST(SpatialCache, ChildCandidatesAreASubsetOfTheParents) {
  // The tree with maxDepth k is the tree with maxDepth k + 1 cut at depth k (refinement is a
  // deterministic function of the cell): compare the leaves of both at the same points.
  const Mesh mesh = io::load(kMeshes / "elephant.off");
  const TriangleSoA triangles(mesh);
  const std::vector<Vec3> points =
      probes(mesh, SpatialCache(triangles).bounds(), scaledCount(300), 23);
  const double scale = SpatialCache(triangles).bounds().extent().x;
  std::size_t deeper = 0;
  for (int depth = 0; depth < 7; ++depth) {
    const SpatialCache coarse(triangles, {.maxDepth = depth}),
        fine(triangles, {.maxDepth = depth + 1});
    for (const Vec3& p : points) {
      const SpatialCache::Leaf parent = coarse.leafAt(p), child = fine.leafAt(p);
      if (child.depth == parent.depth) {
        ASSERT_TRUE(std::ranges::equal(child.candidates, parent.candidates));
        continue;
      }
      ++deeper;
      ASSERT_EQ(child.depth, parent.depth + 1);
      ASSERT_TRUE(parent.box.contains(child.box.lower) && parent.box.contains(child.box.upper));
      ASSERT_NEAR(child.box.extent().x * 2, parent.box.extent().x, 1e-12 * scale);
      ASSERT_TRUE(std::ranges::includes(parent.candidates, child.candidates)) << toString(p);
      // The bounds tighten (up to the rounding slack): L grows, U shrinks.
      ASSERT_LE(child.upperBound, parent.upperBound + 1e-9 * scale);
      ASSERT_GE(child.lowerBound, parent.lowerBound - 1e-9 * scale);
    }
  }
  EXPECT_GT(deeper, points.size());
}

TEST(SpatialCache, VetoAddsNoCellAndAnswersStayExact) {
  const Mesh mesh = io::load(kMeshes / "elephant.off");
  const TriangleSoA triangles(mesh);
  SpatialCache cache(triangles);
  const std::vector<Vec3> points = probes(mesh, cache.bounds(), scaledCount(200), 29);
  EXPECT_TRUE(cache.refinementAllowed());
  cache.allowRefinement(false);
  EXPECT_FALSE(cache.refinementAllowed());
  const std::vector<Vec3> few(points.begin(), points.begin() + 20);
  expectExact(cache, few, byAllTriangles(triangles, few),
              "vetoed root");  // the root's list: all triangles
  EXPECT_EQ(cache.cellCount(), 1u);
  EXPECT_EQ(cache.leafAt(points[0]).depth, 0);

  cache.allowRefinement(true);
  for (std::size_t i = 0; i < points.size(); i += 10)
    cache.leafAt(points[i]);  // refine around some points
  const std::size_t cells = cache.cellCount();
  EXPECT_GT(cells, 1u);
  cache.allowRefinement(false);
  expectExact(cache, points, byAllTriangles(triangles, points),
              "vetoed, partly refined");  // coarser leaves elsewhere
  EXPECT_EQ(cache.cellCount(), cells);
  for (const Vec3& p : points)
    beyond(cache, p, 1e-3);
  EXPECT_EQ(cache.cellCount(), cells);

  // refineAll is an explicit build: it ignores the veto (and leaves nothing to refine).
  cache.refineAll();
  const std::size_t built = cache.cellCount();
  EXPECT_GT(built, cells);
  cache.allowRefinement(true);
  for (const Vec3& p : points)
    cache.leafAt(p);
  EXPECT_EQ(cache.cellCount(), built);
}

TEST(SpatialCache, BeyondNeverClaimsACloserPoint) {
  std::vector<NamedMesh> meshes = primitiveMeshes();
  meshes.push_back({"elephant", io::load(kMeshes / "elephant.off")});
  for (const auto& [name, mesh] : meshes) {
    const TriangleSoA triangles(mesh);
    const SpatialCache cache(triangles);
    const std::vector<Vec3> points = probes(mesh, cache.bounds(), scaledCount(300), 31);
    const double size = cache.bounds().extent().x;
    std::size_t farPoints = 0, farAnswered = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double distance = std::sqrt(byAllTriangles(triangles, points[i]).distanceSquared);
      const std::string where = name + ", point " + std::to_string(i) + " " + toString(points[i]);
      const double epsilons[] = {0.0,
                                 1e-9 * size,
                                 1e-6 * size,
                                 1e-3 * size,
                                 1e-2 * size,
                                 0.1 * size,
                                 0.5 * size,
                                 distance,
                                 std::nextafter(distance, 0.0),
                                 std::nextafter(distance, INFINITY),
                                 2 * distance};
      for (const double epsilon : epsilons) {
        if (beyond(cache, points[i], epsilon)) {
          ASSERT_GE(distance, epsilon) << where << ", epsilon " << toString(epsilon);
        }
      }
      ASSERT_TRUE(beyond(cache, points[i], 0.0)) << where;  // nothing is closer than 0
      const double epsilon = 1e-2 * size;
      if (distance >= 4 * epsilon) {
        ++farPoints;
        farAnswered += beyond(cache, points[i], epsilon);
      }
    }
    if (name == "one point" || name == "tiny icosphere") continue;  // no point is "far" there
    EXPECT_GT(farPoints, 20u) << name;
    EXPECT_GE(farAnswered, farPoints * 9 / 10)
        << name << ": " << farAnswered << " of " << farPoints;
  }
}

/// Runs `query` from `threads` std::threads at once over the same points, each from its own
/// start, then from an OpenMP loop (parallelFor), on the cache `make()` returns, and checks
/// every answer against `expected`.
template <typename Prepare>
void expectExactFromManyThreads(const TriangleSoA& triangles, const std::vector<Vec3>& points,
                                const std::vector<CachedNearest>& expected, const Prepare& prepare,
                                const std::string& name) {
  constexpr std::size_t kThreads = 4;
  const auto same = [&](const std::vector<CachedNearest>& found, const std::string& how) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(found[i].distanceSquared, expected[i].distanceSquared) << name << how << i;
      ASSERT_EQ(found[i].triangle, expected[i].triangle) << name << how << i;
    }
  };
  {
    SpatialCache cache(triangles);
    prepare(cache);
    std::vector<std::vector<CachedNearest>> answers(kThreads,
                                                    std::vector<CachedNearest>(points.size()));
    std::vector<std::thread> callers;
    for (std::size_t thread = 0; thread < kThreads; ++thread)
      callers.emplace_back([&, thread] {
        for (std::size_t k = 0; k < points.size(); ++k) {
          const std::size_t i = (k + thread * points.size() / kThreads) % points.size();
          answers[thread][i] = nearestTriangle(cache, points[i]);
          if (!cache.leafAt(points[i]).box.contains(points[i])) answers[thread][i].triangle = ~0u;
        }
      });
    for (std::thread& caller : callers)
      caller.join();
    for (const auto& answer : answers)
      same(answer, ", std::thread, point ");
  }
  {
    SpatialCache cache(triangles);
    prepare(cache);
    const int threads = omp_get_max_threads();
    omp_set_num_threads(4);
    std::vector<CachedNearest> answer(points.size());
    parallelFor(0, points.size(), 4, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        answer[i] = nearestTriangle(cache, points[i]);
    });
    omp_set_num_threads(threads);
    same(answer, ", OpenMP, point ");
  }
}

TEST(SpatialCache, ManyThreadsRefineOneCacheAtOnce) {
  const Mesh mesh = io::load(kMeshes / "elephant.off");
  const TriangleSoA triangles(mesh);
  const std::vector<Vec3> points =
      probes(mesh, SpatialCache(triangles).bounds(), scaledCount(400), 37);
  const std::vector<CachedNearest> expected = byAllTriangles(triangles, points);

  // A fresh cache: every thread refines the cells it visits, racing the others.
  expectExactFromManyThreads(
      triangles, points, expected, [](SpatialCache&) {}, "on demand");

  // One thread builds the whole tree while three others query (and refine) it.
  SpatialCache cache(triangles);
  std::vector<std::thread> callers;
  callers.emplace_back([&] { cache.refineAll(); });
  std::vector<std::vector<CachedNearest>> answers(3);
  for (auto& answer : answers)
    callers.emplace_back([&] {
      for (const Vec3& p : points)
        answer.push_back(nearestTriangle(cache, p));
    });
  for (std::thread& caller : callers)
    caller.join();
  for (const auto& answer : answers)
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(answer[i].distanceSquared, expected[i].distanceSquared) << i;
      ASSERT_EQ(answer[i].triangle, expected[i].triangle) << i;
    }
  EXPECT_EQ(cache.cellCount(), buildCache(triangles).cellCount());
  EXPECT_EQ(cache.statistics().cells, cache.cellCount());
}

TEST(SpatialCache, ManyThreadsShareOneVetoedCache) {
  const Mesh mesh = io::load(kMeshes / "elephant.off");
  const TriangleSoA triangles(mesh);
  const std::vector<Vec3> points =
      probes(mesh, SpatialCache(triangles).bounds(), scaledCount(400), 41);
  const std::vector<CachedNearest> expected = byAllTriangles(triangles, points);
  // Partly refined, then vetoed: the threads only read, and get the same exact answers.
  std::size_t cells = 0;
  const auto partlyRefinedThenVetoed = [&](SpatialCache& cache) {
    for (std::size_t i = 0; i < points.size(); i += 7)
      cache.leafAt(points[i]);
    cache.allowRefinement(false);
    cells = cache.cellCount();
  };
  expectExactFromManyThreads(triangles, points, expected, partlyRefinedThenVetoed, "vetoed");
  SpatialCache check(triangles);
  partlyRefinedThenVetoed(check);
  for (const Vec3& p : points)
    nearestTriangle(check, p);
  EXPECT_EQ(check.cellCount(), cells);
}

TEST(SpatialCache, MovedCacheKeepsItsTree) {
  const TriangleSoA triangles(primitives::icosphere(3));
  SpatialCache cache(triangles);
  const Vec3 p{0.3, -0.2, 0.9};
  const SpatialCache::Leaf before = cache.leafAt(p);
  const std::size_t cells = cache.cellCount(), bytes = cache.memoryBytes();
  EXPECT_GT(cells, 1u);
  EXPECT_GT(bytes, triangles.size() * sizeof(Aabb));
  SpatialCache moved(std::move(cache));
  EXPECT_EQ(moved.cellCount(), cells);
  EXPECT_EQ(moved.memoryBytes(), bytes);
  const SpatialCache::Leaf after = moved.leafAt(p);
  EXPECT_EQ(after.candidates.data(), before.candidates.data());  // the same cell, not a copy
  SpatialCache assigned(triangles, {.maxDepth = 0});
  assigned = std::move(moved);
  EXPECT_EQ(assigned.leafAt(p).candidates.data(), before.candidates.data());
  EXPECT_EQ(nearestTriangle(assigned, p).triangle, byAllTriangles(triangles, p).triangle);
  // More cells, more bytes; the cell count and the census agree.
  assigned.refineAll();
  EXPECT_GT(assigned.cellCount(), cells);
  EXPECT_GT(assigned.memoryBytes(), bytes);
  EXPECT_EQ(assigned.statistics().cells, assigned.cellCount());
  EXPECT_EQ((assigned.cellCount() - 1) % 8, 0u);
}

TEST(SpatialCache, RejectsBadInput) {
  const TriangleSoA triangles(primitives::icosphere(1));
  EXPECT_THROW(SpatialCache{TriangleSoA{}}, Error);
  EXPECT_THROW(buildCache(TriangleSoA{}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.maxCandidates = 0}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.maxDepth = -1}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.maxDepth = 21}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.margin = -0.01}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.margin = std::nan("")}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.margin = INFINITY}), Error);
  EXPECT_THROW(SpatialCache(triangles, {.margin = 1e308}), Error);  // a root that is not finite
  try {
    (void)SpatialCache(triangles, {.maxDepth = 42});
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("maxDepth is 42"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(SpatialCache(triangles, {.maxCandidates = 1, .maxDepth = 0, .margin = 0}));
  EXPECT_NO_THROW(SpatialCache(triangles, {.maxDepth = 20}));

  const SpatialCache cache(triangles);
  const Vec3 outside{0, 0, 2};  // the root of the unit sphere reaches 1.5
  EXPECT_FALSE(cache.contains(outside));
  EXPECT_THROW(cache.leafAt(outside), Error);
  EXPECT_THROW(nearestTriangle(cache, outside), Error);
  EXPECT_THROW(beyond(cache, outside, 0.1), Error);
  EXPECT_THROW(cache.leafAt({0, std::nan(""), 0}), Error);
  try {
    cache.leafAt(outside);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("outside"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cache.cellCount(), 1u);
}

}  // namespace
}  // namespace delta
