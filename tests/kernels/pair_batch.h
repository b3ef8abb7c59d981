#pragma once

// Triangle pairs as the batched solvers take them: two TriangleSoA of equal size, pair i being
// (first[i], second[i]); shared by the penalty, hybrid and dispatch tests.

#include <cstdint>
#include <utility>
#include <vector>

#include "delta/core/triangle.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::test {

/// The triangles as a mesh of disjoint triangles (3 vertices each, in order), flattened.
inline TriangleSoA flattenTriangles(const std::vector<Triangle>& triangles) {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> indices;
  vertices.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), {t.a, t.b, t.c});
    indices.push_back({base, base + 1, base + 2});
  }
  return TriangleSoA(Mesh(std::move(vertices), std::move(indices)));
}

struct PairBatch {
  std::vector<Triangle> first, second;
  TriangleSoA firstSoa, secondSoa;

  std::size_t size() const { return first.size(); }
};

inline PairBatch makeBatch(const std::vector<std::pair<Triangle, Triangle>>& pairs) {
  PairBatch batch;
  for (const auto& [a, b] : pairs) {
    batch.first.push_back(a);
    batch.second.push_back(b);
  }
  batch.firstSoa = flattenTriangles(batch.first);
  batch.secondSoa = flattenTriangles(batch.second);
  return batch;
}

}  // namespace delta::test
