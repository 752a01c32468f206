"""The sight points a layout leaves poorly fixed (placement.dilution): too few anchors in
sight, or anchors in sight in a geometry of high GDOP, checked against the Fisher
information of analysis.fim (an independent numpy computation) and against geometry whose
answer is known."""

import numpy as np
import pytest

from analysis.fim import gdop, peb
from placement.dilution import poor_sight_share, poor_sight_share_unchecked


def _scene(seed=0, Q=400, N=24):
    rng = np.random.default_rng(seed)
    points = rng.uniform([0, 0, 0], [8, 6, 2], (Q, 3))
    cand = rng.uniform([0, 0, 2.5], [8, 6, 3], (N, 3))
    seen = rng.random((Q, N)) < 0.45
    layouts = np.stack([rng.choice(N, 8, replace=False) for _ in range(12)])
    return points, cand, seen, layouts


def _reference(points, cand, seen, layouts, k, limit):
    out = []
    for s in layouts:
        V = seen[:, s]
        # the GDOP over the anchors in sight: the PEB at σ = 1 m, the others at σ = ∞
        g = peb(cand[s], points, sigma=np.where(V, 1.0, np.inf))
        poor = V.sum(axis=1) < k
        if limit is not None:
            poor |= ~(g <= limit)
        out.append(poor.mean())
    return np.array(out)


@pytest.mark.parametrize("limit", [None, 2.0, 4.0, 10.0])
@pytest.mark.parametrize("k", [3, 4, 5])
def test_the_poor_share_is_that_of_the_gdop_over_the_anchors_in_sight(k, limit):
    """Per layout: the share of points seeing fewer than k of its anchors, or (with a limit)
    whose anchors in sight have GDOP above it, GDOP from analysis.fim over those anchors."""
    points, cand, seen, layouts = _scene()
    got = poor_sight_share(points, cand, seen, layouts, k, limit)
    ref = _reference(points, cand, seen, layouts, k, limit)
    np.testing.assert_allclose(got, ref, atol=1e-12)
    # the planner's call, on arguments a range table has checked: the same shares
    assert np.array_equal(poor_sight_share_unchecked(points, cand, seen, layouts, k, limit), got)
    assert 0.0 < got.min() and got.max() < 1.0  # the scene has both kinds


def test_a_limit_only_adds_poor_points_and_anchor_order_does_not_matter():
    """A limit never makes a point good; a lower limit marks at least as many; the order
    of a layout's anchors and a common shift of the scene change nothing."""
    points, cand, seen, layouts = _scene(1)
    free = poor_sight_share(points, cand, seen, layouts, 4)
    loose = poor_sight_share(points, cand, seen, layouts, 4, 10.0)
    tight = poor_sight_share(points, cand, seen, layouts, 4, 2.0)
    assert np.all(free <= loose) and np.all(loose <= tight) and np.any(free < tight)
    shuffled = np.random.default_rng(2).permuted(layouts, axis=1)
    shift = np.array([3.0, -1.0, 0.5])
    moved = poor_sight_share(points + shift, cand + shift, seen, shuffled, 4, 2.0)
    np.testing.assert_allclose(moved, tight, atol=1e-12)


def test_anchors_in_one_plane_with_the_tag_are_a_shadow_at_any_limit():
    """Five anchors in the plane z = 1.5: a tag in that plane has no GDOP (singular) and is
    poor however loose the limit; a tag 1 m below is not."""
    ring = np.linspace(0, 2 * np.pi, 5, endpoint=False)
    cand = np.c_[4 + 3 * np.cos(ring), 3 + 2 * np.sin(ring), np.full(5, 1.5)]
    points = np.array([[4.2, 3.1, 1.5], [4.2, 3.1, 0.5]])
    seen = np.ones((2, 5), bool)
    got = [poor_sight_share(points[i : i + 1], cand, seen[:1], [np.arange(5)], 4, 1e6)[0]
           for i in range(2)]  # fmt: skip
    assert got == [1.0, 0.0]
    assert np.isinf(gdop(cand, points[:1])[0])  # the reference agrees it is singular


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"layouts": [[0, 30]]}, "layouts: candidate indices must be in [0, 23]"),
        ({"seen": np.ones((3, 24), bool)}, "seen (Q, N) = (400, 24)"),
        ({"gdop_limit": 0.0}, "gdop_limit: must be"),
        ({"gdop_limit": float("nan")}, "gdop_limit: must be"),
        ({"k": 0}, "k: "),
        ({"points": np.ones((5, 2))}, "points"),
    ],
)
def test_bad_input_is_refused_naming_the_argument(change, message):
    points, cand, seen, layouts = _scene()
    args = {"points": points, "candidates": cand, "seen": seen, "layouts": layouts, "k": 4,
            "gdop_limit": None, **change}  # fmt: skip
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("(", r"\(")
                       .replace(")", r"\)")):  # fmt: skip
        poor_sight_share(**args)
