"""cameras.ifc (issue 33, item 5): the placed cameras written into a copy of the input BIM
model, or into a new IFC4 model. Real files from ../shared/data/plans (SOURCES.md): the
buildingSMART Duplex (IFC2X3, metres), bim-whale's LargeBuilding (IFC2X3, millimetres)
and the Barcelona Pavilion (IFC4, no storeys: its building stands in for one)."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import ifcopenshell
import ifcopenshell.util.element as element
import ifcopenshell.util.placement as placement
import ifcopenshell.util.unit
import ifcopenshell.validate

from camplace.cameras.models import CameraModel
from camplace.core.errors import InputError
from camplace.outputs.cameras_ifc import PSET, ifc_camera_extras, write_cameras_ifc
from camplace.outputs.cameras_ifc_shapes import body_mesh, frustum_mesh
from conftest import SHARED

PLANS = SHARED / "data" / "plans"
DUPLEX, WHALE, PAVILION = (PLANS / n for n in ("Duplex_A_20110907.ifc", "bim-whale_LargeBuilding.ifc",
                                               "Pabellon_de_Barcelona.ifc"))
INTRINSICS = {"model": "pinhole", "width": 1920, "height": 1080, "fx": 1400.0, "fy": 1400.0, "cx": 959.5,
              "cy": 539.5}


def camera(k: int, storey: str, position, rotation=None, **extra) -> dict:
    """A placement.json camera entry (a random rotation of seed k unless given)."""
    rot = Rotation.random(random_state=k).as_matrix() if rotation is None else np.asarray(rotation)
    return {"id": f"C{k + 1}", "candidate_id": 100 + k, "camera": "dome" if k % 2 else "bullet",
            "position": [float(v) for v in position], "rotation": rot.tolist(), "yaw_deg": 10.0 * k,
            "pitch_deg": 30.0, "roll_deg": 0.0, "intrinsics": INTRINSICS, "storey": storey, **extra}


# the Duplex (m): Level 1 floor at 0, Level 2 at 3.1; cameras 2.6 m above each floor, inside its 8.8 x 17.8 m
DUPLEX_CAMERAS = [camera(0, "Level 1", [2.0, 3.0, 2.6], focal_mm=4.0, model="ACME D4",
                         dori_m={"detect": 40.0, "observe": 16.0, "recognise": 8.0, "identify": 4.0}),
                  camera(1, "Level 1", [6.5, 12.0, 2.6]),
                  camera(2, "Level 2", [2.0, 4.0, 5.7]),
                  camera(3, "level 2", [7.0, 15.5, 5.7])]  # the importer's rule: a case-insensitive match


def cameras_of(model) -> list:
    """The camera elements of a written model, in the order written."""
    if model.schema == "IFC2X3":
        return [e for e in model.by_type("IfcFlowTerminal") if e.ObjectType == "CAMERA"]
    return [e for e in model.by_type("IfcAudioVisualAppliance") if e.PredefinedType == "CAMERA"]


def schema_errors(model) -> list:
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, log)
    return log.statements


def assert_round_trip(model, cams: list[dict]) -> None:
    """Each camera element is in its storey, at its position (model units -> m) and rotation."""
    scale = ifcopenshell.util.unit.calculate_unit_scale(model)
    els = cameras_of(model)
    assert len(els) == len(cams)
    for el, cam in zip(els, cams):
        world = placement.get_local_placement(el.ObjectPlacement)
        assert np.abs(world[:3, 3] * scale - cam["position"]).max() < 1e-6
        assert np.abs(world[:3, :3] - np.asarray(cam["rotation"])).max() < 1e-6
        assert element.get_container(el).Name.casefold() == cam["storey"].casefold()
        assert el.Name == cam["id"]


@pytest.fixture(scope="module")
def duplex(tmp_path_factory):
    out = write_cameras_ifc(tmp_path_factory.mktemp("duplex") / "cameras.ifc", DUPLEX_CAMERAS, [], DUPLEX,
                            frustum=True)
    return ifcopenshell.open(str(out))


def test_duplex_copy_is_ifc2x3_and_schema_valid(duplex):
    assert duplex.schema == "IFC2X3"
    # the source has no schema error (checked once, 4 s), so the copy must have none
    assert schema_errors(duplex) == []


def test_duplex_cameras_in_their_storeys_at_their_poses(duplex):
    assert_round_trip(duplex, DUPLEX_CAMERAS)
    storeys = {s.Name: s for s in duplex.by_type("IfcBuildingStorey")}
    assert [element.get_container(e) for e in cameras_of(duplex)] == [storeys["Level 1"]] * 2 + [storeys["Level 2"]] * 2


def test_duplex_keeps_the_source_and_its_global_ids(duplex):
    src = ifcopenshell.open(str(DUPLEX))
    for cls in ("IfcProject", "IfcSite", "IfcBuilding", "IfcBuildingStorey"):
        assert [e.GlobalId for e in duplex.by_type(cls)] == [e.GlobalId for e in src.by_type(cls)]
    kept = {e.GlobalId for e in duplex.by_type("IfcRoot")}
    assert {e.GlobalId for e in src.by_type("IfcRoot")} <= kept
    assert len(duplex.by_type("IfcWallStandardCase")) == len(src.by_type("IfcWallStandardCase"))


def test_duplex_ifc2x3_type_and_property_set(duplex):
    el = cameras_of(duplex)[0]
    typ = element.get_type(el)
    assert typ.is_a("IfcElectricApplianceType") and typ.PredefinedType == "USERDEFINED"
    assert typ.ElementType == "CAMERA" and typ.Name == "bullet"
    assert {element.get_type(e).Name for e in cameras_of(duplex)} == {"bullet", "dome"}
    assert len(duplex.by_type("IfcElectricApplianceType")) == 2  # one type per camera type
    p = element.get_psets(el)[PSET]
    assert (p["CamplaceId"], p["CameraType"], p["Model"], p["CandidateId"]) == ("C1", "bullet", "ACME D4", 100)
    assert (p["FocalLength_mm"], p["Pitch_deg"], p["DORI_Detect_m"], p["DORI_Identify_m"]) == (4.0, 30.0, 40.0, 4.0)
    assert "FocalLength_mm" not in element.get_psets(cameras_of(duplex)[1])[PSET]


def test_duplex_body_and_frustum_in_world(duplex):
    """The body surrounds the camera; the frustum reaches its range (40 m: the farthest DORI)
    along the viewing direction, the rotation's third column."""
    import ifcopenshell.geom

    settings_ = ifcopenshell.geom.settings()
    settings_.set("use-world-coords", True)
    el, cam = cameras_of(duplex)[0], DUPLEX_CAMERAS[0]
    v = np.array(ifcopenshell.geom.create_shape(settings_, el).geometry.verts).reshape(-1, 3)
    d = v - cam["position"]
    forward = d @ np.asarray(cam["rotation"])[:, 2]
    assert np.isclose(np.linalg.norm(d, axis=1).max(), 40.0, atol=1e-6)  # corners 40 m along their rays
    corner = np.array([960.0 / 1400.0, 540.0 / 1400.0, 1.0])  # the corner ray (W / 2 / fx, H / 2 / fy, 1)
    assert np.isclose(forward.max(), 40.0 / np.linalg.norm(corner), atol=1e-6)
    assert forward.min() == pytest.approx(-0.18, abs=1e-6)  # the body's back face


