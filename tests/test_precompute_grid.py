"""Grid files: expansion, and every kind of bad grid rejected with its line before any
solve."""

import textwrap
from pathlib import Path

import pytest

from solver.precompute import GridError, load_grid, parse_grid
from solver.precompute.lines import key_lines

REPO = Path(__file__).resolve().parent.parent


def grid(text: str):
    return parse_grid(textwrap.dedent(text).lstrip("\n"), "g.toml")


def rejected(text: str) -> GridError:
    with pytest.raises(GridError) as info:
        grid(text)
    return info.value


def test_cartesian_product_with_ranges_lists_and_settings():
    g = grid("""
        pairs = [["pdms_1_10", "ecoflex_00_30"], ["pdms_1_15", "ecoflex_00_30"]]
        L_mm = {start = 4.1, stop = 17.1, num = 14}
        t_mm = [0.5, 1.0]
        [settings]
        mesh_level = 0
        element = "hex1"
        """)
    assert len(g) == 2 * 14 * 2
    first = g.points[:14 * 2:2]
    # 14 evenly spaced values from 4.1 to 17.1 are 4.1, 5.1, ..., 17.1 (step 1 mm), exactly
    assert [p.design.L_mm for p in first] == [round(4.1 + i, 9) for i in range(14)]
    assert {p.settings.element for p in g.points} == {"hex1"}
    assert g.points[0].design.body_material.id == "pdms_1_10"
    assert len({p.key for p in g.points}) == len(g)


def test_sweeps_take_top_level_defaults_and_duplicates_are_solved_once():
    g = grid("""
        pairs = [["pdms_1_10", "ecoflex_00_30"]]
        t_mm = 0.5
        [[sweep]]
        L_mm = [4.1, 7.1]
        [[sweep]]
        L_mm = [7.1, 11.1]
        T_mm = 1.5
        [[sweep]]
        L_mm = 7.1
        """)
    assert [(p.design.L_mm, p.design.T_mm) for p in g.points] == [
        (4.1, 1.0), (7.1, 1.0), (7.1, 1.5), (11.1, 1.5)]


def test_custom_materials_can_be_used_in_pairs():
    g = grid("""
        pairs = [["pdms_1_10", "soft"]]
        [materials.soft]
        mu_kpa = [1.0]
        alpha = [2.5]
        """)
    assert g.points[0].design.membrane_material.alpha == (2.5,)


def test_shipped_default_grid_is_valid_and_small():
    g = load_grid(REPO / "grids" / "default.toml")
    assert 20 <= len(g) <= 30
    pairs = {(p.design.body_material.id, p.design.membrane_material.id) for p in g.points}
    assert pairs == {("pdms_1_10", "ecoflex_00_30"), ("pdms_1_15", "ecoflex_00_30"),
                     ("ecoflex_00_30", "pdms_1_15")}
    # the paper's design space (Section 3): L 4.1 to 17.1 mm, t 0.5 to 1.0 mm
    assert min(p.design.L_mm for p in g.points) == 4.1
    assert max(p.design.L_mm for p in g.points) == 17.1
    assert {p.design.t_mm for p in g.points} == {0.5, 0.75, 1.0}
    assert g.settings == type(g.settings)(mesh_level=0)  # solver defaults but the mesh level


@pytest.mark.parametrize("text,line,field,allowed", [
    # unknown keys, at top level, in a sweep, in a range and in [settings]
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\ncolour = "red"\n', 2, "colour", "L_mm"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[[sweep]]\nL_mm = 5.0\nLmm = 4\n', 4, "Lmm",
     "t_mm"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 4, stop = 5, n = 2}\n', 2,
     "n", "num"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n\n[settings]\nmesh = 1\n', 4,
     "settings.mesh", "mesh_level"),
    # negative and out-of-range lengths, in a list spread over lines and in a range
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nt_mm = [0.5,\n  -0.25]\n', 3, "t_mm",
     "0.05 <= t_mm <= 5"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = -1, stop = 5, num = 3}\n', 2,
     "L_mm", "0.5 <= L_mm <= 60"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nT_mm = "thick"\n', 2, "T_mm", "0.1 <= T_mm"),
    # unknown materials (the line of the bad id inside a multi-line list)
    ('pairs = [\n  ["pdms_1_10", "ecoflex_00_30"],\n  ["pdms_1_20", "ecoflex_00_30"],\n]\n', 3,
     "pairs", "ecoflex_00_30, pdms_1_10, pdms_1_15"),
    ('pairs = [["pdms_1_10"]]\n', 1, "pairs", "<membrane id>"),
    ('L_mm = 5.0\n', 1, "pairs", "pdms_1_10"),
    # empty ranges and lists
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 4, stop = 5, num = 0}\n', 2,
     "L_mm", "1 <= num"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 9, stop = 5, num = 3}\n', 2,
     "L_mm", "start <= stop"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n\nt_mm = []\n', 3, "t_mm",
     "one or more values"),
    ('pairs = []\n', 1, "pairs", "<body id>"),
    # a design that does not fit, bad settings values, broken TOML, bad custom material
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nW_mm = 3.0\nb_mm = 3.5\n', 3, "b_mm",
     "b_mm < W_mm"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[settings]\nelement = "tet4"\n', 3,
     "settings.element", "hex2 | hex1"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [4.1, 7.1\n', 2, "toml", "valid TOML"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n\nL_mm = [4.1,, 7.1]\n', 3, "toml",
     "valid TOML"),
    ('pairs = [["x", "ecoflex_00_30"]]\n[materials.x]\nmu_kpa = [1.0, 2.0]\nalpha = [1.0]\n', 3,
     "materials.x.mu_kpa", "1 to 6 terms"),
    # a custom material may not take a built-in id (its records would share the id)
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[materials.pdms_1_10]\nmu_kpa = [1.0]\n'
     'alpha = [2.0]\n', 2, "materials.pdms_1_10", "a new id (built-in: ecoflex_00_30"),
    # settings that settings_from_dict would silently convert (0.5 -> 0, true -> 1.0)
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[settings]\nmesh_level = 0.5\n', 3,
     "settings.mesh_level", "an integer"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[settings]\nmax_angle_deg = true\n', 3,
     "settings.max_angle_deg", "a number"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[settings]\nelement = 1\n', 3,
     "settings.element", "a string"),
    # non-integer and huge num (refused before expanding), sweeps that are not tables
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 4, stop = 5, num = 2.5}\n', 2,
     "L_mm", "an integer 1 <= num <= 100000"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 4, stop = 5, num = 10000000000}'
     '\n', 2, "L_mm", "num <= 100000"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nsweep = [1, 2]\n', 2, "sweep", "[[sweep]]"),
    ('name = 3\npairs = [["pdms_1_10", "ecoflex_00_30"]]\n', 1, "name", "free text"),
])
def test_bad_grids_are_rejected_with_line_field_and_allowed_values(text, line, field, allowed):
    error = rejected(text)
    assert (error.line, error.field) == (line, field), str(error)
    assert allowed in (error.allowed or ""), str(error)
    assert str(error).startswith(f"g.toml, line {line}: {field}: ")


