// `delta ib MESH`: an adaptive Cartesian grid refined around a boundary mesh, with the (signed)
// distance at every grid vertex (ib/adaptive_grid.h); with --steps the boundary moves rigidly every
// step and the grid follows. Prints cells, queries and timings (text or --json); --out writes
// ParaView files.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/ib/adaptive_grid.h"
#include "delta/ib/grid_vtk.h"
#include "delta/io/vtk.h"

#include "commands.h"
#include "files.h"
#include "json.h"
#include "mesh_source.h"
#include "motion_options.h"
#include "progress.h"
#include "run_lock.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

struct IbOptions {
  std::string mesh;
  int levels = ib::GridOptions{}.levels;
  double refineFactor = ib::GridOptions{}.refineFactor;
  std::optional<double> padding;
  bool unsignedDistance = false;
  std::string sign = contactdetection::signName(contactdetection::Sign::pseudonormal);  ///< --sign
  std::optional<double> exactBand;
  std::string steps = "0";
  std::string rotate, translate;
  std::string out;
  int compression = 0;  ///< --compression: zlib's level for the files, 0 none
  bool json = false;
  bool quiet = false;
  bool overwrite = false;  ///< --overwrite: replace an earlier run's output in --out
};

/// The motion of one step: --rotate about the centre of the mesh's box (a point that moves with
/// the mesh), then --translate.
struct StepMotion {
  Quaternion rotation;
  Vec3 translation;
  Vec3 centre;  ///< the centre of the mesh's box where it was loaded

  /// The motion that takes the boundary from `pose` one step on.
  RigidTransform after(const RigidTransform& pose) const {
    return RigidTransform::translationBy(translation) *
           RigidTransform::rotationAbout(rotation, pose.apply(centre));
  }
};

void validate(const IbOptions& options) {
  if (options.levels < 1 || options.levels > 20)
    throw Error("--levels " + std::to_string(options.levels) + " must be from 1 to 20");
  if (!(std::isfinite(options.refineFactor) && options.refineFactor > 0.0))
    throw Error("--refine-factor " + toString(options.refineFactor) +
                " must be finite and positive");
  if (options.padding && !(std::isfinite(*options.padding) && *options.padding >= 0.0))
    throw Error("--padding " + toString(*options.padding) + " must be finite and not negative");
  if (options.exactBand && !(*options.exactBand >= 0.0))
    throw Error("--exact-band " + toString(*options.exactBand) +
                " must be a distance >= 0 (inf: every distance exact)");
  const std::size_t steps = parseStepCount(options.steps, "--steps", 0);
  if (!options.rotate.empty()) parseRotation(options.rotate, "--rotate");
  if (!options.translate.empty()) parseVector(options.translate, "--translate");
  if (options.compression < 0 || options.compression > 9)
    throw Error("--compression " + std::to_string(options.compression) +
                " must be 0 (none) to 9 (smallest)");
  if (steps == 0 && !(options.rotate.empty() && options.translate.empty()))
    throw Error("--rotate and --translate move the boundary every step: give --steps N");
}

ib::GridOptions gridOptions(const IbOptions& options) {
  ib::GridOptions grid;
  grid.levels = options.levels;
  grid.refineFactor = options.refineFactor;
  grid.signedDistance = !options.unsignedDistance;
  grid.sign =
      contactdetection::parseSign(options.sign).value_or(contactdetection::Sign::pseudonormal);
  if (options.padding) grid.padding = *options.padding;
  if (options.exactBand) grid.exactBand = *options.exactBand;
  return grid;
}

/// The grid around `boundary`; a signed grid around an open mesh is refused with a pointer to
/// --unsigned.
ib::AdaptiveGrid makeGrid(const QueryMesh& boundary, const ib::GridOptions& options,
                          const std::string& source) {
  if (options.signedDistance && options.sign == contactdetection::Sign::pseudonormal &&
      !boundary.closed())
    throw Error("mesh '" + source + "' is not closed (" + describeDefects(boundary.topology()) +
                "): signed distances by pseudonormals need a closed mesh; use --sign winding for "
                "the winding-number sign, or --unsigned for unsigned distances");
  return ib::AdaptiveGrid(boundary, options);
}

