#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/core/vec3.h"

/// The values of options that move a mesh (delta contact --rotate-b/--translate-b, delta ib
/// --rotate/--translate). Each throws delta::Error naming `option` and the text when the text is
/// not what it must be.
namespace delta::cli {

/// `count` comma-separated finite numbers, e.g. "1,0,0,90".
std::vector<double> parseNumbers(const std::string& text, std::size_t count, const char* option);

/// "X,Y,Z".
Vec3 parseVector(const std::string& text, const char* option);

/// "AX,AY,AZ,DEGREES": the turn by DEGREES about the axis (AX, AY, AZ), right-handed; the axis
/// must not be zero.
Quaternion parseRotation(const std::string& text, const char* option);

}  // namespace delta::cli
