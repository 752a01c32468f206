"""Bad input is refused up front with a ValueError (API) or one line and exit code 2 (CLI)
naming the argument or file, its value and what is allowed (issue #13)."""

import json
import math
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import analysis
import placement
from analysis import figures
from placement.cli import main
from placement.pso import PSOOptions, pso
from simulation import Chirp, Receiver, Room, System, evaluate_layout, locate, simulate_ranges
from simulation.multipath import image_indices

ROOM = Room.techtile()
A = ROOM.corners_layout()
NODES = ROOM.grid()[::27]
FAST = PSOOptions(particles=3, iterations=1)

# values that are not integers: bools, fractions, strings, containers, NaN
NOT_INTEGERS = st.one_of(
    st.booleans(),
    st.floats().filter(lambda x: not (math.isfinite(x) and x == int(x))),
    st.text(max_size=4),
    st.none(),
    st.lists(st.integers(0, 5), min_size=1, max_size=2),
)
# values that are not real numbers
NOT_REALS = st.one_of(
    st.booleans(),
    st.sampled_from([math.nan, math.inf, -math.inf]),
    st.text(max_size=4),
    st.none(),
    st.lists(st.floats(0, 1), min_size=1, max_size=2),
)
QUICK = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def refused(name, fn, *, within=5.0):
    """fn() raises ValueError naming ``name``, within ``within`` seconds."""
    t0 = time.monotonic()
    with pytest.raises(ValueError) as exc:
        fn()
    assert time.monotonic() - t0 < within
    msg = str(exc.value)
    assert name in msg and "\n" not in msg, msg
    return msg


# -- integer arguments refuse bools, fractions and strings ----------------------------------
@QUICK
@given(NOT_INTEGERS)
def test_room_max_order_is_an_integer(v):
    refused("max_order", lambda: Room(max_order=v))


@QUICK
@given(NOT_INTEGERS)
def test_evaluate_realizations_is_an_integer(v):
    refused("realizations", lambda: evaluate_layout(ROOM, A, realizations=v, nodes=NODES))


@QUICK
@given(NOT_INTEGERS)
def test_random_layout_anchor_count_is_an_integer(v):
    refused("M", lambda: placement.random_layout(ROOM, v, 0))


@QUICK
@given(st.sampled_from(["particles", "iterations", "patience"]), NOT_INTEGERS)
def test_pso_options_counts(field, v):
    refused(field, lambda: PSOOptions(**{field: v}))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: Room(max_order=True), "max_order"),
        (lambda: Room(max_order=2.5), "max_order"),
        (lambda: evaluate_layout(ROOM, A, realizations=True), "realizations"),
        (lambda: evaluate_layout(ROOM, A, rng=1.7), "rng"),
        (lambda: evaluate_layout(ROOM, A, rng=-1), "rng"),
        (lambda: evaluate_layout(ROOM, A, chunk=0.5), "chunk"),
        (lambda: evaluate_layout(ROOM, A, workers=0), "workers"),
        (lambda: placement.random_layout(ROOM, True, 0), "M"),
        (lambda: placement.relax_select(ROOM, 4, samples=True), "samples"),
        (lambda: placement.refine_peb(ROOM, A, multistart=1.5), "multistart"),
        (lambda: placement.exhaustive_search(ROOM, 4, top_k=True), "top_k"),
        (lambda: locate(A, np.ones((2, 4)), max_iter=2.5), "max_iter"),
        (lambda: ROOM.grid((1.5, 2, 2)), "shape"),
        (lambda: image_indices(True), "max_order"),
        (lambda: pso(lambda a, r: 1.0, ROOM, 4.5, options=FAST), "M"),
        (lambda: pso(lambda a, r: 1.0, ROOM, 4, options=FAST, rng=1.7), "rng"),
        (lambda: pso(lambda a, r: 1.0, ROOM, 4, options=FAST, chunksize=True), "chunksize"),
        (lambda: Receiver(window=True), "window"),
    ],
)
def test_counts_refuse_bools_and_fractions(call, name):
    refused(name, call)


def test_integral_floats_and_numpy_integers_are_counts():
    assert Room(max_order=np.int64(2)).max_order == 2
    assert Room(max_order=2.0).max_order == 2
    assert placement.random_layout(ROOM, np.int32(5), 0).shape == (5, 3)


