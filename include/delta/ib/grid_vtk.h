#pragma once

#include "delta/ib/adaptive_grid.h"
#include "delta/io/vtk.h"

namespace delta::ib {

/// The grid as ParaView shows it (write it with io::writeVtu): the leaves of every level as
/// voxels (their corners as Cell::corners lists them, VTK's voxel order) and every grid vertex as
/// a point, in vertex order. Point data: `signed_distance` (negative inside) when the grid's
/// distances are signed, `distance` otherwise, and `error_bound` (AdaptiveGrid::errorBounds: 0
/// where the distance is exact), Float64 as computed; `finest_level` (the finest level of the
/// leaves it is a corner of), UInt8. Cell data: `level`, UInt8.
///
/// A vertex on the face of a coarser leaf is a corner of the finer leaves only, so the file has
/// hanging nodes: ParaView draws it, but interpolation across such a face is not continuous.
///
/// Threading: reads the grid only; any number of threads may call it on one grid that no thread
/// moves meanwhile.
io::VtkVoxelGrid toVtk(const AdaptiveGrid& grid);

}  // namespace delta::ib
