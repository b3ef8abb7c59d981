"""The guide's "Load a mesh and query it" (docs/guide.md) in Python: a closed mesh from a file, the
signed distance of two points to it, and the contacts with a moved copy of it.

    python3 load_and_query.py MESH        (the test runs it on CGAL's fandisk.off)
"""

# [guide:begin query]
import sys
import numpy as np
import delta

mesh = delta.QueryMesh(delta.load(sys.argv[1]))  # checked, then prepared once
points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
r = delta.distance(mesh, points, signed=True)  # one record a point: delta.distance_dtype
for d, triangle in zip(delta.signed_distance(r), r["triangle"]):
    print(f"signed distance {d:g}, triangle {triangle}")
copy = mesh.copy()  # shares the prepared data; moving it rebuilds nothing
copy.transform(delta.RigidTransform.translation_by((0.9, 0, 0)))
touching = delta.contacts(mesh, copy, eps=0.001)  # one record a pair: delta.contact_dtype
print(f"{len(touching)} contact points closer than 2ε")
# [guide:end query]


def distances_by_loop(triangles, point):
    """The distance from `point` to every triangle of `triangles` (m, 3, 3), the brute force: to
    the triangle's plane where the point lies over the triangle, else to its nearest edge."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)
    normal = np.cross(b - a, c - a)
    over = np.linalg.norm(normal, axis=1) > 0
    for u, v in ((a, b), (b, c), (c, a)):
        over &= dot(np.cross(v - u, point - u), normal) >= 0
    to_plane = np.abs(dot(point - a, normal)) / np.linalg.norm(normal, axis=1)

    def to_edge(u, v):
        t = np.clip(dot(point - u, v - u) / dot(v - u, v - u), 0, 1)
        return np.linalg.norm(point - (u + t[:, None] * (v - u)), axis=1)

    to_edges = np.minimum.reduce([to_edge(a, b), to_edge(b, c), to_edge(c, a)])
    return np.where(over, to_plane, to_edges)


# The answers are exact: the same as a loop over every triangle, to the rounding of NumPy's
# arithmetic (relative to the mesh's size), and the triangle is one where that loop finds it.
surface = delta.load(sys.argv[1])
triangles = surface.vertices[surface.triangles]
tolerance = 1e-12 * np.linalg.norm(np.ptp(surface.vertices, axis=0))
for point, answer in zip(points, r):
    nearest = distances_by_loop(triangles, point)
    if not (abs(nearest.min() - answer["distance"]) <= tolerance
            and nearest[answer["triangle"]] - nearest.min() <= tolerance):
        sys.exit(f"point {point}: {answer['distance']!r} at triangle {answer['triangle']}, but a "
                 f"loop over the triangles gives {nearest.min()!r} at {nearest.argmin()}")
# (0, 0, 2) is far outside a mesh of size 1; a copy moved by 0.9 along x overlaps its end.
if r["inside"][1] or len(touching) == 0:
    sys.exit("unexpected: (0, 0, 2) inside, or no contact with the moved copy")
