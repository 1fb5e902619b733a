"""The colours of the paper's figures (Fig. "deviation_errors"), by variant, for
:mod:`ffrf.output.linkage_figures` (its ``colors``)."""

__all__ = ["VARIANT_COLORS"]

#: The paper's colours (orange: stiff, blue: PLA) and two more for the misaligned variants.
VARIANT_COLORS = {"rigid": "tab:orange", "pla": "tab:blue", "pla1": "tab:green", "pla2": "tab:red"}
