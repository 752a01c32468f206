import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import analysis
from simulation import Room


def _expected_nll_hessian(anchors, p, sigma, h=1e-4):
    """Finite-difference Hessian at p of E[−ln f(r|p')] = Σ (d_j(p') − d_j(p))²/(2σ_j²) + c."""
    d0 = np.linalg.norm(p - anchors, axis=1)

    def f(q):
        d = np.linalg.norm(q - anchors, axis=1)
        return np.sum((d - d0) ** 2 / (2 * sigma**2))

    H = np.zeros((3, 3))
    E = np.eye(3) * h
    for i in range(3):
        for j in range(3):
            H[i, j] = (
                f(p + E[i] + E[j]) - f(p + E[i] - E[j]) - f(p - E[i] + E[j]) + f(p - E[i] - E[j])
            ) / (4 * h * h)
    return H


def test_fim_equals_negative_hessian_of_loglikelihood():
    rng = np.random.default_rng(1)
    anchors = rng.uniform(0, 4, size=(6, 3))
    sigma = rng.uniform(0.02, 0.08, size=6)
    pts = rng.uniform(0, 4, size=(5, 3))
    J = analysis.fim(anchors, pts, sigma=sigma)
    for k, p in enumerate(pts):
        np.testing.assert_allclose(J[k], _expected_nll_hessian(anchors, p, sigma), rtol=1e-5)


def test_tetrahedron_closed_form():
    # Regular tetrahedron around the node: Σ u uᵀ = (4/3) I, so PEB = σ √(3 · 3/4) = 1.5 σ.
    u = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
    p = np.array([[1.0, 2.0, 3.0]])
    for r, sigma in [(1.0, 0.04), (3.7, 0.1)]:
        pb = analysis.peb(p + r * u, p, sigma=sigma)
        assert pb[0] == pytest.approx(1.5 * sigma, rel=1e-12)
        assert analysis.crlb_trace(p + r * u, p, sigma=sigma)[0] == pytest.approx(2.25 * sigma**2)
    assert analysis.gdop(p + u, p)[0] == pytest.approx(1.5)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_peb_invariant_under_rigid_motion(seed):
    rng = np.random.default_rng(seed)
    anchors = rng.uniform(-3, 3, size=(5, 3))
    pts = rng.uniform(-3, 3, size=(20, 3))
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    t = rng.normal(size=3) * 10
    sigma = rng.uniform(0.01, 0.1, size=5)
    before = analysis.peb(anchors, pts, sigma)
    after = analysis.peb(anchors @ Q.T + t, pts @ Q.T + t, sigma)
    ok = np.isfinite(before) & (before < 1e3)
    np.testing.assert_allclose(after[ok], before[ok], rtol=1e-6)


def test_crlb_inverts_fim():
    room = Room.techtile()
    nodes = room.grid()
    a = room.corners_layout()
    J = analysis.fim(a, nodes, 0.04)
    C = analysis.crlb(a, nodes, 0.04)
    np.testing.assert_allclose(J @ C, np.broadcast_to(np.eye(3), J.shape), atol=1e-9)
    np.testing.assert_allclose(np.sqrt(np.trace(C, axis1=-2, axis2=-1)), analysis.peb(a, nodes))


def test_coplanar_anchors_give_inf_without_warning():
    anchors = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [4, 4, 0], [2, 1, 0.0]])
    nodes = np.array([[1.0, 1.0, 0.0], [2.0, 3.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pb = analysis.peb(anchors, nodes)
        C = analysis.crlb(anchors, nodes)
        J = analysis.fim(anchors, nodes)
    assert np.isinf(pb[0]) and np.isinf(pb[1]) and np.isinf(pb[3])
    assert np.isfinite(pb[2])
    assert np.isinf(C[0]).all() and np.isfinite(C[2]).all()
    assert not np.isnan(J).any()
    # fewer than three anchors can never localize in 3D
    assert np.isinf(analysis.peb(anchors[:2], nodes)).all()


def test_sigma_shapes_and_layout_batch():
    rng = np.random.default_rng(3)
    room = Room.techtile()
    nodes = room.grid()
    L, M = 7, 6
    layouts = rng.uniform(0.1, 2.0, size=(L, M, 3)) * np.array([4, 2, 1.2])
    s_m = rng.uniform(0.02, 0.06, size=M)
    s_pm = rng.uniform(0.02, 0.06, size=(len(nodes), M))
    batch = analysis.peb(layouts, nodes, s_pm)
    assert batch.shape == (L, len(nodes))
    for i in range(L):
        np.testing.assert_allclose(batch[i], analysis.peb(layouts[i], nodes, s_pm))
        # a per-anchor sigma equals the same sigma written per pair
        np.testing.assert_allclose(
            analysis.peb(layouts[i], nodes, s_m),
            analysis.peb(layouts[i], nodes, np.broadcast_to(s_m, (len(nodes), M))),
        )
    # uniform scaling of sigma scales PEB
    np.testing.assert_allclose(
        analysis.peb(layouts[0], nodes, 0.08), 2 * analysis.peb(layouts[0], nodes, 0.04)
    )


def test_chunking_matches_unchunked(monkeypatch):
    rng = np.random.default_rng(4)
    a = rng.uniform(0, 3, size=(8, 3))
    p = rng.uniform(0, 3, size=(1000, 3))
    full = analysis.peb(a, p)
    fim_mod = sys.modules["analysis.fim"]  # the package attribute is the function
    monkeypatch.setattr(fim_mod, "_CHUNK_ELEMENTS", 100)
    np.testing.assert_array_equal(analysis.peb(a, p), full)


@pytest.mark.parametrize("bad", [0.0, -0.1, np.nan])
def test_bad_sigma_rejected(bad):
    with pytest.raises(ValueError, match="sigma"):
        analysis.peb(np.eye(3), np.zeros((1, 3)), sigma=bad)


def test_bad_shapes_rejected():
    with pytest.raises(ValueError, match="anchors"):
        analysis.peb(np.ones((4, 2)), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="sigma"):
        analysis.peb(np.ones((4, 3)), np.zeros((2, 3)), sigma=np.ones(3))
    with pytest.raises(ValueError, match="finite"):
        analysis.peb(np.full((4, 3), np.nan), np.zeros((2, 3)))


@pytest.mark.parametrize("sigma", [1e-300, 1e-60, 1e-3, 1e3, 1e60, 1e300])
def test_peb_is_linear_in_sigma_over_the_whole_float_range(sigma):
    # PEB = σ · GDOP for a constant σ (eq. 6-7): no overflow of 1/σ² into a false "singular"
    room = Room.techtile()
    a, nodes = room.corners_layout(), room.grid()[::9]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = analysis.peb(a, nodes, sigma)
    np.testing.assert_allclose(got, sigma * analysis.gdop(a, nodes), rtol=1e-12)


def test_a_zero_robust_sigma_gives_a_tiny_bound_not_inf():
    """Over half the errors equal (MAD 0, yet a spread): σ is the smallest positive float,
    and the bound stays finite; errors without any spread are refused."""
    e = np.zeros((3, 10, 4))
    e[0, 0] = 0.01
    sigma = analysis.calibrated_sigma(e)
    assert np.all(sigma == np.finfo(float).tiny)
    room = Room.techtile()
    got = analysis.peb(room.corners_layout(), room.grid()[::27], sigma)
    assert np.all(np.isfinite(got)) and np.all(got < 1e-300)
    with pytest.raises(ValueError, match="no spread"):
        analysis.calibrated_sigma(np.zeros((3, 10, 4)))
