#include "report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/core/version.h"

#include "peers.h"

namespace delta::bench {
namespace {

std::string format(const char* pattern, double value) {
  if (std::isnan(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char text[64];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

/// `text` padded with spaces to `width` columns, on the left or the right ("Δ" and "×" take two
/// bytes and one column: count characters, not bytes).
std::string padded(const std::string& text, std::size_t width, bool left = true) {
  std::size_t columns = 0;
  for (const char c : text)
    columns += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  const std::string fill(width > columns ? width - columns : 0, ' ');
  return left ? text + fill : fill + text;
}

std::string rightAligned(const std::string& text, std::size_t width) {
  return padded(text, width, false);
}

/// Millions of queries a second, from a count and the seconds they took.
double millionsPerSecond(double queries, double seconds) {
  return seconds > 0.0 ? queries / seconds * 1e-6 : kNotMeasured;
}

void printGridTable(const GridReport& grid) {
  if (grid.rows.empty()) return;
  std::printf(
      "\nW5 grid: levels %d, %s distances, finest cell diagonal h = %.6g; %d moves of the "
      "boundary, its furthest vertex %.3g h a move (move columns: means over the moves)\n",
      grid.levels, grid.signedDistance ? "signed" : "unsigned", grid.cellDiagonal, grid.moves,
      grid.step / grid.cellDiagonal);
  std::printf("%3s %9s %9s %9s %4s %9s %s %s | %9s %9s %s %s  %s\n", "thr", "vertices", "leaves",
              "build s", "runs", "queries", rightAligned("Mq/s in Δ", 10).c_str(),
              rightAligned("in Δ", 5).c_str(), "move s", "queries",
              rightAligned("Mq/s in Δ", 10).c_str(), rightAligned("in Δ", 5).c_str(), "agreement");
  for (const GridPhases& row : grid.rows) {
    const double buildQueries = static_cast<double>(row.buildQueries);
    std::printf("%3d %9s %9s %9s %4d %9s %10s %5s | %9s %9s %10s %5s  %s\n", row.threads,
                withCommas(row.vertices).c_str(), withCommas(row.leaves).c_str(),
                format("%.4f", row.buildSeconds).c_str(), row.buildRuns,
                withCommas(row.buildQueries).c_str(),
                format("%.2f", millionsPerSecond(buildQueries, row.buildQuerySeconds)).c_str(),
                format("%.0f%%", 100.0 * row.buildQuerySeconds / row.buildSeconds).c_str(),
                format("%.4f", row.moveSeconds).c_str(),
                withCommas(static_cast<std::size_t>(std::llround(row.moveQueries))).c_str(),
                format("%.2f", millionsPerSecond(row.moveQueries, row.moveQuerySeconds)).c_str(),
                format("%.0f%%", 100.0 * row.moveQuerySeconds / row.moveSeconds).c_str(),
                row.agreement.c_str());
  }
}

void printGridJson(const GridReport& grid) {
  if (grid.rows.empty()) {
    std::printf("null");
    return;
  }
  std::printf(
      "{\"levels\": %d, \"signed\": %s, \"cell_diagonal\": %s, \"moves\": %d, \"step\": %s, "
      "\"rows\": [",
      grid.levels, grid.signedDistance ? "true" : "false", jsonNumber(grid.cellDiagonal).c_str(),
      grid.moves, jsonNumber(grid.step).c_str());
  for (std::size_t r = 0; r < grid.rows.size(); ++r) {
    const GridPhases& row = grid.rows[r];
    const double buildQueries = static_cast<double>(row.buildQueries);
    std::printf(
        "%s\n    {\"threads\": %d, \"vertices\": %zu, \"leaves\": %zu, \"build_s\": %s, "
        "\"build_runs\": %d, \"build_queries\": %zu, \"build_query_s\": %s, "
        "\"build_queries_per_s_in_delta\": %s, \"build_share_in_delta\": %s, \"move_s\": %s, "
        "\"move_queries\": %s, \"move_query_s\": %s, \"move_queries_per_s_in_delta\": %s, "
        "\"move_share_in_delta\": %s, \"agreement\": %s, \"agreed\": %s}",
        r ? "," : "", row.threads, row.vertices, row.leaves, jsonNumber(row.buildSeconds).c_str(),
        row.buildRuns, row.buildQueries, jsonNumber(row.buildQuerySeconds).c_str(),
        jsonNumber(1e6 * millionsPerSecond(buildQueries, row.buildQuerySeconds)).c_str(),
        jsonNumber(row.buildQuerySeconds / row.buildSeconds).c_str(),
        jsonNumber(row.moveSeconds).c_str(), jsonNumber(row.moveQueries).c_str(),
        jsonNumber(row.moveQuerySeconds).c_str(),
        jsonNumber(1e6 * millionsPerSecond(row.moveQueries, row.moveQuerySeconds)).c_str(),
        jsonNumber(row.moveQuerySeconds / row.moveSeconds).c_str(),
        jsonString(row.agreement).c_str(), row.agreed ? "true" : "false");
  }
  std::printf("]}");
}

std::vector<std::string> skippedPeers() {
  std::vector<std::string> skipped;
#if !defined(DELTA_HAVE_EMBREE)
  skipped.push_back("Embree: skipped: not built with Embree");
#endif
#if !defined(DELTA_HAVE_CGAL)
  skipped.push_back("CGAL: skipped: not built with CGAL");
#endif
#if !defined(DELTA_HAVE_FCL)
  skipped.push_back("FCL: skipped: not built with FCL");
#endif
  return skipped;
}

}  // namespace

Row makeRow(const std::string& workload, const std::string& library, int threads) {
  Row row;
  row.workload = workload;
  row.library = library;
  row.threads = threads;
  return row;
}

std::string withCommas(std::size_t value) {
  std::string digits = std::to_string(value), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

/// Fills the peer/Δ ratios of `row` from Δ's row of the same workload and thread count.
void setRatios(Row& row, const std::vector<Row>& rows) {
  for (const Row& reference : rows)
    if (reference.library == "Δ" && reference.workload == row.workload &&
        reference.threads == row.threads) {
      row.ratioQuery = row.querySeconds / reference.querySeconds;
      row.ratioTotal =
          (row.buildSeconds + row.querySeconds) / (reference.buildSeconds + reference.querySeconds);
    }
}
std::string peerVersions() {
  std::string versions;
#if defined(DELTA_HAVE_EMBREE)
  versions += std::string(", Embree ") + embreeVersion();
#endif
#if defined(DELTA_HAVE_CGAL)
  versions += std::string(", CGAL ") + cgalVersion();
#endif
#if defined(DELTA_HAVE_FCL)
  versions += std::string(", FCL ") + fclVersion();
#endif
  return versions;
}

void printTable(const MeshReport& report) {
  std::printf("\n%s: %s triangles, %s vertices, diagonal D = %.6g; %s points (W1-W3)\n",
              std::filesystem::path(report.path).filename().c_str(),
              withCommas(report.triangles).c_str(), withCommas(report.vertices).c_str(),
              report.diagonal, withCommas(report.points).c_str());
  std::printf("%-17s %-8s %3s %9s %9s %4s %8s %8s %8s  %-34s %s\n", "workload", "library", "thr",
              "build s", "query s", "runs", "peer/Δ", "b+q", "B/tri", "agreement (max |diff|/D)",
              "note");
  for (const Row& row : report.rows) {
    std::string agreement = row.agreement;
    if (!std::isnan(row.maxDifference)) agreement += " (" + format("%.1e", row.maxDifference) + ")";
    std::printf("%-17s %s %3d %9s %9s %4d %7s%s %7s%s %8s  %-34s %s\n", row.workload.c_str(),
                padded(row.library, 8).c_str(), row.threads,
                format("%.4f", row.buildSeconds).c_str(), format("%.4f", row.querySeconds).c_str(),
                row.queryRuns, format("%.2f", row.ratioQuery).c_str(),
                std::isnan(row.ratioQuery) ? " " : "×", format("%.2f", row.ratioTotal).c_str(),
                std::isnan(row.ratioTotal) ? " " : "×",
                format("%.0f", row.bytesPerTriangle).c_str(), agreement.c_str(), row.note.c_str());
  }
  printGridTable(report.grid);
  for (const std::string& skipped : skippedPeers())
    std::printf("%s\n", skipped.c_str());
  for (const std::string& dispute : report.disputes)
    std::printf("disagreement: %s\n", dispute.c_str());
}

void printJson(std::size_t points, const std::vector<MeshReport>& reports, bool agreed) {
  std::printf("{\"delta_version\": %s, \"git_commit\": %s, \"peers\": %s, \"points\": %zu,\n",
              jsonString(delta::version()).c_str(), jsonString(delta::gitCommit()).c_str(),
              jsonString(peerVersions().empty() ? "" : peerVersions().substr(2)).c_str(), points);
  std::printf(" \"skipped\": [");
  const std::vector<std::string> skipped = skippedPeers();
  for (std::size_t i = 0; i < skipped.size(); ++i)
    std::printf("%s%s", i ? ", " : "", jsonString(skipped[i]).c_str());
  std::printf("],\n \"agreement\": %s,\n \"meshes\": [", agreed ? "true" : "false");
  for (std::size_t m = 0; m < reports.size(); ++m) {
    const MeshReport& report = reports[m];
    std::printf(
        "%s\n  {\"mesh\": %s, \"triangles\": %zu, \"vertices\": %zu, \"diagonal\": %s, "
        "\"rows\": [",
        m ? "," : "", jsonString(report.path).c_str(), report.triangles, report.vertices,
        jsonNumber(report.diagonal).c_str());
    for (std::size_t r = 0; r < report.rows.size(); ++r) {
      const Row& row = report.rows[r];
      std::printf(
          "%s\n    {\"workload\": %s, \"library\": %s, \"threads\": %d, \"build_s\": %s, "
          "\"query_s\": %s, \"query_runs\": %d, \"ratio_query\": %s, \"ratio_total\": %s, "
          "\"bytes_per_triangle\": %s, \"memory\": %s, \"agreement\": %s, "
          "\"agreed\": %s, \"max_difference_over_diagonal\": %s, \"note\": %s}",
          r ? "," : "", jsonString(row.workload).c_str(), jsonString(row.library).c_str(),
          row.threads, jsonNumber(row.buildSeconds).c_str(), jsonNumber(row.querySeconds).c_str(),
          row.queryRuns, jsonNumber(row.ratioQuery).c_str(), jsonNumber(row.ratioTotal).c_str(),
          jsonNumber(row.bytesPerTriangle).c_str(), jsonString(row.memoryMethod).c_str(),
          jsonString(row.agreement).c_str(), row.agreed ? "true" : "false",
          jsonNumber(row.maxDifference).c_str(), jsonString(row.note).c_str());
    }
    std::printf("],\n   \"grid\": ");
    printGridJson(report.grid);
    std::printf(",\n   \"disagreements\": [");
    for (std::size_t d = 0; d < report.disputes.size(); ++d)
      std::printf("%s%s", d ? ", " : "", jsonString(report.disputes[d]).c_str());
    std::printf("]}");
  }
  std::printf("\n ]}\n");
}

}  // namespace delta::bench
