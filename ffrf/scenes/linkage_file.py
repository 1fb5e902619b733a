r"""Linkage files: a single-loop linkage from its DH table, its joint axes or a Rational Linkages model.

A scene file with a ``[linkage]`` table describes a whole linkage in a few lines; the links, joints,
drive and sensors are generated (:func:`ffrf.scenes.linkage_description.linkage_description`), and
``python -m ffrf run FILE.toml --out DIR`` runs it as ``python -m ffrf bennett`` runs the paper's::

    [linkage]
    name = "my 6R"
    model = "collisions_free_6r"       # one source: a model of rational_linkages.models ...
    scale = 0.1                        #   its lengths times scale (the models are of unit size)
    design_points = false              #   true: links attached where the model's design attaches them
    # dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90], d = [0, 0, 0, 0],
    #       theta_deg = [0, 180, 0, 180]}                   # ... or a closed DH table (paper's convention)
    # axes = [{point = [0, 0, 0], direction = [0, 0, 1]}, ...]   # ... or the joint axes at home
    unit = "mm"                        # lengths of dh, axes and bore offsets (default m)
    driver = 0                         # the driven joint
    tool_link = 3                      # the coupler: its joint points' mean is the coupler point
    start_angle_deg = 0.0              # driver rotation from home at the start (default: a regular pose)
    material = {E = 1.2e9, nu = 0.33, rho = 450.0, name = "PLA", strength = 53e6}   # default PLA (strength: Pa,
                                       #   optional; the assembled links' peak stress is checked against it)
    h = 0.006                          # tetrahedron edge (m), order = 2, modes = 4
    drive = {rpm = 1.0, ramp_time = 1.0}
    revolutions = 1.0
    link_design = {arm_width = 16, arm_thickness = 12}   # the links' dimensions (in unit; LinkDesign)
    clearance_margin = 1.0             # what every two links keep along a revolution of the driver (in unit,
                                       #   default 1 mm): the run checks it (exit 3 if not met) unless
    # check_clearance = false          #   (a model that is not to be printed); and
    collision_free = true              # place the housings along the axes so that the links keep it
                                       #   (ffrf.scenes.collision_free.design_stacking), or give a designed set:
    # stacking = {offsets = [...], spacers = [...], orders = [1, -1, ...]}   # per joint, offsets and spacers in unit
    bore_errors = [{joint = 5, link = 0, twist_deg = 1.0, offset = 0.2, axial = 0.1}]   # as built (offset
                                       # along the normal, axial along the bore, in unit; tilt_deg and
                                       # shift about and along the binormal), or the measured
                                       # bore: {joint, link, point = [...], direction = [...], axial = ...}

    [scene]                            # gravity, beta, mode, outputs, step, rho_inf, joint_offsets, max_steps, ...

A DH table must close at its ``theta_deg`` (default the folded home pose 0, 180, 0, 180 of a 4R with
``d = 0``) and every source must give a *mobile* loop: one that does not move is refused with
:func:`kinematics.explain_mobility`'s reason (which condition fails, by how much). A model of Rational
Linkages starts at a regular pose of its motion polynomial (``t = 0``, else 1, -1, ...:
:func:`kinematics.rational_mechanism.regular_start`) unless ``start_angle_deg`` is given, since its home
pose ``t = infinity`` may be folded flat (singular).

Sizes are checked before anything is built (:mod:`ffrf.scenes.limits`): a run of more than 1e7 time steps or
equilibria (``revolutions``, ``step``) is refused with its estimated time unless ``[scene] max_steps`` lifts the
limit; link lengths outside 1 mm to 10 m, and two bore errors of one bore, are warned about.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ffrf.errors import GeometryError, SceneError
from ffrf.fe.materials import PLA, Material
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.scenes.collision_free import Stacking, design_stacking, designed_axial_gap
from ffrf.scenes.limits import length_unit_problem, linkage_run_steps, steps_problem
from ffrf.scenes.linkage_description import BoreError, LinkageOptions, start_pose
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.scene_schema import LINK_DESIGN, MATERIAL, PARAMETRIC_H_RANGE, SETTINGS, Key, check_table
from ffrf.scenes.schema_keys import between, nonzero_vector
from ffrf.system.drives import rpm
from kinematics import Line, LoopClosureError, LoopFoldError, SingleLoop, explain_mobility
from kinematics.rational_mechanism import (
    MODELS,
    attach_points,
    load_model,
    loop_from_mechanism,
    regular_start,
    tool_link,
)

__all__ = ["LINKAGE", "LINKAGE_SCHEMA", "linkage_options", "load_linkage"]


def _positive(value: Any) -> str | None:
    return None if value > 0 else f"must be > 0, got {value!r}"


def _non_negative(value: Any) -> str | None:
    return None if value >= 0 else f"must be >= 0, got {value!r}"


def _nonzero(value: Any) -> str | None:
    return None if value != 0 else "must not be 0"


def _modes(value: Any) -> str | None:
    return (
        None
        if value >= 1
        else f"must be >= 1, got {value!r}: the run chooses quasi-static or dynamic from each link's longest "
        "fixed-interface period, which a link without modes lacks"
    )


#: Largest bore-error twist (deg): a twist beyond half a turn is the same bore turned the other way.
MAX_BORE_TWIST_DEG = 180.0
#: Largest bore-error offset and axial shift (m): beyond, the bore lies outside any link of this solver.
MAX_BORE_SHIFT = 10.0


def _moving_link(value: Any) -> str | None:
    return None if value >= 1 else f"must be a moving link >= 1, got {value!r}"


def _element_size(value: Any) -> str | None:
    low, high = PARAMETRIC_H_RANGE
    return None if low <= value <= high else f"must lie in [{low:g}, {high:g}] m, got {value!r}"


def _model(value: Any) -> str | None:
    return None if value in MODELS else f"must be one of {list(MODELS)}, got {value!r}"


def _unit(value: Any) -> str | None:
    return None if value in ("m", "mm") else f"must be one of ['m', 'mm'], got {value!r}"


def _order(value: Any) -> str | None:
    return None if value in (1, 2) else f"must be 1 or 2, got {value!r}"


DH = {
    "a": Key("numbers", True),
    "alpha_deg": Key("numbers", True),
    "d": Key("numbers"),
    "theta_deg": Key("numbers"),
}
AXIS = {
    "point": Key("vector3", True),
    "direction": Key("vector3", True, nonzero_vector),
}
BORE_ERROR = {
    "joint": Key("integer", True, _non_negative),
    "link": Key("integer", True, _non_negative),
    "twist_deg": Key("number", False, between(-MAX_BORE_TWIST_DEG, MAX_BORE_TWIST_DEG, closed=True)),
    "offset": Key("number"),
    "axial": Key("number"),
    "tilt_deg": Key("number", False, between(-MAX_BORE_TWIST_DEG, MAX_BORE_TWIST_DEG, closed=True)),
    "shift": Key("number"),
    "point": Key("vector3"),
    "direction": Key("vector3", False, nonzero_vector),
}
STACKING = {
    "offsets": Key("numbers", True),
    "spacers": Key("numbers"),
    "orders": Key("numbers"),
}
DRIVE = {
    "rpm": Key("number", False, _nonzero),
    "omega": Key("number", False, _nonzero),
    "ramp_time": Key("number", False, _positive),
}
LINKAGE = {
    "name": Key("string"),
    "model": Key("string", False, _model),
    "scale": Key("number", False, _positive),
    "design_points": Key("boolean"),
    "dh": Key("table", keys=DH),
    "axes": Key("tables", keys=AXIS),
    "unit": Key("string", False, _unit),
    "driver": Key("integer", False, _non_negative),
    "tool_link": Key("integer", False, _moving_link),
    "start_angle_deg": Key("number", False, between(-360.0, 360.0, closed=True)),
    "material": Key("table", keys=MATERIAL),
    "h": Key("number", False, _element_size),
    "order": Key("integer", False, _order),
    "modes": Key("integer", False, _modes),
    "drive": Key("table", keys=DRIVE),
    "revolutions": Key("number", False, _positive),
    "bore_errors": Key("tables", keys=BORE_ERROR),
    "link_design": Key("table", keys=LINK_DESIGN),
    "collision_free": Key("boolean"),
    "clearance_margin": Key("number", False, _non_negative),
    "check_clearance": Key("boolean"),
    "stacking": Key("table", keys=STACKING),
}
#: A linkage file: ``[linkage]`` and optional ``[scene]`` settings (no bodies, joints or sensors of its own).
LINKAGE_SCHEMA = {"linkage": Key("table", True, keys=LINKAGE), "scene": Key("table", keys=SETTINGS)}


def _loop(spec: dict, where: str) -> tuple[SingleLoop, np.ndarray | None, int | None, Any]:
    """The loop of the one source, the start pose to trace from, the tool link and the mechanism (models)."""
    sources = [key for key in ("model", "dh", "axes") if key in spec]
    if len(sources) != 1:
        raise SceneError(
            f'{where}: give exactly one source: model = "name", dh = {{a, alpha_deg, ...}} or axes = [...], '
            f"got {sources or 'none'}"
        )
    if "scale" in spec and "model" not in spec:
        raise SceneError(f"{where}: 'scale' scales a model; give dh or axes lengths in 'unit' instead")
    if "design_points" in spec and "model" not in spec:
        raise SceneError(f"{where}: 'design_points' takes a model's own link design; dh and axes have none")
    if "unit" in spec and "model" in spec:
        raise SceneError(f"{where}: 'unit' is for dh and axes; a model is scaled by 'scale'")
    length = 1e-3 if spec.get("unit") == "mm" else 1.0
    if "model" in spec:
        mechanism = load_model(spec["model"])
        loop = loop_from_mechanism(mechanism, scale=spec.get("scale", 0.1))
        return loop, regular_start(mechanism, loop), tool_link(mechanism), mechanism
    if "axes" in spec:
        axes = spec["axes"]
        return (
            SingleLoop.from_points_directions(
                [length * np.asarray(a["point"]) for a in axes], [a["direction"] for a in axes]
            ),
            None,
            None,
            None,
        )
    dh = spec["dh"]
    n = len(dh["a"])
    for key in ("alpha_deg", "d", "theta_deg"):
        if key in dh and len(dh[key]) != n:
            raise SceneError(f"{where}, dh: {key!r} has {len(dh[key])} entries but a has {n}; give one per joint")
    theta = np.radians(dh["theta_deg"]) if "theta_deg" in dh else None
    d = length * np.asarray(dh["d"], dtype=float) if "d" in dh else None
    try:
        loop = SingleLoop.from_dh(length * np.asarray(dh["a"], dtype=float), np.radians(dh["alpha_deg"]), d, theta)
    except LoopClosureError as error:
        raise SceneError(
            f"{where}, dh: {error}; for an as-built loop that cannot close, give the nominal table and bore_errors"
        ) from error
    return loop, None, None, None


def _bore_error(entry: dict, length: float, where: str) -> BoreError:
    """A bore error of a linkage file: a twist, offset, tilt and shift, or the line the bore is on (point,
    direction)."""
    measured = "point" in entry or "direction" in entry
    if measured and ("point" not in entry or "direction" not in entry):
        raise SceneError(f"{where}: give both point and direction of the bore's axis")
    if measured and any(key in entry for key in ("twist_deg", "offset", "tilt_deg", "shift")):
        raise SceneError(
            f"{where}: give either twist_deg/offset/tilt_deg/shift or the bore's axis (point, direction), not both"
        )
    axis = Line.from_point_direction(length * np.asarray(entry["point"]), entry["direction"]) if measured else None
    twist, offset = math.radians(entry.get("twist_deg", 0.0)), length * entry.get("offset", 0.0)
    axial = length * entry.get("axial", 0.0)
    tilt, shift = math.radians(entry.get("tilt_deg", 0.0)), length * entry.get("shift", 0.0)
    for key, value in (("offset", offset), ("axial", axial), ("shift", shift)):
        if abs(value) > MAX_BORE_SHIFT:
            raise SceneError(
                f"{where}: {key!r} = {entry[key]!r} is {value:.3g} m, more than {MAX_BORE_SHIFT:g} m: no bore error; "
                "check the unit"
            )
    return BoreError(entry["joint"], entry["link"], twist, offset, axis, axial, tilt, shift)


def _warn_duplicate_bores(entries: list[dict], where: str) -> None:
    """Two bore errors of one bore add up (their twists, offsets and shifts); more likely a copy than meant."""
    seen: dict[tuple[int, int], int] = {}
    for k, entry in enumerate(entries):
        bore = (entry["joint"], entry["link"])
        if bore in seen:
            warnings.warn(
                f"{where}: bore_errors[{seen[bore]}] and bore_errors[{k}] both set the bore of joint {bore[0]} on "
                f"link {bore[1]}; their errors are added: give one entry per bore",
                UserWarning,
                stacklevel=3,
            )
        else:
            seen[bore] = k


def _warn_units(loop: SingleLoop, spec: dict, where: str) -> None:
    """Link lengths outside :data:`ffrf.scenes.limits.LINK_LENGTH_RANGE`: a unit mistake is likelier."""
    dh = loop.dh()
    given = (
        f"scale = {spec.get('scale', 0.1)!r}"
        if "model" in spec
        else f"unit = {spec.get('unit', 'm')!r} (the lengths of dh or axes)"
    )
    problem = length_unit_problem([*map(float, dh.a), *map(float, dh.d)], given)
    if problem is not None:
        warnings.warn(f"{where}: {problem}", UserWarning, stacklevel=3)


def _attach_points(
    spec: dict,
    loop: SingleLoop,
    driver: int,
    start: float,
    origin: np.ndarray | None,
    mechanism: Any,
    design: LinkDesign,
    length: float,
    where: str,
) -> np.ndarray | None:
    """Where the links attach on the axes: the model's design points, a given or designed stacking, or None."""
    chosen = [key for key in ("design_points", "collision_free", "stacking") if spec.get(key, False)]
    if len(chosen) > 1:
        raise SceneError(f"{where}: give one of design_points, collision_free and stacking, got {chosen}")
    if "clearance_margin" in spec and spec.get("check_clearance", True) is False and not spec.get("collision_free"):
        raise SceneError(
            f"{where}: 'clearance_margin' is the margin the run checks (and collision_free designs for), but "
            "check_clearance = false; drop one of them"
        )
    if spec.get("design_points", False):
        return attach_points(mechanism, spec.get("scale", 0.1))
    if "stacking" in spec:
        table = spec["stacking"]
        n = loop.n
        offsets = [length * v for v in table["offsets"]]
        spacers = [length * v for v in table.get("spacers", [0.0] * n)]
        orders = table.get("orders")
        if len(offsets) != n or len(spacers) != n or (orders is not None and len(orders) != n):
            raise SceneError(f"{where}, stacking: give one offset, spacer and order per joint ({n})")
        if min(spacers) < 0.0 or (orders is not None and any(o not in (1, -1) for o in orders)):
            raise SceneError(f"{where}, stacking: spacers must be >= 0 and orders 1 or -1")
        stacking = Stacking(tuple(offsets), tuple(spacers), None if orders is None else tuple(int(o) for o in orders))
        return stacking.attach_points(loop, design)
    if spec.get("collision_free", False):
        margin = length * spec.get("clearance_margin", 1.0e-3 / length)
        phi = start_pose(loop, driver, start, origin)
        shipped = None if mechanism is None else attach_points(mechanism, spec.get("scale", 0.1))
        starts = Stacking.starts_from_design(loop, shipped, design)  # a model's own design is one more start
        try:
            designed = design_stacking(loop, driver, phi, design, margin, starts=starts)
        except (GeometryError, ValueError) as error:
            raise SceneError(f"{where}, collision_free: {error}") from error
        return designed.stacking.attach_points(loop, design)
    return None


