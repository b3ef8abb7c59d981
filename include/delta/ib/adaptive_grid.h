#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/rotation.h"
#include "delta/core/vec3.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

/// Immersed boundaries: an adaptive Cartesian grid refined around a boundary mesh, with the
/// boundary's (signed) distance at every grid vertex.
namespace delta::ib {

/// How an AdaptiveGrid is made. Checked when a grid is made (delta::Error naming the field).
///
/// Threading: a value type; no shared state.
struct GridOptions {
  /// The finest level L (the root cell is level 0; a level-l cell is 2^−l of the domain per
  /// axis). 1 ≤ L ≤ 20.
  int levels = 7;
  /// A cell of level l < L is refined while the smallest |distance| at its eight corners is below
  /// refineFactor × its diagonal. Every point of a cell lies within half a diagonal of a corner,
  /// so any factor above ½ refines every cell the boundary passes through (at exactly ½ a
  /// boundary point at the cell's centre, half a diagonal from every corner, is not below it).
  /// > 0, finite.
  double refineFactor = 1.0;
  /// Signed distances (negative inside; with Sign::pseudonormal the boundary must be closed and
  /// not cross itself, delta::Error otherwise) or unsigned.
  bool signedDistance = true;
  /// How signed distances decide inside (contactdetection::Sign): by pseudonormals (the
  /// default), or by the generalized winding number, which takes open and self-intersecting
  /// boundaries (CAD and scanned meshes with holes). A winding sign can change away from the
  /// surface when such a boundary moves (across a hole), so after a move every vertex is queried
  /// again there (as with exactBand = +∞); on a closed boundary that does not cross itself the
  /// winding sign is the pseudonormal sign and nothing changes.
  contactdetection::Sign sign = contactdetection::Sign::pseudonormal;
  /// The domain the root cell covers: finite, with lower < upper on every axis (delta::Error
  /// otherwise; an inverted box is refused, not replaced). None (the default): the boundary's
  /// box where it is when the grid is made, made a cube about its centre and grown by `padding` ×
  /// its longest side on every side. The domain stays where it is when the boundary moves.
  std::optional<Aabb> domain{};
  /// See `domain`. ≥ 0, finite.
  double padding = 0.1;
  /// After a move, vertices whose |distance| is at most this hold the exact distance to the
  /// boundary where it is now; further vertices keep their sign (exact) and a distance within
  /// errorBound() of the exact one, and are queried again only once that bound could bring them
  /// into the band or change a refinement decision. None (the default): the diagonal of a
  /// level-L cell, so that every corner of every cell the boundary passes through is exact where
  /// refineFactor is above ½ (such cells are then of level L; with a smaller factor a coarser
  /// cell the boundary passes through may keep corners outside the band).
  /// 0: only what refinement needs. +∞: every vertex exact after every move. ≥ 0 (NaN and
  /// negative values: delta::Error).
  std::optional<double> exactBand{};
};

/// One cell of the grid: a box of the octree, at `level`, whose lower corner is `origin` in
/// units of the finest cell (so its side is 2^(L − level) units), with its eight corner vertices
/// in VTK's voxel order (corner c has offset (c & 1, (c >> 1) & 1, (c >> 2) & 1)).
///
/// Threading: a value type; no shared state.
struct Cell {
  std::array<std::uint32_t, 3> origin{};
  std::array<std::uint32_t, 8> corners{};
  std::uint32_t firstChild = kLeaf;  ///< index of its first child in the next level (8 in a row)
  std::uint8_t level = 0;

  static constexpr std::uint32_t kLeaf = std::numeric_limits<std::uint32_t>::max();
  bool leaf() const noexcept { return firstChild == kLeaf; }
};

/// What one build or move did.
///
/// Threading: a value type; no shared state.
struct GridStatistics {
  std::size_t queries = 0;       ///< vertices whose distance was computed
  std::size_t cellsCreated = 0;  ///< cells made (every cell, at a build)
  std::size_t cellsRemoved = 0;  ///< cells coarsened away
  double querySeconds = 0.0;     ///< time inside Δ's distance queries
  double seconds = 0.0;          ///< the whole build or move