def test_mm_model_gets_mm_coordinates(tmp_path):
    cams = [camera(0, "Level 1", [-10.0, 0.5, 2.5]), camera(1, "Level 2", [5.0, -1.0, 6.5])]
    model = ifcopenshell.open(str(write_cameras_ifc(tmp_path / "c.ifc", cams, [], WHALE)))
    assert ifcopenshell.util.unit.calculate_unit_scale(model) == 0.001
    assert_round_trip(model, cams)
    world = placement.get_local_placement(cameras_of(model)[1].ObjectPlacement)
    assert np.allclose(world[:3, 3], [5000.0, -1000.0, 6500.0])
    rel = cameras_of(model)[1].ObjectPlacement.RelativePlacement.Location.Coordinates
    assert np.allclose(rel, [5000.0, -1000.0, 2500.0])  # relative to Level 2's placement at z = 4000 mm


def test_site_moved_and_turned(tmp_path):
    """Poses are world (the model's own x, y, z) whatever the site's placement: here moved by
    (100, 50, 2) m and turned 30° about z, so the storeys' world placements turn too."""
    model = ifcopenshell.open(str(DUPLEX))
    site = model.by_type("IfcSite")[0].ObjectPlacement.RelativePlacement
    a = np.radians(30.0)
    site.Location = model.createIfcCartesianPoint((100.0, 50.0, 2.0))
    site.RefDirection = model.createIfcDirection((float(np.cos(a)), float(np.sin(a)), 0.0))
    site.Axis = model.createIfcDirection((0.0, 0.0, 1.0))
    moved = tmp_path / "moved.ifc"
    model.write(str(moved))
    cams = [camera(0, "Level 1", [101.0, 52.0, 4.6]), camera(1, "Level 2", [98.0, 57.0, 7.7])]
    out = ifcopenshell.open(str(write_cameras_ifc(tmp_path / "c.ifc", cams, [], moved)))
    level_2 = placement.get_local_placement(element.get_container(cameras_of(out)[1]).ObjectPlacement)
    assert np.allclose(level_2[:3, 3], [100.0, 50.0, 5.1]) and np.isclose(level_2[1, 0], np.sin(a))
    assert_round_trip(out, cams)