# -- options ------------------------------------------------------------------------------
def test_pso_options_must_be_pso_options():
    for v in ({"particles": 4}, "fast"):
        msg = refused("options", lambda v=v: pso(lambda a, r: 1.0, ROOM, 4, options=v))
        assert "PSOOptions" in msg


def test_cli_search_options_are_checked(tmp_path, capsys):
    for opt, v in (("--search-starts", "-1"), ("--search-spacing", "0"),
                   ("--search-realizations", "0"), ("--search-spacing", "1e-4"),
                   ("--min-coverage", "1.5"), ("--min-coverage", "-0.1")):  # fmt: skip
        assert main(["plan", opt, v, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and opt in err, err


def test_relax_solver_opts_is_a_mapping():
    refused("solver_opts", lambda: placement.relax_select(ROOM, 4, solver_opts="x"))


# -- bad input is an error, not a failed result ---------------------------------------------
@pytest.mark.parametrize("cost", [5, "variance", None, lambda: 1.0, lambda a, b, c: 1.0])
def test_pso_cost_must_be_callable_with_anchors_and_rng(cost):
    refused("cost", lambda: pso(cost, ROOM, 4, options=FAST, rng=0))


def peb_of(anchors):
    return float(np.mean(analysis.peb(anchors, NODES)))


def test_pso_accepts_a_one_argument_cost_as_seed_then_pso_does():
    res = pso(peb_of, ROOM, 4, options=FAST, rng=0)
    assert res.success and res.failures == 0 and np.isfinite(res.cost)


def test_pso_refuses_an_unpicklable_cost_for_worker_processes():
    with placement.WorkerPool(2) as ex:
        refused("cost", lambda: pso(lambda a, r: 1.0, ROOM, 4, options=FAST, executor=ex))


def test_pso_other_arguments():
    refused("room", lambda: pso(peb_of, "techtile", 4, options=FAST))
    refused("executor", lambda: pso(peb_of, ROOM, 4, options=FAST, executor="pool"))
    refused("callback", lambda: pso(peb_of, ROOM, 4, options=FAST, callback="x"))
    refused("initial", lambda: pso(peb_of, ROOM, 4, options=FAST, initial=np.zeros((2, 5, 3))))


# -- geometry -----------------------------------------------------------------------------
OUTSIDE = [[[9.0, 1.0, 1.0]], [[-0.5, 1.0, 1.0]], [[1.0, 1.0, 3.0]]]


@pytest.mark.parametrize("nodes", OUTSIDE)
@pytest.mark.parametrize(
    "call",
    [
        lambda p: evaluate_layout(ROOM, A, nodes=p),
        lambda p: simulate_ranges(ROOM, A, p),
        lambda p: placement.relax_select(ROOM, 4, spacing=1.6, nodes=p),
        lambda p: placement.exhaustive_search(ROOM, 4, spacing=3.0, nodes=p),
        lambda p: placement.refine_peb(ROOM, A, nodes=p),
        lambda p: placement.seed_then_pso(ROOM, 4, nodes=p, cost="peb", initial=None, rng=0),
        lambda p: placement.PEBCost(ROOM, nodes=p),
        lambda p: placement.SimulatedCost(ROOM, nodes=p),
        lambda p: placement.DrawsCost(ROOM, np.asarray(p)[None]),
    ],
)
def test_nodes_outside_the_room_are_refused(call, nodes):
    msg = refused("nodes", lambda: call(nodes))
    assert "outside the room" in msg


@pytest.mark.parametrize("offset", [0.0, 0.0005])
def test_duplicated_anchors_are_refused(offset):
    lay = np.vstack([A, A[:1] + [0, 0, offset]])
    for call in (
        lambda: evaluate_layout(ROOM, lay, nodes=NODES),
        lambda: simulate_ranges(ROOM, lay, NODES),
        lambda: placement.refine_peb(ROOM, lay),
    ):
        assert "1 mm apart" in refused("anchors", call)


def test_anchors_anywhere_in_the_room_are_evaluated():
    """Decision: evaluate/bounds/simulate_ranges take anchors anywhere inside the room
    (an existing installation); only the optimizers keep them on the mounting surfaces."""
    centre = np.array([[4.0, 2.0, 1.2], [1.0, 1.0, 0.5], [7.0, 3.0, 2.0], [2.0, 3.5, 1.5]])
    ev = evaluate_layout(ROOM, centre, nodes=NODES)
    assert ev.geometry == "3d" and np.all(np.isfinite(ev.errors))
    refused("anchors", lambda: placement.refine_peb(ROOM, centre))  # refinement: on surfaces


def test_collinear_anchors_are_flagged_not_reported_converged():
    line = np.array([[1, 2, 2.37], [3, 2, 2.37], [5, 2, 2.37], [7, 2, 2.37]])
    fix = locate(line, np.full((3, 4), 2.0), full_output=True)
    assert np.all(fix.status == -1) and not fix.success
    ev = evaluate_layout(ROOM, line, nodes=NODES)
    assert ev.geometry == "collinear" and ev.n_unconverged == ev.errors.size
    assert ev.to_dict()["stats"]["anchor_geometry"] == "collinear"
    ceiling = np.array([[1, 1, 2.37], [3, 3, 2.37], [6, 1, 2.37], [7, 3, 2.37]])
    assert evaluate_layout(ROOM, ceiling, nodes=NODES).geometry == "coplanar"
    # several layouts at once: only the collinear one is flagged
    both = locate(np.stack([line, A]), np.full((2, 3, 4), 2.0), full_output=True)
    assert np.all(both.status[0] == -1) and np.all(both.status[1] != -1)


def test_swarm_scores_collinear_layouts_inf():
    line = np.array([[1, 2, 2.37], [3, 2, 2.37], [5, 2, 2.37], [7, 2, 2.37]])
    res = pso(peb_of, ROOM, 4, options=FAST, initial=line[None], rng=0)
    assert np.isinf(res.costs[0][0]) and res.failures == 0
    assert placement.on_surfaces(ROOM, res.anchors).all() and np.isfinite(res.cost)


@pytest.mark.parametrize(
    ("ranges", "says"),
    [
        (-2 * np.ones((2, 4)), "[-1, 100000] m"),
        (np.full((2, 4), np.inf), "finite"),
        (np.full((2, 4), 1e300), "[-1, 100000] m"),
        ("1 2", "numbers"),
    ],
)
def test_locate_refuses_impossible_ranges(ranges, says):
    assert says in refused("ranges", lambda: locate(A, ranges))


def test_locate_accepts_slightly_negative_noisy_ranges():
    """The receiver's noisy ranges reach -0.34 m (c times the window): not an error."""
    fix = locate(A, np.full((1, 4), -0.1), full_output=True)
    assert fix.x.shape == (1, 3)


def test_refine_never_reports_success_with_duplicated_anchors(monkeypatch):
    refine = __import__("placement.refine", fromlist=["from_uv"])
    real = refine.from_uv

    def collapse(room, idx, uv):  # make the solver's answer put two anchors together
        out = real(room, idx, uv)
        out[1] = out[0]
        return out

    monkeypatch.setattr(refine, "from_uv", collapse)
    res = placement.refine_peb(ROOM, placement.random_layout(ROOM, 5, 1), return_info=True)
    assert not res.success and not res.accepted and res.status == 4
    assert res.message.startswith("duplicate_anchors")


# -- physics -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("field", "value", "allowed"),
    [
        ("temperature", 1e9, "[-40, 60] °C"),
        ("temperature", -273.1, "[-40, 60] °C"),
        ("max_order", 200, "[0, 12]"),
        ("size", (1e9, 1, 1), "[0.5, 100] m"),
        ("sound_speed", 4.5, "[250, 450] m/s"),
        ("air_absorption", 100, "[0, 5] 1/m"),
    ],
)
def test_absurd_physics_refused_with_the_range(field, value, allowed):
    assert allowed in refused(field, lambda: Room(**{field: value}))


@QUICK
@given(NOT_REALS)
def test_room_temperature_must_be_a_number(v):
    refused("temperature", lambda: Room(temperature=v))


@QUICK
@given(st.one_of(st.floats(-1e9, -20.01), st.floats(120.01, 1e9), NOT_REALS))
def test_snr_range(v):
    refused("snr_db", lambda: simulate_ranges(ROOM, A, NODES, snr_db=v))
    refused("snr_db", lambda: analysis.PhysicalRangeNoise(ROOM, snr_db=v))


@QUICK
@given(NOT_REALS)
def test_range_sigma_must_be_a_number(v):
    refused("value", lambda: analysis.ConstantRangeNoise(v))


@pytest.mark.parametrize("text", ["", "# only a comment\n"])
def test_empty_toml_is_an_error_naming_the_file(tmp_path, text):
    p = tmp_path / "room.toml"
    p.write_text(text)
    assert "empty" in refused(str(p), lambda: Room.from_toml(p))


# -- wrong exception types -------------------------------------------------------------------
@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: Room(absorption=0.5), "absorption"),
        (lambda: Room(temperature="20"), "temperature"),
        (lambda: Room(size="8x4x2"), "size"),
        (lambda: Room(mounting=5), "mounting"),
        (lambda: Room(name=3), "name"),
        (lambda: Room.from_dict({"size": 5}), "size"),
        (lambda: Room.from_dict(5), "room"),
        (lambda: analysis.ConstantRangeNoise("0.04"), "value"),
        (lambda: simulate_ranges(ROOM, A, NODES, rng="x"), "rng"),
        (lambda: simulate_ranges(ROOM, A, NODES, snr_db=1e6), "snr_db"),
        (lambda: placement.candidate_grid(ROOM, 1e-5), "spacing"),
        (lambda: placement.candidate_grid(ROOM, "a"), "spacing"),
        (lambda: Room(max_order=1000), "max_order"),
        (lambda: image_indices(1000), "max_order"),
        (lambda: ROOM.grid((10**4, 10**4, 10**4)), "shape"),
        (lambda: figures.peb_map(ROOM, A, resolution=1e-5), "resolution"),
        (lambda: placement.relax_select(ROOM, 4, spacing=0.01), "candidates"),
        (lambda: evaluate_layout("techtile", A), "room"),
        (lambda: Chirp(f0="25e3"), "f0"),
        (lambda: Chirp(duration=100.0), "duration"),
        (lambda: analysis.peb(A, NODES, sigma="a"), "sigma"),
        (lambda: analysis.calibrated_sigma(np.ones((2, 3, 4)), k="3"), "k"),
    ],
)
def test_value_error_not_type_memory_or_attribute_error(call, name):
    refused(name, call)


