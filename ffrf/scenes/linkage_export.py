"""A linkage as parts to print, and back: every parametric link of a scene description as STEP and STL
(:func:`ffrf.geometry.link_cad.write_link_cad`, millimetres), its bores sized for a pin, an assembly STEP at the home
pose, a print sheet, and a scene file that runs the printed parts (``python -m ffrf export``).

:func:`export_linkage` writes into one folder

* ``link<k>.step``, ``link<k>.stl``: each link (mm), the same solid :func:`~ffrf.geometry.link_geometry.build_link`
  makes for the solver, with bores of radius ``pin_diameter / 2 + radial_clearance`` (default the design's bore);
* ``assembly.step``: every link at the home pose, where the solver meshes them (the links' CAD coordinates; a run
  starts from the bodies' ``pose``);
* ``print_sheet.json`` and ``print_sheet.md``: per link which bore sits on which joint axis, volume, mass in the
  engine's default material (:data:`ffrf.fe.materials.PLA`), bounding box and smallest wall. The smallest wall is
  taken from the design's dimensions (:func:`smallest_wall`), not measured on the solid;
* ``printed.toml``: the scene description with each parametric link replaced by its STL (``mesh = "link<k>.stl"``,
  ``unit = "mm"``, filled with tetrahedra of the link's own edge ``h``), the bores and the mount selected on the
  printed geometry (``cylinder`` and ``plane`` interfaces in place of the parametric link's named groups).
  ``python -m ffrf run printed.toml`` runs the printed parts as a scene; :func:`printed_linkage` puts them into the
  parametric :class:`~ffrf.scenes.linkage_scene.LinkageScene` for a linkage run (coupler deviation from the ideal
  path).

The solver's STL path keeps the STL's triangles (:func:`ffrf.geometry.meshing.mesh_stl`), so the printed parts are
meshed as finely as their facets: a finer ``tolerance`` makes a better print and a larger FE model (at 0.05 mm the
four links of a 4R, 140 to 250 mm long, outgrew 10 GB while being reduced; at 0.6 mm, the parametric links' own 12
segments per circle, they took about a minute): export for the printer, and coarser to simulate.
"""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

from ffrf.errors import SceneError
from ffrf.fe.materials import PLA, Material
from ffrf.geometry.link_cad import (
    MM,
    LinkPart,
    bore_for_pin,
    segments_per_circle,
    write_assembly_step,
    write_link_cad,
)
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.scenes.builder import Scene, parametric_link
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.scenes.scene_file import load_scene
from ffrf.scenes.scene_toml import scene_toml

__all__ = [
    "PRINTED_SCENE",
    "SMALLEST_WALL_RULE",
    "PrintSheet",
    "export_linkage",
    "printed_linkage",
    "smallest_wall",
]

#: The scene file of the printed parts in an export's folder.
PRINTED_SCENE = "printed.toml"
#: How the print sheet's smallest wall is found.
SMALLEST_WALL_RULE = (
    "from the design's dimensions, not measured on the solid: the smallest of the housing wall (outer radius - bore "
    "radius), the arm's width and thickness and, on the base, the mounting block's height"
)
#: Tolerance (m) of the printed parts' interface selections beyond the facets' deviation: the STL's single-precision
#: coordinates are exact to 1e-8 m at 0.1 m.
_SELECTION_TOLERANCE = 1e-5


def smallest_wall(design: LinkDesign, mount: bool) -> tuple[float, str]:
    """The thinnest wall of a link of ``design`` (m) and which one it is (:data:`SMALLEST_WALL_RULE`)."""
    walls = {
        "housing wall": design.housing_outer_radius - design.bore_radius,
        "arm width": design.arm_width,
        "arm thickness": design.arm_thickness,
    } | ({"mounting block": design.mount_height} if mount else {})
    which = min(walls, key=walls.__getitem__)
    return walls[which], which


