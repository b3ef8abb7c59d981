// The extension module `delta._delta`; the package `delta` (python/delta/__init__.py) re-exports
// it. Every query, build, step and move runs without the GIL.
#include <pybind11/pybind11.h>

#include "delta/core/version.h"

#include "bindings.h"

PYBIND11_MODULE(_delta, module) {
  namespace python = delta::python;
  module.doc() =
      "Δ (delta): triangle-mesh proximity — contacts, distances, inside/outside — for DEM and "
      "immersed-boundary codes. The compiled part of the package `delta`; import `delta`.";
  // Classes take their __module__ (and the submodules their names) from the module's __name__
  // while they are made: "delta" makes them read delta.Mesh, delta.dem.World in signatures,
  // reprs and pickles, the names the package re-exports them under.
  const pybind11::object name = module.attr("__name__");
  module.attr("__name__") = "delta";
  module.attr("__version__") = delta::version();
  module.attr("git_commit") = delta::gitCommit();
  python::bindMesh(module);
  python::bindQuery(module);
  pybind11::module_ dem = module.def_submodule(
      "dem", "The Discrete Element Method: rigid triangulated particles in contact.");
  python::bindDem(dem);
  pybind11::module_ ib = module.def_submodule(
      "ib", "Immersed boundaries: an adaptive grid with the boundary's distance at its vertices.");
  python::bindIb(ib);
  module.attr("__name__") = name;
}
