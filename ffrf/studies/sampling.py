r"""The variants of a study: a grid, or unit samples mapped through each parameter's distribution.

Unit samples :math:`u \in (0, 1)^d` come from a seeded generator, so a study's design is the same on every
machine and every rerun: ``monte_carlo`` (NumPy's PCG64), ``lhs`` (Latin hypercube) and ``sobol`` (scrambled
Sobol sequence) of :mod:`scipy.stats.qmc`; ``saltelli`` the design of Saltelli et al. (2010) for Sobol indices:
a scrambled Sobol sequence of dimension :math:`2d` split into matrices :math:`A` and :math:`B` (N rows each),
and for every parameter :math:`i` the matrix :math:`A_B^{(i)}`, :math:`A` with column :math:`i` taken from
:math:`B`, :math:`N (d + 2)` variants in all (blocks ``A``, ``B``, ``AB0`` ...). A value is the inverse CDF of
its distribution at :math:`u`: :math:`x = \mathrm{low} + u (\mathrm{high} - \mathrm{low})`,
:math:`x = \mu + \sigma \Phi^{-1}(u)`, or ``values[floor(u n)]``. A grid is every combination of the values.

Each variant's id is a hash of the study's base and its parameter values (:func:`variant_id`), so a rerun
recognises the variants it has finished whatever their order.
"""

from __future__ import annotations

import hashlib
import inspect
import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import norm, qmc

from ffrf.studies.spec import Parameter, Study

__all__ = ["Variant", "study_design", "unit_samples", "saltelli_blocks", "values_from_unit", "variant_id"]


@dataclass(frozen=True)
class Variant:
    """One variant: its ``id``, the design ``block`` (``"A"``, ``"B"``, ``"AB0"``, ...; ``""`` outside a
    Saltelli design) and row ``sample`` in it, and its parameter ``values`` (name -> value in the target's unit)."""

    id: str
    block: str
    sample: int
    values: dict[str, float]


def _qmc_seed(engine: type, seed: int) -> dict:
    """scipy >= 1.15 names the seed ``rng``, older versions ``seed``."""
    return {"rng" if "rng" in inspect.signature(engine).parameters else "seed": seed}


def unit_samples(method: str, n: int, d: int, seed: int) -> NDArray[np.float64]:
    """``(n, d)`` seeded unit samples of ``method`` (``monte_carlo``, ``lhs``, ``sobol``)."""
    if method == "monte_carlo":
        return np.random.default_rng(seed).random((n, d))
    if method == "lhs":
        return qmc.LatinHypercube(d, **_qmc_seed(qmc.LatinHypercube, seed)).random(n)
    if method == "sobol":
        return qmc.Sobol(d, scramble=True, **_qmc_seed(qmc.Sobol, seed)).random(n)
    raise ValueError(f"no unit samples for method {method!r}")


def saltelli_blocks(n: int, d: int, seed: int) -> list[tuple[str, NDArray[np.float64]]]:
    """The Saltelli design in unit samples: ``[("A", A), ("B", B), ("AB0", A_B^(0)), ...]``, each ``(n, d)``."""
    both = unit_samples("sobol", n, 2 * d, seed)
    a, b = both[:, :d], both[:, d:]
    blocks = [("A", a), ("B", b)]
    for i in range(d):
        ab = a.copy()
        ab[:, i] = b[:, i]
        blocks.append((f"AB{i}", ab))
    return blocks


def values_from_unit(parameter: Parameter, u: NDArray) -> NDArray[np.float64]:
    """The inverse CDF of ``parameter``'s distribution at the unit samples ``u``."""
    u = np.asarray(u, dtype=float)
    if parameter.distribution == "uniform":
        low, high = parameter.arguments
        return low + u * (high - low)
    if parameter.distribution == "normal":
        mean, std = parameter.arguments
        return mean + std * norm.ppf(u)
    values = np.asarray(parameter.arguments)
    return values[np.minimum((u * len(values)).astype(int), len(values) - 1)]


def variant_id(study: Study, values: dict[str, float]) -> str:
    """A stable id: the hash of the study's base fingerprint and the parameter values (exact, as repr)."""
    text = study.fingerprint + ";" + ";".join(f"{name}={values[name]!r}" for name in sorted(values))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _variant(study: Study, block: str, sample: int, row: NDArray) -> Variant:
    values = {p.name: float(v) for p, v in zip(study.parameters, row, strict=True)}
    return Variant(variant_id(study, values), block, sample, values)


def study_design(study: Study) -> list[Variant]:
    """Every variant of ``study`` in design order (module docstring)."""
    parameters = study.parameters
    if study.method == "grid":
        rows = itertools.product(*(p.arguments for p in parameters))
        return [_variant(study, "", k, np.asarray(row)) for k, row in enumerate(rows)]
    d = len(parameters)
    if study.method == "saltelli":
        blocks = saltelli_blocks(study.samples, d, study.seed)
    else:
        blocks = [("", unit_samples(study.method, study.samples, d, study.seed))]
    design = []
    for name, u in blocks:
        x = np.column_stack([values_from_unit(p, u[:, i]) for i, p in enumerate(parameters)])
        design += [_variant(study, name, k, row) for k, row in enumerate(x)]
    return design
