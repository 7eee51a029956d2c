"""Compiled rigid-body algorithms on a lowered Pinocchio model (numba kernels called from compiled nodes)."""
