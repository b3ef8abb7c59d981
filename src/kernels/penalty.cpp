#include "delta/kernels/penalty.h"

#include <cstring>

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/detail/penalty_newton.h"

namespace delta::kernels {

static_assert(kPenaltyTolerance == detail::PenaltySchedule::kTolerance);
static_assert(kPenaltyIterations == detail::PenaltySchedule::kIterations);

namespace {

BatchStatistics countUnconverged(const PairResults& results) noexcept {
  BatchStatistics statistics;
  statistics.pairs = results.size();
  const std::uint8_t* converged = results.convergedData();
  for (std::size_t i = 0; i < results.size(); ++i)
    statistics.unconverged += converged[i] == 0;
  return statistics;
}

}  // namespace

BatchStatistics penaltyDistances(const TriangleSoA& first, const TriangleSoA& second,
                                 PairResults& results, Isa isa) noexcept {
  const detail::PairStreams out = results.prepare(detail::blockPairCount(first, second));
  detail::batchKernels(isa).penaltyBlocks(detail::soaView(first), detail::soaView(second),
                                          results.size(), out);
  return countUnconverged(results);
}

BatchStatistics penaltyDistances(const Triangle& one, const TriangleSoA& block, std::size_t begin,
                                 std::size_t end, PairResults& results, Isa isa) noexcept {
  const detail::PairStreams out = results.prepare(detail::rangePairCount(block, begin, end));
  detail::batchKernels(isa).penaltyOne(detail::coordinates(one), detail::soaView(block), begin,
                                       results.size(), out);
  return countUnconverged(results);
}

}  // namespace delta::kernels
