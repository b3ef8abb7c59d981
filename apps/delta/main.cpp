// The `delta` command-line tool: how users try Δ on their meshes (see DESIGN.md, "Command-line
// contract"). Every error ends as one line on stderr and a non-zero exit code.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <sstream>
#include <string>

#include "delta/core/error.h"
#include "delta/core/parallel.h"
#include "delta/core/version.h"
#include "delta/io/atomic_file.h"

#include "commands.h"

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

/// Every option and argument that takes a value refuses an empty one (`--eps ''`, `--rotate-b=`):
/// CLI11 would read it as the type's default and the option would silently do nothing.
void refuseEmptyValues(CLI::App& app) {
  const CLI::Validator nonEmpty(
      [](const std::string& value) {
        return value.empty() ? std::string("an empty value is not allowed") : std::string();
      },
      "", "non-empty");
  for (CLI::Option* option : app.get_options())
    if (option->get_expected_min() > 0) option->check(nonEmpty);
  for (CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; }))
    refuseEmptyValues(*command);
}

/// What the command printed reaches standard output, or the run fails: a full disk or a closed
/// file behind stdout would otherwise end in exit code 0 with the output lost. CLI11's help and
/// version go through std::cout, which shares stdout's buffer.
int checkStandardOutput(int code) {
  errno = 0;
  const bool flushFailed = std::fflush(stdout) != 0;  // first: the reason is in errno only now
  const int error = errno;
  std::cout.flush();
  if (!flushFailed && !std::ferror(stdout) && std::cout.good()) return code;
  if (code != 0) return code;  // the run failed already and said so
  return fail("",
              std::string("cannot write to standard output: ") +
                  (flushFailed && error != 0 ? std::strerror(error) : "a write failed"),
              1);
}

/// CLI11's exit for help and version, its text printed through stdout's buffer so that
/// checkStandardOutput sees a failure and its reason (std::endl would flush it early).
int printExit(const CLI::App& app, const CLI::Error& exit) {
  std::ostringstream text;
  const int code = app.exit(exit, text, std::cerr);
  std::fputs(text.str().c_str(), stdout);
  return code;
}

/// Parses the command line and runs the command: the exit code (0, or that of the error shown).
int runCommand(int argc, char** argv) {
  CLI::App app("Δ (delta): triangle-mesh proximity: contacts, distances, inside/outside", "delta");
  app.require_subcommand(1);
  app.set_version_flag(
      "--version", std::string("delta ") + delta::version() + " (git " + delta::gitCommit() + ")");
  app.fallthrough();  // global options may follow the subcommand: delta info MESH --threads 2
  app.add_option_function<int>(
         "--threads", [](int threads) { omp_set_num_threads(threads); },
         "Threads to use, 1 to " + std::to_string(delta::kMaxThreads) +
             " (overrides OMP_NUM_THREADS, which is capped there)")
      ->check(CLI::Range(1, delta::kMaxThreads));
  delta::cli::addInfoCommand(app);
  delta::cli::addBenchCommand(app);
  delta::cli::addContactCommand(app);
  delta::cli::addDistanceCommand(app);
  delta::cli::addDemCommand(app);
  delta::cli::addIbCommand(app);
  delta::cli::addOverlapCommand(app);
  refuseEmptyValues(app);

  try {
    rejectUnknownCommand(app, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return printExit(app, help);
  } catch (const CLI::CallForAllHelp& help) {
    return printExit(app, help);
  } catch (const CLI::CallForVersion& version) {
    return printExit(app, version);
  } catch (const CLI::ParseError& error) {
    return fail("", std::string(error.what()) + " (see delta --help)", 2);
  } catch (const delta::Error& error) {
    return fail("", error.what(), 1);
  } catch (const delta::cli::QuietFailure&) {
    return 1;
  } catch (const std::bad_alloc&) {
    // What the size checks (core/memory.h) estimate to fit, but did not with what else runs.
    return fail("", "out of memory: the input or the options ask for more than is free", 1);
  } catch (const std::exception& error) {
    return fail("internal error: ", error.what(), 3);
  }
  return 0;
}

/// SIGINT, SIGTERM, SIGHUP (a batch system's time limit, a closed terminal): the temporary
/// files being written are removed, then the signal ends the process as it would have (exit
/// status 128 + the signal). Without this a stopped `delta distance --out` left its partial
/// output beside the file it was to replace, as large as it had got. (A `delta dem` run sets
/// handlers of its own while it steps: it finishes the step and writes a checkpoint.)
extern "C" void discardAndEnd(int signal) {
  delta::io::discardTemporaryFiles();
  ::raise(signal);  // SA_RESETHAND: the default action now
}

/// Installs discardAndEnd for the signals that end a run, except those the process was started
/// ignoring (a background job of a non-interactive shell ignores SIGINT, and should go on).
void discardTemporaryFilesOnStop() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction previous {};
    if (::sigaction(signal, nullptr, &previous) != 0 || previous.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = discardAndEnd;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    ::sigaction(signal, &action, nullptr);
  }
}

}  // namespace

int main(int argc, char** argv) {
  discardTemporaryFilesOnStop();
  return checkStandardOutput(runCommand(argc, argv));
}
