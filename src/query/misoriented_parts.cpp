#include "delta/query/misoriented_parts.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <span>

#include "delta/core/parallel.h"

#include "detail/query_mesh_data.h"

namespace delta {
namespace {

/// Vertices of a part a ray may start from before the part is left undecided.
constexpr std::size_t kStartVertices = 32;

/// What placing a part found.
enum class Placement : std::uint8_t { wellOriented, misoriented, undecided };

/// The parts of a closed mesh: its sorted triangles joined across edges (Pseudonormals::across),
/// grouped: part p has triangles[offsets[p], offsets[p + 1]), ascending, and `of` names each
/// triangle's part.
struct Parts {
  std::vector<std::uint32_t> of;
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> triangles;
  std::size_t count() const noexcept { return offsets.size() - 1; }
  std::span<const std::uint32_t> operator[](std::size_t p) const noexcept {
    return {triangles.data() + offsets[p], triangles.data() + offsets[p + 1]};
  }
};

Parts partsOf(const detail::QueryMeshData& mesh) {
  const std::size_t n = mesh.size();
  const detail::Pseudonormals& normals = mesh.pseudonormals();
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), std::uint32_t{0});
  const auto find = [&parent](std::uint32_t k) {
    while (parent[k] != k)
      k = parent[k] = parent[parent[k]];
    return k;
  };
  for (std::uint32_t k = 0; k < n; ++k)
    for (const std::uint32_t other : normals.across[k])
      if (other != detail::Pseudonormals::kNone) {
        const std::uint32_t a = find(k), b = find(other);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
  Parts parts;
  parts.of.assign(n, 0);
  std::vector<std::uint32_t> index(n, std::numeric_limits<std::uint32_t>::max());
  parts.offsets.assign(1, 0);
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t root = find(k);
    if (index[root] == std::numeric_limits<std::uint32_t>::max()) {
      index[root] = static_cast<std::uint32_t>(parts.offsets.size() - 1);
      parts.offsets.push_back(0);
    }
    parts.of[k] = index[root];
    ++parts.offsets[index[root] + 1];
  }
  std::partial_sum(parts.offsets.begin(), parts.offsets.end(), parts.offsets.begin());
  parts.triangles.resize(n);
  std::vector<std::uint32_t> fill(parts.offsets.begin(), parts.offsets.end() - 1);
  for (std::uint32_t k = 0; k < n; ++k)
    parts.triangles[fill[parts.of[k]]++] = k;
  return parts;
}

/// The sign of the volume a closed part encloses (+1 for an outward part): its signed volume
/// about its box's centre, scaled by a power of two to about 1 (exact), where it exceeds a bound
/// on the sum's rounding; 0 within it.
int orientationOf(const detail::QueryMeshData& mesh, std::span<const std::uint32_t> part) {
  Aabb box;
  for (const std::uint32_t k : part)
    for (const std::uint32_t v : mesh.corners[k])
      box.extend(mesh.vertices[v]);
  const double extent = maxAbs(box.extent());
  if (!(extent > 0.0)) return 0;
  const Vec3 centre = box.center();
  const int shift = -std::ilogb(extent);
  const auto scaled = [&centre, shift](const Vec3& v) {
    const Vec3 d = v - centre;
    return Vec3{std::ldexp(d.x, shift), std::ldexp(d.y, shift), std::ldexp(d.z, shift)};
  };
  double sum = 0.0, magnitude = 0.0;
  for (const std::uint32_t k : part) {
    const Triangle t = mesh.triangle(k);
    const Vec3 a = scaled(t.a), b = scaled(t.b), c = scaled(t.c);
    sum += dot(a, cross(b, c));
    magnitude += length(a) * length(b) * length(c);
  }
  // Each term rounds by a few ε of |a||b||c| (the differences included), the sum by n ε of the
  // terms: 4ε (n + 16) of their magnitudes is ample.
  const double bound = 0x1p-50 * (static_cast<double>(part.size()) + 16.0) * magnitude;
  if (sum > bound) return 1;
  if (-sum > bound) return -1;
  return 0;
}

/// Where part `p` stands: its orientation relative to the mesh's against the other parts'
/// winding number at the first of its vertices that an exact ray places.
Placement place(const detail::QueryMeshData& mesh, const Parts& parts, std::uint32_t p) {
  const std::span<const std::uint32_t> part = parts[p];
  const int own = orientationOf(mesh, part);
  if (own == 0) return Placement::wellOriented;  // encloses nothing
  const int orientation = mesh.orientation < 0.0 ? -1 : 1;
  std::vector<std::uint32_t> tried;
  for (const std::uint32_t k : part)
    for (const std::uint32_t v : mesh.corners[k]) {
      if (std::find(tried.begin(), tried.end(), v) != tried.end()) continue;
      if (tried.size() == kStartVertices) return Placement::undecided;
      tried.push_back(v);
      const std::optional<int> around =
          detail::windingOfOtherParts(mesh, mesh.vertices[v], parts.of, p);
      if (!around) continue;
      // An outward part (relative to the mesh) must stand where the others' winding is 0, an
      // inward one where it is 1.
      const int relative = *around * orientation;
      const bool well = own * orientation > 0 ? relative == 0 : relative == 1;
      return well ? Placement::wellOriented : Placement::misoriented;
    }
  return Placement::undecided;
}

MisorientedParts findMisorientedParts(const detail::QueryMeshData& mesh) {
  MisorientedParts result;
  if (!mesh.closed) return result;
  const Parts parts = partsOf(mesh);
  result.parts = parts.count();
  if (result.parts < 2) return result;  // a single closed part bounds a solid
  std::vector<Placement> placed(parts.count(), Placement::wellOriented);
  parallelFor(0, parts.count(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p)
      placed[p] = place(mesh, parts, static_cast<std::uint32_t>(p));
  });
  for (std::size_t p = 0; p < parts.count(); ++p) {
    if (placed[p] == Placement::undecided) ++result.undecided;
    if (placed[p] != Placement::misoriented) continue;
    ++result.count;
    std::uint32_t smallest = std::numeric_limits<std::uint32_t>::max();
    for (const std::uint32_t k : parts[p])
      smallest = std::min(smallest, mesh.order[k]);
    result.triangles.push_back(smallest);
  }
  std::sort(result.triangles.begin(), result.triangles.end());
  if (result.triangles.size() > MisorientedParts::kListedParts)
    result.triangles.resize(MisorientedParts::kListedParts);
  return result;
}

}  // namespace

namespace detail {

const MisorientedParts& QueryMeshData::misorientedParts() const {
  std::call_once(misorientedPartsOnce_,
                 [this] { misorientedParts_ = findMisorientedParts(*this); });
  return misorientedParts_;
}

}  // namespace detail

const MisorientedParts& misorientedParts(const QueryMesh& mesh) {
  return mesh.data().misorientedParts();
}

bool boundsSolid(const QueryMesh& mesh) {
  return mesh.closed() && !selfIntersections(mesh).any() && !misorientedParts(mesh).any();
}

std::string describeMisorientedParts(const MisorientedParts& parts) {
  if (!parts.any()) return {};
  std::string text = std::to_string(parts.count) + " of its " + std::to_string(parts.parts) +
                     (parts.count == 1 ? " parts is" : " parts are") +
                     " oriented against the parts around them (an inside-out part, or a shell "
                     "inside a shell of the same orientation: the winding number is -1 or 2 "
                     "there), such as the part of triangle " +
                     std::to_string(parts.triangles.front());
  return text;
}

}  // namespace delta
