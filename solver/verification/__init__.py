"""Reference problems with independent solutions, used to verify the FE solver.

* ``sphere``: inflation of a thick-walled hollow sphere (octant model) and the exact
  incompressible pressure-stretch curve, a 1D integral.
* ``cantilever``: a slender clamped bar under a small end load and the Timoshenko /
  Euler-Bernoulli tip deflection.
* ``two_balloons``: two equal spheres sharing one pressure under volume control, the
  classic bifurcation past the pressure maximum (tests/test_solver_bifurcation.py).
* ``drive``: small load-stepping helpers that drive a ``SolidModel`` with the
  solver's own ``newton_step`` to prescribed volumes or pressures.

docs/verification-references.md derives the references and records the results.
"""
