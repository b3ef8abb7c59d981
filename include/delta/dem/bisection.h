#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"

namespace delta::dem {

/// How the processes that share one decomposition combine what each of them counted; with MPI,
/// MPI_Allreduce in place with MPI_SUM on MPI_UINT64_T and MPI_MAX on MPI_DOUBLE. Each call is
/// collective: every process makes the same calls, in the same order, with spans of the same
/// size, and every process must get the same result back. An empty function (the default)
/// combines nothing: one process.
///
/// Threading: a value type; Bisection calls the functions on the thread that constructs it.
struct BisectionReduction {
  std::function<void(std::span<std::uint64_t>)> sum;  ///< each value → its sum over the processes
  std::function<void(std::span<double>)> maximum;     ///< each value → its maximum over them
};

}  // namespace delta::dem

namespace delta::detail {
class BisectionBuilder;
}  // namespace delta::detail

namespace delta::dem {

/// Recursive coordinate bisection (Berger and Bokhari 1987): all of space cut by axis-aligned
/// planes into `parts` boxes, its parts' regions, holding about equally many points. Made for a
/// domain decomposition: each process owns the particles whose centres lie in its part
/// (partOf) and sends ghosts to the parts within reach (partsWithin). The processes build it
/// together, each from its share of the points, combining counts through a BisectionReduction:
/// the class itself makes no MPI call.
///
/// The cuts. A node of the tree covers the parts [first, first + c) and N points (over all
/// processes); for c ≥ 2 it is cut along one axis at one value: the lower side (coordinate <
/// cut) gets the first ⌊c/2⌋ parts and T = N·⌊c/2⌋/c points, rounded to the nearest integer
/// (halves down); the upper side (coordinate ≥ cut: a point on a cut belongs to the upper side)
/// gets the rest.
/// - The axis is the longest extent of the bounding box of the node's points, the lowest axis
///   among equals.
/// - The cut lies midway between the T-th and the (T+1)-th smallest coordinate, so that exactly
///   T points lie below it. Where those two are equal (a run of duplicates across the boundary),
///   the lower side gets the count nearest T that a cut can give — the points below the run, or
///   those below and in it; below it where both are as near — and the cut lies midway between
///   the run and the nearest other coordinate on that side.
/// - A lower side that gets no point (T = 0, or duplicates) is given room where there is some:
///   the cut lies midway between the node's lowest coordinate and the node region's lower face
///   (clipped to the bounding box of all points), or on the lowest coordinate where they meet.
/// - A node with no points is cut at the middle of its region clipped to the bounding box of
///   all points, along its longest side.
///
/// So, with distinct coordinates along the cuts, every part gets ⌊N/parts⌋ or ⌈N/parts⌉ of all N
/// points, and exactly the counts that the rule above gives. Duplicates go to one side together:
/// points all equal end up in the last part, and the cuts through them leave some parts a region
/// of zero thickness (lower = upper on that axis, holding no point). With more parts than points
/// some parts hold none. With no points at all, the cuts halve the cube [−1, 1]³ as if it were
/// the points' box. The cuts depend only on the points, not on how they are shared among the
/// processes: every process builds bit for bit the same tree as one process given all points.
///
/// Collective calls, made level by level so that the nodes of a level share them. First one
/// `maximum` (the points' box, whether any point is not finite, and `parts`, so that the
/// processes check it together) and, with parts ≥ 2, one `sum` of the counts. Then each of the
/// ⌈log₂ parts⌉ levels of cuts costs at most 8 `sum` rounds of 256-bin histograms, which narrow
/// the 64-bit order of the doubles 8 bits a round down to the boundary between the T-th and
/// (T+1)-th coordinate of each node being cut, and one `maximum` of the boxes of the nodes it
/// makes, which puts the cuts midway and picks the next level's axes. No call carries more than
/// 2²⁰ values: a level of more than 4096 cuts needs more calls. Each round reads this process's
/// points of the nodes being cut once.
///
/// Threading: a built Bisection is immutable; its const functions may be called from any
/// number of threads at once.
class Bisection {
 public:
  /// The most parts a Bisection may have: 2²⁰.
  static constexpr int kMaxParts = 1 << 20;

  /// One part: all of space.
  Bisection();

  /// The bisection of the points — this process's share of them; empty is fine — into `parts`
  /// parts; `parts` must be the same on every process. Reads the points during construction
  /// only.
  ///
  /// Throws delta::Error when `parts` is not in [1, kMaxParts] (before any collective call), or
  /// a point is not finite, or the processes disagree on `parts`: these after the first
  /// collective call, on every process together (the process with a bad point names its index
  /// and value, the others say that another process has one), so that no process waits for
  /// the others in a call they never make.
  Bisection(std::span<const Vec3> points, int parts, const BisectionReduction& reduction = {});

  /// The same with a weight for each point (e.g. its share of the work): the rule above holds
  /// with every count read as a sum of weights, so the parts get about equal total weight. A
  /// cut cannot split a point: where the boundary falls inside one coordinate's weight, the
  /// lower side gets the sum nearest T that a cut gives (below, where both are as near), as for
  /// duplicates. Equal weights give the cuts of the unweighted call. Throws delta::Error as the
  /// unweighted call does, and also, on every process together, when a weight is 0 or the
  /// weights are not as many as the points.
  Bisection(std::span<const Vec3> points, std::span<const std::uint32_t> weights, int parts,
            const BisectionReduction& reduction = {});

  int parts() const noexcept { return static_cast<int>(regions_.size()); }

  /// The part whose region holds x: regions tile all of space, half-open (a point on a cut
  /// belongs to the upper side). A NaN coordinate counts as above every cut. O(log parts).
  int partOf(const Vec3& x) const noexcept;

  /// Every part whose region comes within `reach` of x: whose region(part) box, faces included,
  /// lies at a distance ≤ reach; in ascending order, written into `out` (cleared first). Always
  /// includes partOf(x). Visits only the nodes of the tree within reach. Throws delta::Error
  /// when x is not finite or reach is negative or NaN (reach = +∞ gives every part).
  void partsWithin(const Vec3& x, double reach, std::vector<int>& out) const;

  /// The region of `part` as a box: [lower, upper) on each axis, the outer faces at ±∞.
  /// Throws delta::Error when `part` is not in [0, parts()).
  Aabb region(int part) const;

 private:
  friend class detail::BisectionBuilder;

  /// A node of the tree. An inner node (axis 0, 1 or 2) sends coordinate < cut to node
  /// `child` and the rest to node `child + 1`; a leaf (axis = kLeaf) is part `child`.
  struct Node {
    static constexpr int kLeaf = -1;
    double cut = 0.0;
    int axis = kLeaf;
    int child = 0;
  };

  void collectWithin(int node, const Aabb& region, const Vec3& x, double reach,
                     std::vector<int>& out) const;

  std::vector<Node> nodes_;    ///< breadth first, the root first
  std::vector<Aabb> regions_;  ///< by part
};

}  // namespace delta::dem
