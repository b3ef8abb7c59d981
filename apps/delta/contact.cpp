// `delta contact MESH_A MESH_B`: where two meshes come closer than 2ε (contact points), or, without
// --eps, their minimum distance and the closest triangle pair.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/io/atomic_file.h"
#include "delta/io/vtk.h"
#include "delta/query/contacts.h"
#include "delta/query/filter.h"
#include "delta/query/minimum_distance.h"

#include "commands.h"
#include "csv.h"
#include "files.h"
#include "json.h"
#include "mesh_source.h"
#include "motion_options.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

struct ContactOptions {
  std::string meshA, meshB;
  std::optional<double> epsilon;
  std::string method = "hybrid";
  std::optional<double> filter;
  SecondMeshMotion moveB;
  std::string out;
  bool json = false;
};

void validate(const ContactOptions& options) {
  options.moveB.validate();
  if (options.epsilon && !(std::isfinite(*options.epsilon) && *options.epsilon > 0.0))
    throw Error("--eps " + toString(*options.epsilon) + " must be finite and positive");
  if (options.filter && !(std::isfinite(*options.filter) && *options.filter > 0.0))
    throw Error("--filter " + toString(*options.filter) + " must be finite and positive");
  if (options.filter && !options.epsilon) throw Error("--filter needs --eps");
  if (!options.out.empty() && !options.epsilon) throw Error("--out needs --eps");
  const std::string extension = extensionOf(options.out);
  if (!options.out.empty() && extension != ".csv" && extension != ".vtp")
    throw Error("--out '" + options.out + "': write .csv or .vtp");
  requireOutputIsNotAnInput(options.out, {options.meshA, options.meshB});
  if (!kernels::parseSolver(options.method))
    throw Error("--method '" + options.method + "': use hybrid, penalty or bruteforce");
}

void writeCsv(const std::vector<ContactPoint>& contacts, const std::string& path) {
  io::AtomicFile file(path);
  file.write("triangle_a,triangle_b,x,y,z,normal_x,normal_y,normal_z,distance,overlap,converged\n");
  writeRows(file, contacts.size(), [&contacts](std::string& text, std::size_t i) {
    const ContactPoint& c = contacts[i];
    appendNumber(text, std::uint64_t{c.first});
    text += ',';
    appendNumber(text, std::uint64_t{c.second});
    for (const double value :
         {c.x.x, c.x.y, c.x.z, c.normal.x, c.normal.y, c.normal.z, c.distance}) {
      text += ',';
      appendNumber(text, value);
    }
    text += c.overlap ? ",1" : ",0";
    text += c.converged ? ",1\n" : ",0\n";
  });
  file.commit();
}

void writeVtp(const std::vector<ContactPoint>& contacts, const std::string& path) {
  std::vector<Vec3> points;
  io::VtkArray normal{"normal", 3, {}}, direction{"direction", 3, {}};
  io::VtkArray gap{"distance", 1, {}};
  io::VtkArray overlap{"overlap", 1, {}, io::VtkType::UInt8};
  io::VtkArray converged{"converged", 1, {}, io::VtkType::UInt8};
  io::VtkArray triangleA{"triangle_a", 1, {}, io::VtkType::UInt32};
  io::VtkArray triangleB{"triangle_b", 1, {}, io::VtkType::UInt32};
  for (const ContactPoint& c : contacts) {
    points.push_back(c.x);
    normal.values.insert(normal.values.end(), {c.normal.x, c.normal.y, c.normal.z});
    direction.values.insert(direction.values.end(), {c.direction.x, c.direction.y, c.direction.z});
    gap.values.push_back(c.distance);
    overlap.values.push_back(c.overlap ? 1.0 : 0.0);
    converged.values.push_back(c.converged ? 1.0 : 0.0);
    triangleA.values.push_back(c.first);
    triangleB.values.push_back(c.second);
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
  data.pointData = {normal, direction, gap, overlap, converged, triangleA, triangleB};
  io::writeVtp(data, path);
}

void run(const ContactOptions& options) {
  validate(options);
  const kernels::Solver solver = *kernels::parseSolver(options.method);
  Stopwatch clock;
  const Mesh a = loadMeshSource(options.meshA).mesh;
  Mesh b = loadMeshSource(options.meshB).mesh;
  options.moveB.apply(b);
  const double loadSeconds = clock.restart();
  const QueryMesh queryA(a), queryB(b);
  const double buildSeconds = clock.restart();

  JsonWriter json;
  json.beginObject().value("method", options.method);
  if (!options.epsilon) {
    const contactdetection::MinimumDistance closest =
        contactdetection::minimumDistance(queryA, queryB, solver);
    const double querySeconds = clock.seconds();
    if (!options.json)
      std::printf("minimum distance %.17g between triangle %u of A and triangle %u of B%s\n",
                  closest.distance, closest.first, closest.second,
                  closest.intersect ? " (they intersect)" : "");
    json.value("min_distance", closest.distance)
        .value("triangle_a", std::size_t{closest.first})
        .value("triangle_b", std::size_t{closest.second})
        .value("intersect", closest.intersect)
        .value("load_s", loadSeconds)
        .value("build_s", buildSeconds)
        .value("query_s", querySeconds);
  } else {
    std::vector<ContactPoint> found =
        contactdetection::contacts(queryA, queryB, *options.epsilon, solver);
    const std::size_t unfiltered = found.size();
    if (options.filter) found = contactdetection::filter(found, *options.filter);
    const double querySeconds = clock.restart();
    const std::size_t overlaps = static_cast<std::size_t>(
        std::count_if(found.begin(), found.end(), [](const ContactPoint& c) { return c.overlap; }));
    if (extensionOf(options.out) == ".csv") writeCsv(found, options.out);
    if (extensionOf(options.out) == ".vtp") writeVtp(found, options.out);
    if (!options.json)
      std::printf(
          "%zu contact points (%zu overlapping)%s, epsilon %g%s\n", found.size(), overlaps,
          options.filter ? (" after filter(h) of " + std::to_string(unfiltered)).c_str() : "",
          *options.epsilon, options.out.empty() ? "" : (", written to " + options.out).c_str());
    json.value("contacts", found.size())
        .value("overlapping", overlaps)
        .value("unfiltered_contacts", unfiltered)
        .value("epsilon", *options.epsilon)
        .value("load_s", loadSeconds)
        .value("build_s", buildSeconds)
        .value("query_s", querySeconds);
  }
  if (options.json) std::printf("%s\n", json.endObject().str().c_str());
}

}  // namespace

void addContactCommand(CLI::App& app) {
  auto options = std::make_shared<ContactOptions>();
  CLI::App* contact = app.add_subcommand(
      "contact", "Contact points of two meshes closer than 2ε, or their minimum distance");
  addMeshPair(*contact, options->meshA, options->meshB, options->moveB);
  contact->add_option("--eps", options->epsilon,
                      "Contact distance ε: pairs closer than 2ε are contacts (without it: the "
                      "minimum distance and the closest triangle pair)");
  contact->add_option("--method", options->method, "Solver: hybrid (default), penalty, bruteforce");
  contact->add_option("--filter", options->filter,
                      "Keep a contact only if no deeper kept contact lies closer than H");
  contact->add_option("--out", options->out,
                      "Write the contact points: FILE.csv (one row each, sorted by triangle ids) "
                      "or FILE.vtp (ParaView)");
  contact->add_flag("--json", options->json, "Print one JSON object instead of text");
  contact->callback([options] { run(*options); });
}

}  // namespace delta::cli