  /// Adds another build's or move's figures to these (totals over a run).
  GridStatistics& operator+=(const GridStatistics& other) noexcept {
    queries += other.queries;
    cellsCreated += other.cellsCreated;
    cellsRemoved += other.cellsRemoved;
    querySeconds += other.querySeconds;
    seconds += other.seconds;
    return *this;
  }
};

/// An octree Cartesian grid over a fixed box (GridOptions::domain), refined around a boundary
/// mesh: a cell is refined while its corners come closer to the boundary than refineFactor × its
/// diagonal, down to level L. Every grid vertex (every corner of every cell; vertices of
/// neighbouring cells of different levels are shared where they coincide, and a finer cell's
/// corner on a coarser neighbour's face is a vertex of the finer cell only) holds the boundary's
/// distance, signed when asked. The grid is built level by level, and each level's new vertices
/// are answered in one batch by contactdetection::distances (in parallel, nearest-first, exact).
///
/// The boundary can move rigidly (moveBoundary / moveBoundaryTo): the grid then refines toward
/// its new position and coarsens away from the old, and only what could have changed is queried
/// again. Each vertex remembers the pose the boundary had when it was queried; the motion since
/// bounds how far its distance can have changed (the largest displacement of the boundary's box,
/// exact for a rigid motion, which is affine). A vertex is queried again when that bound leaves
/// a refinement decision in doubt or could bring it into the exact band; new vertices always are.
/// After every move the cells are exactly those a new grid around the moved boundary would have,
/// and every distance in the band is the one it would have (bit for bit). The prepared boundary
/// (its QueryMesh, tree included) is moved in O(1), never rebuilt.
///
/// Throws delta::Error for bad options (naming the field), for a default domain around a
/// boundary whose vertices all coincide (the domain would have no extent), and for
/// `signedDistance` by pseudonormals with a boundary that is not closed (the message says how it
/// is open and that unsigned distances and the winding sign work) or that crosses itself, and for a
/// grid that would not fit: before each level of a build is made, the cells it leads to are
/// estimated from the cells refined so far (each finer level about 4 times more) and refused, with
/// the estimate and the limit, beyond 32-bit cell indices or the memory limit (core/memory.h; about
/// 200 bytes a cell). Degenerate triangles are part of the boundary like any other. Only the domain
/// is gridded: a boundary that moves (partly) out of it is simply not resolved there.
///
/// Cancellation (core/cancel.h): a build made in a CancelScope polls it between batches of cells
/// and of queries (some tens of milliseconds of work each), on the calling thread; when the poll
/// asks to stop, the constructor throws Cancelled (or what the poll throws) and no grid is made.
/// Moves never poll (they run to the end: a move stopped half-way would leave a grid that is
/// neither before nor after it).
///
/// Threading: building and moving query in parallel (core/parallel.h); one thread may move a
/// grid while no other uses it; const members may be called from any number of threads.
class AdaptiveGrid {
 public:
  /// Builds the grid around `boundary` where it is now (the QueryMesh is copied: it shares the
  /// prepared data, and the caller's copy does not move with the grid's). Throws delta::Error
  /// for bad options (see the class), Cancelled when a CancelScope stops it.
  AdaptiveGrid(const QueryMesh& boundary, const GridOptions& options = {});

  /// Moves the boundary by `motion` (its pose becomes motion ∘ pose) and updates the grid.
  /// Throws delta::Error, changing nothing, for a motion QueryMesh::transform refuses and for one
  /// that would put the boundary, or carry a point of the domain into the boundary's frame,
  /// beyond the coordinate range the distance queries answer (mesh/coordinate_range.h; within
  /// 2⁻⁴⁰ of it, for the rounding). Should anything else stop a move half-way (memory), the grid
  /// is made anew at the pose before it (a fresh build there) and the error passed on. The
  /// statistics returned are those of statistics(), valid until the next move. A motion that
  /// leaves the pose as it is (the identity) changes nothing and queries nothing.
  const GridStatistics& moveBoundary(const RigidTransform& motion);
  /// Puts the boundary at `pose` (from the frame its QueryMesh was prepared in) and updates.
  /// Throws as moveBoundary.
  const GridStatistics& moveBoundaryTo(const RigidTransform& pose);

  const QueryMesh& boundary() const noexcept { return boundary_; }
  /// The options as given, with the domain resolved (a grid made with them has these cells).
  const GridOptions& options() const noexcept { return options_; }
  /// The box the root cell covers (GridOptions::domain resolved).
  const Aabb& domain() const noexcept { return domain_; }
  /// The finest level L.
  int levels() const noexcept { return options_.levels; }

  /// The cells of level l (0 ≤ l ≤ L), inner cells and leaves; delta::Error for another level.
  /// Valid until the next move.
  std::span<const Cell> cells(int level) const;
  /// The number of leaves (the cells a solver computes on) of each level, 0 … L.
  std::vector<std::size_t> leavesPerLevel() const;
  /// Leaves of all levels.
  std::size_t leafCount() const;

