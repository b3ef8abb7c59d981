#pragma once

#include <CLI/CLI.hpp>
#include <string>

/// The `delta` subcommands. Each adds itself to the app with its options and a callback that runs
/// it; a callback reports bad input by throwing delta::Error, which main() turns into one line on
/// stderr and a non-zero exit code.
namespace delta::cli {

void addInfoCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addContactCommand(CLI::App& app);
void addDistanceCommand(CLI::App& app);
void addDemCommand(CLI::App& app);
void addIbCommand(CLI::App& app);
void addOverlapCommand(CLI::App& app);

struct SecondMeshMotion;
/// Adds the two meshes of a two-mesh command (MESH_A, MESH_B, both required) and --translate-b
/// and --rotate-b, read into `motion` (motion_options.h).
void addMeshPair(CLI::App& command, std::string& meshA, std::string& meshB,
                 SecondMeshMotion& motion);

/// Thrown by the ranks of a distributed run for an error that rank 0 has reported already:
/// main() exits with status 1 and prints nothing.
struct QuietFailure {};

}  // namespace delta::cli