def test_rng_accepts_a_seed():
    a = simulate_ranges(ROOM, A, NODES, rng=5)
    b = simulate_ranges(ROOM, A, NODES, rng=np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("size = 5\n", "size"),
        ("absorption = 0.5\n", "absorption"),
        ('temperature = "hot"\n', "temperature"),
        ("max_order = true\n", "max_order"),
        ("size = [8, 4\n", "not valid TOML"),
        ("sise = [1, 2, 3]\n", "sise"),
        ('mounting = "attic"\n', "attic"),
    ],
)
def test_toml_errors_name_the_file_and_key(tmp_path, text, says):
    p = tmp_path / "room.toml"
    p.write_text(text)
    msg = refused(str(p), lambda: Room.from_toml(p))
    assert says in msg


def test_toml_mounting_string_is_one_surface(tmp_path):
    p = tmp_path / "room.toml"
    p.write_text('mounting = "ceiling"\n')
    assert Room.from_toml(p).mounting == ("ceiling",) == Room(mounting="ceiling").mounting


# -- no hang: sizes are estimated first -------------------------------------------------------
def test_huge_realizations_refused_before_spawning_streams():
    msg = refused("realizations", lambda: evaluate_layout(ROOM, A, realizations=10**9), within=1)
    assert "memory" in msg


