"""The strict boundary: every array argument of every binding is read exactly or refused.

The rule (python/src/arrays.h): what is not real numbers (None, strings, booleans, complex
numbers, objects, float128) raises TypeError; real numbers of another shape raise delta.Error (a
ValueError), except for the fixed-size arguments (3-vectors, 3x3 matrices), which pybind11's
overload resolution refuses with a TypeError; NaN or infinite values where finite ones are asked
and integers float64 would round raise delta.Error. Never a read outside the argument's buffer.
"""

import pickle
import re

import numpy as np
import pytest

import delta

NAN = float("nan")

# Values that are not three real numbers: TypeError wherever a 3-vector is asked.
NOT_A_VECTOR = [
    pytest.param((1, 2), id="length-2"),
    pytest.param((1, 2, 3, 4), id="length-4"),
    pytest.param(None, id="None"),
    pytest.param("abc", id="string"),
    pytest.param(b"xyz", id="bytes"),
    pytest.param(5, id="scalar"),
    pytest.param(np.float64(5), id="numpy-scalar"),
    pytest.param((True, False, True), id="bools"),
    pytest.param([1, True, 2], id="a-bool-among-ints"),
    pytest.param(np.array([True, False, True]), id="bool-array"),
    pytest.param((1j, 0, 0), id="complex"),
    pytest.param(np.array([1, 2, 3], dtype=object), id="object-array"),
    pytest.param(np.zeros((3, 1)), id="shape-3x1"),
    pytest.param(np.zeros((1, 3)), id="shape-1x3"),
    pytest.param(np.array([1, 2, 3], dtype=np.longdouble), id="float128"),
    pytest.param({"x": 1}, id="dict"),
    pytest.param([[1, 2], [3]], id="ragged"),
]
# Three numbers that are not allowed: delta.Error.
BAD_VECTOR_VALUES = [
    pytest.param((NAN, 0, 0), id="nan"),
    pytest.param((0, float("inf"), 0), id="inf"),
    pytest.param(np.array([2**53 + 1, 0, 0]), id="int64-beyond-2^53"),
    pytest.param(np.array([2**64 - 1, 0, 0], dtype=np.uint64), id="uint64-max"),
]


def world():
    return delta.dem.World(delta.dem.Parameters(1e-4, 1e-3, 1e-3, 1e5))


def particle_world():
    w = world()
    w.add_shape(delta.dem.ParticleShape.sphere(0.1, 1000.0))
    w.add_particle(0, (0, 0, 0))
    return w


# Every binding that takes a 3-vector, called with `v` in that place.
VECTOR_BINDINGS = {
    "RigidTransform.translation_by": lambda v: delta.RigidTransform.translation_by(v),
    "RigidTransform(translation)": lambda v: delta.RigidTransform(translation=v),
    "RigidTransform.translation=": lambda v: setattr(delta.RigidTransform(), "translation", v),
    "RigidTransform.rotation_about(pivot)": lambda v: delta.RigidTransform.rotation_about(
        delta.Quaternion(), v
    ),
    "Quaternion.from_axis_angle": lambda v: delta.Quaternion.from_axis_angle(v, 1.0),
    "Mesh.translate": lambda v: delta.box().translate(v),
    "Mesh.scale(pivot)": lambda v: delta.box().scale(2.0, v),
    "Mesh.stretch": lambda v: delta.box().stretch(v),
    "Mesh.rotate(axis)": lambda v: delta.box().rotate(v, 1),
    "Mesh.rotate(quaternion, pivot)": lambda v: delta.box().rotate(delta.Quaternion(), v),
    "icosphere(center)": lambda v: delta.icosphere(0, center=v),
    "box(size)": lambda v: delta.box(v),
    "box(center)": lambda v: delta.box(center=v),
    "cylinder(center)": lambda v: delta.cylinder(center=v),
    "quad(center)": lambda v: delta.quad(center=v),
    "granulate(semi_axes)": lambda v: delta.granulate(1, v),
    "dem.Parameters(gravity)": lambda v: delta.dem.Parameters(1e-4, 1e-3, 1e-3, 1e5, gravity=v),
    "dem.Parameters.gravity=": lambda v: setattr(
        delta.dem.Parameters(1e-4, 1e-3, 1e-3, 1e5), "gravity", v
    ),
    "World.add_particle(position)": lambda v: particle_world().add_particle(0, v),
    "World.add_particle(velocity)": lambda v: particle_world().add_particle(0, (1, 0, 0), velocity=v),
    "World.add_obstacle(velocity)": lambda v: world().add_obstacle(delta.quad(), velocity=v),
    "World.set_pose": lambda v: particle_world().set_pose(0, v, delta.Quaternion()),
    "World.set_velocity": lambda v: particle_world().set_velocity(0, v),
    "World.set_angular_velocity": lambda v: particle_world().set_angular_velocity(0, v),
}


