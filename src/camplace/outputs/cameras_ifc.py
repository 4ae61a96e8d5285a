"""cameras.ifc: the placed cameras written back into the BIM model (issue 33).

For an IFC input the file is a copy of the input model (project, site, building, storeys
and every other entity kept with its GlobalId) plus one camera element per camera,
contained in its storey; otherwise a new IFC4 model (metres) with a project, a site, a
building and the storeys at their elevations. The camera element is an IFC4
IfcAudioVisualAppliance (CAMERA) typed by an IfcAudioVisualApplianceType per camera type;
IFC2X3 has neither, so there it is an IfcFlowTerminal (ObjectType 'CAMERA') typed by an
IfcElectricApplianceType (USERDEFINED, ElementType 'CAMERA'). Each element's
IfcLocalPlacement is its pose: the local origin is the camera's position and the local
X, Y, Z axes are the camera's x (right), y (down), z (viewing direction), so its world
matrix (ifcopenshell.util.placement) is placement.json's position (in the model's length
unit) and rotation. See docs/output-contract.md (cameras.ifc).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camplace.cameras.models import CameraModel
from camplace.core.errors import InputError
from camplace.core.files import atomic_write_bytes
from camplace.outputs.cameras_ifc_shapes import body_mesh, camera_model, frustum_mesh, frustum_range, pose_matrix
from camplace.scene.importers.ifc_model import Storey, Structure, length_scale, open_model, structure
from camplace.visibility.viewshed import dori_distances

PSET = "camplace_Camera"  # not 'Pset_': that prefix is buildingSMART's own
ROTATION_TOL = 1e-6


def ifc_camera_extras(camera: CameraModel) -> dict:
    """The keys a camera entry may add for cameras.ifc, from its CameraModel (set to its
    focal length): ``dori_m`` (level -> m, camplace.visibility.viewshed.dori_distances) and
    ``range_m`` (its max_range, the frustum's length)."""
    return {"dori_m": dori_distances(camera), "range_m": float(camera.max_range)}


def write_cameras_ifc(path: Path, cameras: list[dict], storeys: list[dict], source_ifc: Path | None = None,
                      *, project: str = "camplace", frustum: bool = False) -> Path:
    """Write cameras.ifc to ``path`` and return it. ``cameras``: placement.json camera
    entries with ``storey`` (the storey's name, matched as the IFC importer names storeys),
    ``position`` (building x, y, z, m), ``rotation`` (3x3 world-from-camera, OpenCV axes),
    optional ``id``, ``model``, ``focal_mm``, ``dori_m``, ``range_m``; ``storeys``:
    [{"name", "elevation_m"}] (used when ``source_ifc`` is None); ``source_ifc``: the input
    model (.ifc or .ifczip), copied; ``frustum``: add each camera's viewing pyramid to its body."""
    poses = [_pose(i, c) for i, c in enumerate(cameras)]
    if source_ifc is not None:
        model = open_model(Path(source_ifc))
        where = structure(model, length_scale(model))
        label = str(source_ifc)
    else:
        model, where = _new_model(storeys, project)
        label = "the storeys given"
    containers = [_container(model, where, label, i, c) for i, c in enumerate(cameras)]
    body = _body_context(model)
    scale = length_scale(model)
    types: dict[str, object] = {}
    for cam, (pos, rot), storey in zip(cameras, poses, containers):
        _add_camera(model, cam, pose_matrix(pos, rot), storey, body, scale, types, frustum)
    return atomic_write_bytes(path, model.to_string().encode("utf-8"))


def _pose(i: int, cam: dict) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), rotation (3, 3)) of camera ``i``; InputError when malformed."""
    try:
        pos = np.asarray(cam["position"], float).reshape(3)
        rot = np.asarray(cam["rotation"], float).reshape(3, 3)
    except (KeyError, TypeError, ValueError):
        raise InputError(f"cameras[{i}]: expected 'position' [x, y, z] m and 'rotation' 3x3") from None
    if not (np.isfinite(pos).all() and np.allclose(rot.T @ rot, np.eye(3), atol=ROTATION_TOL)
            and np.linalg.det(rot) > 0):
        raise InputError(f"cameras[{i}]: expected a finite position and a rotation matrix (orthonormal, det +1)")
    return pos, rot


def _container(model, where: Structure, label: str, i: int, cam: dict):
    """The spatial element (storey, or the building standing in for one) of camera ``i``."""
    name = cam.get("storey")
    if not isinstance(name, str) or not name:
        raise InputError(f"cameras[{i}].storey: expected the name of a storey, got {name!r}")
    try:
        st = where.by_name(Path(label), name)
    except InputError:
        raise InputError(f"cameras[{i}].storey: no storey named '{name}' in {label}; its storeys are "
                         f"{', '.join(repr(s.name) for s in where.storeys)}") from None
    if st.key:
        return model.by_id(st.key)
    return _first_building(model)


def _first_building(model):
    """The model's first IfcBuilding (one made under its site or project when it has none)."""
    import ifcopenshell.api.aggregate
    import ifcopenshell.api.root

    got = model.by_type("IfcBuilding")
    if got:
        return got[0]
    parent = (model.by_type("IfcSite") or model.by_type("IfcProject"))[0]
    building = ifcopenshell.api.root.create_entity(model, ifc_class="IfcBuilding", name="building")
    ifcopenshell.api.aggregate.assign_object(model, products=[building], relating_object=parent)
    return building


