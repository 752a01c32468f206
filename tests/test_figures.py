"""Figures render headless to the requested pixel size and show what they claim."""

import struct
import subprocess
import sys

import numpy as np
import pytest

import analysis
from analysis import figures as F
from analysis.stacking import stacks
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()
CORNERS = ROOM.corners_layout()
OTHER = np.array([[1.0, 0.03, 2.0], [6.5, 3.97, 0.8], [3.0, 2.0, 2.37], [5.5, 1.2, 2.37]])


def png_size(path) -> tuple[int, int]:
    data = path.read_bytes()[:24]
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def render(fig, tmp_path, name="f.png"):
    path = F.save(fig, tmp_path / name)
    fig.canvas.draw()  # 3D scatter offsets are projected at draw time
    return png_size(path)


def by_gid(ax, gid):
    return [c for c in ax.collections if c.get_gid() == gid]


def colorbar_of(fig):
    cbs = [a for a in fig.axes if a.get_gid() == "colorbar"]
    assert len(cbs) == 1
    return cbs[0]


def data_axes(fig):
    return [a for a in fig.axes if a.get_gid() != "colorbar" and a.get_visible()]


def test_peb_map_size_panels_anchors_and_colorbar_range(tmp_path):
    fig = F.peb_map(
        ROOM, OTHER, heights=[0.5, 1.2], y_cuts=[2.0], x_cuts=[4.0], figsize=(8, 5), dpi=50
    )
    assert render(fig, tmp_path) == (400, 250)
    axs = data_axes(fig)
    assert len(axs) == 4
    lo, hi = np.inf, -np.inf
    for ax in axs:
        (anchors,) = by_gid(ax, "anchors")
        assert len(anchors.get_offsets()) == len(OTHER)
        img = ax.images[0].get_array()
        lo, hi = min(lo, img.min()), max(hi, img.max())
    norm = axs[0].images[0].norm
    assert norm.vmin == pytest.approx(lo) and norm.vmax == pytest.approx(hi)
    cb = colorbar_of(fig)
    assert cb.get_ylabel() == "PEB (m)"
    assert cb.get_ylim() == pytest.approx((lo, hi))
    # the first panel is z = 0.5: a cell value is the PEB at that cell centre
    u, v, vals = F.peb_plane(ROOM, OTHER, "z", 0.5)
    assert axs[0].images[0].get_array()[3, 7] == pytest.approx(vals[7, 3])
    ref = analysis.peb(OTHER, np.array([[u[7], v[3], 0.5]]))[0]
    assert vals[7, 3] == pytest.approx(ref)
    # the y cut shows x horizontally and z vertically, anchors projected
    ycut = axs[3]  # order: heights, x cuts, y cuts
    assert ycut.get_xlabel() == "x (m)" and ycut.get_ylabel() == "z (m)"
    assert np.allclose(by_gid(ycut, "anchors")[0].get_offsets(), OTHER[:, [0, 2]])


def test_peb_map_singular_plane_is_masked_and_excluded_from_the_scale(tmp_path):
    ceiling = np.array([[1.0, 1.0, 2.37], [7.0, 1.0, 2.37], [4.0, 3.5, 2.37], [2.0, 3.0, 2.37]])
    fig = F.peb_map(ROOM, ceiling, heights=[2.37, 1.2], figsize=(6, 4), dpi=40)
    assert render(fig, tmp_path) == (240, 160)
    top, mid = data_axes(fig)
    assert np.all(top.images[0].get_array().mask)  # coplanar anchors: no z information
    finite = mid.images[0].get_array()
    assert not np.any(finite.mask)
    assert top.images[0].norm.vmax == pytest.approx(finite.max())
    assert "singular" in fig.get_suptitle()