@pytest.mark.parametrize("value", NOT_A_VECTOR)
@pytest.mark.parametrize("binding", sorted(VECTOR_BINDINGS))
def test_what_is_not_a_3_vector_is_a_type_error(binding, value):
    with pytest.raises(TypeError):
        VECTOR_BINDINGS[binding](value)


@pytest.mark.parametrize("value", BAD_VECTOR_VALUES)
@pytest.mark.parametrize("binding", sorted(VECTOR_BINDINGS))
def test_non_finite_or_inexact_3_vectors_are_delta_errors(binding, value):
    with pytest.raises(delta.Error, match="3-vector"):
        VECTOR_BINDINGS[binding](value)


def test_the_reproducers_of_issue_21():
    # A translation of 2.6e-315 and a zero gravity were read from past the end of (2,) arrays.
    with pytest.raises(TypeError):
        delta.RigidTransform.translation_by((1, 2))
    with pytest.raises(TypeError):
        delta.dem.Parameters(1e-4, 1e-3, 1e-3, 1e5, gravity=(0, -9.81))
    # An integer angle: the matrix overload read heap contents into its error message; now the
    # axis-angle overload takes it.
    mesh = delta.box().rotate((0, 0, 1), 1)
    expected = delta.box().rotate((0, 0, 1), 1.0)
    np.testing.assert_array_equal(mesh.vertices, expected.vertices)
    with pytest.raises(TypeError) as error:
        delta.box().rotate((0, 0), 1)
    assert "e-3" not in str(error.value)  # no denormal garbage in the message


def test_valid_vectors_of_every_numeric_kind_are_read_exactly():
    for value in [(1, 2, 3), [1.0, 2.0, 3.0], np.array([1, 2, 3], dtype=np.int8),
                  np.array([1, 2, 3], dtype=np.uint64), np.array([1, 2, 3], dtype=np.float32),
                  np.array([1, 2, 3], dtype=">f8"), np.arange(6.0)[1:6:2] - [0, 1, 2],
                  (np.int64(1), np.float32(2), 3)]:
        t = delta.RigidTransform.translation_by(value).translation
        np.testing.assert_array_equal(t, [1.0, 2.0, 3.0])
    exact = delta.RigidTransform.translation_by(np.array([2**53, -(2**53), 0])).translation
    assert exact.tolist() == [2.0**53, -(2.0**53), 0.0]


NOT_A_MATRIX = [np.eye(3)[:2], np.eye(4), np.eye(3).astype(bool), np.eye(3) * 1j, "eye", None,
                np.eye(3).astype(object)]


@pytest.mark.parametrize("value", NOT_A_MATRIX, ids=range(len(NOT_A_MATRIX)))
@pytest.mark.parametrize("binding", ["Quaternion.from_matrix", "Mesh.rotate(matrix)"])
def test_what_is_not_a_3x3_matrix_is_a_type_error(binding, value):
    call = {"Quaternion.from_matrix": delta.Quaternion.from_matrix,
            "Mesh.rotate(matrix)": lambda m: delta.box().rotate(m)}[binding]
    with pytest.raises(TypeError):
        call(value)
    bad = np.eye(3)
    bad[1, 1] = NAN
    with pytest.raises(delta.Error, match="3x3 matrix"):
        call(bad)


