#include "dem_checkpoint.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/dem/checkpoint.h"
#include "delta/io/atomic_file.h"

#include "motion_options.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

/// The signal that asked the run to stop, 0 until one does.
volatile std::sig_atomic_t stopSignal = 0;

extern "C" void requestStop(int signal) {
  stopSignal = signal;
}

std::size_t sizeOf(const std::string& text, const std::string& key, const std::string& origin) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  // At most what --steps takes: a note edited to 2^64 − 1 steps ran for ever.
  if (error != std::errc{} || end != text.data() + text.size() || value > kMaxSteps)
    throw Error("'" + origin + "': the checkpoint's note has " + key + " = '" + printable(text) +
                "', not a count from 0 to " + std::to_string(kMaxSteps));
  return value;
}

/// Whether `text` is a run identity: 16 lowercase hex digits.
bool isRunId(const std::string& text) noexcept {
  return text.size() == 16 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

}  // namespace

std::string newRunId() {
  std::random_device device;
  std::uint64_t bits =
      (std::uint64_t{device()} << 32) ^ device() ^
      static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(bits));
  return text;
}

std::string runMarkerOf(const std::filesystem::path& directory) {
  std::ifstream file(directory / kRunMarkerName, std::ios::binary);
  std::string line;
  if (!file || !std::getline(file, line) || !isRunId(line)) return "";
  return line;
}

void writeRunMarker(const std::filesystem::path& directory, const std::string& run) {
  if (!run.empty()) io::writeFileAtomically(directory / kRunMarkerName, run + "\n");
}

std::string DemRunNote::text() const {
  std::string text = "delta dem\nscenario = " + scenario + "\nsteps = " + std::to_string(steps) +
                     "\noutput_every = " + std::to_string(outputEvery) + "\nframes = " + frames +
                     "\ncheckpoint_every = " + std::to_string(checkpointEvery) +
                     (run.empty() ? "" : "\nrun = " + run) + "\nframe_times =";
  for (const double time : frameTimes) {
    char number[40];
    std::snprintf(number, sizeof number, " %.17g", time);
    text += number;
  }
  return text + "\n";
}

DemRunNote DemRunNote::parse(const std::string& text, const std::string& origin) {
  std::istringstream lines(text);
  std::string line;
  if (!std::getline(lines, line) || line != "delta dem")
    throw Error("'" + origin + "' is a DEM checkpoint but not one of `delta dem` (no run note)");
  DemRunNote note;
  while (std::getline(lines, line)) {
    const std::size_t equals = line.find(" = ");
    const std::string key = line.substr(0, line.find(' '));
    const std::string value = equals == std::string::npos ? "" : line.substr(equals + 3);
    if (key == "scenario")
      note.scenario = value;
    else if (key == "steps")
      note.steps = sizeOf(value, key, origin);
    else if (key == "output_every")
      note.outputEvery = std::max<std::size_t>(1, sizeOf(value, key, origin));
    else if (key == "frames")
      note.frames = value;
    else if (key == "checkpoint_every")
      note.checkpointEvery = sizeOf(value, key, origin);
    else if (key == "run") {
      if (!isRunId(value))
        throw Error("'" + origin + "': the checkpoint's note has run = '" + printable(value) +
                    "', not 16 hex digits");
      note.run = value;
    } else if (key == "frame_times") {
      std::istringstream times(line.substr(key.size() + 2));
      std::string number;
      while (times >> number) {
        double time = 0.0;
        const auto [end, error] =
            std::from_chars(number.data(), number.data() + number.size(), time);
        if (error != std::errc{} || end != number.data() + number.size())
          throw Error("'" + origin + "': the checkpoint's note has a frame time '" + number + "'");
        note.frameTimes.push_back(time);
      }
    }
  }
  if (note.scenario.empty())
    throw Error("'" + origin + "': the checkpoint's note names no scenario");
  return note;
}

DemCheckpoints::DemCheckpoints(std::filesystem::path directory, std::size_t every, DemRunNote note)
    : directory_(std::move(directory)), every_(every), note_(std::move(note)) {
  note_.checkpointEvery = every;
  stopSignal = 0;
  struct sigaction action {};
  action.sa_handler = requestStop;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // a write under way goes on
  sigaction(SIGINT, &action, &previousInterrupt_);
  sigaction(SIGTERM, &action, &previousTerminate_);
  sigaction(SIGHUP, &action, &previousHangUp_);  // a closed terminal, a dropped connection
}

DemCheckpoints::~DemCheckpoints() {
  sigaction(SIGINT, &previousInterrupt_, nullptr);
  sigaction(SIGTERM, &previousTerminate_, nullptr);
  sigaction(SIGHUP, &previousHangUp_, nullptr);
}

int DemCheckpoints::afterStep(const dem::World& world, const DemOutput* output) {
  if (due(world.stepCount())) write(world, output);
  return stopSignal;
}

int DemCheckpoints::pendingSignal() const noexcept {
  return stopSignal;
}

void DemCheckpoints::write(const dem::World& world, const DemOutput* output) {
  if (directory_.empty() || lastStep_ == world.stepCount()) return;
  const Stopwatch clock;
  DemRunNote note = note_;
  if (output) {
    note.frameTimes = output->frameTimes();
    // The log's rows up to this step on the disk before the checkpoint that continues them.
    output->syncLog();
  }
  const std::string bytes = dem::checkpointBytes(world, note.text());
  io::writeFileAtomically(path(), bytes);
  lastStep_ = world.stepCount();
  seconds_ += clock.seconds();
  ++written_;
  bytes_ = bytes.size();
}

}  // namespace delta::cli
