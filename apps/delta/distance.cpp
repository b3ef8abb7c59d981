// `delta distance MESH --points FILE.xyz`: every point's distance to a mesh, its closest point
// and triangle; with --eps only points closer than ε; with --signed inside/outside too.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/io/atomic_file.h"
#include "delta/io/vtk.h"
#include "delta/query/point_distance.h"

#include "commands.h"
#include "files.h"
#include "json.h"
#include "mesh_source.h"
#include "point_source.h"
#include "progress.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

struct DistanceOptions {
  std::string mesh;
  std::string points;
  std::optional<double> epsilon;
  bool signedDistance = false;
  std::string sign;  ///< --sign: "pseudonormal" or "winding" (implies --signed)
  std::string out;
  bool json = false;
  bool quiet = false;
};

/// Points of the first library call; each later call takes as many as the calls before answered
/// in kBatchSeconds (the progress line redraws five times a second), at most 16 times the last
/// call's and kMostBatch. A call is the unit the library works on: an ε-limited batch sieves
/// its points by the bound grid and searches a grid cell's together, and each call runs a few
/// parallel loops whose ends wait for every thread. With calls of 2¹⁶ points, most cells' points
/// fell in different calls: W2 on 10⁷ points took 688–708 ms on one thread against 614–618 ms
/// (docs/performance.md).
constexpr std::size_t kFirstBatch = std::size_t{1} << 16;
constexpr std::size_t kMostBatch = std::size_t{1} << 21;
constexpr double kBatchSeconds = 0.25;

/// The points of the next call, after `done` points took `seconds`.
std::size_t nextBatch(std::size_t last, std::size_t done, double seconds) {
  const double atRate = seconds > 0.0 ? static_cast<double>(done) * (kBatchSeconds / seconds)
                                      : static_cast<double>(kMostBatch);
  // Never below the first call's size: after a last call of a few points, std::clamp's bounds
  // must still be in order.
  const std::size_t most = std::clamp(16 * last, kFirstBatch, kMostBatch);
  return std::clamp(static_cast<std::size_t>(std::min(atRate, static_cast<double>(most))),
                    kFirstBatch, most);
}

bool windingSign(const DistanceOptions& options) {
  return contactdetection::parseSign(options.sign) == contactdetection::Sign::winding;
}

void validate(const DistanceOptions& options) {
  if (!options.sign.empty() && !contactdetection::parseSign(options.sign))
    throw Error("--sign '" + options.sign + "': choose pseudonormal or winding");
  if (options.epsilon && !(std::isfinite(*options.epsilon) && *options.epsilon > 0.0))
    throw Error("--eps " + toString(*options.epsilon) + " must be finite and positive");
  const std::string extension = extensionOf(options.out);
  if (!options.out.empty() && extension != ".csv" && extension != ".vtp")
    throw Error("--out '" + options.out + "': write .csv or .vtp");
}

void writeCsv(const std::vector<Vec3>& points,
              const std::vector<contactdetection::PointDistance>& answers, bool withInside,
              bool withAmbiguous, const std::string& path) {
  io::AtomicFile file(path);
  file.write(std::string(withInside ? "index,distance,closest_x,closest_y,closest_z,triangle,inside"
                                    : "index,distance,closest_x,closest_y,closest_z,triangle") +
             (withAmbiguous ? ",ambiguous\n" : "\n"));
  char line[256];
  for (std::size_t i = 0; i < points.size(); ++i) {
    const contactdetection::PointDistance& a = answers[i];
    const int length =
        !a.found() ? std::snprintf(line, sizeof line, "%zu,,,,,%s\n", i, withInside ? "," : "")
                   : std::snprintf(line, sizeof line, "%zu,%.17g,%.17g,%.17g,%.17g,%u%s\n", i,
                                   a.distance, a.closest.x, a.closest.y, a.closest.z, a.triangle,
                                   withInside ? (a.inside ? ",1" : ",0") : "");
    file.write(std::string_view(line, static_cast<std::size_t>(length) - 1));
    // The winding sign's ambiguity last, after the columns of the other modes.
    file.write(!withAmbiguous ? "\n" : !a.found() ? ",\n" : a.ambiguous ? ",1\n" : ",0\n");
  }
  file.commit();
}