def test_ifc4_copy_and_ifczip(tmp_path):
    """An IFC4 model without storeys (its building stands in, as in the importer), read zipped."""
    zipped = tmp_path / "pavilion.ifczip"
    with zipfile.ZipFile(zipped, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(PAVILION, PAVILION.name)
    cams = [camera(0, "Pabellon", [1.0, 2.0, 2.8]), camera(1, "Pabellon", [10.0, 4.0, 2.8])]
    model = ifcopenshell.open(str(write_cameras_ifc(tmp_path / "c.ifc", cams, [], zipped)))
    assert model.schema == "IFC4"
    assert_round_trip(model, cams)
    assert all(element.get_container(e).is_a("IfcBuilding") for e in cameras_of(model))
    typ = element.get_type(cameras_of(model)[0])
    assert typ.is_a("IfcAudioVisualApplianceType") and typ.PredefinedType == "CAMERA"
    assert typ.HasContext[0].RelatingContext == model.by_type("IfcProject")[0]  # declared in the project
    src = ifcopenshell.open(str(PAVILION))
    assert {e.GlobalId for e in src.by_type("IfcRoot")} <= {e.GlobalId for e in model.by_type("IfcRoot")}


def test_new_ifc4_model_with_storeys(tmp_path):
    storeys = [{"name": "plan-1", "elevation_m": 0.0}, {"name": "plan-2", "elevation_m": 3.5}]
    cams = [camera(0, "plan-1", [1.0, 1.0, 2.5]), camera(1, "plan-2", [2.0, 3.0, 6.0])]
    model = ifcopenshell.open(str(write_cameras_ifc(tmp_path / "c.ifc", cams, storeys, project="shop", frustum=True)))
    assert model.schema == "IFC4" and schema_errors(model) == []
    assert ifcopenshell.util.unit.calculate_unit_scale(model) == 1.0
    assert model.by_type("IfcProject")[0].Name == "shop"
    assert len(model.by_type("IfcSite")) == 1 and len(model.by_type("IfcBuilding")) == 1
    got = {s.Name: (s.Elevation, placement.get_local_placement(s.ObjectPlacement)[2, 3])
           for s in model.by_type("IfcBuildingStorey")}
    assert got == {"plan-1": (0.0, 0.0), "plan-2": (3.5, 3.5)}
    assert_round_trip(model, cams)


def test_bad_storey_is_one_line_naming_it(tmp_path):
    out = tmp_path / "c.ifc"
    with pytest.raises(InputError) as err:
        write_cameras_ifc(out, [camera(0, "Level 1", [1, 1, 2]), camera(1, "Level 9", [1, 1, 2])], [], DUPLEX)
    msg = str(err.value)
    assert "\n" not in msg and "cameras[1].storey" in msg and "'Level 9'" in msg and "'Level 2'" in msg
    assert not out.exists()
    with pytest.raises(InputError, match=r"cameras\[0\].storey: no storey named 'Level 1'"):
        write_cameras_ifc(out, [camera(0, "Level 1", [1, 1, 2])], [{"name": "plan-1", "elevation_m": 0.0}])
    assert not out.exists()


def test_bad_poses_and_storeys_are_refused(tmp_path):
    with pytest.raises(InputError, match=r"cameras\[0\]: expected a finite position and a rotation"):
        write_cameras_ifc(tmp_path / "c.ifc", [camera(0, "a", [0, 0, 1], rotation=2 * np.eye(3))],
                          [{"name": "a", "elevation_m": 0.0}])
    with pytest.raises(InputError, match=r"storeys\[0\]: expected"):
        write_cameras_ifc(tmp_path / "c.ifc", [camera(0, "a", [0, 0, 1])], [{"name": "a"}])
    with pytest.raises(InputError, match=r"storeys: expected unique names, got 'a', 'a'"):
        write_cameras_ifc(tmp_path / "c.ifc", [camera(0, "a", [0, 0, 1])], [{"name": "a", "elevation_m": 0.0}] * 2)
    assert not (tmp_path / "c.ifc").exists()


def test_frustum_of_a_hand_made_pinhole():
    """W = H = 2, fx = fy = 1, cx = cy = 0.5: the pixel edges -0.5 and 1.5 are 1 unit off
    axis at depth 1, so the corners lie on the rays (±1, ±1, 1); range 3 -> length 3."""
    cam = CameraModel.from_intrinsics("c", "pinhole", (2, 2), 1.0, 1.0, 0.5, 0.5)
    v, faces = frustum_mesh(cam, 3.0)
    assert np.allclose(v[0], 0.0)
    assert np.allclose(v[1:], np.array([[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]) * 3.0 / np.sqrt(3))
    assert signed_volume(v, faces) > 0


def signed_volume(v: np.ndarray, faces) -> float:
    f = np.asarray(faces)
    return float(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0)


@settings(max_examples=30, deadline=None)
@given(w=st.integers(64, 4000), h=st.integers(64, 3000), hfov=st.floats(10.0, 170.0), vfov=st.floats(10.0, 170.0),
       rng=st.floats(0.5, 80.0), fisheye=st.booleans())
def test_meshes_closed_and_outward_for_any_lens(w, h, hfov, vfov, rng, fisheye):
    """Every edge is shared by two faces in opposite directions and the volume is positive
    (outward faces), for pinholes and fisheyes up to 170° wide."""
    cam = CameraModel.from_fov("c", "fisheye" if fisheye else "pinhole", (w, h), (hfov, vfov))
    for v, faces in (body_mesh(), frustum_mesh(cam, rng)):
        edges = sorted((a, b) for f in faces for a, b in zip(f, f[1:] + f[:1]))
        assert edges == sorted((b, a) for a, b in edges)
        assert signed_volume(v, faces) > 0


def test_extras_from_a_camera_model():
    cam = CameraModel.pinhole_from_fov("c", (1920, 1080), (90.0, 60.0), max_range=30.0)
    got = ifc_camera_extras(cam)
    assert got["range_m"] == 30.0
    assert set(got["dori_m"]) == {"detect", "observe", "recognise", "identify"}
    # min(fx, fy) = fy = 540 / tan(30°) = 935.3 px: detect (25 px/m) at 37.4 m, beyond the range -> the range;
    # identify (250 px/m) at 3.741 m, found on dori_distances' 400 samples of the range (0.075 m apart)
    assert got["dori_m"]["detect"] == pytest.approx(30.0)
    identify = 540.0 / np.tan(np.radians(30.0)) / 250.0
    assert identify - 30.0 / 400 <= got["dori_m"]["identify"] <= identify
