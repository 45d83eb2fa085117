"""The discrete actuator: mesh, bases, material blocks, cavity, constraints.

Builds once per (design, settings) everything the Newton loop needs, and
evaluates the residual and tangent of the half model at a state (u, p)::

    R(u, p) = f_int(u) - p dV/du          (free dofs)
    K(u, p) = df_int/du - p d2V/du2

Boundary conditions: the end x = 0 of both layers is clamped (u = 0); u_y = 0 on
the symmetry plane y = 0. Units: mm, Pa, uN (= Pa mm^2), nJ.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from solver import cavity as cav
from solver.assembly import (
    MaterialBlock,
    Pattern,
    consistent_pressures,
    evaluate_block,
    make_basis,
    material_block,
    pressure_update,
    scatter_vector,
    sub_block,
)
from solver.design import Design
from solver.mesh import NAMED_DIVISIONS, MeshDivisions, build_mesh
from solver.parallel import map_pair, thread_budget
from solver.settings import SolverSettings


@dataclass
class Evaluation:
    R: np.ndarray           # reduced residual
    K: object               # reduced sparse tangent (None if not requested)
    g: np.ndarray           # reduced dV/du (half volume)
    volume_mm3: float       # half cavity volume
    energy: float
    max_membrane_stretch: float
    load_norm: float        # || p dV/du ||
    tip_force_un: float = float("nan")   # spring force or block reaction on the model, uN
    block_states: list | None = None     # per evaluation unit, for the pressure update
    constraint_error: float = 0.0        # max |M^-1 R_p|: dilatation mismatch of the iterate


class SolidModel:
    """A hyperelastic solid with one fluid cavity, discretised once.

    groups: list of (element indices, OgdenMaterial, is_membrane) covering the mesh.
    fixed_fn: maps the scalar nodes' reference positions (3, nnodes) to a bool
            (nnodes, 3) mask of constrained displacement components (u = 0).
    cavity_facets may be empty (no fluid cavity). ``external_force`` (full vector,
    uN, dead load) may be set after construction; it enters the residual as -f.
    spring: optional (dofs, weights, k_un_per_mm): a linear spring on the weighted
            mean displacement w . u[dofs], energy k/2 (w . u)^2, force k (w . u).
    reaction_dofs: optional constrained dofs whose summed reaction is reported
            (a blocked tip), as the force the solid exerts on the support.
    """

    def __init__(self, mesh, element: str, groups, cavity_facets: np.ndarray,
                 fixed_fn, bulk_ratio: float, spring=None, reaction_dofs=None,
                 basis=None) -> None:
        """``basis``: the scalar ``make_basis(mesh, element)`` when the caller has it."""
        self.mesh = mesh
        basis = make_basis(mesh, element) if basis is None else basis
        self.doflocs = basis.doflocs                                      # (3, nnodes)
        nnodes = basis.N
        self.ndofs = 3 * nnodes
        porder = 1 if element == "hex2" else 0
        self.blocks = []
        for elements, mat, is_membrane in groups:
            mu = np.array(mat.mu_pa)
            alpha = np.array(mat.alpha)
            mu0 = 0.5 * float((mu * alpha).sum())
            self.blocks.append(material_block(basis, np.asarray(elements), mu, alpha,
                                              bulk_ratio * mu0, porder, is_membrane))
        self.mu0_min_pa = min(0.5 * float((b.mu_pa * b.alpha).sum()) for b in self.blocks)
        self.units = evaluation_units(self.blocks, thread_budget())
        self.cavity = (cav.make_cavity(mesh, element, cavity_facets, basis.doflocs)
                       if len(cavity_facets) else None)
        self.external_force: np.ndarray | None = None
        fixed = np.asarray(fixed_fn(basis.doflocs), dtype=bool)
        free = np.nonzero(~fixed.ravel())[0]
        cavity_dofs = [self.cavity.dofs] if self.cavity is not None else []
        self.spring = spring
        spring_dofs = [np.asarray(spring[0])[None, :]] if spring is not None else []
        self.reaction_dofs = reaction_dofs
        # Scatter groups: the first unit (the calling thread's part), the other units and
        # the cavity (the helper's), the spring (see ``evaluate``).
        nlists = len(self.units) + len(cavity_dofs)
        groups = [(0, 1)] + ([(1, nlists)] if nlists > 1 else [])
        groups += [(nlists, nlists + 1)] if spring_dofs else []
        self.pattern = Pattern([unit.block.dofs for unit in self.units] + cavity_dofs
                               + spring_dofs, free, self.ndofs, n_pair_lists=len(self.units),
                               groups=groups)
        self.n_free = len(free)
        self.volume0_mm3 = self._volume(np.zeros(self.ndofs))
        self.timings = {"assembly_s": 0.0, "linear_solve_s": 0.0}

    def _volume(self, u: np.ndarray) -> float:
        return cav.volume(self.cavity, u) if self.cavity is not None else 0.0

    def full(self, u_free: np.ndarray) -> np.ndarray:
        u = np.zeros(self.ndofs)
        u[self.pattern.free] = u_free
        return u

    def consistent_pressures(self, u_free: np.ndarray) -> list[np.ndarray]:
        """Element pressures of the penalty form at u (Pa), per block: the starting
        mixed state, e.g. q = 0 at u = 0."""
        u = self.full(u_free)
        return [consistent_pressures(block, u) for block in self.blocks]

    def pressure_update(self, ev: Evaluation, du_free: np.ndarray,
                        constraint: bool = True) -> list[np.ndarray]:
        """The mixed element pressures' Newton update (Pa) for a displacement update;
        ``constraint=False``: their rate along a displacement rate (no constraint residual)."""
        assert ev.block_states is not None
        du = self.full(du_free)
        per_unit = [pressure_update(unit.block, st, du, constraint)
                    for unit, st in zip(self.units, ev.block_states)]
        return [np.concatenate([dq for unit, dq in zip(self.units, per_unit)
                                if unit.index == i]) for i in range(len(self.blocks))]

    def evaluate(self, u_free: np.ndarray, pressure_pa: float, tangent: bool = True,
                 pressures: list[np.ndarray] | None = None) -> Evaluation:
        """Residual and tangent at (u, p). ``pressures``: the mixed iterate's element
        pressures per block (residual condensed, see solver.assembly); None: the
        penalty form, whose residual is the exact gradient of the energy."""
        t0 = time.perf_counter()
        u = self.full(u_free)
        free = self.pattern.free
        r = np.zeros(self.ndofs)
        energy = 0.0
        lam_membrane: list[float] = []
        states = []
        constraint_error = 0.0

        def part(group: int):
            """Scatter group 0 (the first unit) or 1 (the other units and the cavity's
            volume, gradient and Hessian): their states, the cavity terms, and with the
            tangent their part of the matrix's upper triangle (Pattern.upper_values)."""
            units = self.units[:1] if group == 0 else self.units[1:]
            sts = [evaluate_block(unit.block, u, tangent, None if pressures is None
                                  else pressures[unit.index][unit.elements]) for unit in units]
            terms = None
            if group == 1 and self.cavity is not None:
                terms = (self._volume(u), cav.volume_gradient(self.cavity, u),
                         cav.volume_hessian(self.cavity, u) if tangent else None)
            upper = None
            if tangent:
                mats = [st.stiffness for st in sts] + ([-pressure_pa * terms[2]] if terms
                                                       else [])
                upper = self.pattern.upper_values(group, mats) if mats else None
            for st in sts:          # in the upper triangle now; the pressure update needs
                st.stiffness = None  # only D and R_p
            return sts, terms, upper

        # Two threads when the thread budget allows (solver/parallel.py): the first
        # unit here, the others and the cavity on the helper (``evaluation_units``).
        parts = map_pair(part, [0, 1], split=1)
        block_states = [st for sts, _, _ in parts for st in sts]
        cavity_terms = parts[1][1]
        for block, st in zip((unit.block for unit in self.units), block_states):
            states.append(st)
            constraint_error = max(constraint_error, st.dilatation_error)
            energy += st.energy
            r += scatter_vector(self.ndofs, block.dofs, st.residual)
            if block.membrane:
                lam_membrane.append(float(st.lam_max.max()))
        lam_m = max(lam_membrane) if lam_membrane else 1.0
        if cavity_terms is not None:
            vol, gv, _ = cavity_terms
            g = scatter_vector(self.ndofs, self.cavity.dofs, gv)[free]
        else:
            vol, g = 0.0, np.zeros(len(free))
        tip_force = float("nan")
        if self.reaction_dofs is not None:
            # The support holds f_int - p dV/du = reaction; the solid pushes with -reaction.
            full_g = np.zeros(self.ndofs)
            if self.cavity is not None:
                full_g = scatter_vector(self.ndofs, self.cavity.dofs, gv)
            tip_force = -float((r - pressure_pa * full_g)[self.reaction_dofs].sum())
        if self.spring is not None:
            sdofs, weights, k = self.spring
            stretch = float(weights @ u[sdofs])
            r[sdofs] += k * stretch * weights
            energy += 0.5 * k * stretch**2
            tip_force = k * stretch
        R = r[free] - pressure_pa * g
        if self.external_force is not None:
            R = R - self.external_force[free]
        K = None
        if tangent:
            upper = parts[0][2]
            if parts[1][2] is not None:
                upper += parts[1][2]
            if self.spring is not None:
                upper += self.pattern.upper_values(len(self.pattern.groups) - 1,
                                                   [(k * np.outer(weights, weights))[None]])
            K = self.pattern.assemble(upper)
        self.timings["assembly_s"] += time.perf_counter() - t0
        counter = "tangent_evaluations" if tangent else "residual_evaluations"
        self.timings[counter] = self.timings.get(counter, 0) + 1
        return Evaluation(R, K, g, vol, energy, lam_m, float(np.linalg.norm(pressure_pa * g)),
                          tip_force, states if pressures is not None else None,
                          constraint_error)



