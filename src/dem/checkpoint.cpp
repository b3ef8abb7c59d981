#include "delta/dem/checkpoint.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/io/atomic_file.h"
#include "delta/io/regular_file.h"
#include "delta/mesh/mass_properties.h"

#include "detail/finite_state.h"

namespace delta::dem {

namespace {

constexpr std::string_view kMagic = "DELTADEM";
constexpr std::size_t kHeaderBytes = 8 + 4 + 8 + 4;

std::uint32_t crc32Of(std::string_view bytes) noexcept {
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t done = 0; done < bytes.size();) {
    const std::size_t chunk = std::min<std::size_t>(bytes.size() - done, 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + done), static_cast<uInt>(chunk));
    done += chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

/// Appends little-endian fields.
class Writer {
 public:
  void u8(std::uint8_t value) { bytes_.push_back(static_cast<char>(value)); }
  void u32(std::uint32_t value) {
    for (int b = 0; b < 4; ++b)
      bytes_.push_back(static_cast<char>((value >> (8 * b)) & 0xffu));
  }
  void u64(std::uint64_t value) {
    for (int b = 0; b < 8; ++b)
      bytes_.push_back(static_cast<char>((value >> (8 * b)) & 0xffu));
  }
  void f64(double value) { u64(std::bit_cast<std::uint64_t>(value)); }
  void vec(const Vec3& v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }
  void quaternion(const Quaternion& q) {
    f64(q.w);
    f64(q.x);
    f64(q.y);
    f64(q.z);
  }
  void tag(std::string_view name) { bytes_.append(name); }
  void text(std::string_view text) {
    u64(text.size());
    bytes_.append(text);
  }
  void mesh(const Mesh& mesh) {
    u64(mesh.vertices().size());
    for (const Vec3& v : mesh.vertices())
      vec(v);
    u64(mesh.triangles().size());
    for (const TriangleIndices& t : mesh.triangles())
      for (const std::uint32_t index : t)
        u32(index);
  }
  /// A particle's shape and motion state (what the checkpoint and the digest both hold).
  void particle(const Particle& p) {
    u32(p.shape);
    vec(p.position);
    quaternion(p.orientation);
    vec(p.velocity);
    vec(p.angularVelocity);
    vec(p.angularMomentum);
    vec(p.force);
    vec(p.torque);
  }
  void spring(const std::pair<std::uint64_t, TangentialSpring>& entry) {
    u64(entry.first);
    vec(entry.second.displacement);
    f64(entry.second.twist);
  }
  std::string& bytes() noexcept { return bytes_; }

 private:
  std::string bytes_;
};

/// Reads what Writer wrote; every read past the end, and every count larger than the bytes
/// left could hold, throws "corrupt".
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& origin) : bytes_(bytes), origin_(origin) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw Error("'" + origin_ + "': corrupt DEM checkpoint: " + what + " (at byte " +
                std::to_string(kHeaderBytes + position_) + ")");
  }
  void need(std::size_t count) const {
    if (bytes_.size() - position_ < count) fail("a field runs past the end of the payload");
  }
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(bytes_[position_++]);
  }
  std::uint32_t u32() {
    need(4);
    std::uint32_t value = 0;
    for (int b = 0; b < 4; ++b)
      value |= std::uint32_t{static_cast<unsigned char>(bytes_[position_++])} << (8 * b);
    return value;
  }
  std::uint64_t u64() {
    need(8);
    std::uint64_t value = 0;
    for (int b = 0; b < 8; ++b)
      value |= std::uint64_t{static_cast<unsigned char>(bytes_[position_++])} << (8 * b);
    return value;
  }
  double f64() { return std::bit_cast<double>(u64()); }
  Vec3 vec() {
    const double x = f64(), y = f64();
    return {x, y, f64()};
  }
  Quaternion quaternion() {
    Quaternion q;  // as stored, not renormalised: the state must come back to the bit
    q.w = f64();
    q.x = f64();
    q.y = f64();
    q.z = f64();
    return q;
  }
  bool flag() {
    const std::uint8_t value = u8();
    if (value > 1) fail("a flag is " + std::to_string(value));
    return value == 1;
  }
  void tag(std::string_view name) {
    need(name.size());
    if (bytes_.substr(position_, name.size()) != name)
      fail("section " + std::string(name) + " is missing");
    position_ += name.size();
  }
  /// A count of items of at least `itemBytes` each, checked against the bytes left and the
  /// memory limit before anything is allocated.
  std::size_t count(std::size_t itemBytes, const char* what) {
    const std::uint64_t n = u64();
    if (n > (bytes_.size() - position_) / itemBytes)
      fail(std::string(what) + " count " + std::to_string(n) + " is more than the file holds");
    requireMemory(static_cast<double>(n) * static_cast<double>(itemBytes), origin_ + ": " + what);
    return static_cast<std::size_t>(n);
  }
  std::string text() {
    const std::size_t n = count(1, "note byte");
    std::string value(bytes_.substr(position_, n));
    position_ += n;
    return value;
  }
  Mesh mesh(const std::string& what) {
    std::vector<Vec3> vertices(count(24, "vertex"));
    for (Vec3& v : vertices)
      v = vec();
    std::vector<TriangleIndices> triangles(count(12, "triangle"));
    for (TriangleIndices& t : triangles)
      for (std::uint32_t& index : t)
        index = u32();
    try {
      return Mesh(std::move(vertices), std::move(triangles));
    } catch (const Error& error) {
      fail(what + ": " + error.what());
    }
  }
  std::pair<std::uint64_t, TangentialSpring> spring() {
    std::pair<std::uint64_t, TangentialSpring> entry;
    entry.first = u64();
    entry.second.displacement = vec();
    entry.second.twist = f64();
    return entry;
  }
  bool atEnd() const noexcept { return position_ == bytes_.size(); }

 private:
  std::string_view bytes_;
  std::string origin_;
  std::size_t position_ = 0;
};

