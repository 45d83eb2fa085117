"""Stability under volume control (bordered system) versus the tangent alone, and the
constrained unstable modes (solver/stability.py)."""

import numpy as np
import pytest
import scipy.sparse as sp

from solver.discrete import SolidModel
from solver.linear import factorize
from solver.materials import OgdenMaterial
from solver.newton import mixed_newton_step
from solver.settings import SolverSettings
from solver.stability import classify, constrained_modes, volume_control_index
from solver.verification.sphere import octant_shell_mesh, symmetry_mask


def _projected_eigenvalues(K: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Eigenvalues of K on the subspace orthogonal to g (dense reference)."""
    Q, _ = np.linalg.qr(np.column_stack([g, np.eye(len(g))]))
    basis = Q[:, 1:len(g)]
    return np.linalg.eigvalsh(basis.T @ K @ basis)


@pytest.mark.parametrize("g_axis, expected", [(0, 0), (1, 1)])
def test_volume_control_index_matches_the_projected_tangent(g_axis, expected):
    # K has one negative eigenvalue. If g points along that mode (g^T K^-1 g < 0), the
    # constraint removes it: stable at constant volume (a limit point passed). If g is
    # orthogonal to it, the mode keeps the volume: unstable under both controls.
    rng = np.random.default_rng(0)
    Q, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    K = Q @ np.diag([-1.0, 2.0, 3.0, 4.0, 5.0, 6.0]) @ Q.T
    g = Q[:, g_axis] + (0.1 * Q[:, 2] if g_axis == 0 else 0.0)
    fac = factorize(sp.csr_matrix(K), "superlu")
    assert fac.negative_pivots == 1
    gkg = float(g @ fac.solve(g))
    index = volume_control_index(fac.negative_pivots, gkg)
    assert index == expected == int(np.sum(_projected_eigenvalues(K, g) < 0))
    assert classify(fac.negative_pivots, gkg, True) == (
        "bifurcation" if expected else "limit point passed")
    assert classify(fac.negative_pivots, gkg, False) == "bifurcation"


def test_constrained_modes_are_the_projected_eigenpairs():
    rng = np.random.default_rng(1)
    n = 40
    A = sp.random(n, n, density=0.2, random_state=2).toarray()
    K = A + A.T + np.diag(np.linspace(-1.0, 8.0, n))
    g = rng.standard_normal(n)
    fac = factorize(sp.csr_matrix(K), "superlu")
    vals, vecs = constrained_modes(sp.csr_matrix(K), g, fac, k=2)
    ref = _projected_eigenvalues(K, g)
    nearest = ref[np.argsort(np.abs(ref))[:2]]
    assert np.allclose(np.sort(vals), np.sort(nearest), rtol=1e-6, atol=1e-9)
    assert np.abs(g @ vecs).max() < 1e-8 * np.linalg.norm(g)          # volume-neutral
    for lam, v in zip(vals, vecs.T):
        r = K @ v - lam * v
        r -= g * (g @ r) / (g @ g)                                     # projected residual
        assert np.linalg.norm(r) < 1e-6


def test_sphere_past_its_pressure_maximum_is_stable_under_volume_control():
    # The neo-Hookean sphere (exact pressure maximum near lam_a = 1.6): beyond it the
    # tangent at fixed pressure has one negative eigenvalue (test_solver_verification),
    # but the bordered (volume-controlled) system is stable: K alone and the bordered
    # system disagree, and the solver calls it a limit point, not a bifurcation.
    nh = OgdenMaterial("nh", (1.88,), (2.0,))
    sm = octant_shell_mesh(2, 2, "hex2")
    model = SolidModel(sm.mesh, "hex2", [(np.arange(sm.mesh.nelements), nh, True)],
                       sm.cavity_facets, symmetry_mask, 1000.0)
    settings = SolverSettings()
    u, p = np.zeros(model.n_free), 0.0
    q = model.consistent_pressures(u)
    seen = []
    for lam in np.arange(1.1, 2.21, 0.1):
        for sub in (0.5, 1.0):
            v_prev = model.volume0_mm3 * (lam - 0.1) ** 3
            target = v_prev + sub * (model.volume0_mm3 * lam**3 - v_prev)
            out = mixed_newton_step(model, u, q, p, settings, target, None, "auto")
            u, q, p = out.u, out.q, out.pressure_pa
        seen.append((lam, out.negative_pivots, out.g_kinv_g))
    late = [(neg, gkg) for lam, neg, gkg in seen if lam > 1.85]
    assert late and all(neg == 1 and gkg < 0 for neg, gkg in late)     # K alone: unstable
    assert all(volume_control_index(neg, gkg) == 0 for neg, gkg in late)
    assert all(classify(neg, gkg, True) == "limit point passed" for neg, gkg in late)
    early = [(neg, gkg) for lam, neg, gkg in seen if lam < 1.4]
    assert all(neg == 0 and gkg > 0 for neg, gkg in early)


def test_stability_fields_survive_the_store(tmp_path):
    # The two optional Curve members of issue 12 are stored and read back; a record
    # written without them (as every older one) reads as None / -1.
    from dataclasses import replace

    from test_precompute_fakes import fake_curve

    from solver.design import Design
    from solver.store import CurveStore, make_record

    design = Design().validated()
    plain = fake_curve(design)
    flagged = replace(plain, volume_control_negative_eigenvalues=np.array([0, 0, 0, 1, 1, 2]),
                      branch_switch_index=4)
    settings = SolverSettings(mesh_level=0, element="hex1")
    with CurveStore(tmp_path / "db.h5", mode="a") as db:
        db.put(make_record(design, settings, flagged))
        db.put(make_record(Design(L_mm=5.0).validated(), settings, plain))
    with CurveStore(tmp_path / "db.h5") as db:
        back = {r.design.L_mm: r.curve for r in db.records()}
    assert back[design.L_mm].volume_control_negative_eigenvalues.tolist() == [0, 0, 0, 1, 1, 2]
    assert back[design.L_mm].branch_switch_index == 4
    assert back[5.0].volume_control_negative_eigenvalues is None
    assert back[5.0].branch_switch_index == -1


def test_the_full_width_mesh_is_the_half_mesh_and_its_mirror_image():
    # benchmarks/full_width_check.py checks what the symmetry plane hides on this mesh.
    from solver.design import Design
    from solver.mesh import build_mesh

    design = Design(t_mm=0.25).validated()
    half = build_mesh(design, 0)
    full = build_mesh(design, 0, full_width=True)
    assert full.mesh.nelements == 2 * half.mesh.nelements
    assert len(full.cavity_facets) == 2 * len(half.cavity_facets)
    assert full.membrane.sum() == 2 * half.membrane.sum()
    upper = full.mesh.p[:, full.mesh.p[1] >= 0]
    assert np.allclose(np.unique(upper.round(9), axis=1), np.unique(half.mesh.p.round(9), axis=1))
    mirrored = full.mesh.p * np.array([[1.0], [-1.0], [1.0]])
    assert np.allclose(np.unique(mirrored.round(9), axis=1),
                       np.unique(full.mesh.p.round(9), axis=1))