def test_key_lines_handles_comments_strings_and_tables():
    text = textwrap.dedent("""\
        # L_mm = 1 in a comment
        name = "x = [ not a table"   # brackets inside a string
        pairs = [
          ["a", "b"],  # [not a header]
        ]
        [[sweep]]
        L_mm = 4.1
        [[sweep]]
        L_mm = 5.1
        [materials.soft]
        mu_kpa = [1.0]
        """)
    spans = key_lines(text)
    assert spans[("name",)] == (2, 2)
    assert spans[("pairs",)] == (3, 5)
    assert spans[("sweep", 0, "L_mm")] == (7, 7)
    assert spans[("sweep", 1, "L_mm")] == (9, 9)
    assert spans[("materials", "soft", "mu_kpa")] == (11, 11)
    assert ("L_mm",) not in spans


@pytest.mark.parametrize("content, line, words", [
    ("name = 'caf\xe9'\n".encode("latin-1"), 1, "0xe9 at offset 11 is not UTF-8"),
    # UTF-16 without a byte-order mark (with one it is read: test_hostile_s50.py)
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n'.encode("utf-16-le"), 1, "binary"),
    (b'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = 4.1\n\x00\x01\x02', 3, "binary"),
    (b"\x89HDF\r\n\x1a\n" + bytes(range(256)), 1, "not UTF-8"),
])
def test_a_grid_file_that_is_not_utf8_text_is_one_clear_error(tmp_path, content, line,
                                                              words):
    path = tmp_path / "grid.toml"
    path.write_bytes(content)
    with pytest.raises(GridError) as exc:
        load_grid(path)
    assert exc.value.line == line and words in str(exc.value)
    assert str(exc.value).startswith(f"{path}, line {line}: encoding: ")


@pytest.mark.parametrize("depth", [101, 5_000, 200_000])
def test_deeply_nested_toml_is_one_clear_error(depth):
    text = 'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = ' + "[" * depth + "]" * depth
    with pytest.raises(GridError) as exc:
        parse_grid(text, "deep.toml")
    assert str(exc.value) == (f"deep.toml, line 2: toml: values nested {depth} levels deep "
                              "(allowed: at most 100 levels of [ ] and { })")


def test_nesting_a_grid_needs_is_fine():
    grid = parse_grid('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [4.1]\n'
                      '[[sweep]]\nt_mm = {start = 0.5, stop = 1.0, num = 2}\n', "ok.toml")
    assert len(grid) == 2


def test_a_faces_sample_puts_each_design_on_a_face_of_the_box_in_turn():
    """``faces = true``: the Sobol designs moved onto the box's faces, every face in turn
    (coordinate i mod 6 at its low end for even i // 6, else its high end), the other
    coordinates as the plain sample's; a continued sequence (``skip``) goes on in turn."""
    import numpy as np

    from solver.design_space import locate, unit_coordinates

    def units(text: str) -> np.ndarray:
        grid = parse_grid(text)
        return np.array([unit_coordinates(locate(p.design, reduced=True).geometry_mm,
                                          locate(p.design, reduced=True).stiffness_ratio)
                         for p in grid.points])

    base = '[[sample]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\nn = 14\nseed = 11\n'
    plain, faces = units(base), units(base + "faces = true\n")
    d = plain.shape[1]
    for i in range(14):
        j, side = i % d, float((i // d) % 2)
        assert faces[i, j] == pytest.approx(side, abs=1e-6)
        others = np.arange(d) != j
        np.testing.assert_allclose(faces[i, others], plain[i, others], atol=1e-6)
    later = units(base.replace("n = 14", "n = 4") + "skip = 14\nfaces = true\n")
    assert later[0, 14 % d] == pytest.approx(float((14 // d) % 2), abs=1e-6)


def test_a_faces_sample_that_is_not_a_boolean_is_refused():
    with pytest.raises(GridError, match="faces"):
        parse_grid('[[sample]]\nn = 2\nfaces = "yes"\n')
