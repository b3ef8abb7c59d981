#include "delta/mesh/measures.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "delta/core/error.h"
#include "delta/core/format.h"

#include "detail/edges.h"
#include "detail/scaled_frame.h"

namespace delta {

bool isDegenerate(const Triangle& triangle) noexcept {
  Vec3 ab = triangle.b - triangle.a;
  Vec3 ac = triangle.c - triangle.a;
  if (!std::isfinite(maxAbs(ab)) || !std::isfinite(maxAbs(ac))) {
    // Edges longer than the largest double (corners at ±1e308): halved first, exactly for the
    // normal coordinates (a right triangle of legs 2e308 was degenerate: ∞ − ∞ in its cross
    // product).
    ab = triangle.b * 0.5 - triangle.a * 0.5;
    ac = triangle.c * 0.5 - triangle.a * 0.5;
  }
  const double size = std::fmax(maxAbs(ab), maxAbs(ac));
  if (!(size > 0.0)) return true;  // the three vertices coincide
  // Rescale by a power of two near 1/size (exact) so that neither L² nor the cross product can
  // under- or overflow: the answer then depends only on the triangle's shape.
  // (By ldexp: for a subnormal triangle the factor itself is beyond a double.)
  ab = ldexp(ab, -std::ilogb(size));
  ac = ldexp(ac, -std::ilogb(size));
  const Vec3 bc = ac - ab;
  const double longestSquared =
      std::fmax(lengthSquared(ab), std::fmax(lengthSquared(ac), lengthSquared(bc)));
  const double twiceAreaSquared = lengthSquared(cross(ab, ac));
  constexpr double kRelativeArea = 1e-12;
  return !(twiceAreaSquared > kRelativeArea * kRelativeArea * longestSquared * longestSquared);
}

std::size_t degenerateTriangleCount(const Mesh& mesh) noexcept {
  std::size_t count = 0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    if (isDegenerate(mesh.triangle(t))) ++count;
  return count;
}

double surfaceArea(const Mesh& mesh) {
  // Scaled as signedVolume: the cross products (degree 2) overflow from 1e154 on.
  const detail::ScaledFrame frame = detail::scaledFrame(detail::referencedBounds(mesh));
  double twiceArea = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    // b·s − a·s is (b − a)·s exactly (when nothing overflows): the edges keep their accuracy.
    const Triangle triangle = mesh.triangle(t);
    const Vec3 a = frame.scaled(triangle.a);
    twiceArea += length(cross(frame.scaled(triangle.b) - a, frame.scaled(triangle.c) - a));
  }
  return detail::scaledBack(twiceArea * 0.5, 2 * frame.exponent, "surfaceArea", "area");
}

EdgeLengths edgeLengths(const Mesh& mesh) {
  const std::vector<detail::DirectedEdge> edges = detail::sortedDirectedEdges(mesh);
  const std::span<const Vec3> vertices = mesh.vertices();
  // Measured scaled as surfaceArea (a length's square overflows from 1e154 on), then scaled back.
  const detail::ScaledFrame frame = detail::scaledFrame(detail::referencedBounds(mesh));
  EdgeLengths lengths;
  std::size_t distinct = 0;
  double sum = 0.0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (i > 0 && edges[i].key == edges[i - 1].key) continue;
    const double edgeLength =
        distance(frame.scaled(vertices[detail::edgeFirstVertex(edges[i].key)]),
                 frame.scaled(vertices[detail::edgeSecondVertex(edges[i].key)]));
    lengths.min = distinct == 0 ? edgeLength : std::min(lengths.min, edgeLength);
    lengths.max = std::max(lengths.max, edgeLength);
    sum += edgeLength;
    ++distinct;
  }
  if (distinct > 0) lengths.mean = sum / static_cast<double>(distinct);
  // The shortest may be below the normal doubles (an edge of 1e-310 is one): only an overflow,
  // an edge longer than the largest double, is refused.
  if (!std::isfinite(std::ldexp(lengths.max, frame.exponent)))
    throw Error("edgeLengths: the longest edge (" + toString(lengths.max) + " × 2^" +
                std::to_string(frame.exponent) + ") overflows a double");
  lengths.min = std::ldexp(lengths.min, frame.exponent);
  lengths.mean = std::ldexp(lengths.mean, frame.exponent);
  lengths.max = std::ldexp(lengths.max, frame.exponent);
  return lengths;
}

}  // namespace delta
