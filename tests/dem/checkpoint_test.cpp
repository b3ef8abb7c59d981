#include "delta/dem/checkpoint.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <string_view>

#include "delta/core/error.h"
#include "delta/dem/scenarios.h"
#include "delta/mesh/primitives.h"

#include "centimetre_parameters.h"
#include "forged_checkpoint.h"
#include "io/test_files.h"

namespace delta::dem {
namespace {

using delta::io::TempDir;

/// Runs `body` with `threads` OpenMP threads, then restores the count.
void withThreads(int threads, const std::function<void()>& body) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  body();
  omp_set_num_threads(before);
}

bool sameBits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

bool sameBits(const Vec3& a, const Vec3& b) {
  return sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z);
}

bool sameBits(const Quaternion& a, const Quaternion& b) {
  return sameBits(a.w, b.w) && sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z);
}

/// Every particle, the clock, the obstacles and the contacts, bit for bit; and the digests.
void expectSameState(const World& a, const World& b) {
  ASSERT_EQ(a.stepCount(), b.stepCount());
  EXPECT_TRUE(sameBits(a.time(), b.time()));
  ASSERT_EQ(a.particles().size(), b.particles().size());
  for (std::size_t i = 0; i < a.particles().size(); ++i) {
    const Particle& p = a.particles()[i];
    const Particle& q = b.particles()[i];
    EXPECT_EQ(p.shape, q.shape) << i;
    EXPECT_TRUE(sameBits(p.position, q.position)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.orientation, q.orientation)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.velocity, q.velocity)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.angularVelocity, q.angularVelocity)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.angularMomentum, q.angularMomentum)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.force, q.force)) << "particle " << i;
    EXPECT_TRUE(sameBits(p.torque, q.torque)) << "particle " << i;
  }
  ASSERT_EQ(a.obstacles().size(), b.obstacles().size());
  for (std::size_t o = 0; o < a.obstacles().size(); ++o) {
    EXPECT_TRUE(sameBits(a.obstacles()[o].pose.rotation, b.obstacles()[o].pose.rotation));
    EXPECT_TRUE(sameBits(a.obstacles()[o].pose.translation, b.obstacles()[o].pose.translation));
  }
  ASSERT_EQ(a.contacts().size(), b.contacts().size());
  for (std::size_t c = 0; c < a.contacts().size(); ++c) {
    EXPECT_TRUE(sameBits(a.contacts()[c].force, b.contacts()[c].force)) << "contact " << c;
    EXPECT_TRUE(sameBits(a.contacts()[c].couple, b.contacts()[c].couple)) << "contact " << c;
    EXPECT_TRUE(sameBits(a.contacts()[c].volume, b.contacts()[c].volume)) << "contact " << c;
  }
  EXPECT_EQ(a.parameters().contactModel, b.parameters().contactModel);
  EXPECT_TRUE(sameBits(a.energies().total(), b.energies().total()));
  EXPECT_EQ(a.stateDigest(), b.stateDigest());
}

/// The scenarios the restart tests run: small, with friction, contacts at the checkpoint and
/// (hopper) an obstacle that particles touch.
struct Case {
  const char* name;
  std::function<Scenario()> make;
  std::size_t before;  ///< steps before the checkpoint (then on to the next with contacts)
  std::size_t after;   ///< steps after it
};

std::vector<Case> cases() {
  return {
      {"two_particles_grazing", [] { return twoParticles(0.9, 0.4, 0.5); }, 60, 60},
      {"settle", [] { return settle(27, 3); }, 1500, 200},
      {"settle_spheres", [] { return settle(27, 3, ParticleKind::Sphere); }, 1000, 200},
      {"hopper", [] { return hopper(40, 2); }, 6900, 100},
      {"settle_volume_law", [] { return settle(8, 5, ParticleKind::Mesh, ContactModel::volume); },
       1200, 200},
  };
}

class CheckpointRestart : public testing::TestWithParam<int> {};

