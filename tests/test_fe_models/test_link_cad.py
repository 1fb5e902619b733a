"""CAD files of the parametric link (:mod:`ffrf.geometry.link_cad`): the STEP file is the solid the solver meshes,
in millimetres; the STL is closed, outward, and within its facet tolerance of the solid; bores sized for a pin."""

import math

import meshio
import numpy as np
import pytest

from ffrf.errors import GeometryError
from ffrf.geometry.link_cad import MM, bore_for_pin, segments_per_circle, write_link_cad
from ffrf.geometry.link_geometry import LinkDesign, build_link
from ffrf.geometry.meshing import gmsh_session
from ffrf.paper.axes import bennett_axes, paper_link_axes

TOLERANCE = 0.05e-3


@pytest.fixture(scope="module")
def base_link(tmp_path_factory):
    """The paper's base link (mount and two bores) written with 19 mm pins and 0.2 mm clearance."""
    first, second, names = paper_link_axes(0, bennett_axes(90.0))
    design = bore_for_pin(LinkDesign(), 19e-3, 0.2e-3)
    folder = tmp_path_factory.mktemp("cad")
    part = write_link_cad(folder, "link0", first, second, design, names, mount=True, tolerance=TOLERANCE)
    with gmsh_session("metres") as gmsh:  # the solver's own solid, in metres
        build_link(gmsh, first, second, design, names, mount=True)
        volume = gmsh.model.occ.getMass(3, gmsh.model.getEntities(3)[0][1])
    return part, volume


def _read_step_volume(path) -> float:
    with gmsh_session("read") as gmsh:
        solids = [tag for dim, tag in gmsh.model.occ.importShapes(str(path)) if dim == 3]
        gmsh.model.occ.synchronize()
        assert len(solids) == 1
        return gmsh.model.occ.getMass(3, solids[0])


def test_step_file_reads_back_as_the_solver_solid_in_millimetres(base_link):
    part, volume = base_link
    text = part.step.read_text()
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    read = _read_step_volume(part.step)  # OpenCASCADE reads STEP into millimetres
    assert read == pytest.approx(volume / MM**3, rel=1e-6)
    assert part.volume == pytest.approx(volume, rel=1e-6)


def test_step_keeps_the_bore_as_an_exact_cylinder(base_link):
    part, _ = base_link
    with gmsh_session("read") as gmsh:
        gmsh.model.occ.importShapes(str(part.step))
        gmsh.model.occ.synchronize()
        radii = []
        for _, tag in gmsh.model.getEntities(2):
            if gmsh.model.getType(2, tag) == "Cylinder":
                lo, hi = gmsh.model.getParametrizationBounds(2, tag)
                k = gmsh.model.getPrincipalCurvatures(tag, [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])])
                radii.append(1.0 / max(abs(k[0][0]), abs(k[1][0])))
    assert min(radii) == pytest.approx(9.5 + 0.2, rel=1e-9)  # 19 mm pin / 2 + 0.2 mm, in mm


def _stl(path):
    mesh = meshio.read(path)
    return np.asarray(mesh.points, dtype=float), mesh.cells_dict["triangle"]


def test_stl_is_closed_outward_and_within_its_facet_tolerance(base_link):
    part, volume = base_link
    points, triangles = _stl(part.stl)
    assert len(triangles) == part.triangles
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    directed = {tuple(e) for e in edges.tolist()}
    assert len(directed) == len(edges)  # no edge twice in one direction ...
    assert all((b, a) in directed for a, b in directed)  # ... and each once the other way: closed, consistent
    p0, p1, p2 = (points[triangles[:, k]] for k in range(3))
    stl_volume = np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6.0 * MM**3  # > 0: normals point outward
    assert 0.0 < part.facet_deviation <= TOLERANCE
    # every surface point moved by at most the facet deviation: the volumes differ by at most area x deviation
    assert abs(stl_volume - volume) <= part.area * part.facet_deviation
    assert abs(stl_volume - volume) > 1e-4 * volume  # the facets are chords: the STL is not the exact solid


def test_stl_coordinates_are_millimetres_of_the_link(base_link):
    part, _ = base_link
    points, _ = _stl(part.stl)
    lower, upper = points.min(axis=0) * MM, points.max(axis=0) * MM
    assert np.allclose(lower, part.bounding_box[0], atol=1e-6)
    assert np.allclose(upper, part.bounding_box[1], atol=1e-6)
    centre = part.geometry.housing_centers[1]  # a bore's vertices sit on its circle of 9.7 mm
    axis = part.geometry.axes[1].direction
    relative = points * MM - centre
    along = relative @ axis
    radial = np.linalg.norm(relative - np.outer(along, axis), axis=1)
    on_bore = (np.abs(along) < 0.5 * part.geometry.design.housing_length) & (radial < 9.8e-3)
    assert on_bore.sum() > 2 * segments_per_circle(TOLERANCE, 17e-3)
    assert np.allclose(radial[on_bore], 9.7e-3, atol=1e-8)


def test_segments_per_circle_is_the_fewest_within_the_tolerance():
    """Sagitta R (1 - cos(pi / n)) <= t for n segments, > t for n - 1 (module docstring)."""
    for tolerance, radius in ((0.05e-3, 17e-3), (0.01e-3, 9.5e-3), (0.6e-3, 17e-3)):
        n = segments_per_circle(tolerance, radius)
        assert radius * (1 - math.cos(math.pi / n)) <= tolerance < radius * (1 - math.cos(math.pi / (n - 1)))


@pytest.mark.parametrize(
    "pin, clearance, words",
    [
        (19e-3, -0.1e-3, "radial clearance -0.1 mm is negative: the pin would not fit its bore; give a clearance >= 0"),
        (32e-3, 0.1e-3, "needs a 32.2 mm bore, which leaves no wall in the 32 mm housing; give a pin smaller than"),
        (0.0, 0.1e-3, "pin diameter 0 mm must be > 0"),
    ],
)
def test_bad_pin_fits_are_refused_naming_the_fix(pin, clearance, words):
    with pytest.raises(GeometryError) as raised:
        bore_for_pin(LinkDesign(), pin, clearance)
    assert words in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_pin_fit_sets_only_the_bore():
    design = bore_for_pin(LinkDesign(), 12e-3, 0.15e-3)
    assert design.bore_radius == pytest.approx(6.15e-3)
    assert design == LinkDesign(bore_radius=design.bore_radius)
