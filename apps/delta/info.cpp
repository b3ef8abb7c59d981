#include <cstdio>
#include <memory>
#include <string>

#include "delta/mesh/bounding_sphere.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/measures.h"
#include "delta/mesh/topology.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

#include "commands.h"
#include "json.h"
#include "mesh_source.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

struct InfoOptions {
  std::string mesh;
  bool json = false;
};

struct MeshReport {
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  std::size_t degenerate = 0;
  Aabb bounds;
  Sphere sphere;
  double area = 0.0;
  double volume = 0.0;  // meaningful when topology.closed && topology.consistentlyOriented
  Topology topology;
  std::size_t selfIntersections = 0;  ///< crossing pairs of non-adjacent triangles
  PartNesting nesting;                ///< of a closed mesh: how its parts nest
  bool boundsSolid = false;           ///< closed, not crossing itself, its parts nested
  EdgeLengths edges;
  io::LoadStatistics statistics;
  std::size_t meshBytes = 0;
  double loadSeconds = 0.0;
  double analyseSeconds = 0.0;
};

MeshReport analyse(const std::string& source) {
  Stopwatch clock;
  const io::LoadedMesh loaded = loadMeshSource(source);
  MeshReport report;
  report.loadSeconds = clock.restart();
  const Mesh& mesh = loaded.mesh;
  report.triangles = mesh.triangleCount();
  report.vertices = mesh.vertexCount();
  report.degenerate = degenerateTriangleCount(mesh);
  report.bounds = mesh.bounds();
  report.sphere = boundingSphere(mesh);
  report.area = surfaceArea(mesh);
  report.topology = analyzeTopology(mesh);
  if (report.topology.closed && report.topology.consistentlyOriented)
    report.volume = signedVolume(mesh);
  const QueryMesh query(mesh);
  report.selfIntersections = selfIntersections(query).count;
  report.nesting = partNesting(query);
  report.boundsSolid = boundsSolid(query);
  report.edges = edgeLengths(mesh);
  report.statistics = loaded.statistics;
  report.meshBytes = mesh.memoryBytes();
  report.analyseSeconds = clock.seconds();
  return report;
}

bool hasVolume(const MeshReport& r) {
  return r.topology.closed && r.topology.consistentlyOriented;
}

void printJson(const std::string& source, const MeshReport& r) {
  JsonWriter json;
  json.beginObject()
      .value("mesh", source)
      .value("triangles", r.triangles)
      .value("vertices", r.vertices)
      .value("degenerate_triangles", r.degenerate)
      .beginObject("bounds")
      .value("lower", r.bounds.lower)
      .value("upper", r.bounds.upper)
      .endObject()
      .beginObject("bounding_sphere")
      .value("center", r.sphere.center)
      .value("radius", r.sphere.radius)
      .endObject()
      .value("area", r.area);
  if (hasVolume(r))
    json.value("volume", r.volume);
  else
    json.null("volume");
  json.value("closed", r.topology.closed)
      .value("manifold", r.topology.manifold)
      .value("consistently_oriented", r.topology.consistentlyOriented)
      .value("boundary_edges", r.topology.boundaryEdges)
      .value("non_manifold_edges", r.topology.nonManifoldEdges)
      .value("self_intersections", r.selfIntersections)
      .value("parts", r.nesting.parts)
      .value("misoriented_parts", r.nesting.misoriented)
      .value("pinched_vertices", r.nesting.pinched)
      .value("flat_parts", r.nesting.flat)
      .value("undecided_parts", r.nesting.undecided)
      .value("bounds_solid", r.boundsSolid)
      .beginObject("mesh_size")
      .value("min_edge", r.edges.min)
      .value("mean_edge", r.edges.mean)
      .value("max_edge", r.edges.max)
      .endObject()
      .value("points_skipped", r.statistics.pointsSkipped)
      .value("lines_skipped", r.statistics.linesSkipped)
      .value("precision", io::toString(r.statistics.precision))
      .value("load_s", r.loadSeconds)
      .value("analyse_s", r.analyseSeconds)
      .value("mesh_bytes", r.meshBytes)
      .value("peak_memory_bytes", peakResidentBytes())
      .endObject();
  std::printf("%s\n", json.str().c_str());
}

void printText(const std::string& source, const MeshReport& r) {
  const auto yesNo = [](bool flag) { return flag ? "yes" : "no"; };
  std::printf("mesh                 %s\n", source.c_str());
  std::printf("triangles            %zu (%zu degenerate)\n", r.triangles, r.degenerate);
  std::printf("vertices             %zu\n", r.vertices);
  if (r.statistics.pointsSkipped + r.statistics.linesSkipped > 0)
    std::printf("skipped              %zu points, %zu lines\n", r.statistics.pointsSkipped,
                r.statistics.linesSkipped);
  std::printf("bounds               [%.9g, %.9g, %.9g] .. [%.9g, %.9g, %.9g]\n", r.bounds.lower.x,
              r.bounds.lower.y, r.bounds.lower.z, r.bounds.upper.x, r.bounds.upper.y,
              r.bounds.upper.z);
  std::printf("bounding sphere      centre [%.9g, %.9g, %.9g], radius %.9g\n", r.sphere.center.x,
              r.sphere.center.y, r.sphere.center.z, r.sphere.radius);
  std::printf("area                 %.9g\n", r.area);
  if (hasVolume(r))
    std::printf("volume               %.9g\n", r.volume);
  else
    std::printf("volume               - (not a closed, consistently oriented surface)\n");
  std::printf("closed               %s (%zu boundary edges)\n", yesNo(r.topology.closed),
              r.topology.boundaryEdges);
  std::printf("manifold             %s (%zu non-manifold edges)\n", yesNo(r.topology.manifold),
              r.topology.nonManifoldEdges);
  std::printf("oriented             %s (%zu misoriented edges)\n",
              yesNo(r.topology.consistentlyOriented), r.topology.misorientedEdges);
  std::printf("self-intersections   %zu%s\n", r.selfIntersections,
              r.selfIntersections == 0 ? "" : " pairs of triangles cross (--sign winding)");
  if (r.topology.closed && r.topology.consistentlyOriented) {
    const PartNesting& n = r.nesting;
    std::printf(
        "parts                %zu (%zu misoriented, %zu flat, %zu undecided), %zu pinched "
        "vertices\n",
        n.parts, n.misoriented, n.flat, n.undecided, n.pinched);
    std::printf("bounds a solid       %s\n",
                r.boundsSolid ? "yes" : "no (pseudonormal signs refused: --sign winding)");
  }
  std::printf("mesh size h          min %.6g, mean %.6g, max %.6g (edge length)\n", r.edges.min,
              r.edges.mean, r.edges.max);
  std::printf("load                 %.3f s (analysis %.3f s)\n", r.loadSeconds, r.analyseSeconds);
  std::printf("memory               mesh %.2f MB, peak resident %.1f MB\n",
              static_cast<double>(r.meshBytes) / 1e6,
              static_cast<double>(peakResidentBytes()) / 1e6);
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* info =
      app.add_subcommand("info", "Describe a mesh: size, bounds, area, volume, topology");
  info->add_option("MESH", options->mesh, meshSourceHelp())->required();
  info->add_flag("--json", options->json, "Print one JSON object instead of text");
  info->callback([options] {
    const MeshReport report = analyse(options->mesh);
    if (options->json)
      printJson(options->mesh, report);
    else
      printText(options->mesh, report);
  });
}

}  // namespace delta::cli