TEST_P(CheckpointRestart, NPlusMStepsEqualAnUninterruptedRunBitForBit) {
  withThreads(GetParam(), [] {
    for (const Case& c : cases()) {
      SCOPED_TRACE(c.name);
      Scenario whole = c.make();
      Scenario stopped = c.make();
      whole.world.run(c.before);
      stopped.world.run(c.before);
      for (std::size_t extra = 0; stopped.world.contacts().empty() && extra < 1000; ++extra) {
        whole.world.step();  // on to a step with contacts
        stopped.world.step();
      }
      // The checkpoint must hold the state the next step depends on: contacts with friction.
      EXPECT_GT(stopped.world.contacts().size(), 0u);
      const std::string bytes = checkpointBytes(stopped.world, "a note");
      Checkpoint restarted = readCheckpoint(bytes, "bytes");
      EXPECT_EQ(restarted.note, "a note");
      expectSameState(stopped.world, restarted.world);
      EXPECT_EQ(checkpointBytes(restarted.world, "a note"), bytes);  // nothing lost
      whole.world.run(c.after);
      restarted.world.run(c.after);
      expectSameState(whole.world, restarted.world);
    }
  });
}

INSTANTIATE_TEST_SUITE_P(Threads, CheckpointRestart, testing::Values(1, 2));

// A World's copy holds copies of its pairs' contact and overlap caches (World::Held), not the
// same ones: the copy and the original, stepped in turn, each step as an uninterrupted run.
TEST(Checkpoint, ACopiedWorldStepsAsTheOriginalWithCachesOfItsOwn) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Scenario original = c.make();
    original.world.run(c.before);
    World copy = original.world;
    for (std::size_t s = 0; s < c.after; ++s) {
      original.world.step();
      copy.step();
      if (s == c.after / 2) original.world.run(3);  // ahead: the copy's caches left behind
    }
    Scenario uninterrupted = c.make();
    uninterrupted.world.run(c.before + c.after);
    expectSameState(uninterrupted.world, copy);
    uninterrupted.world.run(3);
    expectSameState(uninterrupted.world, original.world);
  }
}

TEST(Checkpoint, DigestIsTheSameOnOneAndTwoThreads) {
  std::string one, two;
  withThreads(1, [&] {
    Scenario scenario = settle(27, 3);
    scenario.world.run(300);
    one = scenario.world.stateDigest();
  });
  withThreads(2, [&] {
    Scenario scenario = settle(27, 3);
    scenario.world.run(300);
    two = scenario.world.stateDigest();
  });
  EXPECT_EQ(one, two);
  EXPECT_EQ(one.size(), 16u);
  Scenario other = settle(27, 3);
  other.world.run(301);
  EXPECT_NE(other.world.stateDigest(), one);
}

TEST(Checkpoint, VolumeLawDigestIsTheSameOnOneAndTwoThreads) {
  std::string one, two;
  for (const int threads : {1, 2})
    withThreads(threads, [&] {
      Scenario scenario = settle(27, 3, ParticleKind::Mesh, ContactModel::volume);
      scenario.world.run(1300);  // the first layer has landed
      EXPECT_GT(scenario.world.contacts().size(), 0u);
      (threads == 1 ? one : two) = scenario.world.stateDigest();
    });
  EXPECT_EQ(one, two);
}

TEST(Checkpoint, AVersion1CheckpointLoadsAsAPointLawWorld) {
  // Version 1 had no contact model byte (after the gravity in PARM) and no couples or volumes
  // in CONT. A world that has not stepped has no contacts: its version 1 file is the version 2
  // one less that byte.
  Scenario scenario = settle(8, 5);
  const std::string bytes = checkpointBytes(scenario.world, "old");
  constexpr std::size_t kHeader = 24, kModelByte = kHeader + 4 + 7 * 8 + 3 * 8;
  ASSERT_EQ(bytes[kModelByte], 0);  // the point law
  std::string payload = bytes.substr(kHeader);
  payload.erase(kModelByte - kHeader, 1);
  std::string header = bytes.substr(0, kHeader);
  header[8] = 1;  // the version; then the payload size and its CRC made to match
  const std::string old = fuzz::withMatchingHeader(header + payload);
  Checkpoint loaded = readCheckpoint(old, "old");
  EXPECT_EQ(loaded.note, "old");
  EXPECT_EQ(loaded.world.parameters().contactModel, ContactModel::point);
  expectSameState(scenario.world, loaded.world);
  EXPECT_EQ(checkpointBytes(loaded.world, "old"), bytes);  // written again as version 2
  scenario.world.run(20);
  loaded.world.run(20);
  expectSameState(scenario.world, loaded.world);
}

