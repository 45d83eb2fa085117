"""The discrete model: residual = gradient of the energy, tangent = derivative of the
residual, cavity volume and its derivatives, fast assembly path = general path."""

import numpy as np
import pytest

from solver import Design, SolverSettings
from solver import cavity as cav
from solver.assembly import element_stiffness, evaluate_block, full_element_matrices
from solver.discrete import ActuatorModel


@pytest.fixture(scope="module", params=["hex1", "hex2"])
def model(request):
    return ActuatorModel(Design(L_mm=4.1), SolverSettings(mesh_level=0, element=request.param,
                                                          bulk_ratio=50))


def _state(model, seed=1):
    return np.random.default_rng(seed).standard_normal(model.n_free) * 2e-3


def test_undeformed_cavity_volume_is_the_chamber(model):
    # Half chamber: L x b/2 x h = 4.1 x 0.9 x 0.15 mm^3.
    assert model.volume0_mm3 == pytest.approx(4.1 * 0.9 * 0.15, rel=1e-12)


def test_rigid_translation_keeps_volume(model):
    u = np.zeros(model.ndofs)
    u[0::3] = 0.3
    u[2::3] = -0.2
    assert cav.volume(model.cavity, u) == pytest.approx(model.volume0_mm3, rel=1e-12)


def test_pressure_load_is_the_volume_derivative(model):
    u = model.full(_state(model))
    g = cav.volume_gradient(model.cavity, u)
    d = np.random.default_rng(5).standard_normal(model.ndofs) * 1e-3
    h = 1e-4
    fd = (cav.volume(model.cavity, u + h * d) - cav.volume(model.cavity, u - h * d)) / (2 * h)
    # Central differences: O(h^2) truncation, measured 1.4e-7 relative on hex1 level 0;
    # a wrong derivative is off by O(1).
    assert (g * d[model.cavity.dofs]).sum() == pytest.approx(fd, rel=5e-7)


def test_volume_hessian_is_the_gradient_derivative(model):
    u = model.full(_state(model))
    H = cav.volume_hessian(model.cavity, u)
    d = np.random.default_rng(6).standard_normal(model.ndofs) * 1e-3
    h = 1e-5
    fd = (cav.volume_gradient(model.cavity, u + h * d)
          - cav.volume_gradient(model.cavity, u - h * d)) / (2 * h)
    Hd = np.einsum("fxy,fy->fx", H, d[model.cavity.dofs])
    assert np.abs(Hd - fd).max() < 1e-7 * np.abs(fd).max()
    assert np.allclose(H, H.transpose(0, 2, 1))


def test_residual_is_the_energy_gradient(model):
    u, p = _state(model), 300.0
    ev = model.evaluate(u, p)

    def potential(v):
        e = model.evaluate(v, p, tangent=False)
        return e.energy - p * e.volume_mm3

    d = np.random.default_rng(2).standard_normal(model.n_free) * 1e-3
    h = 1e-4
    fd = (potential(u + h * d) - potential(u - h * d)) / (2 * h)
    assert ev.R @ d == pytest.approx(fd, rel=1e-7)


def test_tangent_is_the_residual_derivative(model):
    u, p = _state(model), 300.0
    ev = model.evaluate(u, p)
    d = np.random.default_rng(3).standard_normal(model.n_free) * 1e-3
    h = 1e-5
    fd = (model.evaluate(u + h * d, p, False).R - model.evaluate(u - h * d, p, False).R) / (2 * h)
    assert np.abs(ev.K @ d - fd).max() < 1e-7 * np.abs(fd).max()
    assert abs(ev.K - ev.K.T).max() < 1e-12 * abs(ev.K).max()


def _two_field(block, u, q):
    """The uncondensed mixed residuals (r_u, R_p) and the tangent pieces at (u, q)."""
    st = evaluate_block(block, u, True, q)
    kmr = block.bulk_pa * np.einsum("emn,en->em", block.Minv, st.constraint)
    r_u = st.residual - np.einsum("ema,em->ea", st.D, kmr)
    K_uu = (full_element_matrices(st.stiffness)
            - block.bulk_pa * np.matmul(st.D.transpose(0, 2, 1), block.Minv @ st.D))
    return r_u, st.constraint, K_uu, st.D


def test_mixed_linearisation_is_exact_off_the_constraint(model):
    # Newton on (u, q) is exact when both residuals are linearised exactly, at element
    # pressures q that do NOT satisfy the constraint (the iterates' case):
    #   d r_u = K_uu du + D^T dq,   d R_p = D du - M dq / K   (solver/assembly.py).
    block = model.blocks[1]
    rng = np.random.default_rng(8)
    u = model.full(_state(model))
    q = rng.standard_normal(block.Minv.shape[:2]) * 50.0            # Pa, arbitrary
    du = model.full(rng.standard_normal(model.n_free) * 1e-3)
    dq = rng.standard_normal(q.shape) * 10.0
    r_u, R_p, K_uu, D = _two_field(block, u, q)
    assert np.abs(R_p).max() > 1e-6                                 # off the constraint
    h = 1e-5
    plus = _two_field(block, u + h * du, q + h * dq)
    minus = _two_field(block, u - h * du, q - h * dq)
    due = du[block.dofs]
    lin_u = np.einsum("eab,eb->ea", K_uu, due) + np.einsum("ema,em->ea", D, dq)
    lin_p = np.einsum("ema,ea->em", D, due) - np.einsum("emn,en->em", block.M, dq) / block.bulk_pa
    fd_u = (plus[0] - minus[0]) / (2 * h)
    fd_p = (plus[1] - minus[1]) / (2 * h)
    assert np.abs(lin_u - fd_u).max() < 1e-7 * np.abs(fd_u).max()
    assert np.abs(lin_p - fd_p).max() < 1e-7 * np.abs(fd_p).max()


