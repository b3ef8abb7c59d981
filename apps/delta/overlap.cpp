// `delta overlap MESH_A MESH_B`: the solid two closed meshes share (A ∩ B): its volume, centroid
// and surface integrals per connected region and in all, and the curves where the surfaces cross.
#include "delta/query/overlap.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/io/vtk.h"

#include "commands.h"
#include "files.h"
#include "json.h"
#include "mesh_source.h"
#include "motion_options.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

namespace cd = contactdetection;

struct OverlapCliOptions {
  std::string meshA, meshB;
  SecondMeshMotion moveB;
  std::string out;
  bool json = false;
  bool quiet = false;
};

void validate(const OverlapCliOptions& options) {
  if (!options.out.empty() && extensionOf(options.out) != ".vtp")
    throw Error("--out '" + options.out + "': write the curves as FILE.vtp");
  requireOutputIsNotAnInput(options.out, {options.meshA, options.meshB});
  options.moveB.validate();
}

/// Throws delta::Error unless every number of `region` (called `what`) is finite: a non-finite
/// answer is never printed or written.
void requireFinite(const cd::OverlapRegion& region, const std::string& what) {
  for (const double value : {region.volume, region.curveLength})
    if (!std::isfinite(value))
      throw Error("overlap: the " + what + " has a non-finite value " + toString(value));
  for (const Vec3& v : {region.centroid, region.areaVector, region.areaVectorB, region.moment})
    if (!isFinite(v))
      throw Error("overlap: the " + what + " has a non-finite vector " + toString(v));
}

void requireFinite(const cd::Overlap& found) {
  requireFinite(found.total, "total");
  for (std::size_t r = 0; r < found.regions.size(); ++r)
    requireFinite(found.regions[r], "region " + std::to_string(r));
  for (std::size_t c = 0; c < found.curves.size(); ++c) {
    if (!std::isfinite(found.curves[c].length))
      throw Error("overlap: curve " + std::to_string(c) + " has a non-finite length " +
                  toString(found.curves[c].length));
    for (const Vec3& p : found.curves[c].points)
      if (!isFinite(p))
        throw Error("overlap: curve " + std::to_string(c) + " has a non-finite point " +
                    toString(p));
  }
}

/// The curves as VTK polylines, one cell a curve (a closed curve ends at its first point, stored
/// once). Cell data: curve, region, closed, length. Point data: triangle_a, triangle_b, the
/// triangles of the segment that starts at the point (at the last point of an open curve: of the
/// segment that ends there).
void writeCurves(const std::vector<cd::IntersectionCurve>& curves, const std::string& path) {
  io::VtkPolyData data;
  io::VtkArray curveId{"curve", 1, {}, io::VtkType::UInt32};
  io::VtkArray region{"region", 1, {}, io::VtkType::UInt32};
  io::VtkArray closed{"closed", 1, {}, io::VtkType::UInt8};
  io::VtkArray length{"length", 1, {}};
  io::VtkArray triangleA{"triangle_a", 1, {}, io::VtkType::UInt32};
  io::VtkArray triangleB{"triangle_b", 1, {}, io::VtkType::UInt32};
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const cd::IntersectionCurve& curve = curves[c];
    const std::size_t segments = curve.trianglesA.size();
    if (segments == 0 || curve.points.size() != segments + 1) continue;
    const std::size_t first = data.points.size();
    const std::size_t stored = curve.closed ? segments : segments + 1;
    std::vector<std::uint32_t> line;
    for (std::size_t i = 0; i < stored; ++i) {
      data.points.push_back(curve.points[i]);
      line.push_back(static_cast<std::uint32_t>(first + i));
      const std::size_t segment = std::min(i, segments - 1);
      triangleA.values.push_back(curve.trianglesA[segment]);
      triangleB.values.push_back(curve.trianglesB[segment]);
    }
    if (curve.closed) line.push_back(static_cast<std::uint32_t>(first));
    data.lines.push_back(std::move(line));
    curveId.values.push_back(static_cast<double>(c));
    region.values.push_back(static_cast<double>(curve.region));
    closed.values.push_back(curve.closed ? 1.0 : 0.0);
    length.values.push_back(curve.length);
  }
  data.pointData = {triangleA, triangleB};
  data.cellData = {curveId, region, closed, length};
  io::writeVtp(data, path);
}

void regionJson(JsonWriter& json, const cd::OverlapRegion& region) {
  json.value("volume", region.volume)
      .value("centroid", region.centroid)
      .value("area_vector", region.areaVector)
      .value("area_vector_b", region.areaVectorB)
      .value("moment", region.moment)
      .value("curve_length", region.curveLength)
      .value("triangles", region.triangles);
}

std::string vectorText(const Vec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.9g, %.9g, %.9g)", v.x, v.y, v.z);
  return text;
}

