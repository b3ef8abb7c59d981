// The exact point–triangle kernel in lanes (exact_lanes.h), written once and included once per
// ISA, inside a namespace that first defines, for that ISA: Lanes (kWidth doubles), Mask, and
// splat, load (aligned), store (aligned), fmadd, squareRoot, select (mask, yes, no), both (the
// lanes set in both masks), bits (lane i → bit i) and the ordered comparisons greaterOrEqual,
// greater, less, lessOrEqual and equal (false where a lane is NaN). No include guard: it is meant
// to be included once per ISA.

struct Vec {
  Lanes x, y, z;
};

[[gnu::always_inline]] inline Vec minus(const Vec& a, const Vec& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
[[gnu::always_inline]] inline Vec plus(const Vec& a, const Vec& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
[[gnu::always_inline]] inline Vec times(const Vec& a, const Lanes& s) {
  return {a.x * s, a.y * s, a.z * s};
}
[[gnu::always_inline]] inline Lanes dot(const Vec& a, const Vec& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
[[gnu::always_inline]] inline Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// Kahan's a·b − c·d (robust_geometry.h's differenceOfProducts).
[[gnu::always_inline]] inline Lanes differenceOfProducts(const Lanes& a, const Lanes& b,
                                                         const Lanes& c, const Lanes& d) {
  const Lanes cd = c * d;
  const Lanes roundingOfCd = fmadd(-c, d, cd);
  return fmadd(a, b, -cd) + roundingOfCd;
}
[[gnu::always_inline]] inline Vec select(Mask mask, const Vec& yes, const Vec& no) {
  return {select(mask, yes.x, no.x), select(mask, yes.y, no.y), select(mask, yes.z, no.z)};
}
/// robust_geometry.h's closestOnSegment, its squared distance: s0 + t·direction, t the clamped
/// projection parameter (0 for a zero-length segment), exactly s1 at t = 1.
[[gnu::always_inline]] inline Lanes segmentDistance(const Vec& p, const Vec& s0, const Vec& s1,
                                                    const Vec& direction) {
  const Lanes zero = splat(0.0), one = splat(1.0);
  const Lanes squaredLength = dot(direction, direction);
  const Mask long_ = greater(squaredLength, zero);
  // std::clamp(x, 0, 1): x < 0 ? 0 : 1 < x ? 1 : x.
  const Lanes x = dot(minus(p, s0), direction) / select(long_, squaredLength, one);
  Lanes t = select(less(x, zero), zero, select(less(one, x), one, x));
  t = select(long_, t, zero);
  const Vec point = select(equal(t, one), s1, plus(s0, times(direction, t)));
  const Vec offset = minus(p, point);
  return dot(offset, offset);
}

[[gnu::always_inline]] inline Lanes lengthSquared(const Vec& v) {
  return dot(v, v);
}

/// closestPointOnTriangle(point, mesh.triangle(sorted[i])).distanceSquared into out[i] for
/// i < count (1 to kWidth), in one register of lanes.
inline void distances(const QueryMeshData& mesh, const Vec3& point, const std::uint32_t* sorted,
                      std::size_t count, double* out) noexcept {
  // The lanes' triangles (the padding repeats the first: finite, and ignored).
  alignas(64) double corner[9][kWidth];
  for (std::size_t i = 0; i < kWidth; ++i) {
    const Triangle t = mesh.triangle(sorted[i < count ? i : 0]);
    const Vec3* vertices[3] = {&t.a, &t.b, &t.c};
    for (std::size_t v = 0; v < 3; ++v)
      for (std::size_t axis = 0; axis < 3; ++axis)
        corner[3 * v + axis][i] = (*vertices[v])[axis];
  }
  const Vec a{load(corner[0]), load(corner[1]), load(corner[2])};
  const Vec b{load(corner[3]), load(corner[4]), load(corner[5])};
  const Vec c{load(corner[6]), load(corner[7]), load(corner[8])};
  const Vec p{splat(point.x), splat(point.y), splat(point.z)};

  // closestPointOnTriangle: the frame of a.
  const Vec u = minus(b, a), v = minus(c, a), r = minus(p, a);
  const Lanes zero = splat(0.0);
  const Vec origin{zero, zero, zero};
  // makeLocalTriangle(0, u, v): the edges, the longest, the accurate normal, flatness.
  const Vec edge0 = minus(u, origin), edge1 = minus(v, u), edge2 = minus(origin, v);
  // std::max({…}) keeps the first of equals and skips what does not compare greater.
  Lanes longest = lengthSquared(edge0);
  longest = select(less(longest, lengthSquared(edge1)), lengthSquared(edge1), longest);
  longest = select(less(longest, lengthSquared(edge2)), lengthSquared(edge2), longest);
  const Vec u0 = minus(u, origin), v0 = minus(v, origin);  // accurateNormal's b − a, c − a
  const Vec plain = cross(u0, v0);
  const Mask wellConditioned =
      greaterOrEqual(lengthSquared(plain), splat(0.5) * lengthSquared(u0) * lengthSquared(v0));
  // The exact differences of b − 0 and c − 0 have zero low parts: accurateCross alone (plus
  // signed zeros).
  const Vec accurate{differenceOfProducts(u0.y, v0.z, u0.z, v0.y),
                     differenceOfProducts(u0.z, v0.x, u0.x, v0.z),
                     differenceOfProducts(u0.x, v0.y, u0.y, v0.x)};
  const Vec normal = select(wellConditioned, plain, accurate);
  const Lanes normalSquared = lengthSquared(normal);
  const Lanes flatBound = splat(4.0 * std::numeric_limits<double>::epsilon()) * longest;
  const Mask notFlat = greater(normalSquared, flatBound * flatBound);

  // closestOnLocalFace: the projection, where it lies inside all three edges by more than the
  // areas' rounding (insideLocalFace and faceAreaBound, in their operations).
  const auto magnitude = [&zero](const Lanes& x) { return select(less(x, zero), -x, x); };
  const auto sizeOf = [&magnitude](const Vec& x) {
    return (magnitude(x.x) + magnitude(x.y)) + magnitude(x.z);
  };
  const Lanes normalSize = sizeOf(normal), pointSize = sizeOf(r);
  const Lanes longestEdge = squareRoot(longest);
  // Each edge's area against its bound: beyond it (inside that edge's line), and not below
  // minus it (not surely outside: within the rounding of the line, or inside).
  struct Side {
    Mask inside, notOutside;
  };
  const auto side = [&](const Vec& edge, const Vec& w) {
    const Lanes area = dot(normal, cross(edge, w));
    const Lanes bound = splat(64.0 * std::numeric_limits<double>::epsilon()) * normalSize *
                        (sizeOf(edge) * (pointSize + longestEdge) + longestEdge * sizeOf(w));
    return Side{greater(area, bound), greaterOrEqual(area, -bound)};
  };
  const Vec ap = minus(r, origin);
  const Side side0 = side(edge0, ap), side1 = side(edge1, minus(r, u)),
             side2 = side(edge2, minus(r, v));
  const Mask inside = both(both(notFlat, side0.inside), both(side1.inside, side2.inside));
  // sideOfLocalFace's kNearEdge: the scalar kernel decides those lanes by exact signs.
  const unsigned nearEdge =
      bits(both(both(notFlat, side0.notOutside), both(side1.notOutside, side2.notOutside))) &
      ~bits(inside);
  const Lanes safeSquared = select(notFlat, normalSquared, splat(1.0));
  const Vec foot = minus(r, times(normal, dot(normal, ap) / safeSquared));
  const Lanes face = lengthSquared(minus(r, foot));

  // The nearest of the three edges (the first strictly smaller squared distance, as the scalar
  // loop takes it).
  Lanes edges = splat(std::numeric_limits<double>::infinity());
  for (const Lanes& distance :
       {segmentDistance(r, origin, u, edge0), segmentDistance(r, u, v, edge1),
        segmentDistance(r, v, origin, edge2)})
    edges = select(less(distance, edges), distance, edges);
  const Lanes squared = select(inside, face, edges);
  // The scalar kernel's exact boundary test (a point exactly on a vertex or an edge gets 0): it
  // runs where the square is positive and within kExactBoundaryCheck·L², the lanes that pass
  // take the scalar kernel's value (rare: a point within rounding of a triangle's boundary).
  // So do the lanes of a tiny triangle, which the scalar kernel solves scaled up, and those whose
  // projection lies within the areas' rounding of an edge's line (nearEdge).
  const unsigned nearBoundary =
      bits(both(greater(squared, zero),
                lessOrEqual(squared, splat(kernels::kExactBoundaryCheck) * longest))) |
      bits(less(longest, splat(kernels::kTinyTriangleSquared))) | nearEdge;
  alignas(64) double result[kWidth];
  store(result, squared);
  for (std::size_t i = 0; i < count; ++i)
    out[i] = nearBoundary >> i & 1
                 ? kernels::closestPointOnTriangle(point, mesh.triangle(sorted[i])).distanceSquared
                 : result[i];
}
