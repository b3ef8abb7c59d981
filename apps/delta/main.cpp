// The `delta` command-line tool: how users try Δ on their meshes (see DESIGN.md, "Command-line
// contract"). Every error ends as one line on stderr and a non-zero exit code.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "delta/core/error.h"
#include "delta/core/version.h"

namespace {

/// Errors are shown as one line, whatever a dependency put into the message.
int fail(const char* prefix, std::string message, int code) {
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  std::fprintf(stderr, "delta: %s%s\n", prefix, message.c_str());
  return code;
}

/// CLI11 reports a mistyped subcommand as "a subcommand is required"; name it instead.
void rejectUnknownCommand(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--threads") ++i;  // its value
    if (argument.starts_with("-")) continue;
    for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; }))
      if (command->get_name() == argument) return;
    std::string known;
    for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; }))
      known += (known.empty() ? "" : ", ") + command->get_name();
    throw CLI::ExtrasError("unknown command '" + argument + "' (commands: " + known + ")",
                           CLI::ExitCodes::ExtrasError);
  }
}

}  // namespace

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app("Δ (delta): triangle-mesh proximity: contacts, distances, inside/outside", "delta");
  app.require_subcommand(1);
  app.set_version_flag(
      "--version", std::string("delta ") + delta::version() + " (git " + delta::gitCommit() + ")");
  app.fallthrough();  // global options may follow the subcommand: delta info MESH --threads 2
  app.add_option_function<int>(
         "--threads", [](int threads) { omp_set_num_threads(threads); },
         "Threads to use (overrides OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 4096));
  delta::cli::addInfoCommand(app);
  delta::cli::addBenchCommand(app);
  delta::cli::addContactCommand(app);
  delta::cli::addDistanceCommand(app);
  delta::cli::addDemCommand(app);
  delta::cli::addIbCommand(app);

  try {
    rejectUnknownCommand(app, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForVersion& version) {
    return app.exit(version);
  } catch (const CLI::ParseError& error) {
    return fail("", std::string(error.what()) + " (see delta --help)", 2);
  } catch (const delta::Error& error) {
    return fail("", error.what(), 1);
  } catch (const delta::cli::QuietFailure&) {
    return 1;
  } catch (const std::exception& error) {
    return fail("internal error: ", error.what(), 3);
  }
  return 0;
}
