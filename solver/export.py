"""Field output of a converged state: VTU for ParaView (meshio), per element.

Point data: displacement (mm). Cell data: layer (0 body, 1 membrane), largest
principal stretch, and von Mises equivalent of the Cauchy stress (Pa), each the
average over the element's quadrature points. The mesh written is the
deformed-able vertex mesh (corner nodes; for hex2 the mid-nodes are dropped).
"""

from __future__ import annotations

import numpy as np

from solver.assembly import deformation_gradient
from solver.discrete import SolidModel
from solver.ogden import stress_and_tangent


def element_fields(model: SolidModel, u_free: np.ndarray) -> dict[str, np.ndarray]:
    u = model.full(u_free)
    ne = model.mesh.nelements
    stretch = np.zeros(ne)
    mises = np.zeros(ne)
    layer = np.zeros(ne)
    for block in model.blocks:
        F = deformation_gradient(block, u)
        J = np.linalg.det(F)
        _, P, _, lam = stress_and_tangent(F, block.mu_pa, block.alpha)
        # Cauchy stress of the isochoric part plus the projected pressure is not kept
        # here; the deviatoric (isochoric) Cauchy stress carries the von Mises measure.
        sigma = P @ np.transpose(F, (0, 1, 3, 2)) / J[..., None, None]
        dev = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3
        vm = np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev))
        elements = block.elements
        stretch[elements] = lam.mean(axis=1)
        mises[elements] = vm.mean(axis=1)
        layer[elements] = 1.0 if block.membrane else 0.0
    return {"max_principal_stretch": stretch, "von_mises_pa": mises, "layer": layer}


def write_vtu(path: str, model: SolidModel, u_free: np.ndarray) -> None:
    import meshio

    u = model.full(u_free).reshape(-1, 3)
    nv = model.mesh.nvertices
    points = model.mesh.p.T
    cells = [("hexahedron", model.mesh.t.T)]
    fields = element_fields(model, u_free)
    meshio.write(path, meshio.Mesh(points, cells,
                                   point_data={"displacement_mm": u[:nv]},
                                   cell_data={k: [v] for k, v in fields.items()}))