def test_huge_random_layout_refused():
    refused("M", lambda: placement.random_layout(ROOM, 10**9, 0), within=1)


# -- the CLI: one line, exit code 2, before any work -----------------------------------------
def run_cli(argv, capsys, within=5.0):
    t0 = time.monotonic()
    code = main(argv)
    seconds = time.monotonic() - t0
    captured = capsys.readouterr()
    assert code == 2, captured
    assert seconds < within
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    return captured.err


@pytest.fixture
def files(tmp_path):
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile.txt").write_text("x")
    (tmp_path / "ok.json").write_text(json.dumps({"anchors": A.tolist()}))
    (tmp_path / "dup.json").write_text(json.dumps({"anchors": np.vstack([A, A[:1]]).tolist()}))
    (tmp_path / "empty.toml").write_text("")
    return tmp_path


@pytest.mark.parametrize(
    ("argv", "names"),
    [
        (["plan", "--room", "{t}/adir", "--out", "{t}/o"], "--room"),
        (["bounds", "--room", "{t}/missing.toml"], "--room"),
        (["bounds", "--room", "{t}/empty.toml"], "empty.toml"),
        (["evaluate", "--layout", "{t}/adir", "--out", "{t}/o"], "--layout"),
        (["evaluate", "--layout", "{t}/dup.json", "--out", "{t}/o"], "1 mm apart"),
        (["plan", "--checkpoint", "{t}/adir", "--out", "{t}/o"], "--checkpoint"),
        (["bounds", "--out", "{t}/adir"], "--out"),
        (["plan", "--out", "{t}/afile.txt"], "--out"),
        (["evaluate", "--layout", "{t}/ok.json", "--out", "{t}/afile.txt"], "--out"),
        (["peb-map", "--out", "{t}/m.gif"], "--out"),
        (["report", "{t}/afile.txt"], "RESULT_DIR"),
        (["plan", "--anchors", "300", "--out", "{t}/o"], "--anchors"),
        (["plan", "--anchors", "3.5", "--out", "{t}/o"], "--anchors"),
        (["plan", "--particles", "1", "--out", "{t}/o"], "--particles"),
        (["plan", "--eval-timeout", "0", "--out", "{t}/o"], "--eval-timeout"),
        (["plan", "--finalist-exact-draws", "13", "--out", "{t}/o"], "--finalist-exact-draws"),
        (["plan", "--workers", "-1", "--out", "{t}/o"], "--workers"),
        (["plan", "--validate-realizations", "1000000000", "--out", "{t}/o"], "--validate-"),
        (["evaluate", "--layout", "{t}/ok.json", "--realizations", "0", "--out", "{t}/o"], "--r"),
        (["evaluate", "--layout", "{t}/ok.json", "--snr", "1e6", "--out", "{t}/o"], "--snr"),
        (["bounds", "--sigma", "nan"], "--sigma"),
        (["peb-map", "--resolution", "1e-4", "--out", "{t}/m.png"], "--resolution"),
        (["peb-map", "--dpi", "100000", "--out", "{t}/m.png"], "--dpi"),
        (["peb-map", "--size", "1000", "1000", "--out", "{t}/m.png"], "--size"),
        (["peb-map", "--height", "9", "--out", "{t}/m.png"], "--height"),
        (["report", "{t}/adir", "--dpi", "0"], "--dpi"),
        (["frobnicate"], "frobnicate"),
    ],
)
def test_cli_bad_input_one_line_exit_2(files, capsys, argv, names):
    err = run_cli([a.replace("{t}", str(files)) for a in argv], capsys)
    assert names in err, err


