"""The table a compiled node's kernels read (:mod:`.euler_node_kernel`): its layout, declared once here, and the
accessors that view its entries.

A node's arrays arrive by address: ``tbl[k]`` is the address of entry ``k`` (a C-contiguous array), its
dimensions are ``ints[SHAPES + 3k : SHAPES + 3k + 3]``.  The entries are the fields of the lowered model and of its
workspace (:mod:`.lowering`), then :data:`NODE_ARRAYS` and :data:`SCRATCH_ARRAYS`; ``E_<NAME>`` is the entry of
each.  ``ints`` also holds the sizes (``NQ`` .. ``NC``), the residual items (``ITEM_FIELDS`` integers each, from
``ints[ITEMS]``), the cost stack's item starts (from ``ints[STARTS]``) and the contacts (``CONTACT_FIELDS`` each,
from ``ints[CONTACTS]``).
"""

from __future__ import annotations

from crocopy.kernels import carray, compiled, float64_pointer, int64_pointer, matrix_at, vector_at

from .contact_kernel import ContactWorkspace
from .lowering import RigidBodyModel, RigidBodyWorkspace

STATE, CONTROL, PLACEMENT, TRANSLATION, ROTATION, VELOCITY, CONE, COM, USER = range(9)
"""Residual kinds.  ``CONE``: ``r = A λ_c`` (friction and wrench cones; the item's frame field is the contact's first
row, its reference field the force components ``ncf``, ``A`` row-major in ``par``); ``COM``: ``r = com - cref``;
``USER``: a :class:`~crocopy.models.residual_numba.ResidualModelNumba`, whose two C callbacks (item fields
``RESIDUAL_ADDRESS``, ``JACOBIANS_ADDRESS``) the node calls with its kinematics (item field ``FLAGS``: what they
read, and ``u`` dependence; ``N_PARAMETERS``: the length of its parameters in ``par``)."""

KIND = {"state": STATE, "control": CONTROL, "placement": PLACEMENT, "translation": TRANSLATION,
        "rotation": ROTATION, "velocity": VELOCITY, "cone": CONE, "com": COM}
"""The kinds written into this kernel, by the ``compiled_kind`` name a residual class declares beside its maths
(with its ``compiled_parameters()``); ``USER`` residuals bring their own functions."""

WORLD, LOCAL, LOCAL_WORLD_ALIGNED = 0, 1, 2
"""Pinocchio's reference frames (``int(pinocchio.ReferenceFrame)``)."""

(NQ, NV, NU, U_START, N_ITEMS, EUCLIDEAN, NJOINTS, NFRAMES, N_STACK, ITEMS, STARTS, TERMINAL, N_CONTACTS, CONTACTS,
 NC) = range(15)
SHAPES = 15
ITEM_FIELDS = 10
FLAGS, RESIDUAL_ADDRESS, JACOBIANS_ADDRESS, N_PARAMETERS = range(6, 10)
"""Fields of a ``USER`` item after the six every item has (kind, first row, rows, frame, reference, offset)."""
CONTACT_FIELDS = 4

NODE_ARRAYS = (
    "xnext", "dx", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu",
    "a", "dFx", "dFu", "Minv", "dLx", "dLu", "dLxx", "dLxu", "dLuu",
    "r", "lb", "ub", "act_weights", "item_costs", "item_weights", "weights", "Ar", "Arr",
    "Jx", "Ju", "Jc", "HJx", "Juc", "HJu", "S", "gains", "ref_R", "ref_p", "kin", "user_dims", "user_Ru",
)
"""The node's own arrays (its data's, its cost stack's, its actuation matrix and contacts)."""
SCRATCH_ARRAYS = (
    "tau", "dtau_dq", "dtau_dv", "J6", "K6", "m6", "R3", "p3", "v6", "Jq", "Jv", "rows", "gap",
    "Jcs", "a0", "lam", "da0_dx", "df_dx", "df_du", "com", "Jcom",
    "cJ6", "cY", "cG", "cz", "cw", "cm6", "cJ66", "cR3", "cp3",
)
"""Scratch of one node evaluation, shared by the nodes of one model with the same ``nu`` and contact rows (a
kernel call leaves nothing there that a later call reads)."""
N_RB, N_WS = len(RigidBodyModel._fields) - 4, len(RigidBodyWorkspace._fields)
RB_ARMATURE = RigidBodyModel._fields.index("armature") - 4
"""Entry of the armature (each node's own: the Pinocchio model's plus the dynamics model's)."""
NODE = N_RB + N_WS
(E_XNEXT, E_DX, E_FX, E_FU, E_LX, E_LU, E_LXX, E_LXU, E_LUU,
 E_A, E_DFX, E_DFU, E_MINV, E_DLX, E_DLU, E_DLXX, E_DLXU, E_DLUU,
 E_R, E_LB, E_UB, E_ACT_W, E_ITEM_COSTS, E_ITEM_WEIGHTS, E_WEIGHTS, E_AR, E_ARR,
 E_JX, E_JU, E_JC, E_HJX, E_JUC, E_HJU, E_S, E_GAINS, E_REF_R, E_REF_P, E_KIN, E_USER_DIMS, E_USER_RU,
 E_TAU, E_DTAU_DQ, E_DTAU_DV, E_J6, E_K6, E_M6, E_R3, E_P3, E_V6, E_JQ, E_JV, E_ROWS, E_GAP,
 E_JCS, E_A0, E_LAM, E_DA0_DX, E_DF_DX, E_DF_DU, E_COM, E_JCOM,
 E_CJ6) = range(NODE, NODE + len(NODE_ARRAYS) + len(SCRATCH_ARRAYS) - 8)