/// --out DIR: grid.vtu and boundary.vtp for a static grid; for a moving one grid_NNNNNN.vtu and
/// boundary_NNNNNN.vtp a step (step 0 included) and grid.pvd and boundary.pvd, rewritten after
/// every step so that a run cut short leaves series that open. The files are encoded as
/// `encoding` says.
class IbOutput {
 public:
  IbOutput(std::filesystem::path directory, bool series, io::VtkWriteOptions encoding)
      : directory_(std::move(directory)), series_(series), encoding_(encoding) {
    makeOutputFolder(directory_);
  }

  /// Writes the grid and the boundary (`mesh` moved to where the grid's boundary is) of `step`.
  void write(const ib::AdaptiveGrid& grid, const Mesh& mesh, std::size_t step) {
    Mesh boundary = mesh;
    boundary.transform(grid.boundary().pose());
    const std::string gridFile = series_ ? frameFileName("grid", step, ".vtu") : "grid.vtu";
    const std::string boundaryFile =
        series_ ? frameFileName("boundary", step, ".vtp") : "boundary.vtp";
    io::writeVtu(ib::toVtk(grid), directory_ / gridFile, encoding_);
    io::writeVtp(io::VtkPolyData::fromMesh(boundary), directory_ / boundaryFile, encoding_);
    if (!series_) return;
    const double time = static_cast<double>(step);
    gridSeries_.push_back({time, gridFile});
    boundarySeries_.push_back({time, boundaryFile});
    io::writePvd(gridSeries_, directory_ / "grid.pvd");
    io::writePvd(boundarySeries_, directory_ / "boundary.pvd");
  }

  const std::filesystem::path& directory() const noexcept { return directory_; }

 private:
  std::filesystem::path directory_;
  bool series_;
  io::VtkWriteOptions encoding_;
  std::vector<io::VtkSeriesEntry> gridSeries_, boundarySeries_;
};

/// What a run measured: the build, and the moves summed.
struct IbSummary {
  double loadSeconds = 0.0;
  double buildSeconds = 0.0;  ///< wall clock: the boundary's QueryMesh and the grid
  ib::GridStatistics build;
  ib::GridStatistics moves;  ///< summed over the steps
  std::size_t steps = 0;
  double writeSeconds = 0.0;

  std::size_t queries() const { return build.queries + moves.queries; }
  double querySeconds() const { return build.querySeconds + moves.querySeconds; }
  double queriesPerSecond() const { return static_cast<double>(queries()) / querySeconds(); }
  /// Of the time the grid's builds and moves took, the share inside Δ's distance queries.
  double shareInDelta() const { return querySeconds() / (build.seconds + moves.seconds); }
  double perStep(double total) const { return steps ? total / static_cast<double>(steps) : 0.0; }
};

void printJson(const ib::AdaptiveGrid& grid, const IbSummary& run) {
  JsonWriter json;
  json.beginObject()
      .value("triangles", grid.boundary().size())
      .value("signed", grid.options().signedDistance)
      .value("sign", contactdetection::signName(grid.options().sign))
      .value("levels", grid.levels())
      .value("cells", grid.leafCount())
      .beginArray("cells_per_level");
  for (std::size_t leaves : grid.leavesPerLevel())
    json.value({}, leaves);
  json.endArray()
      .value("vertices", grid.vertexCount())
      .value("exact_band", grid.exactBand())
      .value("queries", run.queries())
      .value("queries_per_s", run.queriesPerSecond())
      .value("load_s", run.loadSeconds)
      .value("build_s", run.buildSeconds)
      .value("build_queries", run.build.queries)
      .value("steps", run.steps)
      .value("step_s", run.perStep(run.moves.seconds))
      .value("step_queries", run.perStep(static_cast<double>(run.moves.queries)))
      .value("share_in_delta", run.shareInDelta())
      .value("query_s", run.querySeconds())
      .value("write_s", run.writeSeconds)
      .value("threads", threadCount());
  std::printf("%s\n", json.endObject().str().c_str());
}