def test_cli_checks_outputs_before_computing(files, capsys):
    """plan/evaluate --out FILE used to fail after the whole computation."""
    argv = ["plan", "--anchors", "4", "--no-progress", "--out", str(files / "afile.txt")]
    assert "exists and is not a directory" in run_cli(argv, capsys, within=3)


def test_cli_unexpected_failure_is_one_line_exit_1(monkeypatch, capsys):
    import placement.cli.bounds as bounds

    def boom(*a, **k):
        raise RuntimeError("something broke\nbadly")

    monkeypatch.setattr(bounds, "error_stats", boom)
    assert main(["bounds"]) == 1
    err = capsys.readouterr().err
    assert err == "anchorplan bounds: error: RuntimeError: something broke badly\n"


@pytest.mark.parametrize("room", [None, "techtile", {"size": [8, 4, 2.4]}])
@pytest.mark.parametrize(
    "call",
    [
        lambda r: simulate_ranges(r, A, NODES),
        lambda r: evaluate_layout(r, A),
        lambda r: placement.candidate_grid(r, 0.5),
        lambda r: placement.random_layout(r, 4, 0),
        lambda r: placement.project(r, A),
        lambda r: placement.relax_select(r, 4),
        lambda r: placement.refine_peb(r, A),
        lambda r: pso(peb_of, r, 4, options=FAST),
        lambda r: analysis.PhysicalRangeNoise(r),
        lambda r: figures.peb_map(r, A),
    ],
)
def test_room_must_be_a_room(call, room):
    assert "simulation.Room" in refused("room", lambda: call(room))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: locate(A, np.ones((2, 4)), region="x"), "region"),
        (lambda: locate(A, np.ones((2, 4)), x0="x"), "x0"),
        (lambda: analysis.error_stats("abc"), "errors"),
        (lambda: analysis.dop(np.ones((2, 3)), np.ones((2, 4, 4))), "range_errors"),
        (lambda: placement.on_surfaces(ROOM, "abc"), "points"),
        (lambda: ROOM.check_anchors(A, min_anchors=True), "min_anchors"),
        (lambda: figures.peb_plane(ROOM, A, axis=2.5, value=1.0), "axis"),
        (lambda: PSOOptions(inertia=5.0), "inertia"),
    ],
)
def test_neighbours_of_the_issue_examples(call, name):
    refused(name, call)


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"exact_draws": 2.5}, "exact_draws"),
        ({"exact_draws": -1}, "exact_draws"),
        ({"exact_draws": 2}, "exact_draws"),  # more than the one draw
        ({"mount_tolerance": math.nan}, "mount_tolerance"),
        ({"mount_tolerance": None}, "mount_tolerance"),
        ({"statistic": ["variance"]}, "statistic"),
        ({"room": None}, "room"),
        ({"nodes": np.zeros((0, 3, 3))}, "nodes"),
    ],
)
def test_draws_cost_settings_are_checked(kw, name):
    refused(name, lambda: placement.DrawsCost(**{"room": ROOM, "nodes": NODES[None], **kw}))