def test_homogeneous_matrices():
    motion = delta.RigidTransform.translation_by((1, 2, 3))
    np.testing.assert_array_equal(delta.RigidTransform.from_matrix(motion.matrix).translation,
                                  [1, 2, 3])
    with pytest.raises(delta.Error, match="shape"):
        delta.RigidTransform.from_matrix(np.eye(3))
    for not_numbers in [np.eye(4).astype(bool), None, "eye", np.eye(4) * 1j]:
        with pytest.raises(TypeError):
            delta.RigidTransform.from_matrix(not_numbers)
    inf = np.eye(4)
    inf[0, 3] = np.inf
    with pytest.raises(delta.Error, match="value 3"):
        delta.RigidTransform.from_matrix(inf)


# Every binding that takes an array of points, called with `p` there.
def points_bindings():
    mesh = delta.icosphere(1)
    return {
        "distance": lambda p: delta.distance(mesh, p),
        "point_contacts": lambda p: delta.point_contacts(mesh, p, 0.1),
        "Quaternion.rotate": lambda p: delta.Quaternion().rotate(p),
        "RigidTransform.apply": lambda p: delta.RigidTransform().apply(p),
        "Mesh(vertices)": lambda p: delta.Mesh(p, [[0, 1, 2]]),
        "ib.AdaptiveGrid(domain)": lambda p: delta.ib.AdaptiveGrid(mesh, levels=2, domain=p),
    }