void printText(const cd::Overlap& found, const std::string& out, double loadSeconds,
               double buildSeconds, double querySeconds) {
  if (!found.any()) {
    std::printf("no overlap: the meshes share no volume");
  } else {
    const cd::OverlapRegion& total = found.total;
    std::printf("overlap volume %.17g in %zu region%s\n", total.volume, found.regions.size(),
                found.regions.size() == 1 ? "" : "s");
    std::printf("  centroid %s\n", vectorText(total.centroid).c_str());
    std::printf("  area vector of A's surface inside B %s, moment %s\n",
                vectorText(total.areaVector).c_str(), vectorText(total.moment).c_str());
    std::printf("  %zu intersection curve%s of %zu segments, length %.9g", found.curves.size(),
                found.curves.size() == 1 ? "" : "s", found.segments, total.curveLength);
    for (std::size_t r = 0; r < found.regions.size() && found.regions.size() > 1; ++r) {
      const cd::OverlapRegion& region = found.regions[r];
      std::printf("\n  region %zu: volume %.17g, centroid %s, curve length %.9g, %zu triangles", r,
                  region.volume, vectorText(region.centroid).c_str(), region.curveLength,
                  region.triangles);
    }
  }
  if (found.touching > 0)
    std::printf("%s%zu touching piece%s without volume", found.any() ? "\n  " : "; ",
                found.touching, found.touching == 1 ? "" : "s");
  if (found.coplanar > 0 && found.any())
    std::printf(
        "\n  %zu coplanar triangle pair%s: area vectors and moments %s", found.coplanar,
        found.coplanar == 1 ? "" : "s",
        found.oneSided ? "one side's (the other side's query refused)" : "the mean of both sides");
  std::printf("\nload %.3f s, build %.3f s, query %.3f s%s\n", loadSeconds, buildSeconds,
              querySeconds, out.empty() ? "" : (", curves written to " + out).c_str());
}

void printJson(const cd::Overlap& found, double loadSeconds, double buildSeconds,
               double querySeconds) {
  JsonWriter json;
  json.beginObject().value("volume", found.total.volume).beginArray("regions");
  for (const cd::OverlapRegion& region : found.regions) {
    json.beginObject();
    regionJson(json, region);
    json.endObject();
  }
  json.endArray()
      .value("centroid", found.total.centroid)
      .value("area_vector", found.total.areaVector)
      .value("area_vector_b", found.total.areaVectorB)
      .value("moment", found.total.moment)
      .value("curve_length", found.total.curveLength)
      .value("curves", found.curves.size())
      .value("segments", found.segments)
      .value("touching", found.touching)
      .value("coplanar", found.coplanar)
      .value("one_sided", found.oneSided)
      .value("load_s", loadSeconds)
      .value("build_s", buildSeconds)
      .value("query_s", querySeconds);
  std::printf("%s\n", json.endObject().str().c_str());
}

void run(const OverlapCliOptions& options) {
  validate(options);
  Stopwatch clock;
  const Mesh a = loadMeshSource(options.meshA).mesh;
  Mesh b = loadMeshSource(options.meshB).mesh;
  options.moveB.apply(b);
  const double loadSeconds = clock.restart();
  const QueryMesh queryA(a), queryB(b);
  const double buildSeconds = clock.restart();
  cd::Overlap found;
  try {
    found = cd::overlap(queryA, queryB);  // with the curves: their count is reported
  } catch (const Error& error) {
    std::string_view reason = error.what();
    if (reason.starts_with("overlap: ")) reason.remove_prefix(9);
    throw Error("overlap of '" + options.meshA + "' (A) and '" + options.meshB +
                "' (B): " + std::string(reason));
  }
  const double querySeconds = clock.restart();
  requireFinite(found);
  if (!options.out.empty()) writeCurves(found.curves, options.out);
  if (options.json)
    printJson(found, loadSeconds, buildSeconds, querySeconds);
  else if (!options.quiet)
    printText(found, options.out, loadSeconds, buildSeconds, querySeconds);
}

}  // namespace

void addOverlapCommand(CLI::App& app) {
  auto options = std::make_shared<OverlapCliOptions>();
  CLI::App* overlap = app.add_subcommand(
      "overlap", "The volume two closed meshes share and the curves where their surfaces cross");
  addMeshPair(*overlap, options->meshA, options->meshB, options->moveB);
  overlap->add_option("--out", options->out,
                      "Write the intersection curves as FILE.vtp (ParaView): one polyline a "
                      "curve, cell data curve, region, closed, length; point data triangle_a, "
                      "triangle_b (the triangles of the segment starting there)");
  overlap->add_flag("--json", options->json, "Print one JSON object instead of text");
  overlap->add_flag("--quiet", options->quiet, "Print nothing but errors (unless --json)");
  overlap->callback([options] { run(*options); });
}

}  // namespace delta::cli
