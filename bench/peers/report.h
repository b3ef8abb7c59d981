#pragma once

// The report of bench/peers/peers_bench.cpp: one row per workload, library and thread count,
// printed as a table per mesh or as one JSON object.

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace delta::bench {

inline constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();

struct Row {
  std::string workload;
  std::string library;
  int threads = 1;
  double buildSeconds = kNotMeasured;
  double querySeconds = kNotMeasured;
  int queryRuns = 0;
  double ratioQuery = kNotMeasured;  // peer / Δ at the same thread count
  double ratioTotal = kNotMeasured;  // (build + query) peer / Δ
  double bytesPerTriangle = kNotMeasured;
  std::string memoryMethod;
  std::string agreement;  // "reference", "yes" or "NO (disagreements)"
  bool agreed = true;
  double maxDifference = kNotMeasured;  // max |peer − Δ| / D
  std::string note;
};

/// W5's adaptive grid (ib::AdaptiveGrid) at one thread count: its build, and a run of moves of
/// the boundary. "In Δ" is the time inside Δ's distance queries (GridStatistics::querySeconds).
struct GridPhases {
  int threads = 1;
  std::size_t vertices = 0;
  std::size_t leaves = 0;
  double buildSeconds = kNotMeasured;  // the median build (GridStatistics::seconds)
  int buildRuns = 0;
  std::size_t buildQueries = 0;
  double buildQuerySeconds = kNotMeasured;
  double moveSeconds = kNotMeasured;  // means over the moves
  double moveQueries = kNotMeasured;
  double moveQuerySeconds = kNotMeasured;
  std::string agreement;  // against a direct query and the first thread count
  bool agreed = true;
};

/// W5's grid at every thread count, and how it was made and moved.
struct GridReport {
  int levels = 0;
  bool signedDistance = false;
  double cellDiagonal = kNotMeasured;  // of a finest cell, h
  int moves = 0;
  double step = kNotMeasured;  // how far the furthest vertex moves in one move
  std::vector<GridPhases> rows;
};

struct MeshReport {
  std::string path;
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  double diagonal = 0.0;
  std::size_t points = 0;
  std::vector<Row> rows;
  GridReport grid;                    // W5 (no rows when W5 was not run)
  std::vector<std::string> disputes;  // brute-force verdicts on disagreements
};

Row makeRow(const std::string& workload, const std::string& library, int threads);

/// 1234567 → "1,234,567".
std::string withCommas(std::size_t value);

/// Fills the peer/Δ ratios of `row` from Δ's row of the same workload and thread count in `rows`.
void setRatios(Row& row, const std::vector<Row>& rows);

/// ", Embree 3.13.5, CGAL 5.5.1, FCL 0.7.0": the peers this program was built with.
std::string peerVersions();

/// The mesh's table, W5's grid table, the peers it was built without, and the disagreements'
/// verdicts.
void printTable(const MeshReport& report);

/// One JSON object for the whole run on stdout.
void printJson(std::size_t points, const std::vector<MeshReport>& reports, bool agreed);

}  // namespace delta::bench
