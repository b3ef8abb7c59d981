// `delta distance MESH --points FILE.xyz`: every point's distance to a mesh, its closest point
// and triangle; with --eps only points closer than ε; with --signed inside/outside too.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/io/atomic_file.h"
#include "delta/io/vtk.h"
#include "delta/query/point_distance.h"

#include "commands.h"
#include "csv.h"
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
  requireOutputIsNotAnInput(options.out, {options.mesh, options.points});
}

/// What the summary line (or JSON) says of the answers, added up call by call.
struct Summary {
  std::size_t found = 0, inside = 0, ambiguous = 0;
  double nearest = INFINITY, farthest = -INFINITY;

  void add(std::span<const contactdetection::PointDistance> answers) noexcept {
    for (const contactdetection::PointDistance& a : answers) {
      if (!a.found()) continue;
      ++found;
      inside += a.inside;
      ambiguous += a.ambiguous;
      nearest = std::min(nearest, a.distance);
      farthest = std::max(farthest, a.distance);
    }
  }
};

/// --out FILE.csv, one row per point in input order, written call by call into an AtomicFile:
/// the file appears whole when commit() succeeds, and not at all when the run fails or is
/// interrupted before.
class CsvRows {
 public:
  CsvRows(const std::string& path, bool withInside, bool withAmbiguous)
      : file_(path), withInside_(withInside), withAmbiguous_(withAmbiguous) {
    file_.write(std::string(withInside ? "index,distance,closest_x,closest_y,closest_z,triangle,"
                                         "inside"
                                       : "index,distance,closest_x,closest_y,closest_z,triangle") +
                (withAmbiguous ? ",ambiguous\n" : "\n"));
  }

  /// The rows of points first, first + 1, …
  void add(std::size_t first, std::span<const contactdetection::PointDistance> answers) {
    writeRows(file_, answers.size(), [&](std::string& text, std::size_t k) {
      const contactdetection::PointDistance& a = answers[k];
      appendNumber(text, std::uint64_t{first + k});
      if (!a.found()) {
        text += withInside_ ? ",,,,,," : ",,,,,";
      } else {
        for (const double value : {a.distance, a.closest.x, a.closest.y, a.closest.z}) {
          text += ',';
          appendNumber(text, value);
        }
        text += ',';
        appendNumber(text, std::uint64_t{a.triangle});
        if (withInside_) text += a.inside ? ",1" : ",0";
      }
      // The winding sign's ambiguity last, after the columns of the other modes.
      text += !withAmbiguous_ ? "\n" : !a.found() ? ",\n" : a.ambiguous ? ",1\n" : ",0\n";
    });
  }

  void commit() { file_.commit(); }

 private:
  io::AtomicFile file_;
  bool withInside_, withAmbiguous_;
};

/// --out FILE.vtp: the points with their distance (NaN beyond ε; negative inside with --signed),
/// closest point and triangle (−1 beyond ε) as point data, gathered call by call and written
/// at the end: ParaView colours the cloud by distance.
class VtpColumns {
 public:
  VtpColumns(std::size_t count, bool withInside)
      : distance_{withInside ? "signed_distance" : "distance", 1, {}}, withInside_(withInside) {
    // The three columns, beside the points already held (requireMemory weighs a total against
    // the machine's memory, not what is free).
    requireMemory(
        static_cast<double>(count) * (5 * sizeof(double) + sizeof(Vec3)),
        "the points and their --out .vtp columns for " + std::to_string(count) + " points");
    distance_.values.reserve(count);
    closest_.values.reserve(3 * count);
    triangle_.values.reserve(count);
  }

  void add(std::span<const contactdetection::PointDistance> answers) {
    for (const contactdetection::PointDistance& a : answers) {
      distance_.values.push_back(!a.found()    ? std::nan("")
                                 : withInside_ ? a.signedDistance()
                                               : a.distance);
      const Vec3 c = a.found() ? a.closest : Vec3{std::nan(""), std::nan(""), std::nan("")};
      closest_.values.insert(closest_.values.end(), {c.x, c.y, c.z});
      triangle_.values.push_back(a.found() ? a.triangle : -1.0);
    }
  }