TEST(Checkpoint, SaveAndLoadAFileThenContinue) {
  const TempDir folder;
  Scenario whole = settle(8, 5);
  whole.world.run(400);
  whole.world.save(folder / "run.ckpt");
  World loaded = World::load(folder / "run.ckpt");
  EXPECT_EQ(loaded.stateDigest(), whole.world.stateDigest());
  whole.world.run(50);
  loaded.run(50);
  expectSameState(whole.world, loaded);
  // Saving again replaces the file whole.
  loaded.save(folder / "run.ckpt");
  EXPECT_EQ(loadCheckpoint(folder / "run.ckpt").world.stateDigest(), loaded.stateDigest());
}

TEST(Checkpoint, ASetTimeStepAndAWorldNeverSteppedComeBack) {
  Scenario scenario = twoParticles();
  scenario.world.setTimeStep(scenario.world.parameters().timeStep / 2);
  World copy = readCheckpoint(checkpointBytes(scenario.world)).world;
  EXPECT_TRUE(sameBits(copy.parameters().timeStep, scenario.world.parameters().timeStep));
  scenario.world.run(10);
  copy.run(10);
  expectSameState(scenario.world, copy);
}

/// The message of the delta::Error that `action` throws ("" when it does not).
std::string errorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

std::string loadError(const std::string& bytes) {
  return errorOf([&] { readCheckpoint(bytes, "ck"); });
}

TEST(CheckpointErrors, ForeignTruncatedCorruptAndOtherVersions) {
  Scenario scenario = settle(8, 5);
  scenario.world.run(100);
  const std::string bytes = checkpointBytes(scenario.world, "note");

  EXPECT_NE(loadError("").find("not a Δ DEM checkpoint"), std::string::npos);
  EXPECT_NE(loadError("solid cube\nfacet").find("not a Δ DEM checkpoint"), std::string::npos);
  EXPECT_NE(loadError("DELTA").find("truncated"), std::string::npos);  // cut in the magic
  for (const std::size_t size :
       {std::size_t{8}, std::size_t{20}, std::size_t{24}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string message = loadError(bytes.substr(0, size));
    EXPECT_NE(message.find("truncated"), std::string::npos) << size << ": " << message;
    EXPECT_NE(message.find("'ck'"), std::string::npos) << message;
  }
  EXPECT_NE(loadError(bytes + "x").find("corrupt"), std::string::npos);
  for (const std::size_t at : {std::size_t{30}, bytes.size() / 2, bytes.size() - 1}) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    EXPECT_NE(loadError(flipped).find("corrupt"), std::string::npos) << at;
  }
  std::string newer = bytes;
  newer[8] = static_cast<char>(kCheckpointVersion + 1);
  EXPECT_NE(loadError(newer).find("format version " + std::to_string(kCheckpointVersion + 1)),
            std::string::npos)
      << loadError(newer);

  const TempDir folder;
  EXPECT_NE(errorOf([&] { World::load(folder / "missing.ckpt"); }).find("missing.ckpt"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { World::load(folder.path()); }).find("cannot read"), std::string::npos);
  const std::filesystem::path cut = folder.write("cut.ckpt", bytes.substr(0, 100));
  const std::string message = errorOf([&] { World::load(cut); });
  EXPECT_NE(message.find("cut.ckpt"), std::string::npos) << message;
  EXPECT_NE(message.find("truncated"), std::string::npos) << message;
}

/// Two icospheres side by side on a floor, sliding with friction: contacts and springs of both
/// kinds, with an obstacle.
World slidingPair() {
  World world(test::centimetreParameters(0.01, 1.0, 0.5, 0.5, {0, 0, -9.81}));
  world.addShape(primitives::icosphere(2, 0.01), 2500.0);
  world.addObstacle(primitives::quad(1.0, 1.0));
  world.addParticle(0, {{-0.0099, 0, 0.0099}, {}, {0.2, 0.1, 0}, {}});
  world.addParticle(0, {{0.0099, 0, 0.0099}, {}, {0.1, -0.1, 0}, {}});
  world.run(20);
  return world;
}