/// Whether `q` is an orientation as a World holds one: finite and of unit norm up to rounding
/// (every orientation a World makes is renormalised; Quaternion's product, World::addParticle).
/// Anything else would turn a body by a rotation the file does not say.
bool unitQuaternion(const Quaternion& q) noexcept {
  const double norm2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  return std::abs(norm2 - 1.0) <= 1e-9;  // false for NaN and ±∞
}

/// The ids of pair key `key` (lower id, then the other particle's id or the obstacle's index:
/// World's neighbour list) name a particle and a particle after it, or a particle and an
/// obstacle.
bool pairKeyInRange(std::uint64_t key, bool withObstacle, std::size_t particles,
                    std::size_t obstacles) noexcept {
  const std::uint64_t first = key >> 32, second = key & 0xffffffffu;
  return first < particles &&
         (withObstacle ? second < obstacles : first < second && second < particles);
}

/// FNV-1a over the bytes, then a SplitMix64 finaliser so that every bit depends on every byte.
std::uint64_t hash64(std::string_view bytes) noexcept {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  hash ^= hash >> 30;
  hash *= 0xbf58476d1ce4e5b9ull;
  hash ^= hash >> 27;
  hash *= 0x94d049bb133111ebull;
  hash ^= hash >> 31;
  return hash;
}

}  // namespace

/// World's private members, written and restored (World declares it a friend).
class CheckpointCodec {
 public:
  static std::string payload(const World& world, std::string_view note) {
    Writer out;
    const Parameters& p = world.parameters_;
    out.tag("PARM");
    for (const double value : {p.timeStep, p.epsilon, p.filterDistance, p.stiffness, p.restitution,
                               p.friction, p.tangentialStiffnessRatio})
      out.f64(value);
    out.vec(p.gravity);
    out.u8(static_cast<std::uint8_t>(p.contactModel));
    out.f64(world.time_);
    out.u64(world.stepCount_);
    out.u8(world.forcesCurrent_ ? 1 : 0);
    out.f64(world.elasticEnergy_);

    out.tag("SHAP");
    out.u64(world.shapes_.size());
    for (const ParticleShape& shape : world.shapes_) {
      out.f64(shape.density());
      out.f64(shape.volume());
      out.f64(shape.mass());
      out.vec(shape.centroid());
      for (const double entry : shape.inertia().entries)
        out.f64(entry);
      out.f64(shape.isSphere() ? shape.boundingRadius() : 0.0);
      out.mesh(shape.mesh());
    }

    out.tag("PART");
    out.u64(world.owned_);
    for (std::size_t i = 0; i < world.owned_; ++i)
      out.particle(world.particles_[i]);

    out.tag("SPRG");
    for (const auto* springs : {&world.particleSprings_, &world.obstacleSprings_}) {
      out.u64(springs->size());
      for (const auto& entry : *springs)
        out.spring(entry);
    }

    out.tag("OBST");
    out.u64(world.obstacles_.size());
    for (const Obstacle& obstacle : world.obstacles_) {
      out.mesh(obstacle.mesh);
      out.quaternion(obstacle.pose.rotation);
      out.vec(obstacle.pose.translation);
      out.vec(obstacle.motion.velocity);
      out.vec(obstacle.motion.angularVelocity);
      out.vec(obstacle.motion.pivot);
    }

    out.tag("CONT");
    const std::span<const Contact> contacts = world.contacts();
    out.u64(contacts.size());
    for (const Contact& contact : contacts) {
      out.vec(contact.point.x);
      out.vec(contact.point.normal);
      out.vec(contact.point.direction);
      out.f64(contact.point.distance);
      out.u8(contact.point.overlap ? 1 : 0);
      out.u8(contact.point.converged ? 1 : 0);
      out.u32(contact.point.first);
      out.u32(contact.point.second);
      out.u32(contact.first);
      out.u32(contact.second);
      out.u8(contact.withObstacle ? 1 : 0);
      out.f64(contact.depth);
      out.vec(contact.force);
      out.vec(contact.couple);
      out.f64(contact.volume);
    }

    out.tag("NOTE");
    out.text(note);
    return std::move(out.bytes());
  }