void printText(const std::string& source, const ib::AdaptiveGrid& grid, const IbSummary& run,
               const IbOutput* output) {
  const Vec3 size = grid.domain().extent();
  std::printf("%s: %zu triangles, %s distances; domain %.6g x %.6g x %.6g, levels 0-%d\n",
              source.c_str(), grid.boundary().size(),
              grid.options().signedDistance ? "signed" : "unsigned", size.x, size.y, size.z,
              grid.levels());
  std::printf("leaf cells per level:");
  for (std::size_t leaves : grid.leavesPerLevel())
    std::printf(" %zu", leaves);
  std::printf(" (%zu in all), %zu vertices, exact band %.6g\n", grid.leafCount(),
              grid.vertexCount(), grid.exactBand());
  std::printf("build: %zu queries in %.3f s (%.0f%% of it in the queries)\n", run.build.queries,
              run.buildSeconds, 100.0 * run.build.querySeconds / run.build.seconds);
  if (run.steps > 0)
    std::printf("%zu steps: %.4f s and %.0f queries a step (%zu cells made, %zu removed)\n",
                run.steps, run.perStep(run.moves.seconds),
                run.perStep(static_cast<double>(run.moves.queries)), run.moves.cellsCreated,
                run.moves.cellsRemoved);
  std::printf("%zu queries, %.3g queries/s, %.0f%% of the grid's time in Δ's queries; load %.3f s",
              run.queries(), run.queriesPerSecond(), 100.0 * run.shareInDelta(), run.loadSeconds);
  if (output)
    std::printf(", written to %s in %.3f s", output->directory().string().c_str(),
                run.writeSeconds);
  std::printf("\n");
}

void run(const IbOptions& options) {
  validate(options);
  const std::size_t steps = parseStepCount(options.steps, "--steps", 0);
  std::unique_ptr<RunLock> lock;  // held until the output is written (declared before it)
  std::unique_ptr<IbOutput> output;
  if (!options.out.empty()) {
    // One run at a time in the folder, and none over an earlier run's files: a static grid's
    // grid.vtu beside an earlier moving run's grid.pvd, which ParaView would open instead.
    makeOutputFolder(options.out);
    lock = std::make_unique<RunLock>(options.out, "delta ib");
    if (!lock->note().empty()) std::fprintf(stderr, "delta: note: %s\n", lock->note().c_str());
    clearEarlierOutput(options.out,
                       options.overwrite ? EarlierOutput::Overwrite : EarlierOutput::Refuse,
                       ibOutputFiles(options.out), "--overwrite replaces it");
    output = std::make_unique<IbOutput>(options.out, steps > 0,
                                        io::VtkWriteOptions{options.compression});
  }
  IbSummary summary;
  Stopwatch clock;
  const Mesh mesh = loadMeshSource(options.mesh).mesh;
  summary.loadSeconds = clock.restart();
  ib::AdaptiveGrid grid = makeGrid(QueryMesh(mesh), gridOptions(options), options.mesh);
  summary.buildSeconds = clock.restart();
  summary.build = grid.statistics();
  if (output) output->write(grid, mesh, 0);
  summary.writeSeconds += clock.restart();

  const StepMotion motion{
      options.rotate.empty() ? Quaternion{} : parseRotation(options.rotate, "--rotate"),
      options.translate.empty() ? Vec3{} : parseVector(options.translate, "--translate"),
      mesh.bounds().center()};
  Progress progress("ib", steps, showProgress(options.quiet || options.json));
  for (std::size_t step = 1; step <= steps; ++step) {
    summary.moves += grid.moveBoundary(motion.after(grid.boundary().pose()));
    summary.steps = step;
    if (output) {
      clock.restart();
      output->write(grid, mesh, step);
      summary.writeSeconds += clock.restart();
    }
    progress.update(step);
  }
  if (options.json)
    printJson(grid, summary);
  else
    printText(options.mesh, grid, summary, output.get());
}

/// A default value as the help shows it: "0.1", not "0.10000000000000001".
std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

constexpr const char* kFooter =
    R"(Threads: delta --threads N ib ... (or OMP_NUM_THREADS).

