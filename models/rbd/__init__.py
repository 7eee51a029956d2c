"""Compiled rigid-body algorithms on a lowered Pinocchio model (numba kernels called from compiled nodes).

- :mod:`.joint_types`: joint codes of a lowered model.
- :mod:`.lowering`: ``lower_model(model) -> RigidBodyModel`` (plain arrays) and ``make_workspace``.
- :mod:`.dynamics_kernel`: forward kinematics, forward dynamics (CRBA + tree-sparse factor), mass inverse,
  RNEA derivatives, generalized gravity, frame placement / Jacobian / velocity / velocity derivatives.
"""
