"""The HTML report: self-contained, valid, and showing the numbers of its inputs."""

import base64
import json
import re
from html.parser import HTMLParser
from types import SimpleNamespace

import numpy as np
import pytest

import analysis
import placement
from analysis import report as rp
from placement.cli import main
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()
OPT = np.array([[0.6, 0.03, 1.3], [6.1, 0.03, 0.9], [1.2, 3.97, 1.6], [5.7, 3.97, 1.5]])
VOID = {"meta", "img", "br", "hr", "input", "link", "col", "source", "wbr"}


class Checker(HTMLParser):
    """Collects tags, attributes and text; checks that non-void tags are balanced."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.imgs, self.urls, self.tags = [], [], [], [], []
        self.text = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        a = dict(attrs)
        for k in ("src", "href", "data", "action", "poster"):
            if k in a:
                self.urls.append(a[k])
        if tag == "img":
            self.imgs.append(a)
        if tag not in VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"unbalanced </{tag}> (open: {self.stack[-3:]})")
        else:
            self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def check_html(text: str) -> Checker:
    assert text.startswith("<!DOCTYPE html>")
    c = Checker()
    c.feed(text)
    c.close()
    assert not c.errors and not c.stack, (c.errors, c.stack)
    # nothing external: no remote URL anywhere, every resource an inline data: URI
    plain = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "DATA", text)
    assert not re.search(r"(https?:)?//[a-z0-9]", plain, re.I)
    assert "<script" not in plain and "<link" not in plain and "@import" not in plain
    assert "url(" not in plain and "<iframe" not in plain
    for u in c.urls:
        assert u.startswith("data:image/png;base64,"), u[:40]
    for img in c.imgs:
        png = base64.b64decode(img["src"].split(",", 1)[1])
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        assert img.get("alt")
    return c


def fake_evaluate(room, anchors, realizations=1, rng=0, nodes=None, **kw):
    """A fast stand-in with the shapes of simulation.Evaluation (synthetic errors)."""
    rng = np.random.default_rng(rng)
    nodes = room.grid() if nodes is None else nodes
    R, P, M = realizations, len(nodes), len(anchors)
    est = nodes + rng.normal(0, 0.3, (R, P, 3))
    errors = np.linalg.norm(est - nodes, axis=-1)
    range_errors = rng.normal(0, 0.04, (R, P, M))
    return SimpleNamespace(
        anchors=np.asarray(anchors, float),
        errors=errors,
        estimates=est,
        range_errors=range_errors,
        rmse=analysis.node_rmse(errors),
        dop=analysis.dop(errors, range_errors),
        dop_rms=analysis.dop_rms(errors, range_errors),
    )


def write_result(d, validation=True, history=True, extra=None):
    rng = np.random.default_rng(0)
    errors = rng.gamma(2.0, 0.4, (4, 270))
    T = 6
    bah = [ROOM.corners_layout() + (OPT - ROOM.corners_layout()) * t / (T - 1) for t in range(T)]
    result = {
        "room": ROOM.to_dict(),
        "anchors": OPT.tolist(),
        "cost": 0.9848,
        "cost_name": "variance",
        "history": list(np.linspace(1.6, 0.9848, T)) if history else [],
        "best_anchors_history": [b.tolist() for b in bah] if history else [],
        "nfev": 48,
        "nit": T,
        "message": "reached the maximum number of iterations",
        "success": True,
        "seeds": [
            {"name": "relax-A", "anchors": bah[1].tolist(), "cost": 1.65, "mean_peb": 0.08},
            {"name": "relax-D", "anchors": bah[2].tolist(), "cost": None, "mean_peb": 0.08},
        ],
        "validation": {
            "realizations": 4,
            "seed": 7,
            "std": float(np.std(errors)),
            "mean": float(np.mean(errors)),
            "p95": float(np.percentile(errors, 95)),
            "rms": float(np.sqrt(np.mean(errors**2))),
            "mean_peb": 0.177,
            "per_node": {
                "rmse": np.sqrt(np.mean(errors**2, axis=0)).tolist(),
                "dop": (2.0 + rng.random(270)).tolist(),
                "dop_rms": (3.0 + rng.random(270)).tolist(),
            },
            "errors": errors.tolist(),
            **(extra or {}),
        }
        if validation
        else {},
        "timings": {"seeding": 1.5, "pso": 12.5, "validation": 0.5, "total": 14.0},
        "settings": {"M": 4, "particles": 8, "sigma": 0.04, "options": {"tol": 1e-3}},
    }
    (d / "result.json").write_text(json.dumps(result))
    (d / "layout.json").write_text(json.dumps({"anchors": OPT.tolist()}))
    return result, errors


def test_report_from_result_json_with_simulator(tmp_path, monkeypatch):
    monkeypatch.setattr(rp, "_evaluator", lambda: fake_evaluate)
    result, errors = write_result(tmp_path)
    naive = placement.naive_layout(ROOM, 4)
    path, rep = rp.write_report(tmp_path, realizations=3, dpi=40, comparisons={"naive": naive})
    assert path == tmp_path / "report.html"
    text = path.read_text()
    c = check_html(text)
    assert len(c.imgs) == len(rep.figures) == 10
    titles = " | ".join(rep.figures)
    wanted = ("Plan view", "Coverage", "PEB map", "PEB at the evaluation nodes", "RMSE",
              "Error CDFs", "Bound vs", "DOP difference", "Layouts", "PSO evolution")  # fmt: skip
    for want in wanted:
        assert want in titles
    names = [e.name for e in rep.layouts]
    assert names == ["optimized", "naive", "corners", "initial relax-A", "initial relax-D"]
    body = "".join(c.text)
    # σ / mean / P95 of the stored validation, mean PEB computed here, coordinates
    v = result["validation"]
    for key in ("std", "mean", "p95", "rms"):
        assert f"{v[key]:.3f}" in body
    mean_peb = np.mean(analysis.peb(OPT, NODES, 0.04))
    assert f"{mean_peb:.3f}" in body
    for a in OPT:
        assert f"{a[0]:.3f}" in body and f"{a[2]:.3f}" in body
    # both DOPs, labelled: the stored paper DOP and the RMS-based one
    assert "DOP (paper" in body and "DOPRMS" in body
    assert f"{np.mean(v['per_node']['dop']):.2f}" in body
    assert f"{np.mean(v['per_node']['dop_rms']):.2f}" in body
    # gap table: median RMSE/PEB of the optimized layout from the stored per-node RMSE
    rmse = np.asarray(v["per_node"]["rmse"])
    ratio = np.median(rmse / analysis.peb(OPT, NODES, 0.04))
    assert f"{ratio:.2f}" in body
    assert "numpy" in body and np.__version__ in body
    assert "simulated for this report (R = 3)" in body  # the naive and corners references
    assert f"{naive[0, 0]:.3f}" in body
    # reading order: headline, layout (coordinates and plan view), comparison, ..., settings
    heads = ('class="cards"', "<h2>Layout</h2>", "Plan view", "<h2>Comparison")
    heads += ("<h2>Figures</h2>", "<h2>Settings</h2>", "<h2>Software</h2>")
    order = [text.index(h) for h in heads]
    assert order == sorted(order)
    # timings: one row per phase
    assert "Time per phase" in body and "seeding" in body and "14.0" in body
    assert "Held-out" not in body and "Mounting tolerance" not in body


def test_report_shows_the_plans_validation_sections(tmp_path, monkeypatch):
    monkeypatch.setattr(rp, "_evaluator", lambda: None)
    extra = {
        "held_out": {
            "grid": {"std": 0.611, "mean": 0.722, "p95": 1.833, "nodes": 150},
            "random": {"std": 0.644, "mean": 0.755, "p95": 1.866, "nodes": 200},
        },
        "mounting": {"tolerance_m": 0.05, "draws": 20, "std": 0.677, "mean": 0.788, "p95": 1.899},
    }
    write_result(tmp_path, history=False, extra=extra)
    rep = rp.build_report(tmp_path, dpi=30)
    body = "".join(check_html(rep.html).text)
    assert "Held-out nodes" in body and "Mounting tolerance" in body
    for x in ("0.611", "0.722", "1.833", "150", "0.644", "200", "0.050", "20", "0.677", "1.899"):
        assert x in body
    # what the tags see first, then σ; a file without the median shows "–" there
    lead = "<th>median (m)</th><th>mean (m)</th><th>P95 (m)</th><th>σ (m)</th>"
    assert rep.html.count(lead) == 3  # the comparison, held-out and mounting tables
    assert '<td class="l">grid</td><td>150</td><td>–</td><td>0.722</td>' in rep.html
    extra["held_out"]["grid"]["median"] = 0.533
    write_result(tmp_path, history=False, extra=extra)
    html = rp.build_report(tmp_path, dpi=30).html
    assert '<td class="l">grid</td><td>150</td><td>0.533</td><td>0.722</td>' in html
    # malformed optional sections do not break the report
    extra = {"held_out": {"grid": "n/a"}, "mounting": 3}
    write_result(tmp_path, history=False, extra=extra)
    check_html(rp.build_report(tmp_path, dpi=30).html)


def test_the_median_card_is_the_validations_median(tmp_path):
    # the committed techtile plan: the card shows the median its validation stored
    import shutil
    from pathlib import Path

    src = Path(__file__).resolve().parent.parent / "docs" / "examples" / "techtile"
    for name in ("result.json", "layout.json"):
        shutil.copy(src / name, tmp_path / name)
    median = json.loads((src / "result.json").read_text())["validation"]["median"]
    rep = rp.build_report(tmp_path, realizations=0, dpi=20)
    assert f"<b>{median:.3f} m</b><span>median error (optimized, at the nodes)" in rep.html


def test_a_penalized_starting_layouts_cost_says_what_it_means(tmp_path, monkeypatch):
    monkeypatch.setattr(rp, "_evaluator", lambda: None)
    result, _ = write_result(tmp_path, history=False)
    result["seeds"][0]["cost"] = 1.2e14  # below the coverage target
    result["seeds"][1]["cost"] = 1.1e12 + 0.3  # 10 % of the node realizations without a fix
    (tmp_path / "result.json").write_text(json.dumps(result))
    body = "".join(check_html(rp.build_report(tmp_path, dpi=20).html).text)
    assert "below the coverage target" in body and "10 % without a fix" in body
    assert "1.2e+14" not in body and "1.1e+12" not in body


def test_a_reports_simulations_report_their_progress(tmp_path):
    write_result(tmp_path, history=False)
    calls = []
    rp.build_report(tmp_path, realizations=1, dpi=20, progress=lambda *c: calls.append(c))
    # the optimized layout (its per-axis errors) and the corners layout, one step each
    assert calls == [("report simulations", 0, 2), ("report simulations", 1, 2)]
    with pytest.raises(ValueError, match="progress"):
        rp.build_report(tmp_path, realizations=1, progress="yes")


def test_report_without_simulator_skips_simulated_figures(tmp_path, monkeypatch):
    monkeypatch.setattr(rp, "_evaluator", lambda: None)
    write_result(tmp_path, validation=False, history=False)
    rep = rp.build_report(tmp_path, dpi=40)
    check_html(rep.html)
    assert not any("RMSE" in t or "CDF" in t for t in rep.figures)
    assert any("not available" in n for n in rep.notes)
    assert any("history" in n for n in rep.notes)
    assert "not available" in rep.html


def test_report_from_evaluation_json_only(tmp_path, monkeypatch):
    monkeypatch.setattr(rp, "_evaluator", lambda: None)
    ev = fake_evaluate(ROOM, OPT, realizations=3, rng=1)
    data = {
        "room": ROOM.to_dict(),
        "anchors": OPT.tolist(),
        "nodes": NODES.tolist(),
        "realizations": 3,
        "seed": 1,
        "stats": {"std": 0.123, "mean": 0.456, "p95": 1.789, "rms": 0.5},
        "per_node": {"rmse": ev.rmse.tolist(), "dop": ev.dop.tolist()},
        "errors": ev.errors.tolist(),
    }
    (tmp_path / "evaluation.json").write_text(json.dumps(data))
    rep = rp.build_report(tmp_path, sigma=0.03, dpi=40)
    c = check_html(rep.html)
    body = "".join(c.text)
    assert [e.name for e in rep.layouts] == ["evaluated", "corners"]
    assert "No naive comparison layout was given" in body
    assert "0.123" in body and "0.456" in body and "1.789" in body
    assert "σr = 0.03 m" in body.replace("\n", "")
    assert any("Bound vs" in t for t in rep.figures)


def test_report_merges_the_same_layout_from_both_files(tmp_path):
    write_result(tmp_path)
    ev = fake_evaluate(ROOM, OPT, realizations=9, rng=2)
    (tmp_path / "evaluation.json").write_text(
        json.dumps(
            {
                "room": ROOM.to_dict(),
                "anchors": OPT.tolist(),
                "realizations": 9,
                "stats": {"std": 0.3, "mean": 0.4, "p95": 0.9, "rms": 0.5},
                "per_node": {"rmse": ev.rmse.tolist(), "dop": ev.dop.tolist()},
                "errors": ev.errors.tolist(),
            }
        )
    )
    layouts = rp.collect_layouts(rp.load_results(tmp_path), ROOM, NODES)
    opt = layouts[0]
    assert [e.role for e in layouts] == ["optimized", "reference", "initial", "initial"]
    assert opt.sim.realizations == 9 and opt.sim.source == "evaluation.json"


def test_report_bad_inputs(tmp_path, capsys):
    with pytest.raises(FileNotFoundError):
        rp.build_report(tmp_path)
    (tmp_path / "result.json").write_text("{not json")
    with pytest.raises(ValueError, match="JSON"):
        rp.build_report(tmp_path)
    assert main(["report", str(tmp_path / "missing")]) == 2
    assert "not a folder" in capsys.readouterr().err


def test_cli_report_with_the_real_simulator(tmp_path, capsys):
    write_result(tmp_path)
    out = tmp_path / "sub" / "r.html"
    argv = ["report", str(tmp_path), "--out", str(out), "--realizations", "2", "--dpi", "50"]
    assert main([*argv, "--figures", str(tmp_path / "figs")]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    c = check_html(out.read_text())
    assert len(c.imgs) == 10
    assert out.stat().st_size < 1_500_000
    pngs = sorted((tmp_path / "figs").glob("*.png"))
    assert len(pngs) == 10 and pngs[0].name == "01-plan-view-of-the-optimized-layout.png"
    # the CLI compares with the naive layout of the same M, simulated here
    body = "".join(c.text)
    assert "σ of the naive layout" in body and "σ of the corners layout" in body
    # the files are the embedded images
    assert base64.b64encode(pngs[0].read_bytes()).decode() == c.imgs[0]["src"].split(",")[1]


def test_report_with_one_realization_skips_the_dop_map(tmp_path, monkeypatch):
    def one(room, anchors, realizations=1, rng=0, nodes=None, **kw):
        ev = fake_evaluate(room, anchors, realizations, rng, nodes)
        assert np.all(np.isinf(ev.dop))  # σ_r = 0 with one realization
        return ev

    monkeypatch.setattr(rp, "_evaluator", lambda: one)
    write_result(tmp_path, validation=False)
    rep = rp.build_report(tmp_path, realizations=1, dpi=30)
    check_html(rep.html)
    assert not any("DOP" in t for t in rep.figures)
    assert any("DOP difference map skipped" in n for n in rep.notes)
    assert any("RMSE" in t for t in rep.figures)


@pytest.mark.parametrize(
    "anchors",
    [
        [[1, 1, 1], [1, 1, 1], [2, 2, 2], [3, 1, 1]],  # two coincident anchors
        [[1, 1, 1], [2, 2, 2], [3, 1, 1]],  # too few for 3D positioning
        [[1, 1, 1], [2, 2, 2], [3, 1, 1], [9, 1, 1]],  # one outside the room
    ],
)
def test_report_refuses_a_layout_that_no_plan_could_return(tmp_path, anchors):
    result, _ = write_result(tmp_path)
    (tmp_path / "result.json").write_text(json.dumps({**result, "anchors": anchors}))
    with pytest.raises(ValueError, match="optimized layout: anchors"):
        rp.write_report(tmp_path, realizations=0, dpi=40)
