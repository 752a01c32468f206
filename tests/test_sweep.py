import dataclasses
import json

import numpy as np
import pytest

import placement
from placement.anchor_sweep import SweepRow, sweep
from placement.cli import main
from placement.cli.sweep import parse_counts, row_line
from placement.plan import LOCAL_SWARM
from placement.simselect import SearchOptions
from placement.validation import ValidationOptions
from simulation import Room

ROOM = Room.techtile()
SWARM = dataclasses.replace(LOCAL_SWARM, particles=3, iterations=1)
NODES = ROOM.grid()[::27]
SMALL = SearchOptions(
    spacing=2.0,
    chains=1,
    evaluations=30,
    random_starts=3,
    neighbours=8,
    batch=4,
    patience=3,
    fine_spacings=(1.0,),
)
QUICK = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=10, mount_draws=1)


def test_sweep_rows_and_recommendation():
    kw = dict(search=SMALL, swarm=SWARM, validation=QUICK, nodes=NODES)
    res = sweep(ROOM, [5, 4], target_p95=100.0, rng=0, progress=False, **kw)
    assert [r.M for r in res.rows] == [4, 5]
    for r in res.rows:
        assert r.anchors.shape == (r.M, 3) and placement.on_surfaces(ROOM, r.anchors).all()
        assert 0 < r.std and r.std <= r.p95 + 1e-12
    assert res.recommended == 4  # every P95 is below 100 m: the smallest M
    none = sweep(ROOM, [4], target_p95=1e-6, rng=0, progress=False, **kw)
    assert none.recommended is None
    d = json.loads(res.to_json())
    assert d["kind"] == "sweep" and [r["M"] for r in d["rows"]] == [4, 5]
    # the same M in a sweep and alone (same rng, same shared-table settings) agree
    alone = sweep(ROOM, [4], rng=0, progress=False, **kw)
    np.testing.assert_array_equal(alone.rows[0].anchors, res.rows[0].anchors)


def test_sweep_rejects_bad_input():
    with pytest.raises(ValueError, match="anchors"):
        sweep(ROOM, [3, 4])
    with pytest.raises(ValueError, match="anchors"):
        sweep(ROOM, [])
    with pytest.raises(ValueError, match="target_p95"):
        sweep(ROOM, [4], target_p95=-1)
    assert parse_counts("4-6") == [4, 5, 6] and parse_counts("4, 8") == [4, 8]
    for bad in ("6-4", "four", "4-", "4,4", "\u0661\u0662"):  # a repeat; Arabic-Indic 12
        with pytest.raises(ValueError, match="--anchors"):
            parse_counts(bad)


def test_a_sweep_row_reads_the_field_first_and_the_nodes_without_a_field_check():
    row = SweepRow(M=10, std=0.021, mean=0.009, p95=0.019, held_out_std=0.3,
                   held_out_p95=0.4, mounting_std=0.02, mounting_p95=0.05,
                   anchors=np.zeros((10, 3)), seconds=159.0, availability=1.0,
                   field_std=0.3, field_mean=0.040, field_p95=0.080, field_median=0.016,
                   field_verified=0.62)  # fmt: skip
    line = row_line(row)
    assert line.startswith("field median 0.016 m, mean 0.040 m, P95 0.080 m, verified 62.0 %")
    assert line.index("sigma 0.021") > line.index("P95 0.080")
    no_field = row_line(dataclasses.replace(row, field_median=float("nan")))
    assert no_field.startswith("mean 0.009 m, sigma 0.021 m, P95 0.019 m, availability 100.00 %")
    assert "field" not in no_field


def test_sweep_cli_bad_input_exit_2(tmp_path, capsys):
    assert main(["sweep", "--anchors", "3-5", "--out", str(tmp_path)]) == 2
    assert "--anchors" in capsys.readouterr().err
    assert main(["sweep", "--target-p95", "0", "--out", str(tmp_path)]) == 2
    assert "--target-p95" in capsys.readouterr().err
    argv = ["sweep", "--effort", "quick", "--validate-realizations", "-1", "--out", str(tmp_path)]
    assert main(argv) == 2
    assert "--validate-realizations" in capsys.readouterr().err


def test_sweep_report_renders(tmp_path):
    from analysis.sweep_report import write_sweep_report

    kw = dict(search=SMALL, swarm=SWARM, validation=QUICK, nodes=NODES)
    res = sweep(ROOM, [4], target_p95=100.0, rng=0, progress=False, **kw)
    (tmp_path / "sweep.json").write_text(res.to_json())
    page = write_sweep_report(tmp_path).read_text()
    assert "Recommended: M = 4" in page and "data:image/png;base64," in page


def test_placement_sweep_is_the_function():
    from placement.anchor_sweep import sweep as fn

    assert placement.sweep is fn and callable(placement.sweep)


def test_a_sweep_row_is_the_plan_for_that_M():
    """The sweep's shared table is the one a plan builds (the run's stream "table"), so its
    row for M is ``seed_then_pso(M=...)`` with the same arguments."""
    kw = dict(search=SMALL, swarm=SWARM, validation=QUICK, nodes=NODES, progress=False)
    res = sweep(ROOM, [4, 5], rng=3, **kw)
    for row in res.rows:
        plan = placement.seed_then_pso(ROOM, row.M, rng=3, **kw)
        np.testing.assert_array_equal(row.anchors, plan.anchors)
        assert row.std == plan.validation.std and row.p95 == plan.validation.p95