/// A checkpoint's bytes with a field changed and the header's size and CRC made to match, as a
/// file made by hand (or by a program that is not Δ) would have them.
class Forged {
 public:
  explicit Forged(const std::string& bytes) : bytes_(bytes) {}
  /// Where the first `tag` after `from` starts.
  std::size_t section(const char* tag, std::size_t from = 24) const {
    const std::size_t at = bytes_.find(tag, from);
    EXPECT_NE(at, std::string::npos) << tag;
    return at;
  }
  std::uint64_t u64(std::size_t at) const {
    std::uint64_t value = 0;
    for (int b = 0; b < 8; ++b)
      value |= std::uint64_t{static_cast<unsigned char>(bytes_[at + b])} << (8 * b);
    return value;
  }
  Forged& u64(std::size_t at, std::uint64_t value) {
    for (int b = 0; b < 8; ++b)
      bytes_[at + b] = static_cast<char>((value >> (8 * b)) & 0xffu);
    return *this;
  }
  Forged& u32(std::size_t at, std::uint32_t value) {
    for (int b = 0; b < 4; ++b)
      bytes_[at + b] = static_cast<char>((value >> (8 * b)) & 0xffu);
    return *this;
  }
  Forged& f64(std::size_t at, double value) { return u64(at, std::bit_cast<std::uint64_t>(value)); }
  /// The forged file: its bytes with the CRC made to match.
  std::string forged() const { return fuzz::withMatchingHeader(bytes_); }
  /// The load error of the forged file ("" when it loads).
  std::string error() const { return loadError(forged()); }

 private:
  std::string bytes_;
};

