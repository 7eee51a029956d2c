"""Joint type codes of a lowered model (``RigidBodyModel.jtype``), shared by the dynamics and Lie-group kernels.

=================  =====  ====  ====  ==========================================================
code               value  nq    nv    Pinocchio joint
=================  =====  ====  ====  ==========================================================
``FREEFLYER``      0      7     6     ``JointModelFreeFlyer`` (``q = [p, quaternion xyzw]``, SE(3))
``REVOLUTE``       1      1     1     ``JointModelRX/RY/RZ``, ``JointModelRevoluteUnaligned``
``REVOLUTE_UB``    2      2     1     ``JointModelRUBX/RUBY/RUBZ`` (``q = [cos θ, sin θ]``)
``PRISMATIC``      3      1     1     ``JointModelPX/PY/PZ``, ``JointModelPrismaticUnaligned``
=================  =====  ====  ====  ==========================================================

The axis of a revolute or prismatic joint is stored apart (``RigidBodyModel.axis``), so aligned and
unaligned joints share a code.
"""

FREEFLYER = 0
REVOLUTE = 1
REVOLUTE_UB = 2
PRISMATIC = 3

NQ = {FREEFLYER: 7, REVOLUTE: 1, REVOLUTE_UB: 2, PRISMATIC: 1}
NV = {FREEFLYER: 6, REVOLUTE: 1, REVOLUTE_UB: 1, PRISMATIC: 1}