  std::size_t vertexCount() const noexcept { return keys_.size(); }
  /// Where vertex v is.
  Vec3 position(std::uint32_t v) const noexcept;
  /// All vertex positions, in vertex order.
  std::vector<Vec3> positions() const;
  /// The distance to the boundary at each vertex (signed: negative inside), in vertex order.
  std::span<const double> distances() const noexcept { return distance_; }
  /// How far each vertex's distance may be from the exact one for the boundary where it is now
  /// (0 for vertices queried since the last move, and for all of them after a build).
  std::vector<double> errorBounds() const;
  /// The band within which distances are exact after a move (GridOptions::exactBand resolved).
  double exactBand() const noexcept { return exactBand_; }

  /// How many of the boundary's past poses the vertices' distances date from (1 after a build;
  /// poses no vertex dates from are forgotten, so a long run does not pile them up).
  std::size_t rememberedPoses() const noexcept { return poses_.size(); }
  /// The diagonal of a level-l cell (2^−l of the domain's; any l, meaningful for 0 ≤ l ≤ L).
  double cellDiagonal(int level) const noexcept;
  /// What the last build or move did.
  const GridStatistics& statistics() const noexcept { return statistics_; }

 private:
  /// Makes the levels anew from the root, reusing the cells and distances that are still valid,
  /// then brings the band's distances up to date.
  void refine();
  /// How far each remembered distance may be off at pose `now` (slackOfEpoch_).
  void updateSlacks(std::uint32_t now);
  /// Per cell of `level`: 1 to refine (its smallest corner distance below the threshold, from
  /// the remembered bounds or, in doubt, fresh distances), 0 to keep a leaf.
  void decideRefinement(int level, std::uint32_t now, std::vector<std::uint8_t>& decision);
  /// A build's estimate of its finest cells (for the memory check before refining).
  double finestCellsEstimate() const;
  /// Level + 1: the children of the cells `decision` refines, carried over from `old` where they
  /// were refined before (`fromOld`: each cell's index in old, or kNotOld; `nextFromOld` gets
  /// the children's). Returns how many were carried.
  std::size_t makeNextLevel(int level, const std::vector<std::uint8_t>& decision,
                            const std::vector<std::vector<Cell>>& old,
                            const std::vector<std::uint32_t>& fromOld,
                            std::vector<std::uint32_t>& nextFromOld);
  /// Brings every vertex that may be within the exact band up to date.
  void refreshBand(std::uint32_t now);
  /// Queues vertex v for the next query() (once per pass), with an upper bound of its distance.
  void queue(std::uint32_t v, double upperBound);
  /// Computes the distance of the queued vertices, in one batch.
  void query();
  /// The vertex at integer position (x, y, z), made (and queued) if new: a corner of the root, or
  /// of the children of `parent`, whose corners bound its distance.
  std::uint32_t vertexAt(std::uint32_t x, std::uint32_t y, std::uint32_t z, const Cell* parent);
  /// Where the vertex with this integer position (packed) is.
  Vec3 positionOfKey(std::uint64_t key) const noexcept;
  /// Drops the vertices no cell refers to.
  void compact();
  /// Drops the poses no vertex was queried at (so that they do not pile up over a long run).
  void forgetUnusedPoses();
  /// The hash-table slot of `key`: where it is, or the empty slot where it would go.
  std::size_t slotOf(std::uint64_t key) const noexcept;
  void rebuildTable(std::size_t capacity);

  QueryMesh boundary_;
  GridOptions options_;  ///< as given, checked, with the domain resolved
  Aabb domain_;
  double exactBand_ = 0.0;
  std::uint32_t resolution_ = 0;  ///< 2^L: finest cells per axis

  std::vector<std::vector<Cell>> levels_;

  // Vertices, by index: integer position (packed), distance, and the pose (an index into poses_)
  // the boundary had when the distance was computed.
  std::vector<std::uint64_t> keys_;
  std::vector<double> distance_;
  std::vector<std::uint32_t> epoch_;
  std::vector<std::uint32_t> queuedAt_;  ///< the pass that last queued the vertex
  std::vector<RigidTransform> poses_;    ///< the boundary's poses that some vertex was queried at
  std::vector<double> slackOfEpoch_;     ///< bound of the motion since each pose

  // Integer position → vertex index: open addressing, linear probing, power-of-two capacity.
  std::vector<std::uint64_t> tableKeys_;
  std::vector<std::uint32_t> tableValues_;

  std::uint32_t pass_ = 0;
  std::vector<std::uint32_t> pending_;
  std::vector<double> pendingBounds_;
  std::vector<Vec3> batchPoints_;
  std::vector<contactdetection::PointDistance> batchAnswers_;
  GridStatistics statistics_;
};

}  // namespace delta::ib
