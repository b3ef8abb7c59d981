"""Δ (delta): triangle-mesh proximity — contacts, distances, inside/outside.

Load or build meshes, move them, and find where two meshes, or points and a mesh, come closer than
ε, with NumPy arrays in and out::

    import numpy as np
    import delta

    a = delta.granulate(3)
    b = delta.granulate(4).translate((1.8, 0.2, 0.1))
    touching = delta.contacts(a, b, eps=0.05)            # structured array, delta.contact_dtype
    kept = delta.filter(touching, h=0.1)
    mesh = delta.QueryMesh(delta.load("armadillo.off"))  # prepare once, query many times
    r = delta.distance(mesh, np.random.rand(1000, 3), signed=True)
    print(r["distance"], r["closest"], r["triangle"], r["inside"])

Every query, build, DEM step and grid move runs without the global interpreter lock, in parallel
over the cores (Delta's thread pool; OMP_NUM_THREADS), so Python threads run queries side by side. Bad input
raises delta.Error (a ValueError) naming what and where. Submodules: delta.dem (the Discrete
Element Method) and delta.ib (immersed boundaries: an adaptive grid).
"""

import numpy as _np

from . import _delta
from ._signatures import attach as _attach

# inspect.signature and help() see the extension's parameters (delta/_signatures.py).
for _module in (_delta, _delta.dem, _delta.ib):
    _attach(_module)
del _module

from ._delta import (
    NO_TRIANGLE,
    Error,
    IntersectionCurve,
    Mesh,
    MinimumDistance,
    Overlap,
    OverlapRegion,
    Quaternion,
    QueryMesh,
    RigidTransform,
    __version__,
    box,
    contact_dtype,
    contacts,
    cylinder,
    distance,
    distance_dtype,
    filter,
    git_commit,
    granulate,
    icosphere,
    load,
    load_with_statistics,
    minimum_distance,
    overlap,
    point_contacts,
    quad,
    save,
)
from . import dem, ib

__all__ = [
    "NO_TRIANGLE",
    "Error",
    "IntersectionCurve",
    "Mesh",
    "MinimumDistance",
    "Overlap",
    "OverlapRegion",
    "Quaternion",
    "QueryMesh",
    "RigidTransform",
    "box",
    "contact_dtype",
    "contacts",
    "cylinder",
    "dem",
    "distance",
    "distance_dtype",
    "filter",
    "git_commit",
    "granulate",
    "ib",
    "icosphere",
    "load",
    "load_with_statistics",
    "minimum_distance",
    "overlap",
    "point_contacts",
    "quad",
    "save",
    "signed_distance",
]


def signed_distance(result):
    """The signed distance of a `distance(..., signed=True)` result: negative inside.

    `result` is a structured array of delta.distance_dtype; returns a float64 array of its shape.
    Raises TypeError for anything else.
    """
    if not isinstance(result, (_np.ndarray, _np.void)) or result.dtype != distance_dtype:
        raise TypeError(
            "signed_distance: result must be a NumPy array of delta.distance_dtype "
            "(what distance(..., signed=True) returns), not "
            + (
                f"one of dtype {result.dtype}"
                if isinstance(result, (_np.ndarray, _np.void))
                else type(result).__name__
            )
        )
    return _np.where(result["inside"], -result["distance"], result["distance"])