TEST(CheckpointErrors, ValuesNoWorldHoldsAreRefusedThoughTheChecksumMatches) {
  const World world = slidingPair();
  ASSERT_EQ(world.contacts().size(), 3u);
  const Forged good(checkpointBytes(world));
  EXPECT_EQ(good.error(), "");  // the forging itself changes nothing
  const std::size_t springs = good.section("SPRG");
  ASSERT_EQ(good.u64(springs + 4), 1u);        // the particles' springs
  ASSERT_EQ(good.u64(springs + 12 + 40), 2u);  // the obstacles'

  // SHAP: a count, then per shape its density, volume, mass, centroid (24 bytes), inertia (72),
  // sphere radius and mesh: the numbers must be the mesh's (up to the rounding of deriving them
  // again), or the body would move as another.
  const std::size_t shape0 = good.section("SHAP") + 12;
  const double volume = std::bit_cast<double>(good.u64(shape0 + 8));
  EXPECT_EQ(Forged(good).f64(shape0 + 8, volume * (1.0 + 0x1p-40)).error(), "");
  EXPECT_NE(Forged(good).f64(shape0 + 8, volume * 1.001).error().find("do not match the mesh"),
            std::string::npos);
  const double ixx = std::bit_cast<double>(good.u64(shape0 + 48));
  EXPECT_NE(Forged(good).f64(shape0 + 48, ixx * 1.001).error().find("do not match the mesh"),
            std::string::npos);
  EXPECT_NE(Forged(good).f64(shape0 + 48, 0.0).error().find("do not match the mesh"),
            std::string::npos);  // a singular inertia (its inverse not finite)
  // A sphere shape's numbers are the sphere's.
  Scenario spheres = settle(2, 1, ParticleKind::Sphere);
  const Forged sphere(checkpointBytes(spheres.world));
  const std::size_t sphere0 = sphere.section("SHAP") + 12;
  EXPECT_EQ(sphere.error(), "");
  EXPECT_NE(Forged(sphere)
                .f64(sphere0 + 120, 1.01 * std::bit_cast<double>(sphere.u64(sphere0 + 120)))
                .error()
                .find("do not match"),
            std::string::npos);  // the radius

  // PART: a count, then per particle its shape (4 bytes), position (24), orientation (32), ...
  const std::size_t particle0 = good.section("PART") + 12;
  const std::size_t orientation = particle0 + 4 + 24;
  for (const double w : {0.0, 2.0, 1.0 + 1e-6}) {
    const std::string message = Forged(good).f64(orientation, w).error();
    EXPECT_NE(message.find("corrupt DEM checkpoint: particle 0's orientation is not a unit"),
              std::string::npos)
        << w << ": " << message;
  }
  Forged rounded(good);  // every component 2⁻⁴⁰ larger: within rounding of a unit quaternion
  for (std::size_t k = 0; k < 4; ++k)
    rounded.f64(orientation + 8 * k,
                std::bit_cast<double>(good.u64(orientation + 8 * k)) * (1.0 + 0x1p-40));
  EXPECT_EQ(rounded.error(), "");

  // SPRG: the particles' springs (a count, then per spring its key, displacement and twist),
  // then the obstacles'.
  EXPECT_NE(Forged(good).f64(springs + 12 + 8, std::nan("")).error().find("not finite"),
            std::string::npos);
  for (const std::uint64_t key :
       {std::uint64_t{1} << 32 | 0, std::uint64_t{0} << 32 | 0, std::uint64_t{0} << 32 | 2})
    EXPECT_NE(Forged(good).u64(springs + 12, key).error().find("a spring's pair key names no pair"),
              std::string::npos)
        << std::hex << key;
  // A spring far longer than its contact's forces could have made it (particle 0's on the
  // floor, along x) is finite, and reads; the Coulomb limit then makes it NaN (and its force),
  // which the step refuses to end with (a checkpoint of it would not read back).
  World stretched = readCheckpoint(Forged(good).f64(springs + 12 + 40 + 16, 1e306).forged()).world;
  const std::string message = errorOf([&] { stretched.run(5); });
  EXPECT_NE(message.find("particle 0 is no longer finite at step 21"), std::string::npos)
      << message;
  const std::size_t obstacleSprings = springs + 12 + 40;
  EXPECT_NE(Forged(good)
                .u64(obstacleSprings + 8, std::uint64_t{0} << 32 | 1)  // obstacle 1 of 1
                .error()
                .find("a spring's pair key names no pair"),
            std::string::npos);

  // OBST: the mesh (vertex count, vertices, triangle count, triangles), then the pose.
  const std::size_t obstacle = good.section("OBST") + 12;
  const std::size_t vertices = good.u64(obstacle);
  const std::size_t triangles = good.u64(obstacle + 8 + 24 * vertices);
  const std::size_t pose = obstacle + 8 + 24 * vertices + 8 + 12 * triangles;
  for (const double w : {0.0, 3.0, std::nan("")})
    EXPECT_NE(Forged(good).f64(pose, w).error().find("obstacle 0's pose is not a rotation"),
              std::string::npos)
        << w;
  EXPECT_NE(Forged(good).f64(pose + 32, std::nan("")).error().find("obstacle 0's pose is not a"),
            std::string::npos);  // the translation

  // CONT: per contact its point (x, normal, direction, distance, two flags, two triangles),
  // then the pair (two ids, a flag), the depth, force, couple and volume.
  const std::size_t contact0 = good.section("CONT") + 12;
  const std::size_t ids = contact0 + 3 * 24 + 8 + 2 + 8;
  EXPECT_NE(Forged(good).f64(contact0 + 24, std::nan("")).error().find("contact 0 has a value"),
            std::string::npos);
  EXPECT_NE(Forged(good).u32(ids, 7).error().find("contact 0 names no pair"), std::string::npos);
  EXPECT_NE(Forged(good).u32(ids + 4, 9).error().find("contact 0 names no pair"),
            std::string::npos);
  EXPECT_EQ(Forged(good).u32(ids - 8, 319).error(), "");  // an icosphere of 2 subdivisions
  EXPECT_NE(Forged(good).u32(ids - 8, 320).error().find("contact 0 names a triangle"),
            std::string::npos);
}

}  // namespace
}  // namespace delta::dem