  /// `version`: 1 (before the volume law: no contact model, no couples) or 2.
  static Checkpoint restore(Reader& in, std::uint32_t version) {
    in.tag("PARM");
    Parameters p;
    for (double* value : {&p.timeStep, &p.epsilon, &p.filterDistance, &p.stiffness, &p.restitution,
                          &p.friction, &p.tangentialStiffnessRatio})
      *value = in.f64();
    p.gravity = in.vec();
    if (version >= 2) {
      const std::uint8_t model = in.u8();
      if (model > static_cast<std::uint8_t>(ContactModel::volume))
        in.fail("contact model " + std::to_string(model) + " is neither point (0) nor volume (1)");
      p.contactModel = static_cast<ContactModel>(model);
    }
    const auto checkedWorld = [&in](const Parameters& parameters) {
      try {
        return World(parameters);  // checks the parameters
      } catch (const Error& error) {
        in.fail(error.what());
      }
    };
    Checkpoint checkpoint{checkedWorld(p), {}};
    World& world = checkpoint.world;
    world.time_ = in.f64();
    const std::uint64_t steps = in.u64();
    world.stepCount_ = static_cast<std::size_t>(steps);
    const bool forcesCurrent = in.flag();
    world.elasticEnergy_ = in.f64();
    // The elastic energy may be +∞: a sum beyond a double's range, which a World may hold
    // (World::energies); never NaN.
    if (!std::isfinite(world.time_) || std::isnan(world.elasticEnergy_))
      in.fail("time not finite or elastic energy not a number");

    in.tag("SHAP");
    const std::size_t shapes = in.count(8 * 16 + 16, "shape");
    for (std::size_t k = 0; k < shapes; ++k) {
      const double density = in.f64();
      MassProperties properties;
      properties.volume = in.f64();
      properties.mass = in.f64();
      properties.centroid = in.vec();
      for (double& entry : properties.inertia.entries)
        entry = in.f64();
      const double sphereRadius = in.f64();
      const std::string what = "shape " + std::to_string(k);
      Mesh body = in.mesh(what);
      try {
        world.addShape(detail::restoredShape(body, density, properties, sphereRadius));
      } catch (const Error& error) {
        in.fail(what + ": " + error.what());
      }
    }

    in.tag("PART");
    const std::size_t particles = in.count(4 + 8 * 22, "particle");
    if (particles > std::numeric_limits<std::uint32_t>::max()) in.fail("too many particles");
    world.particles_.resize(particles);
    world.ids_.resize(particles);
    for (std::size_t i = 0; i < particles; ++i) {
      Particle& particle = world.particles_[i];
      particle.shape = in.u32();
      if (particle.shape >= shapes)
        in.fail("particle " + std::to_string(i) + " has shape " + std::to_string(particle.shape) +
                " of " + std::to_string(shapes));
      particle.position = in.vec();
      particle.orientation = in.quaternion();
      particle.velocity = in.vec();
      particle.angularVelocity = in.vec();
      particle.angularMomentum = in.vec();
      particle.force = in.vec();
      particle.torque = in.vec();
      if (!detail::holdsFiniteState(particle))
        in.fail("particle " + std::to_string(i) + " has a value that is not finite");
      if (!unitQuaternion(particle.orientation))
        in.fail("particle " + std::to_string(i) + "'s orientation is not a unit quaternion");
      world.ids_[i] = static_cast<std::uint32_t>(i);
    }
    world.owned_ = particles;

    in.tag("SPRG");
    for (auto* springs : {&world.particleSprings_, &world.obstacleSprings_}) {
      springs->resize(in.count(8 * 5, "spring"));
      for (auto& entry : *springs) {
        entry = in.spring();
        if (!detail::holdsFiniteState(entry.second))
          in.fail("a spring has a value that is not finite");
      }
      for (std::size_t s = 1; s < springs->size(); ++s)
        if (!((*springs)[s - 1].first < (*springs)[s].first)) in.fail("springs out of order");
    }

    in.tag("OBST");
    const std::size_t obstacles = in.count(8 * 18, "obstacle");
    for (std::size_t o = 0; o < obstacles; ++o) {
      const std::string what = "obstacle " + std::to_string(o);
      Mesh mesh = in.mesh(what);
      RigidTransform pose;
      pose.rotation = in.quaternion();
      pose.translation = in.vec();
      ObstacleMotion motion;
      motion.velocity = in.vec();
      motion.angularVelocity = in.vec();
      motion.pivot = in.vec();
      if (!unitQuaternion(pose.rotation) || !isFinite(pose.translation))
        in.fail(what + "'s pose is not a rotation and a finite translation");
      try {
        world.addObstacle(mesh, motion);
      } catch (const Error& error) {
        in.fail(what + ": " + error.what());
      }
      world.obstacles_.back().pose = pose;
    }
    // The springs' keys, now that the obstacles are known: a spring of no pair could never be
    // found, and one is a sign of a file that no World wrote.
    for (const bool withObstacle : {false, true})
      for (const auto& entry : withObstacle ? world.obstacleSprings_ : world.particleSprings_)
        if (!pairKeyInRange(entry.first, withObstacle, particles, obstacles))
          in.fail("a spring's pair key names no pair of the file's " + std::to_string(particles) +
                  " particles and " + std::to_string(obstacles) + " obstacles");

    in.tag("CONT");
    world.records_.pending = false;
    world.records_.contacts.resize(
        in.count(8 * 14 + 2 + 16 + 1 + (version >= 2 ? 8 * 4 : 0), "contact"));
    for (Contact& contact : world.records_.contacts) {
      contact.point.x = in.vec();
      contact.point.normal = in.vec();
      contact.point.direction = in.vec();
      contact.point.distance = in.f64();
      contact.point.overlap = in.flag();
      contact.point.converged = in.flag();
      contact.point.first = in.u32();
      contact.point.second = in.u32();
      contact.first = in.u32();
      contact.second = in.u32();
      contact.withObstacle = in.flag();
      contact.depth = in.f64();
      contact.force = in.vec();
      if (version >= 2) {
        contact.couple = in.vec();
        contact.volume = in.f64();
      }
      checkContact(in, world, contact);
    }

    in.tag("NOTE");
    checkpoint.note = in.text();
    if (!in.atEnd()) in.fail("bytes after the last section");
    world.forcesCurrent_ = forcesCurrent;  // addObstacle cleared it
    return checkpoint;
  }

