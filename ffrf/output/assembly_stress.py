r"""Stress state of an assembled linkage: von Mises stress, strain energy and joint reactions per link.

After the static assembly (:func:`ffrf.scenes.assembly.assemble`: gravity, then the
misalignment of the variants ``pla1``/``pla2`` closed elastically by continuation) every link
carries the elastic displacement :math:`u = \Psi\zeta` in its body frame (Eq. (HCB-3),
``docs/formulation.md``). Per link this module reports

* the von Mises stress of each element, the largest of its four corner values
  (:meth:`ffrf.fe.fe_model.FEModel.vertex_strains`: constant in a P1 element, linear in a P2 one,
  so its extremes are at the corners), its largest value, the centroid of that element (body
  coordinates, which are the mesh's coordinates) and the nearest interface (bore or mounting
  face) with its distance;
* the strain energy :math:`\tfrac12 u^T K u = \tfrac12\zeta^T K_{red}\zeta`;
* the reactions of the joints on its bores from the multipliers: the first three rows of a
  :class:`~ffrf.system.joints.MarkerJoint` are the world force (N), the further rotation rows the
  moments about the joint's x and y axes (N m; Eq. (J2)), and a driven joint's last row the
  driving torque.

The pure functions take plain arrays; :func:`scene_assembly_stress`
adapts any built scene (:class:`ffrf.scenes.builder.Scene`: ``bodies[k].fe``, ``.reduction``, ``.interfaces``) and
:func:`write_assembly_vtu` writes the deformed assembly for ParaView. A body given by its matrices
(:class:`~ffrf.fe.external_model.ExternalFEModel`) has no elements and material of ours: it reports its strain
energy and reactions, no stresses (``None`` in the summary), and is left out of the ``.vtu``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.fe.fe_model import FEModel
from ffrf.mesh.tet_mesh import signed_volumes
from ffrf.reduction.component_modes_post import element_strains, von_mises_stress

__all__ = [
    "LinkStress",
    "AssemblyStress",
    "element_von_mises",
    "nodal_average",
    "nearest_feature",
    "link_stress",
    "strain_energy_only",
    "joint_reactions",
    "scene_assembly_stress",
    "write_assembly_vtu",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class LinkStress:
    """Stress state of one link (SI units); ``element_von_mises`` (Pa) per tetrahedron."""

    link: int
    max_von_mises_pa: float
    max_location_m: NDArray[np.float64]
    nearest_feature: str
    feature_distance_m: float
    strain_energy_j: float
    element_von_mises: NDArray[np.float64] = field(repr=False)
    reactions: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def has_stress(self) -> bool:
        """False for a body given by its matrices: no elements of ours, no stress."""
        return bool(np.isfinite(self.max_von_mises_pa))

    def as_dict(self) -> dict:
        """JSON-ready summary (no per-element arrays; ``None`` where a body from matrices has no stress)."""
        stress = self.has_stress
        out = {
            "link": self.link,
            "max_von_mises_pa": self.max_von_mises_pa if stress else None,
            "max_location_m": self.max_location_m.tolist() if stress else None,
            "nearest_feature": self.nearest_feature if stress else None,
            "feature_distance_m": self.feature_distance_m if stress else None,
            "strain_energy_j": self.strain_energy_j,
            "reactions": self.reactions,
        }
        if self.reactions:
            out["max_reaction_force_n"] = max(r["force_n"] for r in self.reactions.values())
            out["max_reaction_moment_nm"] = max(r["moment_nm"] for r in self.reactions.values())
        return out

    def line(self) -> str:
        """One line of text (MPa, mm, mJ), as the ``bennett`` command prints it."""
        where = (
            f"max von Mises {1e-6 * self.max_von_mises_pa:.3f} MPa at "
            f"({', '.join(f'{1e3 * x:.1f}' for x in self.max_location_m)}) mm, "
            f"{1e3 * self.feature_distance_m:.1f} mm from {self.nearest_feature}"
            if self.has_stress
            else "no stress (given by its matrices, no elements of ours)"
        )
        text = f"link {self.link}: {where}; strain energy {1e3 * self.strain_energy_j:.4g} mJ"
        if self.reactions:
            d = self.as_dict()
            text += (
                f"; largest joint reaction {d['max_reaction_force_n']:.3g} N, "
                f"{1e3 * d['max_reaction_moment_nm']:.3g} N mm"
            )
        return text


@dataclass(frozen=True, eq=False)
class AssemblyStress:
    """Stress state of every link at the assembled coordinates ``q``."""

    links: tuple[LinkStress, ...]
    q: NDArray[np.float64] = field(repr=False)

    def as_dict(self) -> dict:
        return {
            "links": [link.as_dict() for link in self.links],
            "max_von_mises_pa": max((link.max_von_mises_pa for link in self.links if link.has_stress), default=None),
            "strain_energy_j": sum(link.strain_energy_j for link in self.links),
        }


def element_von_mises(
    nodes: ArrayLike, tets: ArrayLike, displacement: ArrayLike, E: float, nu: float
) -> NDArray[np.float64]:
    """Von Mises stress (Pa) of each P1 tetrahedron for nodal ``displacement`` (N, 3)."""
    return von_mises_stress(element_strains(nodes, tets, displacement), E, nu)


def nodal_average(n_points: int, tets: ArrayLike, element_values: ArrayLike, volumes: ArrayLike) -> NDArray[np.float64]:
    """Volume-weighted average of element values at the vertices (for ParaView point data)."""
    tets = np.asarray(tets, dtype=np.int64)
    weights = np.repeat(np.abs(np.asarray(volumes, dtype=float))[:, None], 4, axis=1)
    total = np.bincount(tets.ravel(), weights.ravel(), minlength=n_points)
    summed = np.bincount(
        tets.ravel(), (weights * np.asarray(element_values, dtype=float)[:, None]).ravel(), minlength=n_points
    )
    return summed / np.where(total > 0.0, total, 1.0)


def nearest_feature(point: ArrayLike, features: Mapping[str, ArrayLike]) -> tuple[str, float]:
    """Name of the feature (node cloud, e.g. a bore's interface nodes) nearest to ``point``, and the distance."""
    point = np.asarray(point, dtype=float)
    distances = {
        name: float(np.min(np.linalg.norm(np.asarray(xyz, dtype=float) - point, axis=1)))
        for name, xyz in features.items()
    }
    name = min(distances, key=distances.__getitem__)
    return name, distances[name]


def link_stress(index: int, fe: FEModel, displacement: ArrayLike, features: Mapping[str, ArrayLike]) -> LinkStress:
    """Von Mises field, its maximum and where, and the strain energy of one link.

    ``fe`` the link's FE model, ``displacement`` (N, 3) elastic displacements of all its nodes
    (midside nodes included for P2) in the mesh axes, ``features``: name -> (k, 3) coordinates of
    the nodes of each interface (bores, mounting face).
    """
    u = np.asarray(displacement, dtype=float).reshape(-1)
    stress = von_mises_stress(fe.vertex_strains(u), fe.material.E, fe.material.nu).max(axis=1)
    worst = int(np.argmax(stress))
    centroid = fe.nodes[fe.mesh.tets[worst]].mean(axis=0)
    name, distance = nearest_feature(centroid, features)
    energy = 0.5 * float(u @ (fe.stiffness @ u))
    return LinkStress(index, float(stress[worst]), centroid, name, distance, energy, stress)


def strain_energy_only(index: int, stiffness, displacement: ArrayLike) -> LinkStress:
    """The strain energy 1/2 u^T K u of a body without elements of ours (given by its matrices); no stress."""
    u = np.asarray(displacement, dtype=float).reshape(-1)
    nan = float("nan")
    return LinkStress(index, nan, np.full(3, nan), "", nan, 0.5 * float(u @ (stiffness @ u)), np.zeros(0))


def joint_reactions(
    names: Sequence[str], sizes: Sequence[int], driven: Sequence[bool], multipliers: ArrayLike
) -> dict[str, dict[str, float]]:
    """Force (N) and moment (N m) magnitudes of joints whose multipliers follow one another.

    Rows per joint: three world forces, then rotation rows (Eq. (J2)); a driven joint's last row
    is its driving torque (Eq. (J3)), reported as ``torque_nm`` and left out of ``moment_nm``.
    """
    lam = np.asarray(multipliers, dtype=float)
    out, row = {}, 0
    for name, size, is_driven in zip(names, sizes, driven, strict=True):
        rows = lam[row : row + size]
        rotation = rows[3:-1] if is_driven else rows[3:]
        out[name] = {"force_n": float(np.linalg.norm(rows[:3])), "moment_nm": float(np.linalg.norm(rotation))}
        if is_driven:
            out[name]["torque_nm"] = float(rows[-1])
        row += size
    return out


def scene_assembly_stress(scene, q: ArrayLike, multipliers: ArrayLike | None = None) -> AssemblyStress:
    """:func:`link_stress` of every link of ``scene`` at coordinates ``q``; with ``multipliers``
    (ordered as ``scene.system.all_constraints``) also the reactions of the joints on each link."""
    from ffrf.system.joints import MarkerJoint

    q = np.asarray(q, dtype=float)
    system = scene.system
    reactions: dict[str, dict[str, float]] = {}
    bodies_of: dict[str, tuple[int, ...]] = {}
    if multipliers is not None:
        lam = np.asarray(multipliers, dtype=float)
        joints = [(k, c) for k, c in enumerate(system.all_constraints) if isinstance(c, MarkerJoint)]
        for k, joint in joints:
            reactions.update(
                joint_reactions(
                    [joint.name],
                    [joint.size],
                    [joint.angle is not None],
                    lam[int(system.rows[k]) : int(system.rows[k + 1])],
                )
            )
            bodies_of[joint.name] = tuple(joint.bodies)
    out = []
    for link in scene.bodies:
        zeta = q[system.block(link.index)][7:]
        features = {name: link.fe.nodes[itf.nodes] for name, itf in link.interfaces.items()}
        u = link.reduction.basis @ zeta
        fe = link.fe
        stress = (
            link_stress(link.index, fe, u, features)
            if isinstance(fe, FEModel)
            else strain_energy_only(link.index, fe.stiffness, u)
        )
        own = {name: r for name, r in reactions.items() if link.index in bodies_of[name]}
        out.append(
            LinkStress(
                stress.link,
                stress.max_von_mises_pa,
                stress.max_location_m,
                stress.nearest_feature,
                stress.feature_distance_m,
                stress.strain_energy_j,
                stress.element_von_mises,
                own,
            )
        )
    return AssemblyStress(tuple(out), q.copy())


def write_assembly_vtu(
    path: str | Path, scene, stress: AssemblyStress, modes: Mapping[str, NDArray] | None = None
) -> Path | None:
    """The deformed assembly as one ``.vtu``: all links' tetrahedra at their current positions, point data
    ``displacement`` (current minus reference, for "Warp By Vector"), ``elastic_displacement`` (world axes),
    ``von_mises`` (Pa, volume-weighted vertex average), ``body``; cell data ``von_mises`` (Pa). ``modes`` adds a
    point field per named coordinate vector (a mode of Eq. (B1)): the vertices' motion along it, to first order,
    scaled to a largest vertex motion of one. Bodies given by their matrices are left out (logged); ``None`` and
    no file when no body has elements of ours."""
    import meshio

    from ffrf.output.paraview import _frame_points  # one definition of a body's current vertex positions

    path = Path(path)
    pairs = list(zip(scene.bodies, stress.links, strict=True))
    meshed = [(link, result) for link, result in pairs if isinstance(link.fe, FEModel)]
    left_out = [link.name for link, _ in pairs if not isinstance(link.fe, FEModel)]
    if left_out:
        logger.warning(
            "%s: bodies %s are left out: given by their matrices, they have no elements of ours (build a body from "
            "a mesh to see its stresses)",
            path,
            left_out,
        )
    if not meshed:
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    points, elastic, reference, tets, nodal, body, offset = [], [], [], [], [], [], 0
    for link, link_result in meshed:
        fe = link.fe
        n = len(fe.mesh.points)
        current, world_elastic = _frame_points(fe, link.reduction.basis, stress.q[scene.system.block(link.index)])
        points.append(current)
        elastic.append(world_elastic)
        reference.append(fe.nodes[:n])
        tets.append(fe.mesh.tets + offset)
        nodal.append(
            nodal_average(n, fe.mesh.tets, link_result.element_von_mises, signed_volumes(fe.nodes[:n], fe.mesh.tets))
        )
        body.append(np.full(n, float(link.index)))
        offset += n
    points_all = np.vstack(points)
    mode_data = {name: _mode_motion(scene, meshed, stress.q, vector) for name, vector in (modes or {}).items()}
    meshio.write(
        path,
        meshio.Mesh(
            points_all,
            [("tetra", np.vstack(tets))],
            point_data={
                "displacement": points_all - np.vstack(reference),
                "elastic_displacement": np.vstack(elastic),
                "von_mises": np.concatenate(nodal),
                "body": np.concatenate(body),
                **mode_data,
            },
            cell_data={"von_mises": [np.concatenate([s.element_von_mises for _, s in meshed])]},
        ),
    )
    return path


def _mode_motion(scene, meshed: list, q: NDArray, mode: NDArray) -> NDArray[np.float64]:
    """Vertex motions of the meshed bodies along ``mode`` (central difference of their positions), scaled to a
    largest motion of one."""
    from ffrf.output.paraview import _frame_points

    step = 1e-6 / max(float(np.abs(mode).max()), 1e-300)
    motions = []
    for link, _ in meshed:
        block = scene.system.block(link.index)
        ahead = _frame_points(link.fe, link.reduction.basis, q[block] + step * mode[block])[0]
        behind = _frame_points(link.fe, link.reduction.basis, q[block] - step * mode[block])[0]
        motions.append((ahead - behind) / (2.0 * step))
    motion = np.vstack(motions)
    return motion / max(float(np.linalg.norm(motion, axis=1).max()), 1e-300)
