"""record_key: same inputs, same key; any change of design or settings, a new key."""

from dataclasses import fields, replace

import pytest

from solver.design import Design
from solver.materials import MATERIALS, make_material
from solver.settings import DEFAULT_MESH_LEVEL, SolverSettings
from solver.store import record_key
from solver.store.keys import canonical_json

# Pinned: computed by this implementation (KEY_VERSION 3; version 1 gave
# 7a6747211b2edacb59ed14347eb03e2b before the mesh levels were redefined, version 2
# b8183475f8bbcdba8151ed6fd5c94bed before the default level-0 divisions changed) for the paper's
# standard design and these explicit settings (explicit, so a change of a default does not
# move it). If this changes, every stored database loses its keys: bump KEY_VERSION and say so in
# docs/database.md rather than editing the number. (A new SolverSettings field enters the key
# only at a non-default value, solver/store/keys.py ADDED_SETTINGS, so this key holds.)
STANDARD_KEY = "b8183475f8bbcdba8151ed6fd5c94bed"
PINNED_SETTINGS = SolverSettings(
    mesh_level=1, element="hex2", control="volume", max_angle_deg=90.0,
    max_pressure_pa=20000.0, max_volume_ul=50.0, flow_ul_s=2.5, bulk_ratio=1000.0,
    newton_tol=1e-8, max_newton_iter=25, max_steps=400, tip="free", spring_k_n_per_m=0.0,
    mesh_divisions="former")      # the mesh of every version-2 record: left out of the key


def test_key_is_pinned_for_the_standard_design():
    assert record_key(Design(), PINNED_SETTINGS) == STANDARD_KEY


def test_key_is_32_hex_digits_and_defaults_to_default_settings():
    key = record_key(Design())
    assert len(key) == 32 and int(key, 16) >= 0
    assert key == record_key(Design(), SolverSettings())


def test_equivalent_inputs_give_the_same_key():
    base = record_key(Design(L_mm=7.1, t_mm=0.5), SolverSettings())
    # an int where a float is expected, float noise far below the rounding, and the
    # resolved body length / chamber offset given explicitly
    assert record_key(Design(L_mm=7.1 + 1e-13, t_mm=0.5)) == base
    assert record_key(Design(L_mm=7.1, t_mm=0.5, T_mm=1)) == base
    assert record_key(Design(L_mm=7.1, body_length_mm=12.0, chamber_offset_mm=2.45)) == base
    explicit = SolverSettings(mesh_level=DEFAULT_MESH_LEVEL, max_angle_deg=90)
    assert record_key(Design(), explicit) == base


@pytest.mark.parametrize("name,value", [
    ("L_mm", 7.2), ("t_mm", 0.75), ("T_mm", 1.5), ("b_mm", 1.7), ("h_mm", 0.2), ("W_mm", 3.5),
    ("body_length_mm", 14.0), ("chamber_offset_mm", 3.0),
    ("body_material", MATERIALS["pdms_1_15"]), ("membrane_material", MATERIALS["pdms_1_15"]),
])
def test_every_design_field_changes_the_key(name, value):
    assert record_key(replace(Design(), **{name: value})) != record_key(Design())


def test_every_setting_changes_the_key():
    # one valid non-default value per field; a new SolverSettings field fails here until
    # it is added (a field missing from the key would silently merge different solves)
    changed = {"mesh_level": 2, "element": "hex1", "control": "pressure", "max_angle_deg": 45.0,
               "max_pressure_pa": 1e4, "max_volume_ul": 20.0, "flow_ul_s": 5.0,
               "bulk_ratio": 100.0, "newton_tol": 1e-9, "max_newton_iter": 30,
               "max_steps": 200, "tip": "blocked", "spring_k_n_per_m": 1.0,
               "mesh_divisions": "fine_x"}
    assert {f.name for f in fields(SolverSettings)} == set(changed)
    keys = {record_key(Design(), SolverSettings())}
    for name, value in changed.items():
        # a spring stiffness needs a spring tip (refused on the others: it would key a
        # second record of one solve); two stiffnesses, two keys
        tip = {"tip": "spring"} if name == "spring_k_n_per_m" else {}
        keys.add(record_key(Design(), replace(SolverSettings(), **tip, **{name: value})))
    keys.add(record_key(Design(), SolverSettings(tip="spring", spring_k_n_per_m=2.0)))
    assert len(keys) == 2 + len(changed)