def test_peb_map_log_scale_for_wide_ranges_and_bad_arguments():
    flat = np.array([[1.0, 0.03, 2.3], [7.0, 0.03, 2.3], [4.0, 0.03, 2.0], [4.0, 3.97, 2.3]])
    fig = F.peb_map(ROOM, flat, heights=[2.3], dpi=30)
    norm = data_axes(fig)[0].images[0].norm
    assert type(norm).__name__ == "LogNorm" and norm.vmax / norm.vmin > 10
    fig = F.peb_map(ROOM, flat, heights=[2.3], vmax=1.0, scale="linear", dpi=30)
    assert data_axes(fig)[0].images[0].norm.vmax == 1.0
    with pytest.raises(ValueError, match="value"):
        F.peb_map(ROOM, CORNERS, heights=[3.0])
    with pytest.raises(ValueError, match="scale"):
        F.peb_map(ROOM, CORNERS, scale="cubic")
    with pytest.raises(ValueError, match="anchors"):
        F.peb_map(ROOM, CORNERS[:, :2])


def test_scatter3d_nodes_anchors_aim_and_colorbar(tmp_path):
    values = analysis.peb(OTHER, NODES)
    values[5] = np.inf
    fig = F.scatter3d(ROOM, NODES, values, OTHER, figsize=(5, 4), dpi=60)
    assert render(fig, tmp_path) == (300, 240)
    (ax,) = data_axes(fig)
    assert len(by_gid(ax, "nodes")[0].get_offsets()) == len(NODES) - 1
    assert len(by_gid(ax, "nodes-invalid")[0].get_offsets()) == 1
    assert len(by_gid(ax, "anchors")[0].get_offsets()) == len(OTHER)
    assert len(by_gid(ax, "aim")[0].get_segments()) == 3 * len(OTHER)  # shaft + 2 heads
    finite = values[np.isfinite(values)]
    assert colorbar_of(fig).get_ylim() == pytest.approx((finite.min(), finite.max()))
    assert colorbar_of(fig).get_ylabel() == "PEB (m)"
    fig = F.scatter3d(ROOM, NODES, values, label="RMSE (m)", vmin=0.0, vmax=0.1, dpi=30)
    cb = colorbar_of(fig)
    assert cb.get_ylabel() == "RMSE (m)" and cb.get_ylim() == pytest.approx((0.0, 0.1))
    assert not by_gid(data_axes(fig)[0], "anchors")
    with pytest.raises(ValueError, match="values"):
        F.scatter3d(ROOM, NODES, values[:10])


def test_error_cdfs_one_line_per_layout_per_panel(tmp_path):
    rng = np.random.default_rng(1)
    e = {"corners": rng.gamma(2.0, 0.5, (6, 270)), "optimized": rng.gamma(2.0, 0.3, (6, 270))}
    e["corners"][0, :27] = np.nan  # failed fixes: 27 of 1620
    ax_err = {k: rng.normal(0, 0.4, (6, 270, 3)) for k in e}
    fig = F.error_cdfs(e, ax_err, figsize=(8, 6), dpi=50)
    assert render(fig, tmp_path) == (400, 300)
    axs = data_axes(fig)
    assert len(axs) == 4
    for ax in axs:
        lines = [ln for ln in ax.lines if str(ln.get_gid()).startswith("cdf:")]
        assert sorted(ln.get_gid() for ln in lines) == ["cdf:corners", "cdf:optimized"]
    (euc,) = [ln for ln in axs[0].lines if ln.get_gid() == "cdf:corners"]
    assert euc.get_ydata()[-1] == pytest.approx(1 - 27 / 1620)  # failures keep F < 1
    x = np.sort(e["optimized"].ravel())
    (opt,) = [ln for ln in axs[0].lines if ln.get_gid() == "cdf:optimized"]
    assert opt.get_xdata()[-1] == x[-1] and opt.get_ydata()[-1] == 1.0
    p95 = np.percentile(e["optimized"], 95)
    assert f"P95 {p95:.3g} m" in opt.get_label()
    colors = F.layout_colors(["corners", "optimized"])
    assert euc.get_color() == colors["corners"]
    # Euclidean only: one panel
    fig = F.error_cdfs({"a": e["optimized"]}, dpi=30)
    assert len(data_axes(fig)) == 1


def test_error_cdfs_are_reduced_for_large_samples():
    e = np.random.default_rng(2).gamma(2.0, 0.5, 100_000)
    fig = F.error_cdfs({"big": e}, dpi=30)
    (ln,) = [ln for ln in data_axes(fig)[0].lines if ln.get_gid() == "cdf:big"]
    x, f = ln.get_xdata(), ln.get_ydata()
    assert len(x) <= 2000 and x[-1] == e.max() and f[-1] == 1.0
    # the kept points lie on the exact ECDF
    assert np.allclose(f, np.searchsorted(np.sort(e), x, side="right") / e.size)