def test_costs_refuse_a_room_that_is_not_a_room():
    refused("room", lambda: placement.PEBCost("techtile"))
    refused("room", lambda: placement.SimulatedCost(room={"size": (8, 4, 2.4)}))


@pytest.mark.parametrize(
    ("index", "uv", "name"),
    [
        ([7, 0], [[0.5, 0.5], [0.5, 0.5]], "index"),  # no surface 7
        ([0.5], [[0.5, 0.5]], "index"),
        (None, [[0.5, 0.5]], "index"),
        ([0], None, "uv"),
        ([0], 5.0, "uv"),
        ([0, 1], [[0.5, 0.5]], "uv"),
        ([0], [[1e6, 0.5]], "uv"),  # far off the south wall
        ([0], [[0.5, math.nan]], "uv"),
    ],
)
def test_from_uv_refuses_what_names_no_point_on_a_surface(index, uv, name):
    refused(name, lambda: placement.from_uv(ROOM, index, uv))


def test_repeated_candidates_are_refused_not_returned_as_coincident_anchors():
    cand = placement.candidate_grid(ROOM, 0.5)
    twice = np.vstack([cand[[0, 5, 10, 15, 20]], cand[:1]])
    refused("candidates", lambda: placement.exhaustive_search(ROOM, 6, candidates=twice))
    refused("candidates", lambda: placement.relax_select(ROOM, 6, candidates=twice))


def test_a_checkpoint_in_a_new_folder_is_written(tmp_path):
    path = tmp_path / "new" / "sub" / "state.json"
    placement.seed_then_pso(
        ROOM, 4, cost="peb", initial=None, swarm=placement.PSOOptions(particles=3, iterations=1),
        validation=placement.ValidationOptions(realizations=0), progress=False, rng=0,
        checkpoint=path, nodes=NODES,
    )  # fmt: skip
    state = json.loads(path.read_text())  # the swarm after its one iteration
    assert state["nfev"] == 3 and len(state["x"]) == 3


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: Receiver(window=33), "window"),  # the default high-pass pads by 33
        (lambda: Receiver(window=120, highpass_order=40), "window"),
        (lambda: System(Chirp(f0=1e6, f1=9e5)), "chirp"),
        (lambda: System(receiver=Receiver(highpass_cutoff=1e-9)), "highpass_cutoff"),
        (lambda: System(chirp="x"), "chirp"),
        (lambda: System(receiver="x"), "receiver"),
        (lambda: System(positioning="x"), "positioning"),
    ],  # fmt: skip
)
def test_chirp_and_receiver_must_work_together(call, name):
    refused(name, call)


