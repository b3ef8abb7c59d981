// The parts of the extension module `delta._delta`, one a layer (python/src/<layer>.cpp), each
// adding its classes and functions to the module (or to its submodule).
#pragma once

#include <pybind11/pybind11.h>

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// delta.Error, Quaternion, RigidTransform, Mesh, primitives, load and save.
void bindMesh(py::module_& module);
/// QueryMesh, contacts, point_contacts, distance, filter, minimum_distance, overlap.
void bindQuery(py::module_& module);
/// The submodule dem: Parameters, ParticleShape, World, RestitutionMeter, scenarios.
void bindDem(py::module_& dem);
/// The submodule ib: AdaptiveGrid.
void bindIb(py::module_& ib);

}  // namespace delta::python