A cell of level l < L is split while the smallest |distance| at its corners is below
F x its diagonal, so the finest cells (level L) line the boundary. With --steps T the
boundary moves T times by --rotate (about the centre of its box, which moves with it) and
then --translate; the grid refines toward it and coarsens behind it, and only distances
that could have changed are computed again.

--out DIR writes, for ParaView (File > Open, then Apply):
  static (no --steps):  grid.vtu (leaf cells as voxels; point data signed_distance or
                        distance, and error_bound; cell data level) and boundary.vtp
  with --steps T:       grid.pvd + grid_NNNNNN.vtu and boundary.pvd + boundary_NNNNNN.vtp,
                        one file each for step 0 (the start) to T; the .pvd time is the step
Distances and coordinates are Float64 as computed, levels UInt8, connectivity Int32. The data
are not compressed by default, so that writing costs less than the queries (zlib takes about
as long as they do); --compression 1 makes the files ~4x smaller. A run holds DIR/.delta.lock
while it writes (a second run into DIR is refused meanwhile), and a folder that holds an earlier
run's output is refused unless --overwrite (which removes only those files).)";

}  // namespace

void addIbCommand(CLI::App& app) {
  auto options = std::make_shared<IbOptions>();
  const ib::GridOptions defaults;
  CLI::App* ib = app.add_subcommand(
      "ib", "Immersed boundary: an adaptive grid refined around a mesh, distance at every vertex");
  ib->footer(kFooter);
  ib->add_option("MESH", options->mesh, meshSourceHelp())->required();
  ib->add_option("--levels", options->levels,
                 "Finest level L, 1 to 20: the finest cells are 2^-L of the domain per axis "
                 "(default " +
                     std::to_string(defaults.levels) + ")")
      ->type_name("L");
  ib->add_option("--refine-factor", options->refineFactor,
                 "Split a cell while its corners are closer than F x its diagonal (default " +
                     shortNumber(defaults.refineFactor) + ")")
      ->type_name("F");
  ib->add_option("--padding", options->padding,
                 "Grow the mesh's box (made a cube) by P x its longest side on every side to make "
                 "the domain (default " +
                     shortNumber(defaults.padding) + ")")
      ->type_name("P");
  ib->add_flag("--unsigned", options->unsignedDistance,
               "Unsigned distances (the default, signed, needs a closed mesh; see --sign)");
  ib->add_option("--sign", options->sign,
                 "How signed distances decide inside: pseudonormal (default; a mesh that bounds a "
                 "solid: closed, not crossing itself, its parts nested) or winding (the "
                 "generalized winding number > 1/2: open "
                 "and self-intersecting meshes too)")
      ->check(CLI::IsMember({contactdetection::signName(contactdetection::Sign::pseudonormal),
                             contactdetection::signName(contactdetection::Sign::winding)}));
  ib->add_option("--exact-band", options->exactBand,
                 "After a move, distances up to B are exact, further ones within a stated bound "
                 "(default: the diagonal of a finest cell; 0: only what refinement needs; inf: all "
                 "exact)")
      ->type_name("B");
  ib->add_option("--steps", options->steps, "Move the boundary T times (default 0: a static grid)")
      ->type_name("T");
  ib->add_option("--rotate", options->rotate,
                 "Each step turn the mesh about the centre of its box: axis AX,AY,AZ and DEGREES")
      ->type_name("AX,AY,AZ,DEGREES");
  ib->add_option("--translate", options->translate,
                 "Each step move the mesh by X,Y,Z (after "
                 "turning)")
      ->type_name("X,Y,Z");
  ib->add_option("--out", options->out,
                 "Write the grid and the boundary for ParaView into folder DIR (made if missing)")
      ->type_name("DIR");
  ib->add_option("--compression", options->compression,
                 "zlib level of the files --out writes: 0 none (default, the fastest to write), "
                 "1 fastest to 9 smallest")
      ->type_name("LEVEL");
  ib->add_flag("--overwrite", options->overwrite,
               "Replace the output of an earlier run in --out (a run is refused otherwise)");
  ib->add_flag("--json", options->json, "Print one JSON object instead of text");
  ib->add_flag("--quiet", options->quiet, "No progress line");
  ib->callback([options] { run(*options); });
}

}  // namespace delta::cli
