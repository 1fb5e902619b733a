"""The vendored input files of Exudyn's TestModels, read by ``ffrf.fe.matrix_import``.

Truth: Exudyn 1.13.6's own ``FEMinterface`` on the same files (nodes, elements, M, K, node sets and
surface weights), the git blob ids of the files in Exudyn's repository, and physics that uses
neither reader: the mass equals density x volume (density from the ``*Density`` line, volume
from the element geometry), the rigid-body motions carry no strain energy, and a point mass adds
exactly its value.
"""

from __future__ import annotations

import hashlib
import lzma
import re
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse.linalg import norm as sparse_norm

from ffrf.errors import InterfaceError
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.fe.matrix_import import abaqus_model, read_npz_model, write_npz_model
from ffrf.fe.node_selection import node_at_point, nodes_in_box, nodes_in_plane, surface_area_weights, surface_triangles

DATA = Path(__file__).parents[2] / "validation" / "data" / "exudyn_testmodels"
BLOCKS = ("C3D4", "C3D10", "C3D8", "C3D20", "C3D20R")
#: name -> (input file, mass file, stiffness file, instance)
MODELS = {
    "rotor": ("rotorDiscTest.inp", "rotorDiscTestMASS1.mtx.xz", "rotorDiscTestSTIF1.mtx.xz", "rotor-1"),
} | {
    kind: (f"abaqus/block{kind}.inp", f"abaqus/block{kind}_MASS1.mtx.xz", f"abaqus/block{kind}_STIF1.mtx.xz", "block-1")
    for kind in BLOCKS
}


@cache
def ours(name: str) -> ExternalFEModel:
    inp, mass, stiffness, instance = MODELS[name]
    return abaqus_model(DATA / inp, DATA / mass, DATA / stiffness, instance)


@cache
def exudyns(name: str):
    from exudyn.FEM import FEMinterface

    inp, mass, stiffness, instance = MODELS[name]
    fem = FEMinterface()
    fem.ImportFromAbaqusInputFile(str(DATA / inp), typeName="Instance", name=instance)
    fem.ReadMassMatrixFromAbaqus(str(DATA / mass))  # numpy.loadtxt decompresses .xz itself
    fem.ReadStiffnessMatrixFromAbaqus(str(DATA / stiffness))
    return fem


def _density(inp: Path) -> float:
    """The number on the line after ``*Density`` (read here, not by the reader under test)."""
    lines = inp.read_text().splitlines()
    return float(lines[[line.strip().lower() for line in lines].index("*density") + 1].split(",")[0])


def _volume(nodes: np.ndarray, elements: dict[str, np.ndarray]) -> float:
    """Volume from the corner nodes: tetrahedra |det|/6; hexahedra by 2x2x2 Gauss quadrature of
    det J of the trilinear map (exact: det J is quadratic in each coordinate). The files' elements
    have straight edges, so the corners fix the geometry."""
    total = 0.0
    for kind, table in elements.items():
        if kind.startswith("Tet"):
            p = nodes[table[:, :4]]
            total += np.abs(np.linalg.det(p[:, 1:] - p[:, :1])).sum() / 6.0
        else:
            corners = nodes[table[:, :8]]  # Abaqus order: bottom face 0-3, top face 4-7
            signs = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1]])
            signs = np.vstack([signs, [-1, 1, 1]])
            g = 1.0 / np.sqrt(3.0)
            for xi in np.array(np.meshgrid([-g, g], [-g, g], [-g, g])).reshape(3, -1).T:
                # dN_k/dxi_a = s_ka prod_{b != a} (1 + s_kb xi_b) / 8
                shape_gradients = np.empty((8, 3))
                for a in range(3):
                    others = [b for b in range(3) if b != a]
                    shape_gradients[:, a] = signs[:, a] * np.prod(1.0 + signs[:, others] * xi[others], axis=1) / 8.0
                jacobian = np.einsum("eki,ka->eia", corners, shape_gradients)
                total += np.abs(np.linalg.det(jacobian)).sum()  # Gauss weights are 1
    return float(total)


def _blob_ids() -> dict[str, str]:
    rows = re.findall(
        r"^\| `([^`]+)` \| `[^`]+` \| \d+ \| \d+ \| `([0-9a-f]{40})` \|$", (DATA / "README.md").read_text(), re.M
    )
    return dict(rows)


# ---------------------------------------------------------------------------------------------


