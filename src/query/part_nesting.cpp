#include "delta/query/part_nesting.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <span>
#include <tuple>

#include "delta/core/parallel.h"

#include "../kernels/detail/exact_predicates.h"
#include "../mesh/detail/union_find.h"
#include "detail/query_mesh_data.h"

namespace delta {
namespace {

/// Vertices of a part a ray may start from before the part is left undecided.
constexpr std::size_t kStartVertices = 32;

/// What placing a part found.
enum class Placement : std::uint8_t { wellOriented, misoriented, flat, undecided };

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
  std::vector<std::uint32_t> parent;
  detail::UnionFind<std::uint32_t> sets(parent);
  sets.reset(n);
  for (std::uint32_t k = 0; k < n; ++k)
    for (const std::uint32_t other : normals.across[k])
      if (other != detail::Pseudonormals::kNone) sets.join(k, other);
  Parts parts;
  parts.of.assign(n, 0);
  std::vector<std::uint32_t> index(n, std::numeric_limits<std::uint32_t>::max());
  parts.offsets.assign(1, 0);
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t root = sets.find(k);
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

}  // namespace

namespace detail {

std::optional<int> volumeSign(const QueryMeshData& mesh, std::span<const std::uint32_t> part) {
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
  // Summed with Neumaier's compensation: the sum's own error is 2ε of the sum and nε² of the
  // terms, where a plain sum's grew as nε of them (a closed slab of 643,200 triangles 1e-9 thick
  // went to the exact sum below).
  double sum = 0.0, compensation = 0.0, magnitude = 0.0;
  for (const std::uint32_t k : part) {
    const Triangle t = mesh.triangle(k);
    const Vec3 a = scaled(t.a), b = scaled(t.b), c = scaled(t.c);
    const double term = dot(a, cross(b, c)), next = sum + term;
    compensation += std::abs(sum) >= std::abs(term) ? (sum - next) + term : (term - next) + sum;
    sum = next;
    magnitude += length(a) * length(b) * length(c);
  }
  sum += compensation;
  // Each term rounds by a few ε of |a||b||c| (the differences included: 10ε at most), the
  // compensated sum by 2ε of itself and 2nε² of the terms: 16ε and 4nε² of the magnitudes,
  // and 4ε of the sum, are ample.
  const double n = static_cast<double>(part.size());
  const double bound = (0x1p-49 + 0x1p-104 * n) * magnitude + 0x1p-51 * std::abs(sum);
  if (sum > bound) return 1;
  if (-sum > bound) return -1;
  // In doubt (a thin part, or one of volume 0): the exact sum decides.
  detail::ExactTripleProductSum exact;
  for (const std::uint32_t k : part) {
    const Triangle t = mesh.triangle(k);
    if (!detail::predicatesExactAt(t.a) || !detail::predicatesExactAt(t.b) ||
        !detail::predicatesExactAt(t.c))
      return std::nullopt;
    exact.add(t.a, t.b, t.c);
  }
  return exact.sign();
}

}  // namespace detail

namespace {

/// Where part `p` stands: its orientation relative to the mesh's against the other parts'
/// winding number at the first of its vertices that an exact ray places.
Placement place(const detail::QueryMeshData& mesh, const Parts& parts, std::uint32_t p) {
  const std::span<const std::uint32_t> part = parts[p];
  // One part is the whole mesh, whose sign the QueryMesh found when it was prepared.
  const std::optional<int> own =
      parts.count() == 1 ? mesh.exactVolumeSign : detail::volumeSign(mesh, part);
  if (!own) return Placement::undecided;
  if (*own == 0) {
    // Flat, unless it has no area either (a fold (c, c, a) alone, whose edges pair with each
    // other): nothing of it has a side to name.
    // Exactly: a rounded cross product is 0 for a needle 2⁻¹⁰⁰ wide and not for three collinear
    // points. (Coordinates the exact predicates do not take count as area: flat.)
    const bool area = std::any_of(part.begin(), part.end(), [&mesh](std::uint32_t k) {
      const Triangle t = mesh.triangle(k);
      if (!detail::predicatesExactAt(t.a) || !detail::predicatesExactAt(t.b) ||
          !detail::predicatesExactAt(t.c))
        return true;
      return detail::exactCrossLeadingSign(t.a, t.b, t.a, t.c) != 0;
    });
    return area ? Placement::flat : Placement::wellOriented;
  }
  if (parts.count() == 1) return Placement::wellOriented;  // nothing to place it against
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
      const bool well = *own * orientation > 0 ? relative == 0 : relative == 1;
      return well ? Placement::wellOriented : Placement::misoriented;
    }
  return Placement::undecided;
}

/// Marks the pinched vertices of a closed mesh: those at the same coordinates as another, and
/// those whose triangles make more than one fan (walked across the edges that leave the vertex,
/// which a consistently oriented surface turns round it one way), or where a walk meets a
/// triangle that holds the vertex twice or an edge with no partner.
std::vector<bool> pinchedVertices(const detail::QueryMeshData& mesh) {
  const std::size_t n = mesh.vertices.size();
  std::vector<bool> pinched(n, false);
  std::vector<std::uint32_t> byPlace(n);
  std::iota(byPlace.begin(), byPlace.end(), std::uint32_t{0});
  const auto at = [&mesh](std::uint32_t v) {
    const Vec3& p = mesh.vertices[v];
    return std::tuple(p.x, p.y, p.z);
  };
  std::sort(byPlace.begin(), byPlace.end(),
            [&at](std::uint32_t a, std::uint32_t b) { return at(a) < at(b); });
  for (std::size_t i = 1; i < n; ++i)
    if (at(byPlace[i]) == at(byPlace[i - 1])) pinched[byPlace[i]] = pinched[byPlace[i - 1]] = true;
  // Each vertex's triangles, counted, and one of them (sorted index) to walk from.
  // (A triangle that names a vertex twice has no area and is no part of a fan: its edges pair
  // with each other.)
  std::vector<std::uint32_t> count(n, 0), start(n, 0);
  for (std::uint32_t k = 0; k < mesh.size(); ++k) {
    const TriangleIndices& c = mesh.corners[k];
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
    for (const std::uint32_t v : c) {
      ++count[v];
      start[v] = k;
    }
  }
  const detail::Pseudonormals& normals = mesh.pseudonormals();
  const auto slotOf = [&mesh](std::uint32_t k, std::uint32_t v) -> int {
    const TriangleIndices& c = mesh.corners[k];
    const int matches = (c[0] == v) + (c[1] == v) + (c[2] == v);
    if (matches != 1) return -1;
    return c[0] == v ? 0 : c[1] == v ? 1 : 2;
  };
  for (std::uint32_t v = 0; v < n; ++v) {
    if (pinched[v] || count[v] == 0) continue;
    std::uint32_t k = start[v], steps = 0;
    do {
      const int slot = slotOf(k, v);
      if (slot < 0 || ++steps > count[v]) break;
      k = normals.across[k][static_cast<std::size_t>(slot)];  // the edge leaving v
    } while (k != detail::Pseudonormals::kNone && k != start[v]);
    if (k != start[v] || steps != count[v]) pinched[v] = true;
  }
  return pinched;
}

PartNesting findPartNesting(const detail::QueryMeshData& mesh) {
  PartNesting result;
  if (!mesh.closed) return result;
  const Parts parts = partsOf(mesh);
  result.parts = parts.count();
  const std::vector<bool> pinched = pinchedVertices(mesh);
  result.pinchedTriangle = std::numeric_limits<std::uint32_t>::max();
  for (std::size_t v = 0; v < pinched.size(); ++v)
    result.pinched += pinched[v];
  if (result.pinched > 0)
    for (std::uint32_t k = 0; k < mesh.size(); ++k)
      for (const std::uint32_t v : mesh.corners[k])
        if (pinched[v]) result.pinchedTriangle = std::min(result.pinchedTriangle, mesh.order[k]);
  if (result.pinched == 0) result.pinchedTriangle = 0;
  std::vector<Placement> placed(parts.count(), Placement::wellOriented);
  parallelFor(0, parts.count(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p)
      placed[p] = place(mesh, parts, static_cast<std::uint32_t>(p));
  });
  for (std::size_t p = 0; p < parts.count(); ++p) {
    if (placed[p] == Placement::undecided) ++result.undecided;
    if (placed[p] == Placement::flat) ++result.flat;
    if (placed[p] != Placement::misoriented) continue;
    ++result.misoriented;
    std::uint32_t smallest = std::numeric_limits<std::uint32_t>::max();
    for (const std::uint32_t k : parts[p])
      smallest = std::min(smallest, mesh.order[k]);
    result.misorientedTriangles.push_back(smallest);
  }
  std::sort(result.misorientedTriangles.begin(), result.misorientedTriangles.end());
  if (result.misorientedTriangles.size() > PartNesting::kListed)
    result.misorientedTriangles.resize(PartNesting::kListed);
  return result;
}

}  // namespace

