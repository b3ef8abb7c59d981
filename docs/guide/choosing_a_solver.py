"""The guide's "Choosing a solver" (docs/guide.md) in Python: the three triangle–triangle solvers
through the contact query."""

import sys

import numpy as np

import delta

a = delta.QueryMesh(delta.granulate(1))
b = delta.QueryMesh(delta.granulate(2))
b.transform(delta.RigidTransform.translation_by((1.8, 0.1, 0.2)))
epsilon = 0.05

# [guide:begin query]
exact = delta.contacts(a, b, eps=epsilon)  # method="hybrid": exact, SIMD
reference = delta.contacts(a, b, eps=epsilon, method="bruteforce")  # exact, scalar
approximate = delta.contacts(a, b, eps=epsilon, method="penalty")  # may miss or misplace
# [guide:end query]
print(f"{len(exact)} contacts (hybrid), {len(reference)} (brute force), "
      f"{len(approximate)} (penalty)")

# The hybrid's contacts are the brute force's: the same pairs, distances to 1e-12 of the size.
same = (0 < len(exact) == len(reference)
        and np.array_equal(exact["triangle_a"], reference["triangle_a"])
        and np.array_equal(exact["triangle_b"], reference["triangle_b"])
        and np.all(np.abs(exact["distance"] - reference["distance"]) <= 1e-12 * 2.0))
if not same:
    sys.exit("the hybrid's contacts differ from the brute force's")
