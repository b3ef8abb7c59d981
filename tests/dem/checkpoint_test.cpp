#include "delta/dem/checkpoint.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include "delta/core/error.h"
#include "delta/dem/scenarios.h"

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

/// The CRC-32 (zlib's polynomial) of `bytes`, to forge a checkpoint of the older format.
std::uint32_t crc32Of(std::string_view bytes) {
  std::uint32_t crc = 0xffffffffu;
  for (const char c : bytes) {
    crc ^= static_cast<unsigned char>(c);
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
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
  std::string old = bytes.substr(0, kHeader);
  old[8] = 1;  // the version, then the payload size and its CRC, little-endian
  for (int b = 0; b < 8; ++b)
    old[12 + b] = static_cast<char>((std::uint64_t{payload.size()} >> (8 * b)) & 0xffu);
  const std::uint32_t crc = crc32Of(payload);
  for (int b = 0; b < 4; ++b)
    old[20 + b] = static_cast<char>((crc >> (8 * b)) & 0xffu);
  old += payload;
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

}  // namespace
}  // namespace delta::dem
