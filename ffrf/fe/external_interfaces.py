"""Interfaces of a model given by its nodes and matrices (:class:`ffrf.fe.external_model.ExternalFEModel`).

The rule of every selector of :mod:`ffrf.fe.interfaces` holds here too: a node set is weighted by the surface
area it spans, unless a weight per node is given. The surface comes from the model's volume elements
(:func:`ffrf.fe.node_selection.surface_triangles`; each triangle whose three corners are in the set adds a third
of its area to each corner, eq. (X4), Exudyn's ``GetNodeWeightsFromSurfaceAreas``). A model without elements
spans no area: its interfaces need their weights given (equal weights, as Exudyn's
``MarkerSuperElementPosition`` with ``1/n`` each, or a weight per node).
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from ffrf.errors import InterfaceError
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.interfaces import InterfaceNodes, checked_node_list, given_weights
from ffrf.fe.node_selection import surface_area_weights, surface_triangles

__all__ = ["external_interface"]


def external_interface(
    model: ExternalFEModel, name: str, nodes: ArrayLike, weights: ArrayLike | None = None
) -> InterfaceNodes:
    """Interface ``name`` of ``model`` on ``nodes`` (0-based): given ``weights`` normalised to sum 1, else the
    surface-area weights of the model's elements; ``area`` is the spanned area (m^2), NaN with given weights."""
    where = f"interface {name!r} of {model.name}"
    unique, first = checked_node_list(nodes, model.n_nodes, where)
    if weights is not None:
        return InterfaceNodes(name, unique, given_weights(weights, first, where), float("nan"))
    if not model.elements:
        raise InterfaceError(
            f"interface {name!r} of {model.name}: the model has no elements, so its nodes span no surface area; "
            'add weights = "equal" to the interface or a weight per node (second column of a nodes_file), or give '
            "the elements (nodes from an Abaqus .inp, elements_<type> in the .npz)"
        )
    areas = surface_area_weights(model.nodes, surface_triangles(model.elements), unique, normalize=False)
    return InterfaceNodes(name, unique, areas / areas.sum(), float(areas.sum()))
