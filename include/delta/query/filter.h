#pragma once

#include <span>
#include <vector>

#include "delta/core/contact_point.h"

namespace delta::contactdetection {

/// The seed's redundancy elimination, filter(h): walk the contact points by ascending normal
/// length (ties in input order) and keep a point unless a point kept before it lies closer than
/// `h` (strictly, compared as squares: |x − x_kept|² < h²). So the closest contact is always kept,
/// and of a cluster of points closer together than the mesh size h only the deepest survives, while
/// separate contact regions (a concave particle touching at two places) keep a point each.
///
/// Returns the kept points in their input order. Exactly the result of that quadratic definition,
/// computed in O(n log n) with a uniform grid of cells no smaller than h (points closer than h
/// lie in neighbouring cells, the cells' rounding included). Throws delta::Error when `h` is not
/// finite and positive or lies outside [2⁻⁴⁸¹, 2²⁰⁰] (where h² would be subnormal, or squared
/// distances could overflow), and when a point is not finite or lies beyond the coordinate
/// range (±2²⁰⁰, mesh/coordinate_range.h) or a normal is not finite. No points: none kept.
/// Coincident points (distance 0 < h) keep only the first by that order; points exactly h apart are
/// both kept. Overlap markers play no part: an overlapping point is ordered by its normal length
/// like any other.
///
/// Threading: a pure function; may be called from any number of threads at once.
std::vector<ContactPoint> filter(std::span<const ContactPoint> contacts, double h);

}  // namespace delta::contactdetection
