"""The HTML report of an anchor-count sweep folder (``sweep.json`` of ``anchorplan
sweep``): the recommendation, the table of the field median / mean / P95 and σ against M,
the curves and every planned layout, in one self-contained file."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

from analysis.figures import png_bytes, sweep_curves
from analysis.paper import TABLE1
from analysis.percent import percent_cell
from simulation.output import write_file


def _num(v) -> str:
    return "–" if v is None or v != v else f"{v:.3f}"


def sweep_html(data: dict, dpi: float = 100) -> str:
    """The report of a sweep's ``to_dict()`` (as read back from ``sweep.json``)."""
    rows = data["rows"]
    paper = TABLE1 if data.get("room", {}).get("name") == "techtile" else None
    fig = sweep_curves(
        rows, data.get("target_p95"), paper, dpi=dpi, target_coverage=data.get("target_coverage")
    )
    png = png_bytes(fig, palette=True)
    target = data.get("target_p95")
    goal = f"availability ≥ {100 * data.get('target_availability', 0.99):g} %"
    if data.get("target_coverage"):
        goal += f", line of sight ≥ {100 * data['target_coverage']:g} %"
    if target is not None:
        goal += f" and field P95 ≤ {target:g} m"
    if data.get("recommended") is None:
        verdict = f"No anchor count of the sweep reaches {goal}."
    else:
        verdict = (
            f"<b>Recommended: M = {data['recommended']}</b>, the smallest anchor count whose "
            f"validated {goal}."
        )
    # what the tags see first (random tags, anchors as mounted), then σ and the nodes
    head = "<tr><th>M</th><th>field median / mean / P95 (m)</th><th>field σ (m)</th>"
    head += "<th>σ (m)</th><th>mean (m)</th><th>P95 (m)</th><th>availability</th>"
    head += "<th>held-out σ (m)</th><th>mounting-error σ (m)</th><th>seconds</th>"
    head += "<th>paper σ / mean / P95 (m)</th></tr>" if paper else "</tr>"
    body = []
    for r in rows:
        ref = ""
        if paper:
            p = paper.get(r["M"])
            ref = f"<td>{p['std']} / {p['mean']} / {p['p95']}</td>" if p else "<td>–</td>"
        body.append(
            f"<tr><td>{r['M']}</td>"
            f"<td>{' / '.join(_num(r.get(k)) for k in ('field_median', 'field_mean', 'field_p95'))}"
            f"</td><td>{_num(r.get('field_std'))}</td>"
            f"<td>{_num(r['std'])}</td><td>{_num(r['mean'])}</td>"
            f"<td>{_num(r['p95'])}</td><td>{percent_cell(r.get('availability'))}</td>"
            f"<td>{_num(r['held_out_std'])}</td>"
            f"<td>{_num(r['mounting_std'])}</td><td>{r['seconds']:.0f}</td>{ref}</tr>"
        )
    layouts = "".join(
        f"<h3>M = {r['M']}</h3><pre>"
        + "\n".join(f"{x:7.3f} {y:7.3f} {z:7.3f}" for x, y, z in r["anchors"])
        + "</pre>"
        for r in rows
    )
    name = html.escape(str(data.get("room", {}).get("name", "room")))
    img = base64.b64encode(png).decode()
    return (
        f"<!doctype html><html><head><meta charset='utf-8'><title>anchorplan sweep: {name}"
        "</title><style>body{font-family:sans-serif;max-width:60em;margin:auto}"
        "td,th{padding:2px 8px;text-align:right}</style></head><body>"
        f"<h1>How many anchors: {name}</h1><p>{verdict}</p>"
        f"<table>{head}{''.join(body)}</table>"
        f"<p><img alt='errors against M' src='data:image/png;base64,{img}'></p>"
        "<p>field: the Euclidean position error of random tags in the zones with the "
        "anchors mounted within the run's tolerance (a sweep of an earlier version has no "
        "median or mean: –); "
        "σ, mean and P95 of the Euclidean position error at the evaluation nodes (the "
        "paper's statistics, over the fixes), each layout validated with its own noise; "
        "availability: the share of node realizations with a fix; held-out σ at nodes "
        "the optimizer never scored; mounting-error σ with the anchors mounted within the "
        "run's tolerance of their planned points.</p>"
        f"<h2>Layouts (m)</h2>{layouts}"
        f"<h2>Settings</h2><pre>{html.escape(json.dumps(data.get('settings', {}), indent=1))}"
        "</pre></body></html>"
    )


def write_sweep_report(result_dir, out=None, dpi: float = 100) -> Path:
    """Write ``report.html`` (or ``out``) for the sweep folder ``result_dir``."""
    result_dir = Path(result_dir)
    data = json.loads((result_dir / "sweep.json").read_text())
    path = Path(out) if out is not None else result_dir / "report.html"
    return write_file(path, sweep_html(data, dpi=dpi))