def test_bound_gap_cdfs_peb_and_rmse_lines_per_layout(tmp_path):
    peb = {"a": analysis.peb(CORNERS, NODES), "b": analysis.peb(OTHER, NODES)}
    rmse = {"a": 4 * peb["a"], "b": 2 * peb["b"]}
    fig = F.bound_gap_cdfs(peb, rmse, figsize=(6, 4), dpi=50)
    assert render(fig, tmp_path) == (300, 200)
    (ax,) = data_axes(fig)
    gids = sorted(str(ln.get_gid()) for ln in ax.lines if ":" in str(ln.get_gid()))
    assert gids == ["peb:a", "peb:b", "rmse:a", "rmse:b"]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("median RMSE/PEB 4" in t for t in labels)
    assert any("median RMSE/PEB 2" in t for t in labels)
    (ra,) = [ln for ln in ax.lines if ln.get_gid() == "rmse:a"]
    (pa,) = [ln for ln in ax.lines if ln.get_gid() == "peb:a"]
    assert ra.get_color() == pa.get_color() == F.layout_colors(["a", "b"])["a"]
    assert pa.get_linestyle() == "--"


def test_dop_difference_layers_symmetric_scale(tmp_path):
    rng = np.random.default_rng(3)
    a, b = 2.5 + rng.normal(0, 0.3, 270), 1.7 + rng.normal(0, 0.3, 270)
    b[10] = np.inf
    fig = F.dop_difference(
        ROOM, NODES, a, b, anchors_a=CORNERS, anchors_b=OTHER, figsize=(9, 6), dpi=40
    )
    assert render(fig, tmp_path) == (360, 240)
    axs = data_axes(fig)
    assert len(axs) == 5  # one panel per node height of the 9 × 6 × 5 grid
    d = a - b
    lim = np.max(np.abs(d[np.isfinite(d)]))
    assert colorbar_of(fig).get_ylim() == pytest.approx((-lim, lim))
    # the first layer (z = 0.05 m) shows the nodes with z index 0, x along columns
    mesh = [c for c in axs[0].collections if c.get_gid() == "dop"][0]
    layer = mesh.get_array().reshape(6, 9)
    grid = NODES.reshape(9, 6, 5, 3)
    assert np.allclose(layer, (a - b).reshape(9, 6, 5)[:, :, 0].T)
    assert np.allclose(grid[:, :, 0, 2], 0.05)
    assert [len(c.get_offsets()) for c in by_gid(axs[0], "anchors")] == [4, 4]
    ma, mb = np.mean(a), np.mean(b[np.isfinite(b)])
    assert f"initial {ma:.3g} → optimized {mb:.3g}" in fig.get_suptitle()


def test_dop_difference_scatter_for_irregular_nodes(tmp_path):
    nodes = np.random.default_rng(4).uniform([0.1] * 3, [7.9, 3.9, 2.3], (50, 3))
    fig = F.dop_difference(ROOM, nodes, np.full(50, 2.0), np.linspace(1, 3, 50), dpi=40)
    (ax,) = data_axes(fig)
    assert ax.name == "3d"
    assert colorbar_of(fig).get_ylim() == pytest.approx((-1.0, 1.0))
    with pytest.raises(ValueError, match="layers"):
        F.dop_difference(ROOM, nodes, np.ones(50), np.ones(50), kind="layers")


def test_layout_views_one_panel_per_layout(tmp_path):
    layouts = {
        "M=4": CORNERS,
        "M=6": np.vstack([CORNERS, [[4.0, 0.03, 1.2], [4.0, 3.97, 1.2]]]),
        "pso": OTHER,
    }
    fig = F.layout_views(ROOM, layouts, figsize=(9, 3), dpi=50)
    assert render(fig, tmp_path) == (450, 150)
    axs = data_axes(fig)
    assert len(axs) == 3
    colors = F.layout_colors(list(layouts))
    for ax, (name, a) in zip(axs, layouts.items(), strict=True):
        (coll,) = by_gid(ax, "anchors")
        assert len(coll.get_offsets()) == len(a)
        assert np.allclose(coll.get_facecolor()[0][:3], _rgb(colors[name]))
        assert f"M = {len(a)}" in ax.get_title() or f"M={len(a)}" in ax.get_title()
    with pytest.raises(ValueError):
        F.layout_views(ROOM, {})


