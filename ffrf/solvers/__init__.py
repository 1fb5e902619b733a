"""Statics and quasi-statics, generalized-alpha, the variational midpoint rule and shared pieces."""
