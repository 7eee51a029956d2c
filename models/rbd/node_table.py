"""The table a compiled node's kernels read (:mod:`.euler_node_kernel`): its layout, declared once here, and the
accessors that view its entries.

A node's arrays arrive by address: ``tbl[k]`` is the address of entry ``k`` (a C-contiguous array), its
dimensions are ``ints[SHAPES + 3k : SHAPES + 3k + 3]``.  The entries are the fields of the lowered model and of its
workspace (:mod:`.lowering`), then the node arrays and the scratch, each declared once here as an :class:`Entry`
(name, shape over the node's sizes, owner, dtype) in :data:`NODE_ARRAYS` and :data:`SCRATCH_ARRAYS`.  From that
declaration come the entries' indices (:data:`ENTRIES`, and the kernels' constants ``E_<NAME>``), the scratch
(:func:`make_arrays`) and the check of every array a node lists (:func:`check_arrays`: a wrong shape or dtype
raises, naming the entry, before any kernel reads it); ``tests/test_node_table.py`` checks that every accessor a
kernel applies to an ``E_<NAME>`` has that entry's dimension and dtype.  ``ints`` also holds the sizes (``NQ`` ..
``NC``), the residual items (``ITEM_FIELDS`` integers each, from ``ints[ITEMS]``), the cost stack's item starts (from
``ints[STARTS]``) and the contacts (``CONTACT_FIELDS`` each, from ``ints[CONTACTS]``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from crocopy.kernels import carray, compiled, float64_pointer, int64_pointer, matrix_at, vector_at

from .contact_kernel import CONTACT_WORKSPACE, ContactWorkspace
from .lowering import RigidBodyModel, RigidBodyWorkspace

(STATE, CONTROL, PLACEMENT, TRANSLATION, ROTATION, VELOCITY, CONE, COM, USER, EFFORT, ACCELERATION,
 CONTROL_GRAV, FORCE, CONTACT_CONTROL_GRAV, CENTROIDAL, IMPULSE_COM) = range(16)
"""Residual kinds.  ``CONE``: ``r = A λ_c`` (friction and wrench cones; the item's frame field is the contact's first
row, its reference field the force components ``ncf``, ``A`` row-major in ``par``); ``COM``: ``r = com - cref``;
``EFFORT``: ``r = u - uref`` (a forward-dynamics node's joint efforts are its controls), ``ACCELERATION``:
``r = a - aref`` with the node's acceleration and its derivatives (both 0 at a terminal node); ``CONTROL_GRAV``:
``r = S u - g(q)`` (``-g(q)`` at a terminal node); ``FORCE``: ``r = A λ_c - fref`` (a cone's fields and ``A``, then
``fref``; 0 at a terminal node, which has no force); a cone or force item with ``FLAGS`` 1 reads an impulse node's
impulses (its value kept at that node without control, its Jacobian written after the impulses' derivatives);
``CONTACT_CONTROL_GRAV``: ``r = S u - g(q) + Jcᵀ λ`` (a contact node's gravity-and-contact-force compensating
control; ``-g(q)`` at a terminal node); ``CENTROIDAL``: ``r = h(q, v) - href`` (the centroidal momentum,
:mod:`.com_kernel`); ``IMPULSE_COM``: ``r = Jcom (v⁺ - v)`` (an impulse node's centre-of-mass velocity jump);
``USER``: a :class:`~crocopy.models.residual_numba.ResidualModelNumba`, whose two C callbacks (item fields
``RESIDUAL_ADDRESS``, ``JACOBIANS_ADDRESS``) the node calls with its kinematics (item field ``FLAGS``: what they
read, and ``u`` dependence; ``N_PARAMETERS``: the length of its parameters in ``par``)."""

KIND = {"state": STATE, "control": CONTROL, "placement": PLACEMENT, "translation": TRANSLATION,
        "rotation": ROTATION, "velocity": VELOCITY, "cone": CONE, "com": COM, "effort": EFFORT,
        "acceleration": ACCELERATION, "control_grav": CONTROL_GRAV, "force": FORCE,
        "contact_control_grav": CONTACT_CONTROL_GRAV, "centroidal": CENTROIDAL, "impulse_com": IMPULSE_COM}
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

class Entry(NamedTuple):
    """A node array of the table: its ``name``, its ``shape`` (sizes or expressions over the node's sizes, see
    :func:`entry_shapes`), the owner that makes it, and its ``dtype``."""

    name: str
    shape: tuple
    owner: str
    dtype: type = np.float64


_DATA, _DIFF, _STACK, _NODE, _CONTACTS = "action data", "differential data", "cost stack", "node", "contact set"
_SCRATCH, _CW, _ROWS = "scratch", "contact workspace", "constraint rows"

NODE_ARRAYS = (
    Entry("xnext", ("nx",), _DATA), Entry("dx", ("ndx",), _DATA), Entry("Fx", ("ndx", "ndx"), _DATA),
    Entry("Fu", ("ndx", "nu"), _DATA), Entry("Lx", ("ndx",), _DATA), Entry("Lu", ("nu",), _DATA),
    Entry("Lxx", ("ndx", "ndx"), _DATA), Entry("Lxu", ("ndx", "nu"), _DATA), Entry("Luu", ("nu", "nu"), _DATA),
    Entry("a", ("nv",), _DIFF), Entry("dFx", ("nv", "ndx"), _DIFF), Entry("dFu", ("nv", "nu"), _DIFF),
    Entry("Minv", ("nv", "nv"), _DIFF), Entry("dLx", ("ndx",), _DIFF), Entry("dLu", ("nu",), _DIFF),
    Entry("dLxx", ("ndx", "ndx"), _DIFF), Entry("dLxu", ("ndx", "nu"), _DIFF), Entry("dLuu", ("nu", "nu"), _DIFF),
    Entry("r", ("nr",), _STACK), Entry("lb", ("nr",), _STACK), Entry("ub", ("nr",), _STACK),
    Entry("act_weights", ("nr",), _STACK), Entry("item_costs", ("n_stack",), _STACK),
    Entry("item_weights", ("n_stack",), _STACK), Entry("weights", ("nr",), _STACK), Entry("Ar", ("nr",), _STACK),
    Entry("Arr", ("nr",), _STACK), Entry("Jx", ("nr", "ndx"), _STACK), Entry("Ju", ("nr_u", "nu"), _STACK),
    Entry("cols", ("n_cols",), _STACK, np.int64), Entry("grad", ("n_cols",), _STACK),
    Entry("act_kinds", ("n_stack",), _STACK, np.int64),
    Entry("act_params", ("n_stack",), _STACK),
    Entry("S", ("nv", "nu"), _NODE), Entry("gains", ("n_contacts", 2), _CONTACTS),
    Entry("ref_R", ("n_contacts", 3, 3), _CONTACTS), Entry("ref_p", ("n_contacts", 3), _CONTACTS),
    Entry("kin", ("n_kin",), _NODE), Entry("user_dims", (5,), _NODE, np.int64),
    Entry("user_Ru", ("nr_user", "nu"), _NODE), Entry("stamp", ("n_stamp",), _NODE),
    Entry("c_tbl", ("n_tbl",), _ROWS, np.int64), Entry("c_ints", ("n_c_ints",), _ROWS, np.int64),
    Entry("c_rows", ("n_c_rows",), _ROWS, np.int64), Entry("cr", ("nrc",), _ROWS),
    Entry("cJx", ("nrc", "ndx"), _ROWS), Entry("cJu", ("nrc", "nu"), _ROWS),
    Entry("g", ("ng",), _DATA), Entry("Gx", ("ng", "ndx"), _DATA), Entry("Gu", ("ng", "nu"), _DATA),
    Entry("h", ("nh",), _DATA), Entry("Hx", ("nh", "ndx"), _DATA), Entry("Hu", ("nh", "nu"), _DATA),
    Entry("dg", ("ng",), _DIFF), Entry("dGx", ("ng", "ndx"), _DIFF), Entry("dGu", ("ng", "nu"), _DIFF),
    Entry("dh", ("nh",), _DIFF), Entry("dHx", ("nh", "ndx"), _DIFF), Entry("dHu", ("nh", "nu"), _DIFF),
)
"""The node's own arrays (its data's, its differential data's, its cost stack's, its actuation matrix ``S`` and
contacts, the kinematics its users' residuals read, the stamp of its last values (:data:`OWN`); its constraint
manager's rows, :mod:`.constraint_rows`: the
constraint table and program, the constraint residuals ``cr`` and Jacobians ``cJx``, ``cJu``, and the rows ``g``,
``h`` and Jacobians of the action data and of the differential data), in table order."""
SCRATCH_ARRAYS = (
    Entry("tau", ("nv",), _SCRATCH), Entry("dtau_dq", ("nv", "nv"), _SCRATCH),
    Entry("dtau_dv", ("nv", "nv"), _SCRATCH), Entry("J6", (6, "nv"), _SCRATCH), Entry("K6", (6, "nv"), _SCRATCH),
    Entry("m6", (6, 6), _SCRATCH), Entry("R3", (3, 3), _SCRATCH), Entry("p3", (3,), _SCRATCH),
    Entry("v6", (6,), _SCRATCH), Entry("Jq", ("nv", "nv"), _SCRATCH), Entry("Jv", ("nv", "nv"), _SCRATCH),
    Entry("rows", ("nv", "ndx + nu"), _SCRATCH), Entry("gap", ("ndx",), _SCRATCH),
    Entry("Jcs", ("nc", "nv"), _SCRATCH), Entry("a0", ("nc",), _SCRATCH), Entry("lam", ("nc",), _SCRATCH),
    Entry("da0_dx", ("nc", "ndx"), _SCRATCH), Entry("df_dx", ("nc", "ndx"), _SCRATCH),
    Entry("df_du", ("nc", "nu"), _SCRATCH), Entry("com", (3,), _SCRATCH), Entry("Jcom", (3, "nv"), _SCRATCH),
    *(Entry("c" + name, shape, _CW) for name, shape in CONTACT_WORKSPACE.items()),
)
"""Scratch of one node evaluation, shared by the nodes of one model with the same ``nu`` and contact rows (a
kernel call leaves nothing there that a later call reads); the last ones are the contact kernels' workspace
(:class:`~.contact_kernel.ContactWorkspace`, its fields prefixed with ``c``)."""
N_RB, N_WS = len(RigidBodyModel._fields) - 4, len(RigidBodyWorkspace._fields)
RB_ARMATURE = RigidBodyModel._fields.index("armature") - 4
"""Entry of the armature (each node's own: the Pinocchio model's plus the dynamics model's)."""
NODE = N_RB + N_WS
ENTRIES = {e.name: NODE + k for k, e in enumerate(NODE_ARRAYS + SCRATCH_ARRAYS)}
"""Entry ``k`` of each node and scratch array, by name; each is also the module constant ``E_<NAME>`` (the
kernels' name for it), made here from the declaration."""
globals().update({"E_" + name.upper(): k for name, k in ENTRIES.items()})

OWN_WORKSPACE = ("oR", "op", "oS", "ov", "ow", "oI", "L", "dinv")
"""The workspace fields an Euler node keeps of its own (not the model's shared workspace): what its values leave
(the kinematics, the factor of ``M``) and its derivatives read before writing."""
OWN_SCRATCH = ("Jcs", "a0", "lam", *("c" + name for name in CONTACT_WORKSPACE))
"""The scratch an Euler node keeps of its own for the same reason (the contacts' Jacobian, drift, forces and
workspace)."""
OWN = np.array([N_RB + RigidBodyWorkspace._fields.index(name) for name in OWN_WORKSPACE]
               + [ENTRIES[name] for name in OWN_SCRATCH], dtype=np.int64)
"""The entries of an Euler node's table that are its own arrays (:data:`OWN_WORKSPACE`, :data:`OWN_SCRATCH`):
with them and its ``stamp`` (``[valid, stack value, x, u]``; empty in the impulse node's table), a ``calcDiff`` at
the point of the node's last ``calc`` skips the values (:func:`.euler_node_kernel.node_calc_diff`).  The extra
threads' tables keep these entries (:mod:`.node_threads`)."""


def entry_shapes(entries: tuple, sizes: dict[str, int]) -> list[tuple[int, ...]]:
    """The shapes of ``entries`` for a node of ``sizes`` (``nv, nx, ndx, nu``; the cost stack's rows ``nr``, rows
    that depend on ``u`` ``nr_u``, items ``n_stack``; contact rows ``nc`` and contacts ``n_contacts``; the users'
    kinematics ``n_kin`` and their largest ``u`` rows ``nr_user``, at least 1; the stamp's length ``n_stamp``; the
    constraint rows ``ng``, ``nh``, their residual rows ``nrc``, the lengths ``n_tbl``, ``n_c_ints``, ``n_c_rows`` of
    the constraint table, integers and program; ``ncm = max(nc, 1)`` is added): an expression is evaluated over
    those names.  The shapes are kept per declaration and sizes (the nodes of a problem mostly share theirs)."""
    key = (entries, tuple(sorted(sizes.items())))
    if key not in _SHAPES:
        if len(_SHAPES) > 256:
            _SHAPES.clear()
        names = {**sizes, "ncm": max(sizes.get("nc", 0), 1)}
        _SHAPES[key] = [tuple(_size(d, names) for d in e.shape) for e in entries]
    return _SHAPES[key]


_EXPRESSIONS: dict[str, object] = {}
"""Each size expression compiled once."""
_SHAPES: dict[tuple, list] = {}
"""The shapes of a declaration for given sizes."""


def _size(d: int | str, names: dict[str, int]) -> int:
    if isinstance(d, int):
        return d
    if d in names:
        return names[d]
    if d not in _EXPRESSIONS:
        _EXPRESSIONS[d] = compile(d, "<size>", "eval")
    return int(eval(_EXPRESSIONS[d], {"__builtins__": {}}, names))


def make_arrays(entries: tuple, sizes: dict[str, int]) -> dict[str, np.ndarray]:
    """Zeroed arrays of ``entries`` for a node of ``sizes``, by name."""
    return {e.name: np.zeros(shape, dtype=e.dtype) for e, shape in zip(entries, entry_shapes(entries, sizes))}


def check_arrays(entries: tuple, arrays: list, sizes: dict[str, int]) -> None:
    """Check ``arrays`` against the declaration of ``entries``: C-contiguous, of the declared dtype and shape.

    Raises
    ------
    ValueError
        Naming the entry, its owner, what is declared and what was given.
    """
    for e, shape, a in zip(entries, entry_shapes(entries, sizes), arrays, strict=True):
        if not isinstance(a, np.ndarray) or a.dtype != e.dtype or a.shape != shape or not a.flags.c_contiguous:
            given = (f"{type(a).__name__}" if not isinstance(a, np.ndarray)
                     else f"{a.dtype} array of shape {a.shape}{'' if a.flags.c_contiguous else ', not C-contiguous'}")
            raise ValueError(f"compiled node: entry {e.name!r} ({e.owner}) must be a C-contiguous "
                             f"{np.dtype(e.dtype)} array of shape {shape}, got a {given}")


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


CONTACT_WORKSPACE_ENTRY = ENTRIES["cJ6"]
"""The first entry of the contact workspace."""


@compiled
def entry_contact_workspace(tbl, ints):
    """The contact workspace, from the entry ``CONTACT_WORKSPACE_ENTRY`` on (its fields' order)."""
    k = CONTACT_WORKSPACE_ENTRY
    return ContactWorkspace(
        mat(tbl, ints, k), mat(tbl, ints, k + 1), mat(tbl, ints, k + 2), vec(tbl, ints, k + 3),
        mat(tbl, ints, k + 4), mat(tbl, ints, k + 5), vec(tbl, ints, k + 6),
    )


@compiled
def contact_fields(ints, n):
    """``(frame, rows, reference frame, first row)`` of contact ``n``."""
    b = ints[CONTACTS] + CONTACT_FIELDS * n
    return ints[b], ints[b + 1], ints[b + 2], ints[b + 3]