def _rgb(hex_color):
    h = hex_color.lstrip("#")
    return [int(h[i : i + 2], 16) / 255 for i in (0, 2, 4)]


def test_pso_evolution_panels_and_shared_peb_scale(tmp_path):
    T = 12
    history = np.linspace(2.0, 0.5, T)
    bah = np.array([CORNERS + (OTHER - CORNERS) * t / (T - 1) for t in range(T)])
    fig = F.pso_evolution(ROOM, history, bah, iterations=[1, 6, 12], figsize=(9, 5), dpi=40)
    assert render(fig, tmp_path) == (360, 200)
    axs = data_axes(fig)
    assert len(axs) == 4 and sum(a.name == "3d" for a in axs) == 3
    (hist_line,) = [ln for ln in axs[0].lines if ln.get_gid() == "history"]
    assert np.allclose(hist_line.get_ydata(), history)
    assert np.allclose(hist_line.get_xdata(), np.arange(1, T + 1))
    vals = np.concatenate([analysis.peb(bah[t - 1], NODES) for t in (1, 6, 12)])
    assert colorbar_of(fig).get_ylim() == pytest.approx((vals.min(), vals.max()))
    for ax in axs[1:]:
        assert len(by_gid(ax, "anchors")[0].get_offsets()) == 4
    with pytest.raises(ValueError, match="iterations"):
        F.pso_evolution(ROOM, history, bah, iterations=[0, 13])
    fig = F.pso_history(history, cost_name="variance", unit="m²", marks=[1, 12], dpi=30)
    assert data_axes(fig)[0].get_ylabel() == "best variance (m²)"


def test_layout_colors_stable_distinct():
    names = [f"layout {i}" for i in range(10)]
    c1 = F.layout_colors(names)
    assert len(set(c1.values())) == 10
    assert F.layout_colors(names) == c1
    # a layout keeps its colour when drawn alone
    alone = F.layout_colors(["layout 0"])
    assert alone["layout 0"] == F.layout_colors(["layout 0", "optimized"])["layout 0"]


def test_figure_size_argument_checked():
    with pytest.raises(ValueError, match="figsize"):
        F.new_figure((0, 3))
    with pytest.raises(ValueError, match="dpi"):
        F.new_figure((3, 3), dpi=-1)