  /// A contact read back names a pair of the world and triangles of its meshes, and its
  /// numbers are finite, as every contact a World reports (they are handed on as they are: to
  /// Python's arrays, the contact files).
  static void checkContact(Reader& in, const World& world, const Contact& contact) {
    const std::size_t c = static_cast<std::size_t>(&contact - world.records_.contacts.data());
    const std::string what = "contact " + std::to_string(c);
    const ContactPoint& point = contact.point;
    if (!isFinite(point.x) || !isFinite(point.normal) || !isFinite(point.direction) ||
        !std::isfinite(point.distance) || !std::isfinite(contact.depth) ||
        !isFinite(contact.force) || !isFinite(contact.couple) || !std::isfinite(contact.volume))
      in.fail(what + " has a value that is not finite");
    const std::uint64_t key = std::uint64_t{contact.first} << 32 | contact.second;
    if (!pairKeyInRange(key, contact.withObstacle, world.owned_, world.obstacles_.size()))
      in.fail(what + " names no pair of the file's " + std::to_string(world.owned_) +
              " particles and " + std::to_string(world.obstacles_.size()) + " obstacles");
    const Mesh& second = contact.withObstacle
                             ? world.obstacles_[contact.second].mesh
                             : world.shapes_[world.particles_[contact.second].shape].mesh();
    if (point.first >=
            world.shapes_[world.particles_[contact.first].shape].mesh().triangleCount() ||
        point.second >= second.triangleCount())
      in.fail(what + " names a triangle its meshes do not have");
  }