def load_linkage(document: dict, base: Path | None = None, where: str = "linkage") -> LinkageScene:
    """Check a linkage file (already parsed) and build its linkage (module docstring)."""
    del base  # a linkage file refers to no other file
    loop, options, run = linkage_options(document, where)
    try:
        scene = build_linkage(loop, options, where=f"{where}, linkage")
    except LoopFoldError as error:
        raise SceneError(f"{where}, linkage: the start pose cannot be reached: {error}") from error
    return replace(scene, settings=dict({k: v for k, v in scene.settings.items() if k != "mode"}, **run))


def linkage_options(document: dict, where: str = "linkage") -> tuple[SingleLoop, LinkageOptions, dict]:
    """Check a linkage file (already parsed) and return its nominal loop, the options it builds the linkage with
    and its run settings (``mode``, ``outputs``, ``step``, ``rho_inf``, ``stability`` where given; always
    ``clearance_margin``, m, and ``check_clearance``: what :meth:`ffrf.output.result.Result.add_clearance` judges)."""
    check_table(document, LINKAGE_SCHEMA, where)
    spec = document["linkage"]
    label = f"{where}, linkage"
    try:
        loop, origin, model_tool, mechanism = _loop(spec, label)
    except ValueError as error:  # SingleLoop's own checks (fewer than 4 axes, coinciding neighbours)
        if isinstance(error, SceneError):
            raise
        raise SceneError(f"{label}: {error}") from error
    n = loop.n
    driver = spec.get("driver", 0)
    if driver >= n:
        raise SceneError(f"{label}: driver {driver} does not exist; the loop has joints 0 to {n - 1}")
    mobility = explain_mobility(loop, driver, start=origin)
    if not mobility.mobile:
        raise SceneError(f"{label}: {mobility.summary()}; check the source (dh, axes) or its units")
    _warn_units(loop, spec, label)
    tool = spec.get("tool_link", model_tool)
    if tool is not None and tool >= n:
        raise SceneError(f"{label}: tool_link {tool} does not exist; the moving links are 1 to {n - 1}")
    length = 1e-3 if spec.get("unit") == "mm" else 1.0
    _warn_duplicate_bores(spec.get("bore_errors", []), label)
    errors = tuple(
        _bore_error(e, length, f"{label}, bore_errors[{k}]") for k, e in enumerate(spec.get("bore_errors", []))
    )
    for k, bore in enumerate(errors):
        carried = ((bore.link - 1) % n, bore.link)
        if bore.link >= n or bore.joint not in carried:
            raise SceneError(
                f"{label}, bore_errors[{k}]: link {bore.link} does not carry joint {bore.joint}; link k carries "
                f"joints k-1 and k (link 0 the joints {n - 1} and 0)"
            )
    drive = spec.get("drive", {})
    if ("rpm" in drive) and ("omega" in drive):
        raise SceneError(f"{label}, drive: give rpm (rev/min) or omega (rad/s), not both")
    omega = float(drive["omega"]) if "omega" in drive else rpm(float(drive.get("rpm", 1.0)))
    start = math.radians(spec["start_angle_deg"]) if "start_angle_deg" in spec else None
    if start is None:
        start = float(origin[driver]) if origin is not None else 0.0
    settings = document.get("scene", {})
    steps = linkage_run_steps(
        omega,
        drive.get("ramp_time", 1.0),
        spec.get("revolutions", 1.0),
        settings.get("mode", "auto"),
        settings.get("step"),
    )
    t_end = drive.get("ramp_time", 1.0) + 2.0 * math.pi * spec.get("revolutions", 1.0) / abs(omega)
    if settings.get("step", 0.0) > t_end:
        raise SceneError(
            f"{where}, scene: step = {settings['step']!r} s is longer than the run ({t_end:.4g} s: ramp and "
            "revolutions); give a shorter step"
        )
    problem = steps_problem(steps, settings.get("max_steps"), "max_steps = N in [scene]", " over the run")
    if problem is not None:
        raise SceneError(f"{label}: {problem}")
    material = Material(**spec["material"]) if "material" in spec else PLA
    dimensions = {key: length * value for key, value in spec.get("link_design", {}).items()}
    margin = length * spec.get("clearance_margin", 1.0e-3 / length)
    if spec.get("collision_free", False):  # links designed to keep the margin: an axial gap above it
        dimensions["axial_gap"] = designed_axial_gap(margin, dimensions.get("axial_gap"))
    try:
        design = LinkDesign(**dimensions)
    except GeometryError as error:
        raise SceneError(f"{label}, link_design: {error}") from error
    attach = _attach_points(spec, loop, driver, start, origin, mechanism, design, length, label)
    options = LinkageOptions(
        material=material,
        name=spec.get("name", settings.get("name", "linkage")),
        driver=driver,
        start_angle=start,
        origin=origin,
        h=spec.get("h", 6e-3),
        order=spec.get("order", 2),
        n_modes=spec.get("modes", 4),
        beta=settings.get("beta", 0.005),
        omega=omega,
        ramp_time=drive.get("ramp_time", 1.0),
        revolutions=spec.get("revolutions", 1.0),
        gravity=tuple(settings.get("gravity", (0.0, 0.0, -9.81))),
        bore_errors=errors,
        design=design,
        tool_link=tool,
        exact_gravity=settings.get("exact_gravity", True),
        joint_offsets=settings.get("joint_offsets", "body"),
        attach_points=attach,
        joint_play=settings.get("clearance"),
    )
    run = {key: settings[key] for key in ("mode", "outputs", "step", "rho_inf", "stability") if key in settings}
    run["clearance_margin"] = margin
    run["check_clearance"] = spec.get("check_clearance", True)
    return loop, options, run
