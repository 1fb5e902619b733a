"""File formats of ``ffrf.fe.matrix_import`` on files written here from known matrices.

The truth is the matrix that was written: Matrix Market files by scipy's own ``mmwrite`` (full and
symmetric storage, gzip), Abaqus ``FORMAT=COORDINATE`` files line by line (full, one triangle,
entries split over two lines, compressed), ``.npz`` files in both documented matrix forms.
The Abaqus files of Exudyn's test models are in ``test_exudyn_testmodel_data.py``.
"""

from __future__ import annotations

import bz2
import gzip
import lzma

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.io import mmwrite

from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.matrix_import import (
    read_abaqus_matrix,
    read_abaqus_mesh,
    read_matrix_market,
    read_npz_model,
    write_npz_model,
)

N_NODES = 5


def _symmetric(rng: np.random.Generator, n: int = 3 * N_NODES) -> sp.csr_matrix:
    a = sp.random(n, n, density=0.3, random_state=rng, format="csr")
    return sp.csr_matrix(a + a.T + sp.identity(n) * 10.0)


def _coordinate_lines(matrix: sp.spmatrix) -> list[str]:
    coo = sp.coo_matrix(matrix)
    return [f"{r + 1} {c + 1}  {v:.17e}" for r, c, v in zip(coo.row, coo.col, coo.data, strict=True)]


def _model(rng: np.random.Generator) -> ExternalFEModel:
    nodes = rng.standard_normal((N_NODES, 3))
    mass = sp.diags(rng.uniform(1.0, 2.0, N_NODES).repeat(3))
    return ExternalFEModel(nodes, mass, _symmetric(rng), {"Tet4": np.array([[0, 1, 2, 3], [1, 2, 3, 4]])}, "five")


@pytest.mark.parametrize("symmetry", ["general", "symmetric"])
@pytest.mark.parametrize("compressed", [False, True])
def test_matrix_market_reads_what_scipy_wrote(tmp_path, rng, symmetry, compressed):
    matrix = _symmetric(rng)
    path = tmp_path / "k.mtx"
    mmwrite(path, matrix, symmetry=symmetry, precision=17)
    if compressed:
        (tmp_path / "k.mtx.gz").write_bytes(gzip.compress(path.read_bytes()))
        path = tmp_path / "k.mtx.gz"
    read = read_matrix_market(path, n_dofs=matrix.shape[0])
    assert isinstance(read, sp.csr_matrix)
    assert abs(read - matrix).max() == 0.0


@pytest.mark.parametrize("suffix", ["", ".gz", ".bz2", ".xz"])
@pytest.mark.parametrize("storage", ["full", "lower triangle", "upper triangle", "split entries"])
def test_abaqus_coordinate_file_gives_the_written_matrix(tmp_path, rng, storage, suffix):
    matrix = _symmetric(rng)
    part = {"full": matrix, "lower triangle": sp.tril(matrix), "upper triangle": sp.triu(matrix)}.get(storage, matrix)
    lines = _coordinate_lines(part)
    if storage == "split entries":  # every entry as two halves on separate lines: summed, as scipy's COO does
        lines = [f"{line.split()[0]} {line.split()[1]} {float(line.split()[2]) / 2:.17e}" for line in lines] * 2
    text = "\n".join(lines) + "\n"
    compress = {"": str.encode, ".gz": lambda t: gzip.compress(t.encode()), ".bz2": lambda t: bz2.compress(t.encode())}
    compress[".xz"] = lambda t: lzma.compress(t.encode())
    path = tmp_path / f"m_STIF1.mtx{suffix}"
    path.write_bytes(compress[suffix](text))
    read = read_abaqus_matrix(path, n_dofs=matrix.shape[0])
    assert read.shape == matrix.shape
    assert abs(read - matrix).max() <= 1e-15 * abs(matrix).max()


def test_abaqus_matrix_size_defaults_to_the_largest_dof(tmp_path):
    (tmp_path / "m.mtx").write_text("1 1 2.0\n4 4 3.0\n")
    assert read_abaqus_matrix(tmp_path / "m.mtx").shape == (4, 4)
    assert read_abaqus_matrix(tmp_path / "m.mtx", n_dofs=6).shape == (6, 6)


INP = """*Heading
** a part with the nodes, an instance of it, and an element continued over two lines
*Part, name=Bar
*Node
      1,  0.,  0.,  0.
      2,  1.,  0.,  0.
      3,  1.,  1.,  0.
      4,  0.,  1.,  0.
      5,  0.,  0.,  1.
      6,  1.,  0.,  1.
      7,  1.,  1.,  1.
      8,  0.,  1.,  1.
      9,  0.5, 0.5, 1.5
*Element, type=C3D8R
1, 1, 2, 3, 4, 5, 6, 7,
 8
*Element, type=C3D4
2, 5, 6, 7, 9
*Nset, nset=all, generate
 1, 9, 1
*End Part
*Assembly, name=Assembly
*Instance, name=Bar-1, part=Bar
*End Instance
*End Assembly
*Material, name=steel
*Density
7850.,
"""


def test_abaqus_mesh_of_a_named_part(tmp_path):
    path = tmp_path / "bar.inp"
    path.write_text(INP)
    for name in ("Bar", "bar", None):  # Abaqus names are case-insensitive; None: the only block with nodes
        mesh = read_abaqus_mesh(path, name)
        assert (mesh.name, mesh.kind) == ("Bar", "part")
        assert mesh.nodes.shape == (9, 3)
        np.testing.assert_array_equal(mesh.nodes[8], [0.5, 0.5, 1.5])
        np.testing.assert_array_equal(mesh.elements["Hex8"], [np.arange(8)])
        np.testing.assert_array_equal(mesh.elements["Tet4"], [[4, 5, 6, 8]])


def test_npz_dense_and_triplet_forms_are_one_model(tmp_path, rng):
    model = _model(rng)
    back = read_npz_model(write_npz_model(tmp_path / "m.npz", model))
    np.testing.assert_array_equal(back.nodes, model.nodes)
    assert abs(back.stiffness - model.stiffness).max() == 0.0 and abs(back.mass - model.mass).max() == 0.0
    np.testing.assert_array_equal(back.elements["Tet4"], model.elements["Tet4"])
    np.savez(tmp_path / "dense.npz", nodes=model.nodes, mass=model.mass.toarray(), stiffness=model.stiffness.toarray())
    dense = read_npz_model(tmp_path / "dense.npz")
    assert abs(dense.stiffness - model.stiffness).max() == 0.0 and dense.name == "dense"


def test_scaled_stiffness_and_point_mass_leave_the_original_alone(rng):
    model = _model(rng)
    stiffness, mass = model.stiffness.copy(), model.mass.copy()
    softer = model.with_scaled_stiffness(0.01)
    heavier = model.with_node_mass(2, 0.5)
    assert abs(softer.stiffness - 0.01 * stiffness).max() == 0.0
    assert abs(heavier.mass - mass).sum() == pytest.approx(1.5, rel=1e-15)  # 0.5 kg on x, y and z of node 2
    assert np.flatnonzero((heavier.mass - mass).diagonal()).tolist() == [6, 7, 8]
    assert abs(model.stiffness - stiffness).max() == 0.0 and abs(model.mass - mass).max() == 0.0