def _new_model(storeys: list[dict], project: str):
    """(a new IFC4 model in metres with project, site, building and ``storeys``, its Structure)."""
    import ifcopenshell.api.aggregate
    import ifcopenshell.api.context
    import ifcopenshell.api.geometry
    import ifcopenshell.api.project
    import ifcopenshell.api.root
    import ifcopenshell.api.unit

    api = ifcopenshell.api
    model = api.project.create_file(version="IFC4")
    proj = api.root.create_entity(model, ifc_class="IfcProject", name=project)
    api.unit.assign_unit(model, units=[api.unit.add_si_unit(model, unit_type="LENGTHUNIT")])
    ctx = api.context.add_context(model, context_type="Model")
    api.context.add_context(model, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW",
                            parent=ctx)
    site = api.root.create_entity(model, ifc_class="IfcSite", name="site")
    building = api.root.create_entity(model, ifc_class="IfcBuilding", name="building")
    api.aggregate.assign_object(model, products=[site], relating_object=proj)
    api.aggregate.assign_object(model, products=[building], relating_object=site)
    api.geometry.edit_object_placement(model, product=site)
    api.geometry.edit_object_placement(model, product=building)
    names = [str(st.get("name")) if isinstance(st, dict) else "" for st in storeys]
    if len(set(names)) < len(names):
        raise InputError(f"storeys: expected unique names, got {', '.join(repr(n) for n in names)}")
    out = []
    for k, st in enumerate(storeys):
        try:
            name, z = str(st["name"]), float(st["elevation_m"])
        except (KeyError, TypeError, ValueError):
            raise InputError(f"storeys[{k}]: expected {{'name': str, 'elevation_m': float}}, got {st!r}") from None
        ent = api.root.create_entity(model, ifc_class="IfcBuildingStorey", name=name)
        ent.Elevation = z
        api.aggregate.assign_object(model, products=[ent], relating_object=building)
        m = np.eye(4)
        m[2, 3] = z
        api.geometry.edit_object_placement(model, product=ent, matrix=m)
        out.append(Storey(name, z, ent.id(), building.id()))
    return model, Structure(out, {}, False)


def _body_context(model):
    """The model's Model/Body/MODEL_VIEW subcontext (added under its 3D Model context when missing)."""
    import ifcopenshell.api.context
    import ifcopenshell.util.representation

    got = ifcopenshell.util.representation.get_context(model, "Model", "Body", "MODEL_VIEW")
    if got is not None:
        return got
    parent = ifcopenshell.util.representation.get_context(model, "Model")
    if parent is None:
        parent = ifcopenshell.api.context.add_context(model, context_type="Model")
    return ifcopenshell.api.context.add_context(model, context_type="Model", context_identifier="Body",
                                                target_view="MODEL_VIEW", parent=parent)