def test_physical_noise_uses_the_systems_signal():
    system = System(Chirp(duration=0.05), Receiver(t_wake=0.049))
    noise = analysis.PhysicalRangeNoise(Room(), system=system)
    assert noise.chirp == system.chirp and noise.receiver == system.receiver


@pytest.mark.parametrize("items", [5, True, 2.5])
def test_keepouts_and_zones_must_be_lists_of_boxes(items):
    refused("keepouts", lambda: Room(keepouts=items))
    refused("zones", lambda: Room(zones=items))


def test_sweep_checks_on_row_before_planning():
    kw = dict(cost="peb", initial=None, swarm=placement.PSOOptions(particles=3, iterations=1))
    refused("on_row", lambda: placement.sweep(ROOM, anchors=[4], on_row="x", **kw), within=2)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (
            lambda: placement.relax_select(ROOM, 4, spacing=1.6, solver_opts={"bogus": 1}),
            "solver_opts",
        ),
        (
            lambda: placement.relax_select(ROOM, 4, spacing=1.6, solver_opts={"max_iter": "x"}),
            "solver_opts",
        ),
        (lambda: placement.on_surfaces(ROOM, A, tol=math.nan), "tol"),
        (lambda: placement.to_uv(ROOM, A, tol=-1), "tol"),
        (lambda: placement.allowed_area(None), "room"),
        (lambda: analysis.calibrated_sigma(np.zeros((0, 5, 4)), method="mad"), "range_errors"),
        (lambda: analysis.range_std(np.zeros((0, 5, 4))), "range_errors"),
        (lambda: locate(A, np.ones((2, 4)), region=([1, 1, 1], [0, 0, 0])), "region"),
    ],  # fmt: skip
)
def test_solver_settings_tolerances_and_empty_samples(call, name):
    refused(name, call)


def test_received_windows_checks_the_speed_of_sound_and_the_images():
    from simulation.multipath import compute_paths
    from simulation.received import received_windows

    paths = compute_paths(ROOM, A, NODES[:2])
    for c in (0.0, -343.0, math.nan):
        refused("speed_of_sound", lambda c=c: received_windows(paths, c))
    refused("paths", lambda: received_windows(None, 343.0))
    refused("images", lambda: compute_paths(ROOM, A, NODES[:2], images=5))


def test_reference_nodes_names_grid_shape_and_cardioid_refuses_none():
    from simulation.directivity import cardioid
    from simulation.noise import reference_nodes

    refused("grid_shape", lambda: reference_nodes(ROOM, A, grid_shape=(0, 1, 1)))
    refused("cos_theta", lambda: cardioid(None))


def test_the_small_defects_of_issue_29_raise_value_errors():
    """An empty layout has no bound, a speaker outside the room no SNR, errors without
    spread no σ; ranges beyond 100 km are no indoor measurement. (Ranges down to −1 m stay
    accepted: the paper's receiver reports noisy picks slightly before the direct path.)"""
    from simulation.positioning import locate

    P = ROOM.grid()[:3]
    refused("anchors", lambda: analysis.peb(np.zeros((0, 3)), P))
    outside = np.array([[9.0, 1.0, 1.0], *A[1:]])
    refused("anchors", lambda: analysis.PhysicalRangeNoise(ROOM).sigma(outside, P))
    refused("range_errors",
            lambda: analysis.CalibratedRangeNoise.from_range_errors(np.zeros((10, 4))))  # fmt: skip
    refused("ranges", lambda: locate(A, np.full((1, 4), 1e300)))
    assert np.isfinite(locate(A, np.full((1, 4), -0.3))).all()
    with pytest.raises(TypeError):  # sweep has one seed keyword: rng
        placement.sweep(ROOM, [4], seed=1)