NOT_POINTS = [
    pytest.param(None, id="None"),
    pytest.param("points", id="string"),
    pytest.param(np.ones((3, 3), dtype=bool), id="bool-array"),
    pytest.param([[0, 0, True], [1, 0, 0], [0, 1, 0]], id="a-bool-in-a-list"),
    pytest.param(np.zeros((3, 3), dtype=complex), id="complex"),
    pytest.param(np.zeros((3, 3), dtype=object), id="object-array"),
    pytest.param(np.zeros((3, 3), dtype=np.longdouble), id="float128"),
    pytest.param(np.zeros(3, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")]), id="records"),
]
WRONG_SHAPE = [
    pytest.param(np.zeros((3, 2)), id="(3, 2)"),
    pytest.param(np.zeros(9), id="(9,)"),
    pytest.param(7.0, id="scalar"),
]


@pytest.mark.parametrize("value", NOT_POINTS)
@pytest.mark.parametrize("binding", sorted(points_bindings()))
def test_points_that_are_not_numbers_are_type_errors(binding, value):
    if value is None and binding == "ib.AdaptiveGrid(domain)":
        pytest.skip("domain=None asks for the default domain")
    with pytest.raises(TypeError, match="real numbers"):
        points_bindings()[binding](value)


@pytest.mark.parametrize("value", WRONG_SHAPE)
@pytest.mark.parametrize("binding", sorted(points_bindings()))
def test_points_of_another_shape_are_delta_errors(binding, value):
    with pytest.raises(delta.Error, match="shape"):
        points_bindings()[binding](value)


@pytest.mark.parametrize("binding", sorted(points_bindings()))
def test_points_with_integers_float64_would_round_are_delta_errors(binding):
    inexact = np.array([[0, 0, 0], [1, 0, 0], [0, 2**53 + 1, 0]], dtype=np.int64)
    with pytest.raises(delta.Error, match="2\\^53"):
        points_bindings()[binding](inexact)


@pytest.mark.parametrize("binding", ["distance", "point_contacts", "Quaternion.rotate",
                                     "RigidTransform.apply"])
def test_non_finite_points_are_delta_errors_naming_the_point(binding):
    with pytest.raises(delta.Error, match="point 1"):
        points_bindings()[binding]([[0, 0, 0], [0, NAN, 0], [0, 0, 0]])


def test_moves_that_leave_the_range_of_doubles_are_refused():
    far = delta.RigidTransform.translation_by((1e308, 0, 0))
    with pytest.raises(delta.Error, match="out of the range of doubles"):
        far.apply([[0, 0, 0], [1e308, 0, 0]])


def test_misaligned_and_strided_points_are_read_correctly():
    mesh = delta.icosphere(2)
    points = np.random.default_rng(1).random((50, 3))
    expected = delta.distance(mesh, points)
    raw = np.zeros(points.nbytes + 1, np.uint8)
    misaligned = raw[1:].view(np.float64).reshape(points.shape)
    misaligned[:] = points
    assert not misaligned.flags.aligned
    np.testing.assert_array_equal(delta.distance(mesh, misaligned), expected)
    strided = np.zeros((50, 6))
    strided[:, ::2] = points
    np.testing.assert_array_equal(delta.distance(mesh, strided[:, ::2]), expected)


TRIANGLE_VERTICES = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


@pytest.mark.parametrize(
    "triangles, error, message",
    [
        ([[0, 1, 2.0]], TypeError, "integers, not of dtype float64"),
        ([[0, 1, True]], TypeError, "integers, not booleans"),
        (np.ones((1, 3), dtype=bool), TypeError, "integers, not booleans"),
        (None, TypeError, "integers, not None"),
        ("012", TypeError, "not a string"),
        ([[0, 1, 2, 0]], delta.Error, "shape"),
        ([0, 1, 2], delta.Error, "shape"),
        ([[0, 1, -1]], delta.Error, "vertex -1"),
        (np.array([[0, 1, 2**63]], dtype=np.uint64), delta.Error, "vertex 9223372036854775808"),
        (np.array([[0, 1, 2**32]], dtype=np.int64), delta.Error, "vertex 4294967296"),
        ([[0, 1, 3]], delta.Error, "vertex 3"),
    ],
)
def test_triangle_indices_are_checked(triangles, error, message):
    with pytest.raises(error, match=message):
        delta.Mesh(TRIANGLE_VERTICES, triangles)


def test_triangle_indices_of_any_integer_dtype():
    for dtype in (np.uint8, np.int16, np.uint32, np.int64, np.uint64):
        mesh = delta.Mesh(TRIANGLE_VERTICES, np.array([[0, 1, 2]], dtype=dtype))
        assert mesh.triangles.tolist() == [[0, 1, 2]]


def test_out_arrays_are_checked():
    mesh = delta.icosphere(1)
    points = np.random.default_rng(2).random((4, 3))
    with pytest.raises(TypeError, match="dtype"):
        delta.distance(mesh, points, out=np.empty(4))
    with pytest.raises(TypeError, match="NumPy array"):
        delta.distance(mesh, points, out=[0, 0, 0, 0])
    with pytest.raises(delta.Error, match="shape"):
        delta.distance(mesh, points, out=np.empty(5, delta.distance_dtype))
    with pytest.raises(delta.Error, match="C-contiguous"):
        delta.distance(mesh, points, out=np.empty(8, delta.distance_dtype)[::2])
    read_only = np.empty(4, delta.distance_dtype)
    read_only.setflags(write=False)
    with pytest.raises(delta.Error, match="writeable"):
        delta.distance(mesh, points, out=read_only)
    # A misaligned out (NumPy calls a packed record array aligned) gets the exact answers.
    raw = np.zeros(4 * delta.distance_dtype.itemsize + 1, np.uint8)
    misaligned = raw[1:].view(delta.distance_dtype)
    delta.distance(mesh, points, out=misaligned)
    np.testing.assert_array_equal(misaligned, delta.distance(mesh, points))


def test_out_sharing_memory_with_the_points_is_refused_and_left_unchanged():
    mesh = delta.icosphere(1)
    out = np.zeros(4, delta.distance_dtype)
    out.view(np.float64)[:] = np.random.default_rng(3).random(out.view(np.float64).shape)
    aliased = out.view(np.float64)[:12].reshape(4, 3)  # C-contiguous points inside out
    before = out.copy()
    with pytest.raises(delta.Error, match="shares memory"):
        delta.distance(mesh, aliased, out=out)
    np.testing.assert_array_equal(out, before)
    # A copy of the same numbers works.
    delta.distance(mesh, aliased.copy(), out=out)
    np.testing.assert_array_equal(out, delta.distance(mesh, before.view(np.float64)[:12].reshape(4, 3)))


def test_a_failing_query_leaves_out_unchanged():
    mesh = delta.icosphere(1)
    points = np.random.default_rng(4).random((3000, 3))
    points[2500] = np.nan  # found while the batch is screened, after other answers
    out = np.zeros(3000, delta.distance_dtype)
    with pytest.raises(delta.Error, match="point 2500"):
        delta.distance(mesh, points, out=out)
    np.testing.assert_array_equal(out, np.zeros(3000, delta.distance_dtype))


def contacts():
    a = delta.icosphere(2)
    return delta.contacts(a, a.copy().translate((1.95, 0, 0)), 0.05)


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("distance", NAN, "record 1 has 'distance' nan"),
        ("distance", -1.0, "record 1 has 'distance' -1"),
        ("x", np.inf, "record 1 has 'x'"),
        ("normal", NAN, "record 1 has 'normal'"),
        ("direction", NAN, "record 1 has 'direction'"),
    ],
)
def test_filter_refuses_records_that_are_not_numbers(field, value, message):
    records = contacts()
    assert len(records) > 2
    records[field][1] = value
    with pytest.raises(delta.Error, match=message):
        delta.filter(records, 0.01)