  static std::string canonicalState(const World& world) {
    Writer out;
    out.f64(world.time_);
    out.u64(world.stepCount_);
    // By id: a DistributedWorld's gathered part and a World of one process write alike.
    std::vector<std::pair<std::uint32_t, std::size_t>> order;
    for (std::size_t i = 0; i < world.owned_; ++i)
      order.push_back({world.ids_[i], i});
    std::sort(order.begin(), order.end());
    out.u64(order.size());
    for (const auto& [id, i] : order) {
      out.u32(id);
      out.particle(world.particles_[i]);
    }
    for (const auto* springs : {&world.particleSprings_, &world.obstacleSprings_}) {
      out.u64(springs->size());
      for (const auto& entry : *springs)
        out.spring(entry);
    }
    for (const Obstacle& obstacle : world.obstacles_) {
      out.quaternion(obstacle.pose.rotation);
      out.vec(obstacle.pose.translation);
    }
    return std::move(out.bytes());
  }
};

std::string checkpointBytes(const World& world, std::string_view note) {
  const std::string payload = CheckpointCodec::payload(world, note);
  Writer header;
  header.tag(kMagic);
  header.u32(kCheckpointVersion);
  header.u64(payload.size());
  header.u32(crc32Of(payload));
  std::string bytes = std::move(header.bytes());
  bytes += payload;
  return bytes;
}

Checkpoint readCheckpoint(std::string_view bytes, const std::string& origin) {
  const std::string where = "'" + origin + "': ";
  const std::size_t magic = std::min(bytes.size(), kMagic.size());
  if (bytes.substr(0, magic) != kMagic.substr(0, magic) || bytes.empty())
    throw Error(where + "not a Δ DEM checkpoint (it does not start with \"DELTADEM\")");
  if (bytes.size() < kHeaderBytes)
    throw Error(where + "truncated DEM checkpoint: " + std::to_string(bytes.size()) +
                " bytes, fewer than its " + std::to_string(kHeaderBytes) + "-byte header");
  Reader header(bytes.substr(kMagic.size(), kHeaderBytes - kMagic.size()), origin);
  const std::uint32_t version = header.u32();
  const std::uint64_t size = header.u64();
  const std::uint32_t crc = header.u32();
  if (version < kOldestCheckpointVersion || version > kCheckpointVersion)
    throw Error(where + "DEM checkpoint format version " + std::to_string(version) +
                "; this build of Δ reads versions " + std::to_string(kOldestCheckpointVersion) +
                " to " + std::to_string(kCheckpointVersion));
  const std::string_view payload = bytes.substr(kHeaderBytes);
  if (payload.size() < size)
    throw Error(where + "truncated DEM checkpoint: " + std::to_string(bytes.size()) +
                " bytes of the " + std::to_string(kHeaderBytes + size) + " its header announces");
  if (payload.size() > size)
    throw Error(where + "corrupt DEM checkpoint: " + std::to_string(payload.size() - size) +
                " bytes after the " + std::to_string(kHeaderBytes + size) +
                " its header announces");
  if (crc32Of(payload) != crc)
    throw Error(where + "corrupt DEM checkpoint: the checksum (CRC-32) does not match");
  Reader in(payload, origin);
  return CheckpointCodec::restore(in, version);
}

void saveCheckpoint(const std::filesystem::path& path, const World& world, std::string_view note) {
  io::writeFileAtomically(path, checkpointBytes(world, note));
}

Checkpoint loadCheckpoint(const std::filesystem::path& path) {
  std::string bytes;
  try {
    const io::RegularFile file(path);
    requireMemory(static_cast<double>(file.size()), "reading DEM checkpoint");
    bytes = file.readAll();
  } catch (const Error& error) {
    throw Error("cannot read DEM checkpoint '" + printable(path.string(), 4096) +
                "': " + error.what());
  }
  return readCheckpoint(bytes, path.string());
}

std::string stateDigest(const World& world) {
  const std::uint64_t hash = hash64(CheckpointCodec::canonicalState(world));
  static constexpr char kHex[] = "0123456789abcdef";
  std::string digest(16, '0');
  for (int d = 0; d < 16; ++d)
    digest[static_cast<std::size_t>(d)] = kHex[(hash >> (60 - 4 * d)) & 0xfu];
  return digest;
}

void World::save(const std::filesystem::path& path) const {
  saveCheckpoint(path, *this);
}

World World::load(const std::filesystem::path& path) {
  return std::move(loadCheckpoint(path).world);
}

std::string World::stateDigest() const {
  return dem::stateDigest(*this);
}

}  // namespace delta::dem