namespace detail {

const PartNesting& QueryMeshData::partNesting() const {
  std::call_once(partNestingOnce_, [this] { partNesting_ = findPartNesting(*this); });
  return partNesting_;
}

}  // namespace detail

const PartNesting& partNesting(const QueryMesh& mesh) {
  return mesh.data().partNesting();
}

bool boundsSolid(const QueryMesh& mesh) {
  return mesh.closed() && !selfIntersections(mesh).any() && partNesting(mesh).nested();
}

std::string describePartNesting(const PartNesting& nesting) {
  std::string text;
  const auto add = [&text](const std::string& clause) {
    text += (text.empty() ? "" : "; ") + clause;
  };
  const auto parts = [&nesting](std::size_t count) {
    return std::to_string(count) + " of its " + std::to_string(nesting.parts) +
           (count == 1 ? " parts is" : " parts are");
  };
  if (nesting.misoriented > 0)
    add(parts(nesting.misoriented) +
        " oriented against the parts around them (an inside-out part, or a shell inside a shell "
        "of the same orientation: the winding number is -1 or 2 there), such as the part of "
        "triangle " +
        std::to_string(nesting.misorientedTriangles.front()));
  if (nesting.pinched > 0)
    add("its surface meets itself at " + std::to_string(nesting.pinched) +
        (nesting.pinched == 1 ? " vertex" : " vertices") +
        " (parts touching at a vertex or sharing faces, or a vertex whose triangles make more "
        "than one fan), such as one of triangle " +
        std::to_string(nesting.pinchedTriangle));
  if (nesting.flat > 0)
    add(parts(nesting.flat) +
        " flat, enclosing no volume (such as a triangle stored twice, back to back: its faces' "
        "pseudonormals tie, and either side is named)");
  if (nesting.undecided > 0)
    add(parts(nesting.undecided) +
        " not placed exactly (every ray from its vertices met another part's edge or vertex, or a "
        "coordinate below 2^-250)");
  return text;
}

}  // namespace delta
