#include "report.h"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "peers.h"

namespace delta::bench {
namespace {

constexpr const char* kReference = "Delta";

/// `text` padded with spaces to `width` columns, on the left or the right ("Δ" and "×" take two
/// bytes and one column: count characters, not bytes).
std::string padded(const std::string& text, std::size_t width, bool left = true) {
  std::size_t columns = 0;
  for (const char c : text)
    columns += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  const std::string fill(width > columns ? width - columns : 0, ' ');
  return left ? text + fill : fill + text;
}

/// The table's name of a library: "Delta-signed" → "Δ signed".
std::string shownName(const std::string& library) {
  if (library.rfind(kReference, 0) != 0) return library;
  std::string shown = "Δ" + library.substr(std::string(kReference).size());
  std::replace(shown.begin(), shown.end(), '-', ' ');
  return shown;
}

/// "W1/armadillo/Embree/threads:2" split at its slashes; false for a name of another form.
bool splitName(const std::string& name, std::string& workload, std::string& mesh,
               std::string& library, int& threads) {
  std::vector<std::string> parts(1);
  for (const char c : name)
    if (c == '/')
      parts.emplace_back();
    else
      parts.back() += c;
  const std::string prefix = "threads:";
  if (parts.size() != 4 || parts[3].rfind(prefix, 0) != 0) return false;
  workload = parts[0];
  mesh = parts[1];
  library = parts[2];
  threads = std::atoi(parts[3].c_str() + prefix.size());
  return true;
}

}  // namespace

std::string withCommas(std::size_t value) {
  std::string digits = std::to_string(value), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

void addPeersToContext() {
  std::string skipped;
  const auto skip = [&](const char* peer) {
    skipped += (skipped.empty() ? "" : ", ") + std::string(peer) + " (not built with " + peer + ")";
  };
#if defined(DELTA_HAVE_EMBREE)
  benchmark::AddCustomContext("embree_version", embreeVersion());
#else
  skip("Embree");
#endif
#if defined(DELTA_HAVE_CGAL)
  benchmark::AddCustomContext("cgal_version", cgalVersion());
#else
  skip("CGAL");
#endif
#if defined(DELTA_HAVE_FCL)
  benchmark::AddCustomContext("fcl_version", fclVersion());
#else
  skip("FCL");
#endif
  (void)skip;
  if (!skipped.empty()) benchmark::AddCustomContext("skipped_peers", skipped);
}

bool RatioReporter::ReportContext(const Context& context) {
  display_ = benchmark::CreateDefaultDisplayReporter();
  return display_->ReportContext(context);
}

void RatioReporter::ReportRuns(const std::vector<Run>& runs) {
  for (const Run& run : runs)
    record(run);
  display_->ReportRuns(runs);
}

void RatioReporter::Finalize() {
  display_->Finalize();
}

bool RatioReporter::displaysConsole() const noexcept {
  return display_ == nullptr || dynamic_cast<benchmark::ConsoleReporter*>(display_) != nullptr;
}

void RatioReporter::record(const Run& run) {
  if (run.error_occurred) return;
  const bool median = run.run_type == Run::RT_Aggregate;
  if (median && run.aggregate_name != "median") return;  // mean, stddev, cv
  std::string workload, mesh, library;
  int threads = 1;
  if (!splitName(run.run_name.function_name, workload, mesh, library, threads)) return;
  auto found = std::find_if(measured_.begin(), measured_.end(), [&](const Measured& m) {
    return m.mesh == mesh && m.workload == workload && m.threads == threads;
  });
  if (found == measured_.end()) found = measured_.insert(found, {mesh, workload, threads, {}});
  Time& time = found->byLibrary[library];
  if (time.median && !median) return;  // a repetition after the median was seen
  time = {run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit), median};
  if (library != kReference && std::find(peers_.begin(), peers_.end(), library) == peers_.end())
    peers_.push_back(library);
}

void RatioReporter::printRatios(std::FILE* out) const {
  std::vector<const Measured*> rows;
  std::size_t meshWidth = 4;
  for (const Measured& m : measured_)
    if (m.byLibrary.count(kReference) && m.byLibrary.size() > 1) {
      rows.push_back(&m);
      meshWidth = std::max(meshWidth, m.mesh.size());
    }
  if (rows.empty()) return;
  std::fprintf(out,
               "\npeer/Δ query time (real time; with repetitions, the medians), Δ's time in ms:\n");
  std::fprintf(out, "%s %-8s %7s %10s", padded("mesh", meshWidth).c_str(), "workload", "threads",
               "Δ ms");
  for (const std::string& peer : peers_)
    std::fprintf(out, " %s", padded(shownName(peer), 10, false).c_str());
  std::fprintf(out, "\n");
  for (const Measured* m : rows) {
    const double reference = m->byLibrary.at(kReference).seconds;
    std::fprintf(out, "%s %-8s %7d %10.4g", padded(m->mesh, meshWidth).c_str(), m->workload.c_str(),
                 m->threads, 1e3 * reference);
    for (const std::string& peer : peers_) {
      const auto found = m->byLibrary.find(peer);
      char ratio[32] = "-";
      if (found != m->byLibrary.end())
        std::snprintf(ratio, sizeof ratio, "%.2f×", found->second.seconds / reference);
      std::fprintf(out, " %s", padded(ratio, 10, false).c_str());
    }
    std::fprintf(out, "\n");
  }
}

}  // namespace delta::bench