def test_mixed_form_equals_penalty_on_the_constraint(model):
    u = _state(model)
    penalty = model.evaluate(u, 300.0)
    mixed = model.evaluate(u, 300.0, pressures=model.consistent_pressures(u))
    assert mixed.constraint_error < 1e-12
    assert np.abs(mixed.R - penalty.R).max() < 1e-9 * np.abs(penalty.R).max()
    assert abs(mixed.K - penalty.K).max() < 1e-9 * abs(penalty.K).max()
    assert mixed.energy == pytest.approx(penalty.energy, rel=1e-10)


def test_box_fast_path_equals_general_contraction(model):
    block = model.blocks[0]
    assert block.box_scale is not None      # the actuator mesh is made of boxes
    A = np.random.default_rng(4).standard_normal(block.dN.shape[:2] + (9, 9))
    A = A + np.swapaxes(A, -1, -2)            # a tangent is symmetric in (iJ) <-> (kL)
    fast = element_stiffness(block, A)
    saved, block.box_scale = block.box_scale, None
    try:
        general = element_stiffness(block, A)
    finally:
        block.box_scale = saved
    assert np.abs(fast - general).max() < 1e-12 * np.abs(general).max()


def test_box_fast_path_of_the_whole_block_equals_the_general_one(model):
    # Deformation gradient, residual, pressure coupling D and tangent: the matrix
    # products with the common reference gradients against the per-element einsums.
    block = model.blocks[0]
    u = model.full(_state(model, seed=7))
    q = np.random.default_rng(8).standard_normal((block.dofs.shape[0], block.Np.shape[-1]))
    fast = evaluate_block(block, u, True, 300.0 * q)
    residual_only = evaluate_block(block, u, False, 300.0 * q)
    saved = block.box_scale, block.box_gradients
    block.box_scale = block.box_gradients = None
    try:
        general = evaluate_block(block, u, True, 300.0 * q)
    finally:
        block.box_scale, block.box_gradients = saved
    for name in ("residual", "stiffness", "D", "constraint"):
        a, b = getattr(fast, name), getattr(general, name)
        assert np.abs(a - b).max() < 1e-11 * np.abs(b).max(), name
    assert fast.energy == pytest.approx(general.energy, rel=1e-12)
    assert np.array_equal(residual_only.residual, fast.residual)
    assert residual_only.stiffness is None


def test_tip_spring_tangent_and_force():
    m = ActuatorModel(Design(L_mm=4.1), SolverSettings(mesh_level=0, element="hex1",
                                                       tip="spring", spring_k_n_per_m=2.0))
    u, p = _state(m), 200.0
    ev = m.evaluate(u, p)
    d = np.random.default_rng(7).standard_normal(m.n_free) * 1e-3
    h = 1e-5
    fd = (m.evaluate(u + h * d, p, False).R - m.evaluate(u - h * d, p, False).R) / (2 * h)
    assert np.abs(ev.K @ d - fd).max() < 1e-7 * np.abs(fd).max()
    # Force = k * mean tip z displacement: 2 N/m = 2e3 uN/mm on the whole actuator.
    uz = m.full(u)[3 * m.end_nodes + 2].mean()
    assert m.tip_force_mn(ev) == pytest.approx(2.0 * uz, rel=1e-12)


def test_blocks_on_two_threads_give_the_same_bits(model, monkeypatch):
    # solver/parallel.py: the material blocks are evaluated on two threads when the
    # thread budget (MKL_NUM_THREADS, else OMP_NUM_THREADS) allows; same arithmetic.
    u, p = _state(model), 300.0
    q = model.consistent_pressures(u)
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    results = []
    for threads in ("1", "2"):
        monkeypatch.setenv("OMP_NUM_THREADS", threads)
        results.append(model.evaluate(u, p, pressures=q))
    one, two = results
    assert np.array_equal(one.R, two.R) and np.array_equal(one.K.data, two.K.data)
    assert one.energy == two.energy and one.constraint_error == two.constraint_error


@pytest.mark.parametrize("element", ["hex1", "hex2"])
def test_evaluation_units_change_only_the_summation_order(element, monkeypatch):
    # With a thread budget of two the first block is cut into two evaluation units
    # (solver/discrete.py, evaluation_units); residual and tangent agree to round-off.
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    models = []
    for threads in ("1", "2"):
        monkeypatch.setenv("OMP_NUM_THREADS", threads)
        models.append(ActuatorModel(Design(L_mm=4.1), SolverSettings(element=element,
                                                                     bulk_ratio=50)))
    whole, split = models
    assert len(whole.units) == len(whole.blocks) < len(split.units)
    u, p = _state(whole), 300.0
    q = whole.consistent_pressures(u)
    a, b = whole.evaluate(u, p, pressures=q), split.evaluate(u, p, pressures=q)
    assert np.abs(a.R - b.R).max() < 1e-12 * np.abs(a.R).max()
    assert abs(a.K - b.K).max() < 1e-12 * abs(a.K).max()
    du = np.random.default_rng(9).standard_normal(whole.n_free) * 1e-3
    for qa, qb in zip(whole.pressure_update(a, du), split.pressure_update(b, du)):
        assert np.abs(qa - qb).max() < 1e-12 * np.abs(qa).max()
