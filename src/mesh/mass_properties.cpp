#include "delta/mesh/mass_properties.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/mesh/topology.h"

#include "detail/scaled_frame.h"
#include "detail/vertex_parts.h"

namespace delta {
namespace {

/// Eberly's per-axis subexpressions for one triangle's coordinates w0, w1, w2 along an axis.
struct AxisTerms {
  double f1, f2, f3, g0, g1, g2;
};

constexpr AxisTerms axisTerms(double w0, double w1, double w2) noexcept {
  const double sum01 = w0 + w1;
  const double square0 = w0 * w0;
  const double partial = square0 + w1 * sum01;
  AxisTerms terms{};
  terms.f1 = sum01 + w2;
  terms.f2 = partial + w2 * terms.f1;
  terms.f3 = w0 * square0 + w1 * partial + w2 * terms.f2;
  terms.g0 = terms.f2 + w0 * (terms.f1 + w0);
  terms.g1 = terms.f2 + w1 * (terms.f1 + w1);
  terms.g2 = terms.f2 + w2 * (terms.f1 + w2);
  return terms;
}

/// The mesh's parts (its triangles joined through shared corners) and, per part, the centre of
/// its box, scaled as `frame` scales (frame.scaled, not relative to the frame's origin: a unit
/// tetrahedron beside a part 10⁵⁵ away lost its coordinates in that subtraction): each part's
/// terms are summed about its own centre. A closed mesh's parts are closed, so the integrals of
/// each do not depend on the point they are summed about; about one point for all, parts far
/// apart compared with their size summed terms of R²·L (R their distance from it) into a volume
/// of L³: two boxes 1×2×3 10¹² apart gave −67,108,860. For a mesh of one part the centre is the
/// frame's origin, and every operation is the one a sum about it takes.
struct Parts {
  std::vector<std::uint32_t> ofTriangle;
  std::vector<Vec3> centre;
  double cubedDiagonals = 0.0;  ///< Σ (a part's box diagonal)³, scaled: their volumes' scale
};

Parts partsOf(const Mesh& mesh, const detail::ScaledFrame& frame) {
  const std::span<const TriangleIndices> triangles = mesh.triangles();
  const detail::VertexParts joined = detail::vertexParts(mesh.vertexCount(), triangles);
  Parts parts;
  parts.ofTriangle.resize(triangles.size());
  std::vector<Aabb> boxes(joined.count);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::uint32_t part = joined.ofVertex[triangles[t][0]];
    parts.ofTriangle[t] = part;
    for (const std::uint32_t v : triangles[t])
      boxes[part].extend(frame.scaled(mesh.vertices()[v]));
  }
  for (const Aabb& box : boxes) {
    parts.centre.push_back(box.lower * 0.5 + box.upper * 0.5);
    const double diagonal = box.diagonal();
    parts.cubedDiagonals += diagonal * diagonal * diagonal;
  }
  return parts;
}

/// The integrals over the enclosed solid of 1, x, y, z, x², y², z², xy, yz, zx, in `frame`
/// (D. Eberly, "Polyhedral Mass Properties (Revisited)", 2002: the divergence theorem turns each
/// volume integral into a sum of closed-form triangle integrals), each part's about its centre
/// and then carried to the frame's origin (x = x' + c: ∫x = ∫x' + c·V, ∫xy = ∫x'y' + c_x∫y' +
/// c_y∫x' + c_x·c_y·V).
std::array<double, 10> volumeIntegrals(const Mesh& mesh, const detail::ScaledFrame& frame,
                                       const Parts& parts) {
  std::vector<std::array<double, 10>> ofPart(parts.centre.size(), std::array<double, 10>{});
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const Triangle triangle = mesh.triangle(t);
    std::array<double, 10>& integral = ofPart[parts.ofTriangle[t]];
    const Vec3& centre = parts.centre[parts.ofTriangle[t]];
    const Vec3 p0 = frame.scaled(triangle.a) - centre;
    const Vec3 p1 = frame.scaled(triangle.b) - centre;
    const Vec3 p2 = frame.scaled(triangle.c) - centre;
    const Vec3 n = cross(p1 - p0, p2 - p0);
    const AxisTerms x = axisTerms(p0.x, p1.x, p2.x);
    const AxisTerms y = axisTerms(p0.y, p1.y, p2.y);
    const AxisTerms z = axisTerms(p0.z, p1.z, p2.z);
    integral[0] += n.x * x.f1;
    integral[1] += n.x * x.f2;
    integral[2] += n.y * y.f2;
    integral[3] += n.z * z.f2;
    integral[4] += n.x * x.f3;
    integral[5] += n.y * y.f3;
    integral[6] += n.z * z.f3;
    integral[7] += n.x * (p0.y * x.g0 + p1.y * x.g1 + p2.y * x.g2);
    integral[8] += n.y * (p0.z * y.g0 + p1.z * y.g1 + p2.z * y.g2);
    integral[9] += n.z * (p0.x * z.g0 + p1.x * z.g1 + p2.x * z.g2);
  }
  constexpr std::array<double, 10> kScale = {1.0 / 6,  1.0 / 24, 1.0 / 24,  1.0 / 24,  1.0 / 60,
                                             1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  std::array<double, 10> total{};
  const Vec3 origin = frame.scaled(frame.origin);
  for (std::size_t part = 0; part < ofPart.size(); ++part) {
    std::array<double, 10>& i = ofPart[part];
    for (std::size_t k = 0; k < i.size(); ++k)
      i[k] *= kScale[k];
    const Vec3 c = parts.centre[part] - origin;
    const double v = i[0];
    total[0] += v;
    total[1] += i[1] + c.x * v;
    total[2] += i[2] + c.y * v;
    total[3] += i[3] + c.z * v;
    total[4] += i[4] + 2.0 * c.x * i[1] + c.x * c.x * v;
    total[5] += i[5] + 2.0 * c.y * i[2] + c.y * c.y * v;
    total[6] += i[6] + 2.0 * c.z * i[3] + c.z * c.z * v;
    total[7] += i[7] + c.x * i[2] + c.y * i[1] + c.x * c.y * v;
    total[8] += i[8] + c.y * i[3] + c.z * i[2] + c.y * c.z * v;
    total[9] += i[9] + c.z * i[1] + c.x * i[3] + c.z * c.x * v;
  }
  return total;
}

[[noreturn]] void fail(const std::string& what) {
  throw Error("massProperties: " + what);
}

}  // namespace