/// The points with their distance (NaN beyond ε; negative inside with --signed), closest point
/// and triangle (−1 beyond ε) as point data: ParaView colours the cloud by distance.
void writeVtp(const std::vector<Vec3>& points,
              const std::vector<contactdetection::PointDistance>& answers, bool withInside,
              const std::string& path) {
  io::VtkArray distance{withInside ? "signed_distance" : "distance", 1, {}};
  io::VtkArray closest{"closest", 3, {}}, triangle{"triangle", 1, {}, io::VtkType::Int64};
  for (const contactdetection::PointDistance& a : answers) {
    distance.values.push_back(!a.found()   ? std::nan("")
                              : withInside ? a.signedDistance()
                                           : a.distance);
    const Vec3 c = a.found() ? a.closest : Vec3{std::nan(""), std::nan(""), std::nan("")};
    closest.values.insert(closest.values.end(), {c.x, c.y, c.z});
    triangle.values.push_back(a.found() ? a.triangle : -1.0);
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(points);
  data.pointData = {distance, closest, triangle};
  io::writeVtp(data, path);
}

void run(const DistanceOptions& options) {
  validate(options);
  Stopwatch clock;
  const Mesh mesh = loadMeshSource(options.mesh).mesh;
  const std::vector<Vec3> points = loadPointSource(options.points, mesh.bounds());
  const double loadSeconds = clock.restart();
  const QueryMesh query(mesh);
  const bool signedDistance = options.signedDistance || !options.sign.empty();
  if (signedDistance && !windingSign(options) && !query.closed())
    throw Error("--signed: mesh '" + options.mesh + "' is not closed (" +
                describeDefects(query.topology()) +
                "); --sign winding signs it by its winding number, and unsigned distances work "
                "without --signed");
  const double buildSeconds = clock.restart();

  contactdetection::PointQuery request;
  if (options.epsilon) request.epsilon = *options.epsilon;
  request.signedDistance = signedDistance;
  if (windingSign(options)) request.sign = contactdetection::Sign::winding;
  std::vector<contactdetection::PointDistance> answers(points.size());
  {
    Progress progress("distance", points.size(), showProgress(options.quiet || options.json));
    Stopwatch calls;
    for (std::size_t begin = 0, batch = kFirstBatch; begin < points.size();) {
      const std::size_t count = std::min(batch, points.size() - begin);
      contactdetection::distances(query, std::span(points).subspan(begin, count), request,
                                  std::span(answers).subspan(begin, count));
      begin += count;
      progress.update(begin);
      batch = nextBatch(count, begin, calls.seconds());
    }
  }
  const double querySeconds = clock.restart();

  std::size_t found = 0, inside = 0, ambiguous = 0;
  double nearest = INFINITY, farthest = -INFINITY;
  for (const contactdetection::PointDistance& a : answers) {
    if (!a.found()) continue;
    ++found;
    inside += a.inside;
    ambiguous += a.ambiguous;
    nearest = std::min(nearest, a.distance);
    farthest = std::max(farthest, a.distance);
  }
  if (extensionOf(options.out) == ".csv")
    writeCsv(points, answers, signedDistance, windingSign(options), options.out);
  if (extensionOf(options.out) == ".vtp") writeVtp(points, answers, signedDistance, options.out);
  const double writeSeconds = clock.restart();

  if (options.json) {
    JsonWriter json;
    json.beginObject()
        .value("points", points.size())
        .value("triangles", query.size())
        .value("closed", query.closed());
    if (options.epsilon) json.value("epsilon", *options.epsilon).value("within", found);
    if (signedDistance) json.value("inside", inside);
    if (windingSign(options)) json.value("ambiguous", ambiguous);
    json.value("min_distance", found ? nearest : NAN)
        .value("max_distance", found ? farthest : NAN)
        .value("load_s", loadSeconds)
        .value("build_s", buildSeconds)
        .value("query_s", querySeconds)
        .value("queries_per_s", static_cast<double>(points.size()) / querySeconds)
        .value("write_s", writeSeconds);
    std::printf("%s\n", json.endObject().str().c_str());
    return;
  }
  std::printf("%zu points against %zu triangles", points.size(), query.size());
  if (options.epsilon) std::printf(", %zu closer than %g", found, *options.epsilon);
  if (signedDistance) std::printf(", %zu inside", inside);
  if (windingSign(options)) std::printf(" (%zu ambiguous)", ambiguous);
  if (found) std::printf("; distances %.6g to %.6g", nearest, farthest);
  std::printf("\nload %.3f s, build %.3f s, query %.3f s (%.3g points/s)%s\n", loadSeconds,
              buildSeconds, querySeconds, static_cast<double>(points.size()) / querySeconds,
              options.out.empty() ? "" : (", written to " + options.out).c_str());
}

}  // namespace

void addDistanceCommand(CLI::App& app) {
  auto options = std::make_shared<DistanceOptions>();
  CLI::App* distance = app.add_subcommand(
      "distance", "Distance from points to a mesh: closest point, triangle, inside/outside");
  distance->add_option("MESH", options->mesh, meshSourceHelp())->required();
  distance
      ->add_option("--points", options->points,
                   "FILE.xyz (one point 'x y z' a line), or builtin:uniform:N[:SEED] (N random "
                   "points in the mesh's box grown by 10% per side)")
      ->required();
  distance->add_option("--eps", options->epsilon,
                       "Answer only points closer than ε (the others: empty distance)");
  distance->add_flag("--signed", options->signedDistance,
                     "Also inside/outside (by pseudonormals: the mesh must be closed and not "
                     "cross itself; see --sign)");
  distance->add_option("--sign", options->sign,
                       "How --signed decides inside (implies --signed): pseudonormal (default; "
                       "closed meshes that do not cross themselves) or winding (the generalized "
                       "winding number > 1/2: any mesh, open or self-intersecting; --out .csv adds "
                       "a last column 'ambiguous', 1 where it is within 0.05 of 1/2)");
  distance->add_option("--out", options->out,
                       "Write one row per point in input order: FILE.csv, or FILE.vtp (ParaView)");
  distance->add_flag("--json", options->json, "Print one JSON object instead of text");
  distance->add_flag("--quiet", options->quiet, "No progress line");
  distance->callback([options] { run(*options); });
}

}  // namespace delta::cli
