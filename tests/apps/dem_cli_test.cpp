// Runs `delta dem` as a user would: the two-particle restitution, the ParaView series it writes,
// config files, and one line on stderr with a non-zero exit code for every bad input. Small
// particle counts and few steps keep each run under a second.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::runDelta;
using delta::test::seriesFiles;
using delta::test::slurp;
using delta::test::TemporaryFolder;

/// What a VTK XML PolyData file with raw appended data holds, after checking its structure.
struct VtpSummary {
  bool wellFormed = false;
  std::string problem;
  std::size_t points = 0;
  std::size_t polys = 0;
  std::size_t verts = 0;
  std::vector<std::string> arrays;  ///< names of the DataArrays
};

/// Checks that the XML part (everything but the raw block) nests properly with quoted
/// attributes, and that the raw block is exactly the arrays it is said to hold: every
/// DataArray's offset points at a UInt64 byte count and its bytes, and together they fill it.
VtpSummary readVtp(const fs::path& path) {
  VtpSummary summary;
  const std::string file = slurp(path);
  const std::string opening = "<AppendedData encoding=\"raw\">\n_";
  const std::string closing = "\n</AppendedData>\n</VTKFile>\n";
  const std::size_t raw = file.find(opening);
  if (raw == std::string::npos || file.size() < raw + opening.size() + closing.size() ||
      file.compare(file.size() - closing.size(), closing.size(), closing) != 0) {
    summary.problem = "no raw appended block with the closing tags after it";
    return summary;
  }
  const std::string xml = file.substr(0, raw) + "<AppendedData encoding=\"raw\">" + closing;
  const std::regex tag(R"(<(/?)([A-Za-z?][A-Za-z0-9]*)((\s+[A-Za-z_]+="[^"<>]*")*)\s*(/?[?]?)>)");
  std::vector<std::string> open;
  std::size_t position = 0;
  std::smatch match;
  std::string rest = xml;
  while (std::regex_search(rest, match, tag)) {
    const std::string between = match.prefix();
    if (between.find_first_not_of(" \n") != std::string::npos) {
      summary.problem = "text outside a tag near byte " + std::to_string(position);
      return summary;
    }
    const std::string name = match[2];
    if (name == "?xml") {
    } else if (match[1] == "/") {
      if (open.empty() || open.back() != name) {
        summary.problem = "</" + name + "> closes " + (open.empty() ? "nothing" : open.back());
        return summary;
      }
      open.pop_back();
    } else if (match[5] != "/") {
      open.push_back(name);
    }
    if (name == "Piece" && match[1] != "/") {
      const std::string attributes = match[3];
      const auto count = [&](const std::string& key) {
        std::smatch value;
        const std::regex pattern(key + "=\"([0-9]+)\"");
        return std::regex_search(attributes, value, pattern) ? std::stoull(value[1]) : 0ull;
      };
      summary.points = count("NumberOfPoints");
      summary.polys = count("NumberOfPolys");
      summary.verts = count("NumberOfVerts");
    }
    position += static_cast<std::size_t>(match.position(0) + match.length(0));
    rest = match.suffix();
  }
  if (!open.empty() || rest.find_first_not_of(" \n") != std::string::npos) {
    summary.problem = "unclosed tags or trailing text";
    return summary;
  }
  const std::string block =
      file.substr(raw + opening.size(), file.size() - raw - opening.size() - closing.size());
  const std::regex array(R"re(<DataArray [^>]*Name="([^"]+)"[^>]* offset="([0-9]+)"/>)re");
  std::size_t covered = 0;
  const std::string head = file.substr(0, raw);
  // Compressed (the default): a header of UInt64 words, the number of blocks n, the block size,
  // the last block's size, n compressed sizes, then the blocks. Raw: a UInt64 byte count.
  const bool compressed = head.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos;
  const auto word = [&](std::size_t at) {
    std::uint64_t value = 0;
    if (at + sizeof value <= block.size()) std::memcpy(&value, block.data() + at, sizeof value);
    return value;
  };
  for (auto it = std::sregex_iterator(head.begin(), head.end(), array);
       it != std::sregex_iterator(); ++it) {
    summary.arrays.push_back((*it)[1]);
    const std::size_t offset = std::stoull((*it)[2]);
    if (offset + 8 > block.size()) {
      summary.problem = "array " + summary.arrays.back() + " starts past the block";
      return summary;
    }
    std::size_t bytes = 8 + word(offset);
    if (compressed) {
      const std::uint64_t blocks = word(offset);
      bytes = 8 * (3 + blocks);
      for (std::uint64_t b = 0; b < blocks && offset + bytes <= block.size(); ++b)
        bytes += word(offset + 8 * (3 + b));
    }
    if (offset + bytes > block.size()) {
      summary.problem = "array " + summary.arrays.back() + " ends past the block";
      return summary;
    }
    covered += bytes;
  }
  if (covered != block.size()) {
    summary.problem = "the arrays cover " + std::to_string(covered) + " of " +
                      std::to_string(block.size()) + " bytes";
    return summary;
  }
  summary.wellFormed = true;
  return summary;
}

TEST(DemCli, TwoParticlesMeasureTheRestitutionAsked) {
  const CliRun run = runDelta("dem two-particles --restitution 0.9 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "--json prints one line";
  EXPECT_NEAR(jsonNumber(run.out, "restitution"), 0.9, 0.02 * 0.9) << run.out;
  // Kinetic energy after over before is e²: the total changes by e² − 1.
  EXPECT_NEAR(jsonNumber(run.out, "energy_change"), 0.9 * 0.9 - 1.0, 0.02) << run.out;
  EXPECT_EQ(jsonNumber(run.out, "particles"), 2.0);
  EXPECT_GT(jsonNumber(run.out, "steps"), 0.0);
  EXPECT_GT(jsonNumber(run.out, "max_contacts"), 0.0) << "they collide";
  EXPECT_NE(run.out.find("\"scenario\":\"two-particles\""), std::string::npos) << run.out;
  for (const char* key : {"triangles", "steps_per_s", "contacts_per_step", "max_contacts",
                          "share_contact_detection", "time", "build_s", "run_s", "threads"})
    EXPECT_FALSE(std::isnan(jsonNumber(run.out, key))) << key << " in " << run.out;
}

TEST(DemCli, SettleWritesASeriesParaViewOpens) {
  const TemporaryFolder out("settle");
  const fs::path folder = out.path / "frames";  // made by the command
  const CliRun run =
      runDelta("dem settle --particles 8 --steps 12 --output-every 5 --json --out '" +
               folder.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const double triangles = jsonNumber(run.out, "triangles");
  ASSERT_EQ(jsonNumber(run.out, "particles"), 8.0) << run.out;
  EXPECT_EQ(triangles, 8.0 * 80.0) << "granulates of 80 triangles";
  EXPECT_EQ(jsonNumber(run.out, "frames"), 4.0) << "steps 0, 5, 10 and the last, 12";

  // The default frames: a point per particle, and the shapes to glyph there.
  EXPECT_FALSE(fs::exists(folder / "particles.pvd")) << "the triangles only with --frames";
  const std::vector<std::string> states = seriesFiles(folder / "particles_state.pvd");
  ASSERT_EQ(states.size(), 4u);
  for (const std::string& frame : states) {
    const VtpSummary vtp = readVtp(folder / frame);
    EXPECT_TRUE(vtp.wellFormed) << frame << ": " << vtp.problem;
    EXPECT_EQ(vtp.points, 8u) << frame;
    EXPECT_EQ(vtp.verts, 8u) << frame;
    EXPECT_EQ(vtp.polys, 0u) << frame;
    for (const char* name : {"particle", "shape", "velocity", "angular_velocity", "orientation",
                             "bounding_radius", "Points"})
      EXPECT_NE(std::find(vtp.arrays.begin(), vtp.arrays.end(), name), vtp.arrays.end()) << name;
  }
  const VtpSummary shape = readVtp(folder / "shape_0.vtp");
  EXPECT_TRUE(shape.wellFormed) << shape.problem;
  EXPECT_EQ(shape.polys, 80u) << "a granulate in its body frame";

  const fs::path both = out.path / "both";
  const CliRun withTriangles = runDelta(
      "dem settle --particles 8 --steps 12 --output-every 5 --quiet --frames both --out '" +
      both.string() + "'");
  ASSERT_EQ(withTriangles.exitCode, 0) << withTriangles.err;
  EXPECT_EQ(seriesFiles(both / "particles_state.pvd").size(), 4u);
  const std::vector<std::string> frames = seriesFiles(both / "particles.pvd");
  ASSERT_EQ(frames.size(), 4u);
  for (const std::string& frame : frames) {
    ASSERT_TRUE(fs::exists(both / frame)) << frame;
    const VtpSummary vtp = readVtp(both / frame);
    EXPECT_TRUE(vtp.wellFormed) << frame << ": " << vtp.problem;
    EXPECT_EQ(static_cast<double>(vtp.polys), triangles) << frame;
    EXPECT_EQ(vtp.verts, 0u);
    for (const char* name : {"velocity", "particle", "Points", "connectivity"})
      EXPECT_NE(std::find(vtp.arrays.begin(), vtp.arrays.end(), name), vtp.arrays.end()) << name;
  }
  const fs::path triangleOnly = out.path / "triangles";
  ASSERT_EQ(runDelta("dem settle --particles 8 --steps 2 --quiet --frames triangles --out '" +
                     triangleOnly.string() + "'")
                .exitCode,
            0);
  EXPECT_TRUE(fs::exists(triangleOnly / "particles.pvd"));
  EXPECT_FALSE(fs::exists(triangleOnly / "particles_state.pvd"));
  EXPECT_FALSE(fs::exists(triangleOnly / "shape_0.vtp"));
  expectOneLineError(
      runDelta("dem settle --steps 1 --frames all --out '" + (out.path / "bad").string() + "'"),
      "--frames 'all' is not state, triangles or both");
  const std::vector<std::string> contactFrames = seriesFiles(folder / "contacts.pvd");
  ASSERT_EQ(contactFrames.size(), 4u);
  for (const std::string& frame : contactFrames)
    EXPECT_TRUE(readVtp(folder / frame).wellFormed) << frame;
  const VtpSummary box = readVtp(folder / "obstacles.vtp");
  EXPECT_TRUE(box.wellFormed) << box.problem;
  EXPECT_EQ(box.polys, 10u) << "the open box";

  std::ifstream log(folder / "log.csv");
  std::string header, row;
  std::getline(log, header);
  EXPECT_EQ(header,
            "step,time,kinetic_energy,potential_energy,elastic_energy,total_energy,contacts,"
            "contact_pairs,step_seconds,contact_detection_seconds,energy_change");
  std::size_t rows = 0;
  while (std::getline(log, row))
    ++rows;
  EXPECT_EQ(rows, 13u) << "the start and every step";
}

TEST(DemCli, ContactFramesHoldTheContactPoints) {
  const TemporaryFolder out("contacts");
  const CliRun run =
      runDelta("dem two-particles --output-every 2 --quiet --out '" + out.path.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("restitution"), std::string::npos) << run.out;
  std::size_t withContacts = 0;
  for (const std::string& frame : seriesFiles(out.path / "contacts.pvd")) {
    const VtpSummary vtp = readVtp(out.path / frame);
    ASSERT_TRUE(vtp.wellFormed) << frame << ": " << vtp.problem;
    EXPECT_EQ(vtp.verts, vtp.points) << "each contact point a vertex cell";
    withContacts += vtp.points > 0;
    for (const char* name :
         {"force", "direction", "depth", "couple", "volume", "overlap", "converged"})
      EXPECT_NE(std::find(vtp.arrays.begin(), vtp.arrays.end(), name), vtp.arrays.end()) << name;
  }
  EXPECT_GT(withContacts, 0u);
}

TEST(DemCli, ReadsAConfigFileThatOptionsOverride) {
  const TemporaryFolder folder("config");
  const fs::path config = folder.path / "run.cfg";
  std::ofstream(config) << "# a small settle run\n\nscenario = settle\nparticles = 8   # few\n"
                           "seed = 3\nsteps = 4\nrestitution = 0.7\nfriction=0\n";
  const CliRun fromFile = runDelta("dem '" + config.string() + "' --json");
  ASSERT_EQ(fromFile.exitCode, 0) << fromFile.err;
  EXPECT_NE(fromFile.out.find("\"scenario\":\"settle\""), std::string::npos) << fromFile.out;
  EXPECT_EQ(jsonNumber(fromFile.out, "particles"), 8.0);
  EXPECT_EQ(jsonNumber(fromFile.out, "steps"), 4.0);
  const CliRun overridden = runDelta("dem --config '" + config.string() + "' --steps 2 --json");
  ASSERT_EQ(overridden.exitCode, 0) << overridden.err;
  EXPECT_EQ(jsonNumber(overridden.out, "steps"), 2.0);
  // A UTF-8 byte-order mark before the first key (some editors write one) is not part of it.
  const fs::path marked = folder.path / "marked.cfg";
  std::ofstream(marked) << "\xEF\xBB\xBFscenario = settle\nparticles = 8\nsteps = 4\n";
  const CliRun fromMarked = runDelta("dem '" + marked.string() + "' --json");
  ASSERT_EQ(fromMarked.exitCode, 0) << fromMarked.err;
  EXPECT_EQ(jsonNumber(fromMarked.out, "particles"), 8.0);
}

TEST(DemCli, AConfigsBinaryBytesAreQuotedInHexNotWrittenRaw) {
  // A NUL cut the message short ("scenario 'two-"); other bytes reached the terminal raw.
  const TemporaryFolder folder("config_bytes");
  const fs::path nul = folder.path / "nul.cfg";
  std::ofstream(nul, std::ios::binary) << std::string("scenario = two-\0particles\n", 26);
  const CliRun withNul = runDelta("dem '" + nul.string() + "'");
  expectOneLineError(withNul, "scenario 'two-\\x00particles' is not a scenario");
  const fs::path garbage = folder.path / "garbage.cfg";
  std::ofstream(garbage, std::ios::binary) << "\x1B]0;\x07\xFF\xFE = 3\nsteps = \x1B[2J\n";
  const CliRun withGarbage = runDelta("dem '" + garbage.string() + "'");
  expectOneLineError(withGarbage, ":1: \\x1B]0;\\x07\\xFF\\xFE: unknown key");
  for (const CliRun* run : {&withNul, &withGarbage})
    for (char c : run->err)
      EXPECT_TRUE(static_cast<unsigned char>(c) >= 0x20 || c == '\n') << run->err;
}

TEST(DemCli, UsesAClosedMeshAsTheParticleShape) {
  const CliRun run =
      runDelta("dem settle --particles 8 --steps 3 --particle-mesh builtin:icosphere:1 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(jsonNumber(run.out, "triangles"), 8.0 * 80.0) << run.out;
  expectOneLineError(runDelta("dem settle --steps 1 --particle-mesh builtin:quad"), "closed");
  expectOneLineError(
      runDelta("dem settle --steps 1 --particle-mesh builtin:box --particle-radius 1"),
      "--particle-radius");
}

TEST(DemCli, RejectsBadInputWithOneLine) {
  expectOneLineError(runDelta("dem frobnicate"), "frobnicate");
  expectOneLineError(runDelta("dem two-particles --restitution 1.5"), "--restitution");
  expectOneLineError(runDelta("dem two-particles --restitution -0.1"), "--restitution");
  expectOneLineError(runDelta("dem two-particles --restitution nan"), "--restitution");
  expectOneLineError(runDelta("dem two-particles --friction -1"), "--friction");
  expectOneLineError(runDelta("dem two-particles --offset 1"), "--offset");
  expectOneLineError(runDelta("dem two-particles --steps 0"), "--steps");
  expectOneLineError(runDelta("dem two-particles --steps -5"), "--steps");
  expectOneLineError(runDelta("dem two-particles --steps 2.5"), "--steps");
  expectOneLineError(runDelta("dem settle --particles 0"), "--particles");
  expectOneLineError(runDelta("dem hopper --particles -3"), "--particles");
  expectOneLineError(runDelta("dem two-particles --particles 5"), "--particles");
  expectOneLineError(runDelta("dem settle --offset 0.2"), "--offset");
  expectOneLineError(runDelta("dem settle --output-every 0"), "--output-every");
  expectOneLineError(runDelta("dem --particle-radius 0.01"), "particle_mesh");
  expectOneLineError(runDelta("dem --config /nonexistent/run.cfg"), "/nonexistent/run.cfg");
  expectOneLineError(runDelta("dem two-particles --steps"), "--steps");
  // Wrapped round or saturated by the unsigned conversion, these ran without checkpoints.
  for (const char* every : {"-1", "-5", "18446744073709551616", "1e23", "2.5"})
    expectOneLineError(
        runDelta(std::string("dem two-particles --steps 3 --checkpoint-every ") + every),
        "--checkpoint-every '" + std::string(every) + "' must be a whole number");
}

TEST(DemCli, NamesTheFileLineAndKeyOfABadConfig) {
  const TemporaryFolder folder("bad_config");
  const auto check = [&](const std::string& text, const std::string& needle) {
    const fs::path config = folder.path / "bad.cfg";
    std::ofstream(config) << text;
    expectOneLineError(runDelta("dem '" + config.string() + "'"), config.string() + needle);
  };
  check("scenario = settle\nrestitution = 1.5\n", ":2: restitution");
  check("scenario = settle\nwobble = 2\n", ":2: wobble: unknown key");
  check("# fine\nscenario settle\n", ":2:");
  check("steps = 3\nsteps = 4\n", ":2: steps");
  check("scenario = tumbler\n", ":1: scenario");
  check("particles = many\n", ":1: particles");
  check("steps =\n", ":1: steps");
  check("scenario = two-particles\nparticles = 4\n", ":2: particles");
}

TEST(DemCli, RefusesToWriteIntoAFile) {
  const TemporaryFolder folder("into_file");
  const fs::path file = folder.path / "not_a_folder";
  std::ofstream(file) << "x";
  expectOneLineError(runDelta("dem two-particles --steps 2 --out '" + file.string() + "'"),
                     file.string());
  expectOneLineError(
      runDelta("dem two-particles --steps 2 --out '" + (file / "below").string() + "'"),
      file.string());
  EXPECT_EQ(slurp(file), "x");
}

TEST(DemCli, HasHelpThatDocumentsTheConfig) {
  const CliRun run = runDelta("dem --help");
  EXPECT_EQ(run.exitCode, 0);
  for (const char* text : {"Usage", "two-particles", "--restitution", "particle_mesh", "log.csv"})
    EXPECT_NE(run.out.find(text), std::string::npos) << text;
}

}  // namespace
