#include "delta/query/filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "delta/core/error.h"

namespace delta::contactdetection {
namespace {

ContactPoint contactAt(const Vec3& x, double halfGap, std::uint32_t id) {
  ContactPoint contact;
  contact.x = x;
  contact.normal = {0, 0, halfGap};
  contact.direction = {0, 0, 1};
  contact.distance = 2 * halfGap;
  contact.first = id;
  contact.second = id;
  return contact;
}

/// The seed's definition, quadratic: the reference the fast filter must reproduce exactly.
std::vector<ContactPoint> filterByDefinition(const std::vector<ContactPoint>& contacts, double h) {
  std::vector<std::size_t> order(contacts.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lengthSquared(contacts[a].normal) < lengthSquared(contacts[b].normal);
  });
  std::vector<std::size_t> kept;
  for (std::size_t candidate : order) {
    bool crowded = false;
    for (std::size_t other : kept)
      crowded = crowded || distanceSquared(contacts[other].x, contacts[candidate].x) < h * h;
    if (!crowded) kept.push_back(candidate);
  }
  std::sort(kept.begin(), kept.end());
  std::vector<ContactPoint> result;
  for (std::size_t i : kept)
    result.push_back(contacts[i]);
  return result;
}

void expectSameIds(const std::vector<ContactPoint>& actual,
                   const std::vector<ContactPoint>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i)
    EXPECT_EQ(actual[i].first, expected[i].first);
}

TEST(Filter, KeepsTheDeepestOfAClusterAndSeparateRegions) {
  const std::vector<ContactPoint> contacts = {
      contactAt({0, 0, 0}, 0.3, 0), contactAt({0.05, 0, 0}, 0.1, 1),   // one cluster
      contactAt({0, 0.05, 0}, 0.2, 2), contactAt({5, 0, 0}, 0.4, 3)};  // and a far region
  const std::vector<ContactPoint> kept = filter(contacts, 0.1);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept[0].first, 1u);  // the smallest normal of the cluster
  EXPECT_EQ(kept[1].first, 3u);
}

TEST(Filter, DistanceExactlyHIsNotCloser) {
  const std::vector<ContactPoint> contacts = {contactAt({0, 0, 0}, 0.1, 0),
                                              contactAt({0.5, 0, 0}, 0.2, 1)};
  EXPECT_EQ(filter(contacts, 0.5).size(), 2u);
  EXPECT_EQ(filter(contacts, std::nextafter(0.5, 1.0)).size(), 1u);
}

TEST(Filter, MatchesTheQuadraticDefinitionOnRandomSets) {
  std::mt19937_64 random(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const double offset = trial % 4 == 3 ? 1e7 : 0.0;  // far from the origin too
    std::vector<ContactPoint> contacts;
    // Up to 64 contacts filter on the stack, more through a grid: both sides of the line.
    const std::size_t count = trial < 4 ? std::size_t{63} + trial : 1 + trial * 25;
    for (std::size_t i = 0; i < count; ++i) {
      Vec3 x{offset + unit(random), offset + unit(random), unit(random) * 0.1};
      if (i % 7 == 3) x = contacts[i / 2].x;                     // duplicates
      const double halfGap = std::floor(unit(random) * 5) / 10;  // many ties
      contacts.push_back(contactAt(x, halfGap, static_cast<std::uint32_t>(i)));
    }
    for (double h : {1e-6, 0.01, 0.05, 0.2, 3.0})
      expectSameIds(filter(contacts, h), filterByDefinition(contacts, h));
  }
}

TEST(Filter, HandlesEmptyInputAndRejectsBadH) {
  EXPECT_TRUE(filter({}, 1.0).empty());
  const std::vector<ContactPoint> one = {contactAt({1, 2, 3}, 0.1, 7)};
  EXPECT_EQ(filter(one, 1.0).size(), 1u);
  // Also h whose square would underflow or whose points' squared distances could overflow
  // (1e-170: two coincident points were both kept).
  for (double h : {0.0, -1.0, double(NAN), double(INFINITY), 1e-170, 0x1p-482, 1e300})
    EXPECT_THROW(filter(one, h), Error) << h;
  EXPECT_EQ(filter(one, 0x1p-481).size(), 1u);
  EXPECT_EQ(filter(one, 0x1p200).size(), 1u);
}

TEST(Filter, RefusesPointsThatAreNotFiniteOrBeyondTheCoordinateRange) {
  // A NaN normal would break the sort's ordering; a NaN point was kept silently.
  for (const std::size_t count : {std::size_t{3}, std::size_t{80}}) {
    std::vector<ContactPoint> contacts;
    for (std::uint32_t i = 0; i < count; ++i)
      contacts.push_back(contactAt({i * 1.0, 0, 0}, 0.1, i));
    EXPECT_NO_THROW(filter(contacts, 0.5));
    for (const Vec3& x : {Vec3{NAN, 0, 0}, Vec3{0, INFINITY, 0}, Vec3{0, 0, 1e61}}) {
      std::vector<ContactPoint> bad = contacts;
      bad[1].x = x;
      EXPECT_THROW(filter(bad, 0.5), Error);
    }
    std::vector<ContactPoint> bad = contacts;
    bad[2].normal.y = NAN;
    EXPECT_THROW(filter(bad, 0.5), Error);
  }
}

TEST(Filter, PointsCloserThanHFallInNeighbouringCellsWhateverTheBoxsExtent) {
  // An audit's case: with cells 1e-9 of h wider than h, the cells' rounding (about ε of the
  // box's extent, 2 here) put these two points, 9.99999528e-11 apart, two cells apart for
  // h = 1e-10, and the later one was kept.
  const double h = 1e-10, a = 0.47196848017196857, b = 0.47196848027196853;
  std::vector<ContactPoint> contacts = {contactAt({-1, 0, 0}, 3, 0), contactAt({b, 0, 0}, 1, 1),
                                        contactAt({a, 0, 0}, 2, 2)};
  for (std::uint32_t i = 0; i < 70; ++i)
    contacts.push_back(contactAt({0.6 + 0.005 * i, 1, 1}, 4, 3 + i));
  expectSameIds(filter(contacts, h), filterByDefinition(contacts, h));
  // Pairs just under h apart at random places in boxes of extents 2 to 2e9.
  std::mt19937_64 random(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const double extent = std::pow(10.0, trial % 10), gap = extent * 1e-10;
    std::vector<ContactPoint> pairs = {contactAt({-extent, 0, 0}, 9, 0)};
    for (std::uint32_t i = 1; i < 400; i += 2) {
      const double x = unit(random) * extent;
      double y = std::nextafter(x + gap, 0.0);
      while (!((y - x) * (y - x) < gap * gap))
        y = std::nextafter(y, 0.0);
      const double z = i * 0.01 * extent;  // pairs far apart from one another
      pairs.push_back(contactAt({y, 0, z}, 1, i));
      pairs.push_back(contactAt({x, 0, z}, 2, i + 1));
    }
    expectSameIds(filter(pairs, gap), filterByDefinition(pairs, gap));
  }
}

TEST(Filter, TinyHOnHugeCoordinatesStaysExact) {
  std::vector<ContactPoint> contacts;
  for (std::uint32_t i = 0; i < 50; ++i)
    contacts.push_back(contactAt({1e12 + i * 1e-3, 0, 0}, 0.01 * i, i));
  contacts.push_back(contactAt({-1e12, 0, 0}, 0.0, 99));
  for (double h : {1e-4, 2.5e-3, 0.02})
    expectSameIds(filter(contacts, h), filterByDefinition(contacts, h));
}

}  // namespace
}  // namespace delta::contactdetection