def test_vendored_files_are_exudyns_bytes():
    """Every file in the folder is listed in its README, and decompressed it has the git blob id of
    the file in Exudyn's repository."""
    ids = _blob_ids()
    files = sorted(str(p.relative_to(DATA)) for p in DATA.rglob("*") if p.is_file() and p.name != "README.md")
    assert files == sorted(ids)
    for name, blob in ids.items():
        raw = (DATA / name).read_bytes()
        content = lzma.decompress(raw) if name.endswith(".xz") else raw
        assert hashlib.sha1(b"blob %d\0" % len(content) + content).hexdigest() == blob, name


@pytest.mark.parametrize("name", MODELS)
def test_nodes_elements_and_matrices_equal_exudyns(name):
    model, fem = ours(name), exudyns(name)
    np.testing.assert_array_equal(model.nodes, fem.GetNodePositionsAsArray())
    exudyn_elements = {k: np.asarray(v) for k, v in fem.elements[0].items() if k != "Name"}
    assert model.elements.keys() == exudyn_elements.keys()
    for kind, table in model.elements.items():
        np.testing.assert_array_equal(table, exudyn_elements[kind])
    for label, theirs in (("mass", fem.GetMassMatrix()), ("stiffness", fem.GetStiffnessMatrix())):
        mine = getattr(model, label)
        assert mine.shape == theirs.shape
        # Measured: identical (0.0); both parse the same decimal strings.
        assert abs(mine - theirs).max() <= 1e-15 * abs(theirs).max(), label


@pytest.mark.parametrize("name", MODELS)
def test_total_mass_is_density_times_volume(name):
    """Measured: agreement to 1.5e-14 (C3D20) or better; the blocks are 4 m x 1 m x 1 m of density
    2900 (11600 kg), the rotor 0.00993 m^3 of steel (77.97 kg)."""
    model = ours(name)
    inp = DATA / MODELS[name][0]
    expected = _density(inp) * _volume(model.nodes, model.elements)
    if name != "rotor":
        assert expected == pytest.approx(11600.0, rel=1e-13)  # the volume routine itself, on the box
    assert model.total_mass == pytest.approx(expected, rel=2e-12)
    rigid = rigid_body_modes(model.nodes)
    translations = rigid[:, :3].T @ (model.mass @ rigid[:, :3])
    # Measured: m I3 to 8e-16 relative.
    np.testing.assert_allclose(translations, model.total_mass * np.eye(3), rtol=0, atol=1e-13 * model.total_mass)


@pytest.mark.parametrize("name", MODELS)
def test_rigid_body_motions_carry_no_strain_energy(name):
    """|K r| against |K| |r| for the six rigid motions. Measured: at most 1.7e-16; moving one node
    off a rigid rotation (not a rigid motion) gives 0.015 to 0.11, so the check can fail."""
    model = ours(name)
    rigid = rigid_body_modes(model.nodes)
    norm = sparse_norm(model.stiffness, 1)
    assert np.abs(model.stiffness @ rigid).max() / (norm * np.abs(rigid).max()) < 2e-14
    broken = rigid[:, 3].copy()
    broken[:3] += 1.0  # one node moved: not a rigid motion, so the same check must fail
    assert np.abs(model.stiffness @ broken).max() / (norm * np.abs(broken).max()) > 1e-3


def test_point_mass_adds_exactly_its_value_as_exudyns_add_node_mass():
    """objectFFRFreducedOrderTest.py: 0.1 kg at the disc node (0, 0.19598444, 0.15), stiffness x 0.01.
    Measured: the total mass grows by 0.1 kg to 6e-14 relative (the round-off of 78 kg), the first
    moment by 0.1 kg x the node's position to 3e-15 kg m."""
    model, fem = ours("rotor"), exudyns("rotor")
    node = node_at_point(model.nodes, [0.0, 0.19598444, 0.15])
    assert node == fem.GetNodeAtPoint(point=[0.0, 0.19598444, 0.15])
    loaded = model.with_node_mass(node, 0.1).with_scaled_stiffness(1e-2)
    assert loaded.total_mass - model.total_mass == pytest.approx(0.1, rel=5e-12)
    centre = rigid_body_modes(model.nodes, np.zeros(3))[:, :3].T @ (loaded.mass @ loaded.nodes.reshape(-1))
    before = rigid_body_modes(model.nodes, np.zeros(3))[:, :3].T @ (model.mass @ model.nodes.reshape(-1))
    np.testing.assert_allclose(centre - before, 0.1 * model.nodes[node], rtol=0, atol=3e-13)
    np.testing.assert_array_equal(model.mass.toarray(), ours("rotor").mass.toarray())  # the original is unchanged

    from exudyn.FEM import FEMinterface

    twin = FEMinterface()
    twin.SetWithDictionary(fem.GetDictionary())
    twin.AddNodeMass(node, 0.1)
    twin.ScaleStiffnessMatrix(1e-2)
    assert abs(loaded.mass - twin.GetMassMatrix()).max() == 0.0
    assert abs(loaded.stiffness - twin.GetStiffnessMatrix()).max() <= 1e-15 * abs(loaded.stiffness).max()


