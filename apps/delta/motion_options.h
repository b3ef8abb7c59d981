#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

/// The values of options that move a mesh (delta contact --rotate-b/--translate-b, delta ib
/// --rotate/--translate). Each throws delta::Error naming `option` and the text when the text is
/// not what it must be.
namespace delta::cli {

/// `count` comma-separated finite numbers, e.g. "1,0,0,90".
std::vector<double> parseNumbers(const std::string& text, std::size_t count, const char* option);

/// "X,Y,Z".
Vec3 parseVector(const std::string& text, const char* option);

/// The most time steps `delta ib --steps` and `delta dem --steps` (and a DEM config's `steps`)
/// accept: far beyond any run that ends, small enough that every count stays exact.
inline constexpr std::size_t kMaxSteps = 1'000'000'000'000;

/// A number of time steps: a whole number in decimal digits from `least` (ib: 0, a static grid;
/// dem: 1) to kMaxSteps. The one range check of `delta ib --steps`, `delta dem --steps` and a DEM
/// config's `steps`: throws delta::Error "ORIGIN 'TEXT' must be a whole number from LEAST to
/// 1000000000000" (ORIGIN: the option, or the config file and line).
std::size_t parseStepCount(const std::string& text, const std::string& origin, std::size_t least);

/// "AX,AY,AZ,DEGREES": the turn by DEGREES about the axis (AX, AY, AZ), right-handed; the axis
/// must not be zero.
Quaternion parseRotation(const std::string& text, const char* option);

/// `delta contact`'s and `delta overlap`'s --rotate-b and --translate-b: B turned about the
/// centre of its box, then moved.
struct SecondMeshMotion {
  std::string rotate, translate;
  /// Parses both (so that a bad value is reported before the meshes load).
  void validate() const;
  void apply(Mesh& b) const;
};

}  // namespace delta::cli