def _camera_type(model, name: str, types: dict):
    """The element type of camera type ``name`` (made once per name)."""
    import ifcopenshell.api.project
    import ifcopenshell.api.root

    if name not in types:
        if model.schema == "IFC2X3":
            t = ifcopenshell.api.root.create_entity(model, ifc_class="IfcElectricApplianceType",
                                                    predefined_type="USERDEFINED", name=name)
            t.ElementType = "CAMERA"
        else:  # declared in the project (IfcRelDeclares, IFC4), as authoring tools keep their types
            t = ifcopenshell.api.root.create_entity(model, ifc_class="IfcAudioVisualApplianceType",
                                                    predefined_type="CAMERA", name=name)
            ifcopenshell.api.project.assign_declaration(model, definitions=[t],
                                                        relating_context=model.by_type("IfcProject")[0])
        types[name] = t
    return types[name]


def _add_camera(model, cam: dict, matrix: np.ndarray, storey, body, scale: float, types: dict,
                frustum: bool) -> None:
    """One camera element: contained in ``storey``, placed at ``matrix`` (4x4, m), typed,
    with its body (and frustum) and its property set."""
    import ifcopenshell.api.geometry
    import ifcopenshell.api.root
    import ifcopenshell.api.spatial
    import ifcopenshell.api.type

    api = ifcopenshell.api
    name = _camera_name(cam)
    ifc2x3 = model.schema == "IFC2X3"
    el = api.root.create_entity(model, ifc_class="IfcFlowTerminal" if ifc2x3 else "IfcAudioVisualAppliance", name=name)
    el.Description = "camplace camera"
    el.Tag = name
    api.spatial.assign_container(model, products=[el], relating_structure=storey)
    api.type.assign_type(model, related_objects=[el], relating_type=_camera_type(model, str(cam.get("camera", "camera")),
                                                                                    types), should_map_representations=False)
    if ifc2x3:  # set after assign_type, which clears an occurrence's own type words
        el.ObjectType = "CAMERA"
    else:
        el.PredefinedType = "CAMERA"
    api.geometry.edit_object_placement(model, product=el, matrix=matrix.copy(), is_si=True)
    meshes = [body_mesh()]
    if frustum:
        meshes.append(frustum_mesh(camera_model(cam), frustum_range(cam)))
    reps = [api.geometry.add_mesh_representation(model, context=body, vertices=[v.tolist()], faces=[f],
                                                 unit_scale=scale) for v, f in meshes]  # one call per item:
    rep = reps[0]  # ifcopenshell 0.9 cannot stack items of different vertex counts
    for other in reps[1:]:
        rep.Items = tuple(rep.Items) + tuple(other.Items)
        model.remove(other)
    api.geometry.assign_representation(model, product=el, representation=rep)
    _add_pset(model, el, cam)


def _camera_name(cam: dict) -> str:
    """The element's Name: the camera's ``id``, else 'candidate N'."""
    if cam.get("id") not in (None, ""):
        return str(cam["id"])
    if cam.get("candidate_id") is not None:
        return f"candidate {cam['candidate_id']}"
    return "camera"


def _add_pset(model, el, cam: dict) -> None:
    """The camplace_Camera property set: id, type, model, focal length, yaw/pitch/roll (deg),
    DORI distances (m), resolution (px) — those the entry has."""
    import ifcopenshell.api.pset

    props: dict[str, object] = {"CamplaceId": _camera_name(cam), "CameraType": str(cam.get("camera", ""))}
    if cam.get("model"):
        props["Model"] = str(cam["model"])
    if cam.get("candidate_id") is not None:
        props["CandidateId"] = int(cam["candidate_id"])
    for key, prop in (("focal_mm", "FocalLength_mm"), ("yaw_deg", "Yaw_deg"), ("pitch_deg", "Pitch_deg"),
                      ("roll_deg", "Roll_deg"), ("range_m", "Range_m")):
        if cam.get(key) is not None:
            props[prop] = float(cam[key])
    for level, d in (cam.get("dori_m") or {}).items():
        props[f"DORI_{level.capitalize()}_m"] = float(d)
    k = cam.get("intrinsics") or {}
    if "width" in k and "height" in k:
        props["Resolution_px"] = f"{int(k['width'])}x{int(k['height'])}"
    if "existing" in cam:
        props["Existing"] = bool(cam["existing"])
    pset = ifcopenshell.api.pset.add_pset(model, product=el, name=PSET)
    ifcopenshell.api.pset.edit_pset(model, pset=pset, properties=props)
