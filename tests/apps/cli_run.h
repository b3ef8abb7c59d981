// Running the `delta` executable from a test as a user would, and the command-line contract's
// error rule, for every CLI test file.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace delta::test {

/// What one run of `delta` did.
struct CliRun {
  int exitCode = -1;
  std::string out;
  std::string err;
};

/// A file's bytes.
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

/// A folder in the temporary folder, named for this process, removed with what is in it.
struct TemporaryFolder {
  explicit TemporaryFolder(const std::string& name)
      : path(std::filesystem::temp_directory_path() /
             ("delta_cli_" + std::to_string(::getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TemporaryFolder() { std::filesystem::remove_all(path); }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  std::filesystem::path path;
};

/// Runs `LAUNCHER delta ARGUMENTS` (the build's DELTA_CLI; LAUNCHER e.g. an mpirun command
/// line, or nothing) through the shell, capturing both streams; a death by signal reads as exit
/// code 128 + the signal.
inline CliRun runDeltaUnder(const std::string& launcher, const std::string& arguments) {
  const TemporaryFolder streams("streams");
  const std::string command = launcher + " '" + DELTA_CLI + "' " + arguments + " >'" +
                              (streams.path / "out").string() + "' 2>'" +
                              (streams.path / "err").string() + "'";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.out = slurp(streams.path / "out");
  run.err = slurp(streams.path / "err");
  return run;
}

/// Runs `delta ARGUMENTS` as runDeltaUnder does, with no launcher.
inline CliRun runDelta(const std::string& arguments) {
  return runDeltaUnder("", arguments);
}

/// Starts `delta ARGUMENTS` (no shell) with its streams into `folder`/stdout and stderr, and
/// SIGINT at its default action (a test run in the background may have it ignored); returns its
/// pid, for the test to signal and wait for.
inline pid_t startDelta(const std::vector<std::string>& arguments,
                        const std::filesystem::path& folder) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int out = ::open((folder / "stdout").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open((folder / "stderr").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(err, 2);
    ::signal(SIGINT, SIG_DFL);
    std::vector<char*> argv{const_cast<char*>(DELTA_CLI)};
    for (const std::string& argument : arguments)
      argv.push_back(const_cast<char*>(argument.c_str()));
    argv.push_back(nullptr);
    ::execv(DELTA_CLI, argv.data());
    ::_exit(127);
  }
  return pid;
}

/// The contract for bad input: a non-zero exit (not a crash), nothing on stdout, one line on
/// stderr that contains `needle`.
inline void expectOneLineError(const CliRun& run, const std::string& needle) {
  EXPECT_NE(run.exitCode, 0);
  EXPECT_LT(run.exitCode, 128) << "killed by a signal: " << run.err;
  EXPECT_TRUE(run.out.empty()) << run.out;
  ASSERT_FALSE(run.err.empty());
  EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << "more than one line: " << run.err;
  EXPECT_NE(run.err.find(needle), std::string::npos) << run.err;
}

/// The number after "key": in a JSON line; NaN when the key is missing or not a number.
inline double jsonNumber(const std::string& json, const std::string& key) {
  const std::string marker = "\"" + key + "\":";
  const std::size_t at = json.find(marker);
  if (at == std::string::npos) return NAN;
  const char* begin = json.c_str() + at + marker.size();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  return end == begin ? NAN : value;
}

/// The `file` attributes of a .pvd's data sets, in order.
inline std::vector<std::string> seriesFiles(const std::filesystem::path& pvd) {
  const std::string text = slurp(pvd);
  const std::regex dataSet(
      "<DataSet timestep=\"[^\"]+\" group=\"\" part=\"0\" file=\"([^\"]+)\"/>");
  std::vector<std::string> files;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), dataSet);
       it != std::sregex_iterator(); ++it)
    files.push_back((*it)[1]);
  return files;
}

/// `path` in single quotes, as the CLI's messages name paths.
inline std::string quoted(const std::filesystem::path& path) {
  std::string text(1, '\'');  // appended, not concatenated: GCC 12 warns on "'" + string
  text.append(path.string());
  text.push_back('\'');
  return text;
}

}  // namespace delta::test
