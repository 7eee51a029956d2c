"""Compiled rigid-body algorithms on a lowered Pinocchio model (numba kernels called from compiled nodes).

- :mod:`.joint_types`: joint codes of a lowered model.
- :mod:`.lowering`: ``lower_model(model) -> RigidBodyModel`` (plain arrays) and ``make_workspace``.
- :mod:`.spatial`: 6-vector helpers (spatial motions and forces as tuples) shared by the kernels.
- :mod:`.dynamics_kernel`: forward kinematics, forward dynamics (CRBA + tree-sparse factor), mass inverse,
  RNEA derivatives, frame placement / Jacobian / velocity / velocity derivatives.
- :mod:`.contact_kernel`: contact Jacobian and drift (1D/2D/3D/6D, Baumgarte) with derivatives, the contact forces'
  term of the RNEA derivatives, contact forward dynamics (KKT through the tree-sparse factor) and its derivatives.
- :mod:`.com_kernel`: centre of mass and its Jacobian.
- :mod:`.lie_kernel`: ``log3``/``jlog3``/``log6``/``jlog6`` and the SE(2) maps; :mod:`.configuration_kernel`: the
  configuration space's ``integrate``/``difference``/``dintegrate`` and the multibody state's ``state_diff``/
  ``state_integrate``/``state_jdiff``.
- :mod:`.gravity_kernel`: the generalized gravity ``g(q)`` and its derivatives.
- :mod:`.euler_node`, :mod:`.euler_node_kernel`: the compiled Euler node of free forward dynamics.
"""
