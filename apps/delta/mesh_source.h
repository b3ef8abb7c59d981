#pragma once

#include <string>

#include "delta/io/mesh_io.h"

namespace delta::cli {

/// A mesh named on the command line: a file path, or a built-in primitive
///     builtin:icosphere[:LEVEL]  builtin:box  builtin:cylinder[:SEGMENTS]  builtin:quad
///     builtin:granulate[:SEED]
/// Throws delta::Error for an unknown primitive, a bad parameter, or a file that does not load.
io::LoadedMesh loadMeshSource(const std::string& source);

/// The help text listing the built-in primitives.
const char* meshSourceHelp();

}  // namespace delta::cli