@dataclass
class EvaluationUnit:
    """A range of one material block's elements, evaluated as one piece."""

    index: int              # the block
    elements: slice         # its elements
    block: MaterialBlock    # the block restricted to them


# The first unit's share of the elements. It runs on the calling thread while the
# helper thread does the rest and the cavity (solver/parallel.py); the sparse matrix is
# assembled after both, so the two parts should take equally long.
FIRST_UNIT_SHARE = 0.52


def evaluation_units(blocks: list[MaterialBlock], threads: int) -> list[EvaluationUnit]:
    """The blocks as evaluation units: with two threads or more, the first
    ``FIRST_UNIT_SHARE`` of all elements (in block order, splitting the block that
    straddles it) and the rest; with one, the blocks as they are. Splitting changes only
    the order of summation in the sparse matrix."""
    sizes = [len(b.dofs) for b in blocks]
    cut = int(round(FIRST_UNIT_SHARE * sum(sizes))) if threads >= 2 else 0
    units, start = [], 0
    for i, (block, n) in enumerate(zip(blocks, sizes)):
        pieces = ([slice(0, cut - start), slice(cut - start, n)] if start < cut < start + n
                  else [slice(0, n)])
        for sl in pieces:
            units.append(EvaluationUnit(i, sl, block if sl == slice(0, n)
                                        else sub_block(block, sl)))
        start += n
    return units


