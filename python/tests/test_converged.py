"""The penalty solver's `converged` flag in every contact record (delta.contact_dtype), the same
as the C++ tool's `converged` CSV column; always True for the exact methods."""

import numpy as np

import delta
from conftest import read_csv

EPS = 0.05
TRANSLATE_B = (1.0, 0.1, 0.0)  # two spheres pushed into each other: some pairs not certified


def spheres():
    return delta.icosphere(2), delta.icosphere(2).translate(TRANSLATE_B)


def test_penalty_records_carry_the_converged_flag_of_the_cli(cli, tmp_path):
    a, b = spheres()
    found = delta.contacts(a, b, EPS, method="penalty")
    assert "converged" in delta.contact_dtype.names
    assert found.dtype == delta.contact_dtype and found["converged"].dtype == np.bool_
    assert 0 < np.count_nonzero(~found["converged"]) < len(found)
    out = tmp_path / "contacts.csv"
    cli("contact", "builtin:icosphere:2", "builtin:icosphere:2", "--translate-b", "1,0.1,0",
        "--eps", EPS, "--method", "penalty", "--out", out)
    rows = read_csv(out)
    np.testing.assert_array_equal(found["triangle_a"], [int(row["triangle_a"]) for row in rows])
    np.testing.assert_array_equal(found["triangle_b"], [int(row["triangle_b"]) for row in rows])
    np.testing.assert_array_equal(found["converged"], [row["converged"] == "1" for row in rows])
    # The filter keeps each kept record's flag.
    kept = delta.filter(found, 0.05)
    assert 0 < len(kept) < len(found)
    for record in kept:
        same = (found["triangle_a"] == record["triangle_a"]) & (
            found["triangle_b"] == record["triangle_b"])
        assert found["converged"][same][0] == record["converged"]


def test_exact_methods_are_always_converged():
    a, b = spheres()
    for method in ("hybrid", "bruteforce"):
        found = delta.contacts(a, b, EPS, method=method)
        assert len(found) > 0 and found["converged"].all(), method
