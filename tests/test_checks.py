"""The shared argument checks (simulation.checks): one message style, ValueError only."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from simulation import checks, degeneracy, streams

NOT_NUMBERS = st.one_of(
    st.booleans(),
    st.text(max_size=5),
    st.none(),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
    st.complex_numbers(allow_nan=False, allow_infinity=False).filter(lambda z: z.imag != 0),
)


@given(st.integers(min_value=-(10**6), max_value=10**6))
def test_count_accepts_integers_in_range(n):
    if n >= 2:
        assert checks.count("n", n, low=2) == n
        assert checks.count("n", np.int64(n), low=2) == n
        assert checks.count("n", float(n), low=2) == n
    else:
        with pytest.raises(ValueError, match=r"^n: must be an integer >= 2, got"):
            checks.count("n", n, low=2)


@given(st.one_of(NOT_NUMBERS, st.floats().filter(lambda x: not (math.isfinite(x) and x == int(x)))))
def test_count_rejects_bools_fractions_and_other_types(value):
    with pytest.raises(ValueError, match=r"^particles: must be an integer in \[2, 9\], got "):
        checks.count("particles", value, low=2, high=9)


@given(NOT_NUMBERS)
def test_real_rejects_non_numbers(value):
    with pytest.raises(ValueError, match=r"^temperature: must be a finite number in \[-40, 60\]"):
        checks.real("temperature", value, low=-40, high=60, unit="°C")


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_real_range_and_finiteness(x):
    if math.isfinite(x) and 0 < x <= 1:
        assert checks.real("a", x, low=0, high=1, low_open=True) == x
    else:
        with pytest.raises(ValueError, match=r"^a: must be a finite number in \(0, 1\], got"):
            checks.real("a", x, low=0, high=1, low_open=True)


def test_messages_name_value_and_allowed():
    with pytest.raises(ValueError) as e:
        checks.count("max_order", True, low=0, high=12)
    assert str(e.value) == "max_order: must be an integer in [0, 12], got True (a bool)"
    with pytest.raises(ValueError, match=r"got 1e\+09"):
        checks.real("temperature", 1e9, low=-40, high=60, unit="°C")
    with pytest.raises(ValueError, match=r"must be one of \['A', 'D'\], got 'X'"):
        checks.choice("criterion", "X", ["A", "D"])
    with pytest.raises(ValueError, match=r"search: unknown key\(s\) \['start'\]"):
        checks.known_keys("search", {"start": 1}, ["starts"])


def test_rng():
    g = np.random.default_rng(1)
    assert streams.rng("rng", g) is g
    assert isinstance(streams.rng("rng", 5), np.random.Generator)
    assert isinstance(streams.rng("rng", None), np.random.Generator)
    for bad in (5.0, "5", True, -1, [1, 2], object()):
        with pytest.raises(ValueError, match="^rng: must be a numpy Generator"):
            streams.rng("rng", bad)


def test_flag():
    assert checks.flag("noise", np.bool_(True)) is True
    for bad in (1, "yes", None):
        with pytest.raises(ValueError, match="^noise: must be True or False"):
            checks.flag("noise", bad)


def test_reals_and_points():
    np.testing.assert_array_equal(checks.reals("size", (1, 2, 3), shape=(3,)), [1.0, 2.0, 3.0])
    for bad in ("abc", [1, "a", 2], {"x": 1}, None, [[1, 2], [3]], [1, 2], [True, False, True]):
        with pytest.raises(ValueError, match="^size: "):
            checks.reals("size", bad, shape=(3,))
    with pytest.raises(ValueError, match="finite"):
        checks.reals("size", [1, np.nan, 2])
    with pytest.raises(ValueError, match=r"every entry must be > 0 m, got -1"):
        checks.reals("size", [1, -1, 2], low=0, low_open=True, unit="m")
    assert checks.points("anchors", [[0, 0, 0]]).shape == (1, 3)
    with pytest.raises(ValueError, match=r"anchors: expected shape \(N, 3\)"):
        checks.points("anchors", [[0, 0]])
    with pytest.raises(ValueError, match=r"number of points >= 4, got 1"):
        checks.points("anchors", [[0, 0, 0]], min_rows=4)


def test_geometry_checks():
    size = (8, 4, 2.4)
    checks.inside("nodes", [[0, 0, 0], [8, 4, 2.4]], size)
    with pytest.raises(ValueError, match=r"nodes: 1 point\(s\) lie outside the room .*index 1"):
        checks.inside("nodes", [[1, 1, 1], [9, 1, 1]], size)
    checks.distinct("anchors", [[0, 0, 0], [0, 0, 0.002]])
    with pytest.raises(ValueError, match="anchors: points 0 and 1 are 0.0005 m apart"):
        checks.distinct("anchors", [[0, 0, 0], [0, 0, 0.0005]])
    big = np.random.default_rng(0).uniform(0, 8, (600, 3))
    checks.distinct("candidates", big)
    with pytest.raises(ValueError, match="candidates: points"):
        checks.distinct("candidates", np.vstack([big, big[:1]]))
    line = [[0, 0, 1], [1, 0, 1], [2, 0, 1], [3, 0, 1]]
    plane = [[0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]]
    assert degeneracy.geometry(line) == "collinear" and degeneracy.geometry(plane) == "coplanar"
    assert degeneracy.geometry([[0, 0, 0]] * 4) == "coincident"
    assert degeneracy.geometry([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]) == "3d"
    np.testing.assert_array_equal(degeneracy.anchor_rank(np.array([line, plane])), [1, 2])


def test_check_size(monkeypatch):
    checks.check_size("x", 10, 100)
    with pytest.raises(ValueError, match=r"realizations: 1000000000 would need about 8 GB"):
        checks.check_size("realizations", 8e9, 1e9, value=10**9)
    monkeypatch.setenv("ANCHORPLAN_MEMORY_LIMIT", "1000")
    assert checks.memory_limit() == 1000


def test_paths(tmp_path):
    f = tmp_path / "a.json"
    f.write_text("{}")
    assert checks.input_file("--layout", f) == f
    with pytest.raises(ValueError, match="--layout .*: no such file"):
        checks.input_file("--layout", tmp_path / "missing.json")
    with pytest.raises(ValueError, match="--layout .*: is a directory"):
        checks.input_file("--layout", tmp_path)
    assert checks.input_dir("RESULT_DIR", tmp_path) == tmp_path
    with pytest.raises(ValueError, match="RESULT_DIR .*: not a folder"):
        checks.input_dir("RESULT_DIR", f)
    with pytest.raises(ValueError, match="--out .*: is a directory, expected a file name"):
        checks.output_path("--out", tmp_path)
    with pytest.raises(ValueError, match="--out .*: exists and is not a directory"):
        checks.output_path("--out", f, kind="dir")
    with pytest.raises(ValueError, match=r"--out .*a.json is a file, not a directory"):
        checks.output_path("--out", f / "sub" / "x.json")
    with pytest.raises(ValueError, match=r"must end in one of \['.png'\]"):
        checks.output_path("--out", tmp_path / "x.jpg", suffixes=[".png"])
    assert checks.output_path("--out", tmp_path / "new" / "deeper", kind="dir")
    for bad in ("", None, 3):
        with pytest.raises(ValueError, match="--out: must be a file path"):
            checks.output_path("--out", bad)