@pytest.mark.parametrize("name", MODELS)
def test_node_sets_and_surface_weights_equal_exudyns(name):
    """The selections of the test models: the planes z = 0 (rotor) and x = 0 (blocks), area weights.
    Measured: weights equal to 2.8e-17."""
    model, fem = ours(name), exudyns(name)
    point, normal = ([0, 0, 0], [0, 0, 1]) if name == "rotor" else ([0, 0, 0], [-1, 0, 0])
    selected = nodes_in_plane(model.nodes, point, normal)
    np.testing.assert_array_equal(selected, fem.GetNodesInPlane(point, normal))
    triangles = surface_triangles(model.elements)
    assert {tuple(t) for t in triangles.tolist()} == {tuple(t) for t in fem.GetSurfaceTriangles()}
    weights = surface_area_weights(model.nodes, triangles, selected)
    np.testing.assert_allclose(weights, fem.GetNodeWeightsFromSurfaceAreas(list(selected)), rtol=0, atol=3e-15)
    if name != "rotor":  # the end face of the block, 1 m x 1 m
        raw = surface_area_weights(model.nodes, triangles, selected, normalize=False)
        assert raw.sum() == pytest.approx(1.0, rel=1e-14)  # measured 1.1e-16
    corner = model.nodes[triangles[0, 0]]
    assert node_at_point(model.nodes, corner + 1e-6) == fem.GetNodeAtPoint(list(corner + 1e-6))


@pytest.mark.parametrize("name", MODELS)
def test_nodes_in_box_equal_exudyns_get_nodes_in_cube(name):
    """A box around a corner region and a flat box on a face (bounds included, as ``GetNodesInCube``)."""
    model, fem = ours(name), exudyns(name)
    low, high = model.nodes.min(axis=0), model.nodes.max(axis=0)
    for lower, upper in ((low, low + 0.3 * (high - low)), (low - 1e-3, np.r_[high[:2], low[2]] + 1e-3)):
        selected = nodes_in_box(model.nodes, lower, upper)
        np.testing.assert_array_equal(selected, fem.GetNodesInCube(list(lower), list(upper)))
        assert np.all((model.nodes[selected] >= lower) & (model.nodes[selected] <= upper))
    with pytest.raises(InterfaceError, match="no node in the box"):
        nodes_in_box(model.nodes, high + 1.0, high + 2.0)


def test_netgen_pickle_converts_to_an_npz_model(tmp_path):
    """NGsolveCMStest.py's mesh (Exudyn pickle, read by Exudyn) through our .npz format and back:
    the same arrays; and its physics: a 1 m x 0.2 m x 0.2 m beam of density 1000 weighs 40 kg
    (measured to 2e-16), its end-face weights are Exudyn's (to 6e-17)."""
    from exudyn.FEM import FEMinterface

    ids = _blob_ids()
    raw = (DATA / "netgenTestMesh.pkl").read_bytes()
    assert hashlib.sha1(b"blob %d\0" % len(raw) + raw).hexdigest() == ids["netgenTestMesh.pkl"]  # before unpickling
    fem = FEMinterface()
    fem.LoadFromFile(str(DATA / "netgenTestMesh"), mode="PKL")
    elements = {k: np.asarray(v) for k, v in fem.elements[0].items() if k != "Name"}
    model = ExternalFEModel(
        fem.GetNodePositionsAsArray(), fem.GetMassMatrix(), fem.GetStiffnessMatrix(), elements, "netgenTestMesh"
    )
    back = read_npz_model(write_npz_model(tmp_path / "netgen.npz", model))
    np.testing.assert_array_equal(back.nodes, model.nodes)
    assert abs(back.mass - model.mass).max() == 0.0 and abs(back.stiffness - model.stiffness).max() == 0.0
    np.testing.assert_array_equal(back.elements["Tet4"], model.elements["Tet4"])
    assert back.name == "netgenTestMesh"
    assert model.total_mass == pytest.approx(1000.0 * _volume(model.nodes, model.elements), rel=2e-14)
    assert model.total_mass == pytest.approx(40.0, rel=2e-14)
    weights = surface_area_weights(
        model.nodes, surface_triangles(model.elements), nodes_in_plane(model.nodes, [0, -0.1, -0.1], [-1, 0, 0])
    )
    selected = fem.GetNodesInPlane([0, -0.1, -0.1], [-1, 0, 0])
    np.testing.assert_allclose(weights, fem.GetNodeWeightsFromSurfaceAreas(selected), rtol=0, atol=6e-15)