def test_filter_checks_the_kinds_and_ranges_of_the_fields():
    records = contacts()
    kept = delta.filter(records, 0.01)
    assert 0 < len(kept) <= len(records)
    wide = [(name, "i8" if name.startswith("triangle") else records.dtype[name])
            for name in records.dtype.names]
    ids = records.astype(wide)
    ids["triangle_b"][0] = -1
    with pytest.raises(delta.Error, match="record 0 has 'triangle_b' -1"):
        delta.filter(ids, 0.01)
    as_float = records.astype([(name, "f8" if name.startswith("triangle") else records.dtype[name])
                               for name in records.dtype.names])
    with pytest.raises(TypeError, match="'triangle_a' must hold integers"):
        delta.filter(as_float, 0.01)
    as_int = records.astype([(name, "i1" if name == "overlap" else records.dtype[name])
                             for name in records.dtype.names])
    with pytest.raises(TypeError, match="'overlap' must hold booleans"):
        delta.filter(as_int, 0.01)
    with pytest.raises(TypeError, match="structured array"):
        delta.filter(np.zeros((3, 3)), 0.01)
    for h in (NAN, -1.0, 0.0):
        with pytest.raises(delta.Error):
            delta.filter(records, h)


def test_grid_values_are_refused_not_replaced_by_defaults():
    sphere = delta.icosphere(1)
    with pytest.raises(delta.Error, match="lower < upper"):
        delta.ib.AdaptiveGrid(sphere, levels=2, domain=[[1, 1, 1], [-1, -1, -1]])
    with pytest.raises(delta.Error, match="lower < upper"):
        delta.ib.AdaptiveGrid(sphere, levels=2, domain=[[0, 0, 0], [1, NAN, 1]])
    with pytest.raises(delta.Error, match="exactBand nan"):
        delta.ib.AdaptiveGrid(sphere, levels=2, exact_band=NAN)
    with pytest.raises(delta.Error, match="exactBand -1"):
        delta.ib.AdaptiveGrid(sphere, levels=2, exact_band=-1.0)
    for shape, domain in (("(1, 3)", [[0, 0, 0]]), ("(2, 2)", [[0, 0], [1, 1]]),
                          ("(6,)", np.arange(6.0))):
        with pytest.raises(delta.Error, match=r"shape \(2, 3\): lower, upper corner; not " +
                           re.escape(shape)):
            delta.ib.AdaptiveGrid(sphere, levels=2, domain=domain)
    with pytest.raises(TypeError, match=r"ragged list \(rows of 3 and 2 items\)"):
        delta.ib.AdaptiveGrid(sphere, levels=2, domain=[[0, 0, 0], [1, 1]])
    for option in ({"refine_factor": NAN}, {"padding": NAN}, {"padding": -1.0}, {"levels": 0}):
        with pytest.raises(delta.Error):
            delta.ib.AdaptiveGrid(sphere, **{"levels": 2, **option})
    grid = delta.ib.AdaptiveGrid(sphere, levels=2, domain=[[-2, -2, -2], [2, 2, 2]])
    np.testing.assert_array_equal(grid.domain, [[-2, -2, -2], [2, 2, 2]])
    assert grid.exact_band == grid.cell_diagonal(2)
    for level in (-1, 3, 100):
        with pytest.raises(delta.Error, match="level"):
            grid.cell_diagonal(level)
        with pytest.raises(delta.Error, match="level"):
            grid.cells(level)