MassProperties massProperties(const Mesh& mesh, double density) {
  if (!(std::isfinite(density) && density > 0.0))
    fail("density " + toString(density) + " must be finite and positive");
  const Topology topology = analyzeTopology(mesh);
  if (!topology.closed)
    fail("the mesh is not closed (" + std::to_string(topology.boundaryEdges) + " boundary and " +
         std::to_string(topology.nonManifoldEdges) + " non-manifold edges)");
  if (!topology.consistentlyOriented)
    fail("the mesh is not consistently oriented (" + std::to_string(topology.misorientedEdges) +
         " edges traversed the same way by both their triangles)");

  const Aabb box = detail::referencedBounds(mesh);
  const detail::ScaledFrame frame = detail::scaledFrame(box);
  const Parts parts = partsOf(mesh, frame);
  const std::array<double, 10> integral = volumeIntegrals(mesh, frame, parts);
  const double volume = integral[0];
  // Zero relative to the parts' sizes: rounding alone makes a flat closed part's volume of order
  // 1e-16 · its diagonal³ (in the scaled frame). Not the whole box's: two boxes 10¹² apart were
  // refused as enclosing nothing.
  const double zeroVolume = 1e-12 * parts.cubedDiagonals;
  if (volume < -zeroVolume)
    fail("the mesh is inside-out (signed volume " +
         toString(std::ldexp(volume, 3 * frame.exponent)) + "); reverse its triangles");
  if (!(volume > zeroVolume))
    fail("the mesh encloses zero volume (" + toString(std::ldexp(volume, 3 * frame.exponent)) +
         ")");

  // Centroid in the scaled frame, then the second moments moved from its origin to it.
  const Vec3 c = Vec3{integral[1], integral[2], integral[3]} / volume;
  const double xx = integral[4] - volume * c.x * c.x;
  const double yy = integral[5] - volume * c.y * c.y;
  const double zz = integral[6] - volume * c.z * c.z;
  const double xy = integral[7] - volume * c.x * c.y;
  const double yz = integral[8] - volume * c.y * c.z;
  const double zx = integral[9] - volume * c.z * c.x;

  // Back to the mesh's scale: a volume scales by 2^3e, the second moments by 2^5e. The density
  // multiplies the scaled values first (it may itself be large or small) and is checked with
  // them.
  const int e = frame.exponent;
  const auto back = [](double value, int exponent, const char* what) {
    return detail::scaledBack(value, exponent, "massProperties", what);
  };
  MassProperties properties;
  properties.volume = back(volume, 3 * e, "volume");
  properties.mass = back(density * volume, 3 * e, "mass");
  properties.centroid =
      frame.origin + Vec3{std::ldexp(c.x, e), std::ldexp(c.y, e), std::ldexp(c.z, e)};
  const double moments[6] = {yy + zz, zz + xx, xx + yy, -xy, -yz, -zx};
  double inertia[6];
  for (std::size_t i = 0; i < 6; ++i)
    inertia[i] = moments[i] == 0.0 ? 0.0 : back(moments[i] * density, 5 * e, "inertia tensor");
  properties.inertia =
      Mat3::fromRows({inertia[0], inertia[3], inertia[5]}, {inertia[3], inertia[1], inertia[4]},
                     {inertia[5], inertia[4], inertia[2]});
  return properties;
}

double signedVolume(const Mesh& mesh) {
  // Each part relative to its box's centre (partsOf): the tetrahedra to it then stay as small as
  // the part, and so does the rounding of their sum; scaled to about 1 (detail::ScaledFrame), so
  // that no product of degree 3 under- or overflows whatever the mesh's size.
  const detail::ScaledFrame frame = detail::scaledFrame(detail::referencedBounds(mesh));
  const Parts parts = partsOf(mesh, frame);
  std::vector<double> sixTimesVolume(parts.centre.size(), 0.0);
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const Triangle triangle = mesh.triangle(t);
    const Vec3& centre = parts.centre[parts.ofTriangle[t]];
    sixTimesVolume[parts.ofTriangle[t]] +=
        dot(frame.scaled(triangle.a) - centre,
            cross(frame.scaled(triangle.b) - centre, frame.scaled(triangle.c) - centre));
  }
  double sum = 0.0;
  for (const double part : sixTimesVolume)
    sum += part;
  return detail::scaledBack(sum / 6.0, 3 * frame.exponent, "signedVolume", "volume");
}

}  // namespace delta
