"""Interfaces of a model given by its nodes and matrices (:class:`ffrf.fe.external_model.ExternalFEModel`).

The rule of every selector of :mod:`ffrf.fe.interfaces` holds here too: a node set is weighted by the surface
area it spans, unless a weight per node is given. The surface comes from the model's volume elements
(:func:`ffrf.fe.node_selection.surface_triangles`; each triangle whose three corners are in the set adds a third
of its area to each corner, eq. (X4), Exudyn's ``GetNodeWeightsFromSurfaceAreas``). A model without elements
spans no area: its interfaces need their weights given (equal weights, as Exudyn's
``MarkerSuperElementPosition`` with ``1/n`` each, or a weight per node).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ffrf.errors import InterfaceError
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.interfaces import InterfaceNodes
from ffrf.fe.node_selection import surface_area_weights, surface_triangles

__all__ = ["external_interface"]


def external_interface(
    model: ExternalFEModel, name: str, nodes: ArrayLike, weights: ArrayLike | None = None
) -> InterfaceNodes:
    """Interface ``name`` of ``model`` on ``nodes`` (0-based): given ``weights`` normalised to sum 1, else the
    surface-area weights of the model's elements; ``area`` is the spanned area (m^2), NaN with given weights."""
    selected = np.asarray(nodes, dtype=np.int64).reshape(-1)
    if selected.size == 0:
        raise InterfaceError(f"interface {name!r} of {model.name}: no node selected; check the selection and the units")
    if selected.min() < 0 or selected.max() >= model.n_nodes:
        raise InterfaceError(
            f"interface {name!r} of {model.name}: node index out of range [0, {model.n_nodes}); indices are 0-based"
        )
    unique, first = np.unique(selected, return_index=True)
    if len(unique) != len(selected):
        raise InterfaceError(
            f"interface {name!r} of {model.name}: {len(selected) - len(unique)} duplicate nodes; pass each node once"
        )
    if weights is not None:
        w = np.asarray(weights, dtype=float).reshape(-1)
        if w.shape != selected.shape or not np.all(np.isfinite(w)) or np.any(w < 0.0) or not w.sum() > 0.0:
            raise InterfaceError(
                f"interface {name!r} of {model.name}: weights must be {len(selected)} finite non-negative numbers "
                "with a positive sum"
            )
        return InterfaceNodes(name, unique, w[first] / w.sum(), float("nan"))
    if not model.elements:
        raise InterfaceError(
            f"interface {name!r} of {model.name}: the model has no elements, so its nodes span no surface area; "
            'add weights = "equal" to the interface or a weight per node (second column of a nodes_file), or give '
            "the elements (nodes from an Abaqus .inp, elements_<type> in the .npz)"
        )
    areas = surface_area_weights(model.nodes, surface_triangles(model.elements), unique, normalize=False)
    return InterfaceNodes(name, unique, areas / areas.sum(), float(areas.sum()))