def test_pickled_states_of_the_wrong_length_are_refused():
    with pytest.raises(delta.Error, match="not 2 values"):
        delta.Quaternion.__new__(delta.Quaternion).__setstate__((1.0, 0.0))
    with pytest.raises(delta.Error, match="not 1 values"):
        delta.Mesh.__new__(delta.Mesh).__setstate__((np.zeros((3, 3)),))
    assert pickle.loads(pickle.dumps(delta.Quaternion(1, 2, 3, 4))).w == delta.Quaternion(1, 2, 3, 4).w


# Scalars follow the same rule (python/src/strict_numbers.h): pybind11's own casters took a bool
# as 1 and anything with __float__ (numpy.longdouble, Fraction) as its rounded value.
NOT_A_REAL = [
    pytest.param(True, id="bool"),
    pytest.param(np.bool_(True), id="numpy.bool_"),
    pytest.param(np.longdouble("0.1"), id="longdouble"),
    pytest.param(__import__("fractions").Fraction(1, 3), id="Fraction"),
    pytest.param(0.5j, id="complex"),
    pytest.param("0.5", id="string"),
    pytest.param(np.array([0.5]), id="array of one"),
]


@pytest.mark.parametrize("value", NOT_A_REAL)
def test_a_scalar_that_is_not_a_real_number_is_a_type_error(value):
    mesh = delta.icosphere(1)
    points = np.full((2, 3), 0.5)
    with pytest.raises(TypeError):
        delta.distance(mesh, points, eps=value)
    with pytest.raises(TypeError):
        delta.contacts(mesh, mesh, value)
    with pytest.raises(TypeError):
        mesh.copy().scale(value)
    with pytest.raises(TypeError):
        delta.dem.Parameters(time_step=1e-4, epsilon=0.01, filter_distance=0.01, stiffness=1e3,
                             restitution=value)


@pytest.mark.parametrize("value", [True, np.bool_(False), 2.0, np.float64(2.0), np.uint8(2) > 1])
def test_an_integer_argument_takes_no_bool_or_float(value):
    with pytest.raises(TypeError):
        delta.icosphere(value)
    with pytest.raises(TypeError):
        delta.granulate(value)


def test_scalars_of_real_numbers_are_read_exactly():
    mesh = delta.QueryMesh(delta.icosphere(2))
    points = np.full((3, 3), 0.5)
    expected = delta.distance(mesh, points, eps=0.5)
    for value in (0.5, np.float64(0.5), np.float32(0.5), np.float16(0.5), np.array(0.5)):
        np.testing.assert_array_equal(delta.distance(mesh, points, eps=value), expected)
    for value in (1, np.int64(1), np.uint16(1), np.array(1)):
        np.testing.assert_array_equal(
            delta.distance(mesh, points, eps=value), delta.distance(mesh, points, eps=1.0))
    assert delta.icosphere(np.int32(2)).triangle_count == delta.icosphere(2).triangle_count
    with pytest.raises(delta.Error, match="2\\^53"):
        delta.distance(mesh, points, eps=2**53 + 1)


@pytest.mark.parametrize("value", [None, 2, 0, 0.5, "yes"])
def test_a_truth_value_is_a_bool(value):
    # pybind11's caster of bool took None as False and 2 or 0.5 as True.
    mesh = delta.icosphere(1)
    with pytest.raises(TypeError):
        delta.distance(mesh, np.zeros((1, 3)), signed=value)
    with pytest.raises(TypeError):
        delta.overlap(mesh, mesh, curves=value)
    with pytest.raises(TypeError):
        delta.ib.AdaptiveGrid(mesh, levels=2, signed=value)


def test_integers_beyond_2_53_that_float64_holds_are_taken():
    mesh = delta.QueryMesh(delta.icosphere(1))
    points = np.zeros((1, 3))
    assert delta.distance(mesh, points, eps=2**60)["distance"] == delta.distance(mesh, points)["distance"]
    with pytest.raises(delta.Error, match="2\\^53"):
        delta.distance(mesh, points, eps=2**60 + 1)
    with pytest.raises(delta.Error):
        delta.distance(mesh, points, eps=10**400)
    assert delta.distance(mesh, points, signed=np.bool_(True))["inside"]
