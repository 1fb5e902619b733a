"""Craig-Bampton reduction, inertia invariants, reduced-body files and mode post-processing."""