@dataclass(frozen=True)
class PrintSheet:
    """What :func:`export_linkage` wrote: the parts, the joints each bore sits on, the bores' pin and clearance (m;
    ``None``: the design's own bore), the STL tolerance (m) and the material the masses are in."""

    parts: tuple[LinkPart, ...]
    seats: dict[str, dict[str, str]]  # link -> its bore (or mount face) -> the joint on it
    pin_diameter: float | None
    radial_clearance: float | None
    tolerance: float
    material: Material

    def rows(self) -> list[dict[str, Any]]:
        """One row per link, in mm, cm^3 and g."""
        rows = []
        for part in self.parts:
            g = part.geometry
            wall, which = smallest_wall(g.design, g.has_mount)
            bores = [
                {
                    "bore": name,
                    "joint": self.seats[part.name].get(name, ""),
                    "diameter_mm": 2 * g.design.bore_radius / MM,
                    "centre_mm": (center / MM).tolist(),
                    "axis": axis.direction.tolist(),
                }
                for name, axis, center in zip(g.interface_names, g.axes, g.housing_centers, strict=True)
            ]
            mount = None
            if g.has_mount and g.mount_center is not None and g.mount_normal is not None:
                mount = {
                    "joint": self.seats[part.name].get("mount", ""),
                    "centre_mm": (g.mount_center / MM).tolist(),
                    "normal": g.mount_normal.tolist(),
                }
            lower, upper = part.bounding_box / MM
            rows.append(
                {
                    "link": part.name,
                    "step": part.step.name,
                    "stl": part.stl.name,
                    "bores": bores,
                    "mount": mount,
                    "volume_cm3": part.volume / MM**3 * 1e-3,
                    "mass_g": 1e3 * self.material.rho * part.volume,
                    "bounding_box_mm": {
                        "lower": lower.tolist(),
                        "upper": upper.tolist(),
                        "size": (upper - lower).tolist(),
                    },
                    "smallest_wall_mm": wall / MM,
                    "smallest_wall": which,
                    "stl_triangles": part.triangles,
                    "stl_deviation_mm": part.facet_deviation / MM,
                }
            )
        return rows

    def as_dict(self) -> dict[str, Any]:
        """The sheet as JSON-ready data (``print_sheet.json``)."""
        return {
            "units": "mm in the STEP and STL files and in this sheet (volumes cm^3, masses g)",
            "material": {"name": self.material.name, "rho_kg_m3": self.material.rho},
            "pin_diameter_mm": None if self.pin_diameter is None else self.pin_diameter / MM,
            "radial_clearance_mm": None if self.radial_clearance is None else self.radial_clearance / MM,
            "stl_tolerance_mm": self.tolerance / MM,
            "smallest_wall_rule": SMALLEST_WALL_RULE,
            "assembly": "assembly.step",
            "scene": PRINTED_SCENE,
            "links": self.rows(),
        }

    def markdown(self) -> str:
        """The sheet as a Markdown table (``print_sheet.md``)."""
        fit = "the design's own bores"
        if self.pin_diameter is not None and self.radial_clearance is not None:
            pin, clearance = self.pin_diameter / MM, self.radial_clearance / MM
            fit = f"bores for a {pin:g} mm pin with {clearance:g} mm radial clearance"
        lines = [
            "# Print sheet",
            "",
            f"Files in mm; {fit}; STL facets within {self.tolerance / MM:g} mm of the exact surface; masses in "
            f"{self.material.name} ({self.material.rho:g} kg/m^3). Smallest wall: {SMALLEST_WALL_RULE}.",
            "",
            "| link | bore on joint axis | volume (cm^3) | mass (g) | bounding box (mm) | smallest wall (mm) |",
            "|---|---|---|---|---|---|",
        ]
        for row in self.rows():
            seats = [f"{b['bore']} (d = {b['diameter_mm']:.3f} mm) on {b['joint'] or '-'}" for b in row["bores"]]
            if row["mount"] is not None:
                seats.append(f"mount face on {row['mount']['joint'] or '-'}")
            size = " x ".join(f"{s:.1f}" for s in row["bounding_box_mm"]["size"])
            lines.append(
                f"| {row['link']} | {'; '.join(seats)} | {row['volume_cm3']:.2f} | {row['mass_g']:.1f} | {size} | "
                f"{row['smallest_wall_mm']:.2f} ({row['smallest_wall']}) |"
            )
        return "\n".join(lines) + "\n"


def _seats(description: dict) -> dict[str, dict[str, str]]:
    """Per body, which joint each of its interfaces sits on (the description's joints)."""
    seats: dict[str, dict[str, str]] = {}
    for joint in description.get("joints", []):
        for side in ("0", "1"):
            body, interface = joint.get(f"body{side}"), joint.get(f"interface{side}")
            if body not in (None, "ground") and interface is not None:
                seats.setdefault(body, {})[interface] = joint["name"]
    return seats


