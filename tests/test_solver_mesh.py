"""The mesh generator: graded segments join without slivers, and the named level-0
resolutions are what docs/verification.md says they are."""

from dataclasses import replace

import numpy as np
import pytest

from solver import Design
from solver.mesh import (
    BALANCED_DIVISIONS,
    DEFAULT_DIVISIONS,
    FORMER_DIVISIONS,
    NAMED_DIVISIONS,
    build_mesh,
)
from solver.settings import MESH_DIVISIONS


@pytest.mark.parametrize("divisions", [
    BALANCED_DIVISIONS,
    replace(BALANCED_DIVISIONS, x_chamber_grading=6.0),
    # 16 graded chamber elements on the standard design's 7.1 mm: the rounded end of the
    # graded segment used to sit 1e-15 mm off the chamber end, and the joined x
    # coordinates kept both: an element of zero width (zero Jacobian at assembly)
    replace(FORMER_DIVISIONS, x_chamber_mm=0.75, x_chamber_grading=3.0),
])
@pytest.mark.parametrize("design", [Design(), Design(L_mm=17.3, t_mm=0.55, T_mm=1.9)])
def test_graded_segments_join_without_slivers(divisions, design):
    am = build_mesh(design, 0, divisions)
    d = design.validated()
    x = np.unique(am.mesh.p[0])
    assert np.diff(x).min() > 0.05 * d.L_mm / len(x)
    # the chamber ends are mesh lines
    for end in (d.chamber_offset_mm, d.chamber_offset_mm + d.L_mm):
        assert np.abs(x - end).min() < 1e-12


def test_the_balanced_mesh_is_graded_towards_the_bonded_chamber_ends():
    d = Design().validated()
    x = np.unique(build_mesh(d, 0, BALANCED_DIVISIONS).mesh.p[0])
    x0, x1 = d.chamber_offset_mm, d.chamber_offset_mm + d.L_mm
    inside = (x >= x0 - 1e-12) & (x <= x1 + 1e-12)
    sizes = np.diff(x[inside])
    assert sizes == pytest.approx(np.full(7, d.L_mm / 7))      # uniform, <= 1.1 mm
    left, right = np.diff(x[x <= x0 + 1e-12]), np.diff(x[x >= x1 - 1e-12])
    # each end wall graded 3:1, its smallest element at the chamber end
    assert left[-1] == pytest.approx(left.min()) and left.max() / left.min() == pytest.approx(3)
    assert right[0] == pytest.approx(right.min()) and right.max() / right.min() == pytest.approx(3)
    z = np.unique(build_mesh(d, 0, BALANCED_DIVISIONS).mesh.p[2])
    in_chamber = (z > d.t_mm + 1e-12) & (z < d.t_mm + d.h_mm - 1e-12)
    assert in_chamber.sum() == 1         # two layers through the chamber height


def test_the_default_mesh_is_the_balanced_one():
    from solver.settings import SolverSettings

    assert NAMED_DIVISIONS[SolverSettings().mesh_divisions] == DEFAULT_DIVISIONS
    assert DEFAULT_DIVISIONS == BALANCED_DIVISIONS


def test_named_resolutions_are_the_settings_choices_least_accurate_first():
    assert tuple(NAMED_DIVISIONS) == MESH_DIVISIONS
    nodes = [build_mesh(Design(), 0, NAMED_DIVISIONS[n]).mesh.nvertices
             for n in MESH_DIVISIONS]
    assert nodes[1] < 1.1 * nodes[0] < nodes[2]     # balanced at about the default's cost