def test_a_setting_added_after_version_2_keeps_the_version_2_keys():
    # mesh_divisions = "former" (every version-2 record's mesh) is left out of the
    # canonical text, so those keys stay valid; the default "balanced" and "fine_x" are in
    # it, so no two meshes share a record.
    former = canonical_json(Design(), SolverSettings(mesh_divisions="former"))
    assert "mesh_divisions" not in former
    assert '"mesh_divisions":"balanced"' in canonical_json(Design(), SolverSettings())
    fine = canonical_json(Design(), SolverSettings(mesh_divisions="fine_x"))
    assert '"mesh_divisions":"fine_x"' in fine


def test_a_record_stored_as_default_mesh_reads_as_the_former_mesh_with_its_key(tmp_path):
    """Records written before the balanced mesh became the default say "default": read as
    "former", their key unchanged; a user's "default" is refused with the new names."""
    import h5py
    import pytest
    from test_precompute_fakes import fake_curve

    from solver.errors import InputError
    from solver.settings import settings_from_dict
    from solver.store import CurveStore, make_record
    from solver.store.integrity import seal

    rec = make_record(Design(), SolverSettings(mesh_divisions="former"), fake_curve(Design()))
    path = tmp_path / "old.h5"
    with CurveStore(path, mode="a") as db:
        db.put(rec)
    with h5py.File(path, "r+") as f:       # what an older release wrote
        for group in f["records"].values():
            group["settings"].attrs["mesh_divisions"] = "default"
    image = bytearray(path.read_bytes())   # sealed again, as that release published it
    seal(memoryview(image))
    path.write_bytes(bytes(image))
    with CurveStore(path) as db:
        (back,) = list(db.records())
    assert back.key == rec.key and back.settings.mesh_divisions == "former"
    with pytest.raises(InputError, match="former name"):
        settings_from_dict({"mesh_divisions": "default"})


def test_a_record_stored_before_the_mesh_setting_existed_reads_as_the_former_mesh(tmp_path):
    """The shipped database's oldest records carry no mesh_divisions at all: they were
    solved on the former level 0 (ADDED_SETTINGS), not on today's default, and keep their
    keys (read as the default, the balanced mesh, every one was refused as damaged)."""
    import h5py
    from test_precompute_fakes import fake_curve

    from solver.store import CurveStore, make_record
    from solver.store.integrity import seal

    rec = make_record(Design(), SolverSettings(mesh_divisions="former"), fake_curve(Design()))
    path = tmp_path / "older.h5"
    with CurveStore(path, mode="a") as db:
        db.put(rec)
    with h5py.File(path, "r+") as f:       # what a release before the setting wrote
        for group in f["records"].values():
            del group["settings"].attrs["mesh_divisions"]
    image = bytearray(path.read_bytes())
    seal(memoryview(image))
    path.write_bytes(bytes(image))
    with CurveStore(path) as db:
        (back,) = list(db.records())
    assert back.key == rec.key and back.settings.mesh_divisions == "former"


def test_material_parameters_not_just_the_id_enter_the_key():
    fake = make_material("ecoflex_00_30", [1.3], [3.0])  # a preset's id, other parameters
    assert record_key(Design(membrane_material=fake)) != record_key(Design())
    assert '"mu_kpa":[1.3]' in canonical_json(Design(membrane_material=fake), SolverSettings())