def _printed_interfaces(entry: dict, part: LinkPart) -> list[dict]:
    """The body's interfaces selected on the printed link: each bore a ``cylinder``, the mount face a ``plane``."""
    g = part.geometry
    bores = {
        name: {
            "point": center.tolist(),
            "direction": axis.direction.tolist(),
            "radius": g.design.bore_radius,
            "axial_extent": [-0.5 * g.design.housing_length, 0.5 * g.design.housing_length],
            # the solver's STL path puts nodes on the facets, which lie up to the facet deviation inside the bore
            "tolerance": part.facet_deviation + _SELECTION_TOLERANCE,
        }
        for name, axis, center in zip(g.interface_names, g.axes, g.housing_centers, strict=True)
    }
    printed = []
    for spec in entry["interfaces"]:
        group = spec.get("group")
        if group in bores:
            selection = {"cylinder": bores[group]}
        elif group == "mount" and g.mount_center is not None and g.mount_normal is not None:
            plane = {"point": g.mount_center.tolist(), "normal": g.mount_normal.tolist()}
            selection = {"plane": plane | {"tolerance": _SELECTION_TOLERANCE}}
        else:
            raise SceneError(
                f"body {entry['name']!r}, interface {spec['name']!r}: only the parametric link's own groups (its bores "
                "and mount) can be selected on the printed part"
            )
        printed.append({key: value for key, value in spec.items() if key != "group"} | selection)
    return printed


def export_linkage(
    description: dict,
    folder: str | Path,
    *,
    pin_diameter: float | None = None,
    radial_clearance: float | None = None,
    tolerance: float = 0.05e-3,
    material: Material = PLA,
) -> PrintSheet:
    """Write the parametric links of ``description`` (a scene description, e.g.
    :func:`~ffrf.scenes.linkage_description.linkage_description`) as the files of the module docstring into
    ``folder``. ``pin_diameter``, ``radial_clearance`` (m, both or neither): the bores' radius
    ``pin_diameter / 2 + radial_clearance`` (default the design's bore); ``tolerance``: the largest distance of an STL
    facet from the exact surface (m); ``material``: the print sheet's masses."""
    if (pin_diameter is None) != (radial_clearance is None):
        raise SceneError(
            "give the pin diameter and the radial clearance together (the bore radius is pin / 2 + clearance)"
        )
    bodies = description.get("bodies", [])
    if not bodies or any("parametric" not in body for body in bodies):
        other = [body.get("name") for body in bodies if "parametric" not in body]
        raise SceneError(
            f"export writes parametric links; bodies {other} are given by meshes or matrices, which are their own CAD"
            if other
            else "export: the description has no bodies"
        )
    links = [parametric_link(entry["parametric"], f"body {entry['name']!r}") for entry in bodies]
    if pin_diameter is not None and radial_clearance is not None:  # every bore checked before a file is written
        for link in links:
            link["design"] = bore_for_pin(link["design"], pin_diameter, radial_clearance)
    segments_per_circle(tolerance, max(link["design"].housing_outer_radius for link in links))
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SceneError(f"cannot write to {folder} ({error.strerror}); give a folder you can write to") from error
    printed = copy.deepcopy(description)
    parts = []
    for entry, body, link in zip(bodies, printed["bodies"], links, strict=True):
        h = float(entry["parametric"].get("h", 6e-3))
        part = write_link_cad(folder, entry["name"], **link, h=h, tolerance=tolerance)
        parts.append(part)
        rest = {key: value for key, value in body.items() if key not in ("name", "parametric", "interfaces")}
        body.clear()
        body.update(name=entry["name"], mesh=part.stl.name, unit="mm", h=h, **rest)
        body["interfaces"] = _printed_interfaces(entry, part)
    write_assembly_step(parts, folder / "assembly.step")
    settings = printed.setdefault("scene", {})
    settings["name"] = f"{settings.get('name', 'linkage')} (printed)"
    (folder / PRINTED_SCENE).write_text(scene_toml(printed))
    sheet = PrintSheet(tuple(parts), _seats(description), pin_diameter, radial_clearance, tolerance, material)
    (folder / "print_sheet.json").write_text(json.dumps(sheet.as_dict(), indent=1))
    (folder / "print_sheet.md").write_text(sheet.markdown())
    return sheet


def printed_linkage(linkage: LinkageScene, folder: str | Path) -> LinkageScene:
    """``linkage`` with its links replaced by the printed parts of an export of it (``folder/printed.toml``): the
    same loop, drive and ideal path, for a linkage run of the printed parts
    (:func:`ffrf.scenes.linkage_run.run_linkage`)."""
    scene = load_scene(Path(folder) / PRINTED_SCENE)
    if [b.name for b in scene.bodies] != [b.name for b in linkage.bodies]:
        raise SceneError(
            f"{folder}: the printed bodies {[b.name for b in scene.bodies]} are not the links of {linkage.name!r} "
            f"{[b.name for b in linkage.bodies]}; export this linkage again"
        )
    built = {f.name: getattr(scene, f.name) for f in fields(Scene) if f.name != "settings"}
    return replace(linkage, **built)
