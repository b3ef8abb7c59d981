// The guide's "Distance fields for immersed boundaries" (docs/guide.md): an adaptive grid that
// follows a moving body with its signed distance at every vertex, written for ParaView; and the
// batched query that a code with its own grid calls instead.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "delta/delta.h"

int main() try {
  namespace cd = delta::contactdetection;

  // [guide:begin grid]
  const delta::QueryMesh body(delta::primitives::icosphere(3, 0.3));  // closed: signed distances
  delta::ib::GridOptions options;
  options.levels = 6;                          // the finest cells are 1/64 of the domain
  options.domain = {{-1, -1, -1}, {1, 1, 1}};  // fixed; the body moves inside it
  delta::ib::AdaptiveGrid grid(body, options);
  for (int step = 1; step <= 5; ++step) {
    const delta::ib::GridStatistics& moved =
        grid.moveBoundary(delta::RigidTransform::translationBy({0.05, 0, 0}));
    std::printf("step %d: %zu leaf cells, %zu vertices, %zu queried again\n", step,
                grid.leafCount(), grid.vertexCount(), moved.queries);
  }
  const std::span<const double> phi = grid.distances();     // per vertex, negative inside
  const std::vector<double> error = grid.errorBounds();     // 0 within grid.exactBand()
  delta::io::writeVtu(delta::ib::toVtk(grid), "grid.vtu");  // open it in ParaView
  // [guide:end grid]

  // Every distance is within its error bound of the exact one, and exact in the band.
  const std::vector<delta::Vec3> vertices = grid.positions();
  std::size_t inside = 0;
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const double exact =
        cd::distance(grid.boundary(), vertices[v], {.signedDistance = true}).signedDistance();
    const bool wrong = std::abs(phi[v]) <= grid.exactBand() ? phi[v] != exact
                                                            : std::abs(phi[v] - exact) > error[v];
    if (wrong || std::signbit(phi[v]) != std::signbit(exact)) {
      std::fprintf(stderr, "vertex %zu: %.17g, exact %.17g, error bound %g\n", v, phi[v], exact,
                   error[v]);
      return 1;
    }
    inside += phi[v] < 0.0;
  }

  // [guide:begin own-grid]
  // A code with its own grid: the new vertices of a refinement step, answered in one batch.
  // Within the band they get exact signed distances; beyond it, found() is false.
  const double band = 0.1;
  std::vector<delta::Vec3> newVertices;
  for (int i = 0; i <= 40; ++i)
    newVertices.push_back({-1.0 + 0.05 * i, 0.01, 0.02});
  std::vector<cd::PointDistance> answers(newVertices.size());  // reused: no allocation per batch
  cd::distances(grid.boundary(), newVertices, {.epsilon = band, .signedDistance = true}, answers);
  for (std::size_t i = 0; i < answers.size(); ++i)
    if (answers[i].found())
      std::printf("x = %+.2f: %+.4f\n", newVertices[i].x, answers[i].signedDistance());
  // [guide:end own-grid]

  std::size_t near = 0;
  for (const cd::PointDistance& answer : answers)
    near += answer.found();
  const bool written = std::filesystem::file_size("grid.vtu") > 0;
  return inside > 0 && near > 0 && written ? 0 : 1;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "distance_fields: %s\n", error.what());
  return 1;
}