class ActuatorModel(SolidModel):
    """The half actuator: body A over membrane B, clamped at x = 0, symmetric in y.

    Tip options (settings.tip): "free"; "spring": a linear spring of stiffness k
    (N/m, whole actuator) on the mean z displacement of the end face's nodes, like the
    paper's elastic band; "blocked": u_z = 0 on the end face. The reported force is
    the z force the actuator exerts on the spring or block (mN, whole actuator).
    """

    def __init__(self, design: Design, settings: SolverSettings,
                 divisions: MeshDivisions | None = None) -> None:
        """``divisions``: the level-0 resolution; None takes settings.mesh_divisions
        (explicit divisions are for convergence studies)."""
        self.design = design.validated()
        self.settings = settings
        if divisions is None:
            divisions = NAMED_DIVISIONS[settings.mesh_divisions]
        am = build_mesh(self.design, settings.mesh_level, divisions)
        groups = [(np.nonzero(~am.membrane)[0], self.design.body_material, False),
                  (np.nonzero(am.membrane)[0], self.design.membrane_material, True)]

        x_end = am.end_face_x_mm

        def fixed(X: np.ndarray) -> np.ndarray:
            mask = np.zeros((X.shape[1], 3), dtype=bool)
            mask[X[0] < 1e-9, :] = True           # clamped end
            mask[X[1] < 1e-9, 1] = True           # symmetry plane y = 0
            if settings.tip == "blocked":
                mask[np.abs(X[0] - x_end) < 1e-9, 2] = True
            return mask

        basis = make_basis(am.mesh, settings.element)
        end_nodes = np.nonzero(np.abs(basis.doflocs[0] - x_end) < 1e-9)[0]
        spring = reaction = None
        if settings.tip == "spring":
            # k in N/m = 1e3 uN/mm; the half model carries half of it.
            weights = np.full(len(end_nodes), 1.0 / len(end_nodes))
            spring = (3 * end_nodes + 2, weights, 0.5 * settings.spring_k_n_per_m * 1e3)
        elif settings.tip == "blocked":
            reaction = 3 * end_nodes + 2
        super().__init__(am.mesh, settings.element, groups, am.cavity_facets, fixed,
                         settings.bulk_ratio, spring=spring, reaction_dofs=reaction,
                         basis=basis)
        self.end_nodes = end_nodes

    def tip_force_mn(self, ev: Evaluation) -> float:
        """Whole-actuator tip force in mN (the half model's uN x 2 / 1000)."""
        return 2.0 * ev.tip_force_un / 1000.0

    def injected_volume_ul(self, volume_half_mm3: float) -> float:
        """Cavity volume change of the whole actuator (two halves), ul = mm^3."""
        return 2.0 * (volume_half_mm3 - self.volume0_mm3)

    def end_face_kinematics(self, u_free: np.ndarray) -> tuple[float, np.ndarray]:
        """Bending angle (deg) and centroid displacement (x, z) of the free end face.

        The angle is the rotation about y of the end face, from a least-squares fit
        of the deformed x and z of its nodes against their reference height Z:
        theta = atan2(-dx/dZ, dz/dZ); positive when the tip moves to +z, away
        from the membrane (which lies at the bottom, z < t).
        """
        u = self.full(u_free).reshape(-1, 3)
        nodes = self.end_nodes
        X = self.doflocs[:, nodes]
        x = X + u[nodes].T
        Z = X[2] - X[2].mean()
        dxdZ = float(np.dot(Z, x[0] - x[0].mean()) / np.dot(Z, Z))
        dzdZ = float(np.dot(Z, x[2] - x[2].mean()) / np.dot(Z, Z))
        angle = float(np.degrees(np.arctan2(-dxdZ, dzdZ)))
        disp = u[nodes].mean(axis=0)
        return angle, np.array([disp[0], disp[2]])