@compiled
def vec(tbl, ints, k):
    return vector_at(tbl[k], ints[SHAPES + 3 * k])


@compiled
def mat(tbl, ints, k):
    return matrix_at(tbl[k], ints[SHAPES + 3 * k], ints[SHAPES + 3 * k + 1])


@compiled
def cube(tbl, ints, k):
    s = SHAPES + 3 * k
    return carray(float64_pointer(tbl[k]), (ints[s], ints[s + 1], ints[s + 2]))


@compiled
def ivec(tbl, ints, k):
    return carray(int64_pointer(tbl[k]), (ints[SHAPES + 3 * k],))


@compiled
def entry_model(tbl, ints):
    """The lowered model, from the entries ``0`` to ``N_RB - 1`` (its fields' order)."""
    return RigidBodyModel(
        ints[NQ], ints[NV], ints[NJOINTS], ints[NFRAMES],
        ivec(tbl, ints, 0), ivec(tbl, ints, 1), ivec(tbl, ints, 2), ivec(tbl, ints, 3),
        mat(tbl, ints, 4), ivec(tbl, ints, 5), ivec(tbl, ints, 6), ivec(tbl, ints, 7),
        ivec(tbl, ints, 8), ivec(tbl, ints, 9), cube(tbl, ints, 10), mat(tbl, ints, 11),
        vec(tbl, ints, 12), mat(tbl, ints, 13), cube(tbl, ints, 14), ivec(tbl, ints, 15),
        cube(tbl, ints, 16), mat(tbl, ints, 17), vec(tbl, ints, 18), vec(tbl, ints, 19),
    )


@compiled
def entry_workspace(tbl, ints):
    """The workspace, from the entries ``N_RB`` to ``NODE - 1`` (its fields' order)."""
    k = N_RB
    return RigidBodyWorkspace(
        cube(tbl, ints, k), mat(tbl, ints, k + 1), mat(tbl, ints, k + 2), mat(tbl, ints, k + 3),
        mat(tbl, ints, k + 4), mat(tbl, ints, k + 5), cube(tbl, ints, k + 6), mat(tbl, ints, k + 7),
        mat(tbl, ints, k + 8), mat(tbl, ints, k + 9), cube(tbl, ints, k + 10), cube(tbl, ints, k + 11),
        mat(tbl, ints, k + 12), mat(tbl, ints, k + 13), mat(tbl, ints, k + 14), mat(tbl, ints, k + 15),
        vec(tbl, ints, k + 16), vec(tbl, ints, k + 17), vec(tbl, ints, k + 18), mat(tbl, ints, k + 19),
        mat(tbl, ints, k + 20), vec(tbl, ints, k + 21),
    )


@compiled
def entry_contact_workspace(tbl, ints):
    """The contact workspace, from the entry ``E_CJ6`` on (its fields' order)."""
    k = E_CJ6
    return ContactWorkspace(
        mat(tbl, ints, k), mat(tbl, ints, k + 1), mat(tbl, ints, k + 2), vec(tbl, ints, k + 3),
        vec(tbl, ints, k + 4), vec(tbl, ints, k + 5), mat(tbl, ints, k + 6), mat(tbl, ints, k + 7),
        vec(tbl, ints, k + 8),
    )


@compiled
def contact_fields(ints, n):
    """``(frame, rows, reference frame, first row)`` of contact ``n``."""
    b = ints[CONTACTS] + CONTACT_FIELDS * n
    return ints[b], ints[b + 1], ints[b + 2], ints[b + 3]
