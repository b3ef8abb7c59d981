#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "delta/dem/world.h"

/// @file
/// Checkpoints of a DEM simulation: everything the next step of a World depends on, in one
/// binary file, so that a run stopped after N steps and continued for M more ends bit for bit in
/// the state of N + M uninterrupted steps (on any thread count; `delta dem` under mpirun, on any
/// number of ranks).
///
/// A checkpoint holds the time and the step count; the parameters; every shape (its body-frame
/// mesh, density and mass properties, embedded as stored, so the rebuilt shape is the same to
/// the bit); every particle's shape, pose, velocity, angular velocity, angular momentum and the
/// force and torque of the last evaluation (the next step's first half kick uses them); the
/// friction springs of the touching pairs (keyed by the pair's ids); every obstacle's mesh,
/// motion and pose (an obstacle's pose is accumulated step by step, not a function of time);
/// the contact points and elastic energy of the last evaluation (for output); and a note, text
/// the caller keeps with it (`delta dem` keeps the scenario's settings and its frames there).
/// Nothing else carries from one step to the next: the broad phase and the placed meshes are
/// made anew each step, and the built-in scenarios add no particles after the start (there is
/// no random state to keep).
///
/// Format (version 2), all little-endian, doubles as their IEEE-754 bits:
///
///     "DELTADEM"  u32 version  u64 payload bytes  u32 CRC-32 of the payload (zlib's)  payload
///
/// The payload is a sequence of sections, each a four-letter tag followed by its fields:
/// "PARM" (parameters, time, step, flags), "SHAP" (shapes), "PART" (particles), "SPRG"
/// (springs), "OBST" (obstacles), "CONT" (contacts), "NOTE". Each count is checked against the
/// bytes that remain before anything is allocated. Version 2 added the contact model (a byte
/// after the gravity in "PARM": 0 point, 1 volume) and each contact's couple and overlap volume
/// (after its force in "CONT"); version 1 files (written before the volume law) still load, as
/// point-law worlds with zero couples. Files are always written as version 2.
///
/// Reading throws delta::Error naming the origin (the file) for: a file that is not a
/// checkpoint ("not a Δ DEM checkpoint"), another format version, a file cut short
/// ("truncated": fewer bytes than its header announces), a checksum that does not match or a
/// payload that does not parse ("corrupt"), values a World refuses (as World's builders), and
/// values no World holds though the checksum matches ("corrupt": an orientation or an obstacle's
/// rotation that is not a unit quaternion, a number that is not finite, a friction spring or a
/// contact whose pair key names no pair of the file's particles and obstacles, a contact's
/// triangle its mesh lacks).
///
/// Threading: the functions below read the World they are given (const) and build new ones;
/// they may run concurrently with other const use of the same World, never with a step.
namespace delta::dem {

/// The checkpoint format version this build writes (and the newest it reads).
inline constexpr std::uint32_t kCheckpointVersion = 2;
/// The oldest checkpoint format version this build reads.
inline constexpr std::uint32_t kOldestCheckpointVersion = 1;

/// A World and the note it was saved with.
///
/// Threading: as World.
struct Checkpoint {
  World world;
  std::string note;
};

/// The checkpoint of `world` (with `note`) as bytes, as saveCheckpoint writes them.
std::string checkpointBytes(const World& world, std::string_view note = {});
/// Reads checkpointBytes' bytes; `origin` names them in errors (a path, "bytes"). Throws
/// delta::Error as the file comment says.
Checkpoint readCheckpoint(std::string_view bytes, const std::string& origin = "checkpoint");
/// Writes checkpointBytes(world, note) to `path` atomically (io/atomic_file.h): a reader sees
/// the previous checkpoint or the new one, never a part. Throws delta::Error naming the path and
/// the reason.
void saveCheckpoint(const std::filesystem::path& path, const World& world,
                    std::string_view note = {});
/// Reads the checkpoint at `path`; throws delta::Error naming the path when it cannot be read
/// or is not a valid checkpoint (as readCheckpoint).
Checkpoint loadCheckpoint(const std::filesystem::path& path);

/// A digest of the state that the dynamics carry, for comparing runs: 16 hex digits of a 64-bit
/// hash over the time, the step count and, by particle id, every position, orientation,
/// velocity, angular velocity, angular momentum, force and torque, then the friction springs by
/// pair key and the obstacles' poses, each double as its bits. Equal states give equal digests
/// whatever the thread count (and, through DistributedWorld's gathered state, rank count);
/// timings and statistics are not part of it.
std::string stateDigest(const World& world);

}  // namespace delta::dem