  /// Writes the file, taking the points (the writer's copy would be 24 more bytes a point).
  void write(std::vector<Vec3> points, const std::string& path) {
    io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
    data.pointData = {std::move(distance_), std::move(closest_), std::move(triangle_)};
    io::writeVtp(data, path);
  }

 private:
  io::VtkArray distance_;
  io::VtkArray closest_{"closest", 3, {}};
  io::VtkArray triangle_{"triangle", 1, {}, io::VtkType::Int64};
  bool withInside_;
};

void run(const DistanceOptions& options) {
  validate(options);
  Stopwatch clock;
  const Mesh mesh = loadMeshSource(options.mesh).mesh;
  std::vector<Vec3> points = loadPointSource(options.points, mesh.bounds());
  const std::size_t pointCount = points.size();
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
  std::optional<CsvRows> csv;
  if (extensionOf(options.out) == ".csv")
    csv.emplace(options.out, signedDistance, windingSign(options));
  std::optional<VtpColumns> vtp;
  if (extensionOf(options.out) == ".vtp") vtp.emplace(points.size(), signedDistance);
  // One call's answers at a time (at most kMostBatch): the summary and the output take them
  // as they come, so a run holds no answer per point (10⁷ of them were 400 MB, and allocating
  // them a quarter of W2's query time).
  std::vector<contactdetection::PointDistance> answers;
  Summary summary;
  double querySeconds = 0.0, writeSeconds = 0.0;
  {
    Progress progress("distance", points.size(), showProgress(options.quiet || options.json));
    for (std::size_t begin = 0, batch = kFirstBatch; begin < points.size();) {
      const std::size_t count = std::min(batch, points.size() - begin);
      Stopwatch call;
      if (answers.size() < count) {
        answers.clear();  // nothing to copy when it grows
        answers.resize(count);
      }
      const std::span<contactdetection::PointDistance> these = std::span(answers).first(count);
      contactdetection::distances(query, std::span(points).subspan(begin, count), request, these);
      summary.add(these);
      querySeconds += call.restart();
      if (csv) csv->add(begin, these);
      if (vtp) vtp->add(these);
      writeSeconds += call.restart();
      begin += count;
      progress.update(begin);
      batch = nextBatch(count, begin, querySeconds);
    }
  }
  clock.restart();
  if (csv) csv->commit();
  if (vtp) vtp->write(std::move(points), options.out);  // the last use of the points
  writeSeconds += clock.restart();
  const auto [found, inside, ambiguous, nearest, farthest] = summary;

  if (options.json) {
    JsonWriter json;
    json.beginObject()
        .value("points", pointCount)
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
        .value("queries_per_s", static_cast<double>(pointCount) / querySeconds)
        .value("write_s", writeSeconds);
    std::printf("%s\n", json.endObject().str().c_str());
    return;
  }
  std::printf("%zu points against %zu triangles", pointCount, query.size());
  if (options.epsilon) std::printf(", %zu closer than %g", found, *options.epsilon);
  if (signedDistance) std::printf(", %zu inside", inside);
  if (windingSign(options)) std::printf(" (%zu ambiguous)", ambiguous);
  if (found) std::printf("; distances %.6g to %.6g", nearest, farthest);
  std::printf("\nload %.3f s, build %.3f s, query %.3f s (%.3g points/s)%s\n", loadSeconds,
              buildSeconds, querySeconds, static_cast<double>(pointCount) / querySeconds,
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
                     "Also inside/outside (by pseudonormals: the mesh must bound a solid, closed, "
                     "not crossing itself, its parts nested; see --sign and delta info)");
  distance->add_option("--sign", options->sign,
                       "How --signed decides inside (implies --signed): pseudonormal (default; "
                       "meshes that bound a solid) or winding (the generalized "
                       "winding number > 1/2: any mesh, open or self-intersecting; --out .csv adds "
                       "a last column 'ambiguous', 1 where it is within 0.05 of 1/2)");
  distance->add_option("--out", options->out,
                       "Write one row per point in input order: FILE.csv, or FILE.vtp (ParaView)");
  distance->add_flag("--json", options->json, "Print one JSON object instead of text");
  distance->add_flag("--quiet", options->quiet, "No progress line");
  distance->callback([options] { run(*options); });
}

}  // namespace delta::cli