def test_the_sweep_figure_shows_the_field_figures_beside_the_nodes():
    from analysis.figures import sweep_curves
    from analysis.paper import TABLE1

    rows = [{"M": m, "std": 0.5, "mean": 0.7, "p95": 1.5, "field_std": 0.6 + m / 100,
             "field_mean": 0.8, "field_p95": 2.0} for m in (4, 6)]  # fmt: skip
    ax = sweep_curves(rows, 1.8, TABLE1).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:2] == ["field σ", "σ, evaluation nodes"] and "field P95" in labels
    dashed = [ln for ln in ax.lines if ln.get_linestyle() == "--" and ln.get_label() == "field σ"]
    np.testing.assert_allclose(dashed[0].get_ydata(), [0.64, 0.66])
    # older sweeps without the field check: the nodes' curves alone, named as before
    old = [{k: r[k] for k in ("M", "std", "mean", "p95")} for r in rows]
    labels = [t.get_text() for t in sweep_curves(old).axes[0].get_legend().get_texts()]
    assert labels == ["σ", "mean", "P95"]


def test_the_sweep_table_prints_a_dash_for_a_check_that_did_not_run(capsys):
    from types import SimpleNamespace

    from placement.cli.sweep import _print_table

    nan = float("nan")
    row = SimpleNamespace(M=4, field_std=0.9, field_p95=2.9, field_median=nan, field_mean=1.1,
                          std=0.8, mean=1.0, p95=2.6, availability=1.0, held_out_std=nan,
                          mounting_std=0.85, covered=1.0, coverage_k=4)  # fmt: skip
    res = SimpleNamespace(rows=[row], target_availability=0.99, target_p95=None, recommended=4,
                          target_coverage=0.95)  # fmt: skip
    _print_table(res, None)
    line = capsys.readouterr().out.splitlines()[1]
    assert "nan" not in line and line.split()[-1] == "–" and line.split()[1].startswith("–")


def test_the_sweep_figure_shows_the_field_median_and_the_coverage_with_its_target():
    from analysis.figures import sweep_curves

    rows = [{"M": m, "std": 0.5, "mean": 0.7, "p95": 1.5, "field_std": 0.6, "field_mean": 0.8,
             "field_p95": 2.0, "field_median": 0.01 * m, "covered": c, "coverage_k": 5}
            for m, c in ((16, 0.8), (18, 0.96))]  # fmt: skip
    fig = sweep_curves(rows, 0.2, target_coverage=0.95)
    ax, right = fig.axes
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "field median" in labels and "line of sight, nodes seeing 5 (right)" in labels
    median = next(ln for ln in ax.lines if ln.get_label() == "field median")
    np.testing.assert_allclose(median.get_ydata(), [0.16, 0.18])
    np.testing.assert_allclose(right.lines[0].get_ydata(), [80, 96])
    assert right.lines[1].get_ydata()[0] == pytest.approx(95)  # the target's line
    # no coverage in the rows: one axis, as before
    plain = [{k: v for k, v in r.items() if k not in ("covered", "coverage_k")} for r in rows]
    assert len(sweep_curves(plain, 0.2, target_coverage=0.95).axes) == 1


def test_the_recommendation_reads_the_field_p95_where_there_is_one():
    from placement.anchor_sweep import SweepRow, recommend

    def row(M, p95, field_p95):
        return SweepRow(M, 0.1, 0.05, p95, 0.1, 0.2, 0.1, 0.2, np.zeros((M, 3)), 1.0, 1.0,
                        field_p95=field_p95, covered=1.0, coverage_k=5)  # fmt: skip

    # M = 20 meets the target at the evaluation nodes only; the field says M = 22
    rows = [row(20, 0.10, 0.41), row(22, 0.12, 0.19), row(24, 0.3, float("nan"))]
    assert recommend(rows, 0.2, 0.99, 0.95) == 22
    assert recommend(rows[2:], 0.35, 0.99, 0.95) == 24  # no field check: the nodes' P95


def test_the_sweep_report_and_the_designs_table_lead_with_the_field_median():
    from analysis.sweep_report import sweep_html
    from placement.cli.sweep import design_table

    row = {"M": 6, "std": 0.021, "mean": 0.009, "p95": 0.019, "availability": 1.0,
           "held_out_std": 0.03, "mounting_std": 0.04, "seconds": 12.0,
           "anchors": [[0, 0, 0]], "field_std": 0.3, "field_mean": 0.040, "field_p95": 0.080,
           "field_median": 0.016}  # fmt: skip
    old = {k: v for k, v in row.items() if k not in ("field_median", "field_mean")}
    page = sweep_html({"rows": [row, {**old, "M": 8}], "room": {"name": "hall"}}, dpi=20)
    assert "<th>M</th><th>field median / mean / P95 (m)</th><th>field σ (m)</th>" in page
    assert "<td>6</td><td>0.016 / 0.040 / 0.080</td><td>0.300</td>" in page
    assert "<td>8</td><td>– / – / 0.080</td>" in page  # a sweep without the median
    designs = [{"design": "20ms-first-path", "samples_per_fix": 3840, **row},
               {"design": "1ms-paper", "samples_per_fix": 192, **row,
                "field_median": float("nan")}]  # fmt: skip
    first, good, without = design_table(designs).splitlines()
    assert first.split()[:4] == ["design", "M", "field", "median/mean/P95"]
    assert good.split()[:3] == ["20ms-first-path", "6", "0.016/0.040/0.080"]
    assert without.split()[2] == "–/0.040/0.080"
