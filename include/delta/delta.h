#pragma once

/// Δ's umbrella header: every public concept, layer by layer.

#include "delta/core/aabb.h"
#include "delta/core/aligned_allocator.h"
#include "delta/core/contact_point.h"
#include "delta/core/error.h"
#include "delta/core/mat3.h"
#include "delta/core/parallel.h"
#include "delta/core/rotation.h"
#include "delta/core/sphere.h"
#include "delta/core/triangle.h"
#include "delta/core/vec3.h"
#include "delta/core/version.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/bounding_sphere.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/measures.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/topology.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/filter.h"