def test_no_pyplot_and_lazy_matplotlib():
    code = (
        "import sys, analysis, analysis.report;"
        "assert 'matplotlib' not in sys.modules, 'analysis imports matplotlib';"
        "from analysis import figures as F; from simulation import Room;"
        "r = Room.techtile(); F.png_bytes(F.peb_map(r, r.corners_layout(), dpi=20));"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_dop_difference_clips_heavy_tails_unless_told():
    a = np.full(270, 2.0)
    b = np.full(270, 2.0) - np.linspace(-1, 1, 270)
    b[0] = -500.0  # one extreme node
    fig = F.dop_difference(ROOM, NODES, a, b, dpi=30)
    d = np.abs(a - b)
    p95 = np.percentile(d, 95)
    assert colorbar_of(fig).get_ylim() == pytest.approx((-p95, p95))
    assert "clipped" in fig.get_suptitle()
    fig = F.dop_difference(ROOM, NODES, a, b, vlim=1000.0, dpi=30)
    assert colorbar_of(fig).get_ylim() == pytest.approx((-1000.0, 1000.0))


def test_scatter3d_panels_share_one_scale(tmp_path):
    values = {"corners": analysis.peb(CORNERS, NODES), "optimized": analysis.peb(OTHER, NODES)}
    anchors = {"corners": CORNERS, "optimized": OTHER}
    fig = F.scatter3d_panels(ROOM, NODES, values, anchors, figsize=(8, 3), dpi=50)
    assert render(fig, tmp_path) == (400, 150)
    axs = data_axes(fig)
    assert len(axs) == 2
    allv = np.concatenate(list(values.values()))
    assert colorbar_of(fig).get_ylim() == pytest.approx((allv.min(), allv.max()))
    colors = F.layout_colors(list(values))
    for ax, name in zip(axs, values, strict=True):
        (coll,) = by_gid(ax, "anchors")
        assert len(coll.get_offsets()) == 4
        assert np.allclose(coll.get_facecolor()[0][:3], _rgb(colors[name]))
        assert ax.get_title().startswith(f"{name}: mean {values[name].mean():.3g}")


def test_dop_difference_with_infinite_dop_draws_grey_without_warnings():
    a, b = np.full(270, 2.0), np.full(270, 1.5)
    a[:10] = b[:10] = np.inf
    fig = F.dop_difference(ROOM, NODES, a, b, dpi=30)
    assert colorbar_of(fig).get_ylim() == pytest.approx((-0.5, 0.5))
    masked = sum(
        int(np.sum(c.get_array().mask))
        for ax in data_axes(fig)
        for c in ax.collections
        if c.get_gid() == "dop"
    )
    assert masked == 10


def test_plan_view_numbers_the_anchors_in_plan_and_elevation(tmp_path):
    fig = F.plan_view(ROOM, OTHER, figsize=(8, 3), dpi=40)
    assert render(fig, tmp_path) == (320, 120)
    plan, elevation = data_axes(fig)
    (p,) = by_gid(plan, "anchors")
    (e,) = by_gid(elevation, "anchors")
    np.testing.assert_allclose(p.get_offsets(), OTHER[:, :2])
    np.testing.assert_allclose(e.get_offsets(), OTHER[:, [0, 2]])
    assert [t.get_text() for t in plan.texts] == ["1", "2", "3", "4"]
    # techtile: the ceiling is shaded in the plan, the south and north walls are lines
    assert len([a for a in plan.patches if a.get_gid() == "mounting"]) == 1
    assert len([a for a in plan.lines if a.get_gid() == "mounting"]) == 2


def test_a_slanted_wall_is_seen_edge_on_from_above_and_as_an_area_from_the_south():
    # a trapezoid whose east wall runs from (6, 0) to (8, 4); a duct hangs from the ceiling
    room = Room.from_corners([[0, 0], [6, 0], [8, 4], [0, 4]], 3.0, obstacles=[
        {"min": [1.0, 1.8, 2.5], "max": [5.0, 2.2, 3.0], "name": "duct"}])  # fmt: skip
    plan, elevation = data_axes(F.plan_view(room, OTHER, figsize=(8, 3), dpi=40))
    slanted = [ln.get_xydata() for ln in plan.lines if ln.get_gid() == "mounting"]
    # the slanted wall from above: a line along it (its plane 3 cm inside), from y 0 to 4
    assert any(np.allclose(np.ptp(xy, axis=0), [1.97, 3.94], atol=0.01) for xy in slanted)
    # from the south every line is a wall seen edge-on: vertical or horizontal, no diagonal
    for ln in elevation.lines:
        if ln.get_gid() == "mounting":
            (x0, z0), (x1, z1) = ln.get_xydata()
            assert min(abs(x1 - x0), abs(z1 - z0)) < 1e-9
    quads = [q.get_xy() for q in elevation.patches if q.get_gid() == "mounting"]
    assert any(np.ptp(q[:, 0]) > 1.9 and np.ptp(q[:, 1]) > 2.5 for q in quads)  # the wall's area
    # the duct's label in the plan gives its bottom and top
    assert "2.5–3 m" in [t.get_text() for t in plan.texts]


def test_anchors_on_one_spot_of_a_view_share_a_label():
    # three anchors on one vertical line of the south wall: one spot from above, three
    # from the south
    a = np.array([[1.0, 0.03, 1.0], [4.0, 0.03, 0.5], [4.0, 0.03, 1.5], [4.0, 0.03, 2.3],
                  [4.02, 3.97, 2.0]])  # fmt: skip
    plan, elevation = data_axes(F.plan_view(ROOM, a, figsize=(8, 3), dpi=40))
    assert [t.get_text() for t in plan.texts] == ["1", "2,3,4", "5"]
    assert [t.get_text() for t in elevation.texts] == ["1", "2", "3", "4", "5"]
    # a chain of near spots is one stack; anchors 6 cm apart are not
    chain = np.array([[0, 0], [0.04, 0], [0.08, 0], [1.0, 1.0], [1.06, 1.0]])
    assert stacks(chain) == [[0, 1, 2], [3], [4]]


def test_one_solid_of_several_boxes_gets_one_legible_height_label():
    # a pillar of three boxes meeting face to face, a cabinet touching nothing, a duct
    # touching the pillar's core but hung higher: three labels, dark on a light tag
    room = Room(size=(8.0, 6.0, 3.0), obstacles=[
        {"min": [3.9, 2.6, 0.0], "max": [4.1, 3.4, 3.0], "name": "core"},
        {"min": [3.7, 2.9, 0.0], "max": [3.9, 3.1, 3.0], "name": "west"},
        {"min": [4.1, 2.9, 0.0], "max": [4.3, 3.1, 3.0], "name": "east"},
        {"min": [1.0, 1.0, 0.0], "max": [1.6, 1.4, 1.8], "name": "cabinet"},
        {"min": [4.3, 2.0, 2.5], "max": [7.0, 2.4, 3.0], "name": "duct"}])  # fmt: skip
    plan, _ = data_axes(F.plan_view(room, OTHER, figsize=(8, 3), dpi=40))
    heights = [t for t in plan.texts if t.get_text().endswith(" m")]
    assert sorted(t.get_text() for t in heights) == ["1.8 m", "2.5–3 m", "3 m"]
    (pillar,) = (t for t in heights if t.get_text() == "3 m")
    np.testing.assert_allclose(pillar.xy, (4.0, 3.0))  # on the largest box, the core
    for t in heights:
        assert t.get_color() == "black" and t.get_bbox_patch() is not None


def test_a_column_smaller_than_its_height_tag_has_the_tag_above_it():
    # a car park: 0.5 m columns in a 24 m hall are smaller than their tags, which used to
    # hide them; a ramp wall of 10 m keeps its tag on it
    room = Room(size=(24.0, 15.0, 2.6), obstacles=[
        {"min": [7.25, 4.75, 0.0], "max": [7.75, 5.25, 2.6], "name": "column"},
        {"min": [2.0, 2.0, 0.0], "max": [12.0, 2.3, 1.2], "name": "ramp"}])  # fmt: skip
    anchors = np.array([[1.0, 1.0, 2.5], [23.0, 1.0, 2.5], [12.0, 14.0, 2.5], [20.0, 8.0, 2.5]])
    plan, _ = data_axes(F.plan_view(room, anchors, dpi=40))
    tags = {t.get_text(): t for t in plan.texts if t.get_gid() == "obstacle-height"}
    np.testing.assert_allclose(tags["2.6 m"].xy, (7.5, 5.25))  # the column's top edge
    assert tags["2.6 m"].get_va() == "bottom" and tags["2.6 m"].xyann[1] > 0
    np.testing.assert_allclose(tags["1.2 m"].xy, (7.0, 2.15))  # the wall's centre
    assert tags["1.2 m"].get_va() == "center"


@pytest.mark.parametrize("depth", [6.0, 14.4, 15.0])
def test_the_plan_views_titles_stay_clear_of_the_figures_title(depth):
    # at a depth about 0.6 of the width the equal-aspect plan's title ran into the figure's
    width = 24.0 if depth > 10 else 10.0
    room = Room(size=(width, depth, 2.6))
    fig = F.plan_view(room, np.array([[1, 1, 2.5], [width - 1, 1, 2.5], [1, depth - 1, 2.5],
                                      [width - 1, depth - 1, 2.5]]))  # fmt: skip
    fig.canvas.draw()
    top = fig._suptitle.get_window_extent().y0
    for ax in fig.axes:
        assert ax.title.get_window_extent().y1 < top


def test_a_zone_over_a_floor_plan_is_drawn_inside_the_plan_only():
    # an L whose zone box covers the missing corner: its outline is clipped to the L
    room = Room.from_corners([[0, 0], [6, 0], [6, 3], [3, 3], [3, 5], [0, 5]], 3.0,
                             zones=[{"min": [0.5, 0.5, 1.0], "max": [5.5, 4.5, 1.5]}])  # fmt: skip
    plan, elevation = data_axes(F.plan_view(room, OTHER, figsize=(8, 3), dpi=40))
    (zone,) = (p for p in plan.patches if p.get_gid() == "zones")
    clip = zone.get_clip_path()
    assert clip is not None
    corners = clip.get_fully_transformed_path().vertices
    inv = plan.transData.inverted().transform(corners)
    assert any(np.allclose(v, (3.0, 3.0), atol=1e-6) for v in inv)  # the L's inner corner
    (side,) = (p for p in elevation.patches if p.get_gid() == "zones")
    assert side.get_clip_path() is None  # from the south: the whole box


def test_a_slice_draws_solid_only_the_obstacles_its_plane_cuts():
    # a cabinet up to 1.5 m and a duct from 2.5 m: the slice at 1 m cuts the cabinet only, the
    # one at 2.75 m the duct only; the other is its dashed outline, the map under it visible
    room = Room(size=(6.0, 4.0, 3.0), obstacles=[
        {"min": [1.0, 1.0, 0.0], "max": [2.0, 2.0, 1.5], "name": "cabinet"},
        {"min": [3.0, 1.5, 2.5], "max": [5.5, 2.0, 3.0], "name": "duct"}])  # fmt: skip
    fig = F.coverage_map(room, OTHER, heights=(1.0, 2.75), resolution=0.25, dpi=20)
    for ax, solid in zip(data_axes(fig)[:2], ("cabinet", "duct"), strict=True):  # then the bar
        drawn = {p.get_gid(): p.get_x() for p in ax.patches if "slice" in str(p.get_gid())
                 or p.get_gid() == "obstacles"}  # fmt: skip
        assert drawn == {"obstacles": 1.0 if solid == "cabinet" else 3.0,
                         "off-slice": 3.0 if solid == "cabinet" else 1.0}  # fmt: skip
    # a projection (the layout's plan view) draws both solid
    plan, _ = data_axes(F.plan_view(room, OTHER, figsize=(8, 3), dpi=40))
    assert sorted(p.get_gid() for p in plan.patches if "obstacle" in str(p.get_gid())) == [
        "obstacles", "obstacles"]  # fmt: skip


def test_a_one_panel_maps_title_fits_its_figure():
    # a 16 m hall's PEB map at one height is narrower than its title with the singular note
    room = Room(size=(16.0, 10.0, 7.0), obstacles=[
        {"min": [0, 0, 3.0], "max": [7.0, 10.0, 3.3], "name": "mezzanine"}])  # fmt: skip
    a = np.array([[1.0, 0.03, 2.0], [8.0, 9.97, 4.0], [15.97, 5.0, 1.0], [9.0, 4.0, 6.97],
                  [3.0, 9.97, 1.5]])  # fmt: skip
    for fig in (F.peb_map(room, a, heights=(1.2,), dpi=40),
                F.coverage_map(room, a, heights=(1.2,), dpi=40)):  # fmt: skip
        fig.canvas.draw()
        box = fig._suptitle.get_window_extent()
        assert 0 <= box.x0 and box.x1 <= fig.bbox.x1
    assert "singular" in fig_title(F.peb_map(room, a, heights=(1.2,), dpi=40))


def fig_title(fig) -> str:
    return fig._suptitle.get_text()


def test_dop_difference_says_which_dop():
    a, b = np.full(270, 2.0), np.full(270, 1.5)
    assert "the paper's DOP = σ/σ_r" in F.dop_difference(ROOM, NODES, a, b, dpi=20).get_suptitle()
    rms = F.dop_difference(ROOM, NODES, a, b, definition="rms", dpi=20)
    assert "DOP_RMS(initial)" in rms.get_suptitle() and "RMSE/σ_r" in rms.get_suptitle()
    with pytest.raises(ValueError, match="definition"):
        F.dop_difference(ROOM, NODES, a, b, definition="gdop")
