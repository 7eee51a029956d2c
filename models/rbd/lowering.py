"""A ``pinocchio.Model`` lowered to plain arrays (:class:`RigidBodyModel`) and the scratch the kernels write into.

Both are ``typing.NamedTuple`` of ints and numpy arrays, so each is ONE argument of a numba function.
Joints are numbered as in Pinocchio (``0`` is the universe, ``parent[i] < i``); the subtree of joint ``i``
is the contiguous range ``i .. subtree_end[i] - 1`` (checked when lowering).

=========================  ====================  ===================================================================
field                      shape                 meaning
=========================  ====================  ===================================================================
``nq nv njoints nframes``  int                   sizes
``jtype idx_q idx_v``      ``(njoints,)``        joint code (:mod:`.joint_types`, ``-1`` for the universe), first
                                                 configuration / velocity index
``nvj``                    ``(njoints,)``        velocity size of each joint
``axis``                   ``(njoints, 4)``      unit axis of a revolute / prismatic / helical joint, then
                                                 a helical joint's pitch (:mod:`.joint_types`)
``parent``                 ``(njoints,)``        parent joint (``parent[0] = 0``)
``subtree_end``            ``(njoints,)``        one past the last joint of the subtree of each joint
``depth``                  ``(njoints,)``        number of moving joints from the root to the joint, itself included
``dof_joint``              ``(nv,)``             joint of each velocity index
``dof_parent``             ``(nv,)``             previous velocity index on the path to the root (``-1``: none)
``jR jp``                  ``(njoints, 3, 3)``,  joint placement in its parent (``model.jointPlacements``)
                           ``(njoints, 3)``
``mass com inertia``       ``(njoints,)``,       body inertia in the joint frame: mass, centre of mass, rotational
                           ``(njoints, 3)``,     inertia about the centre of mass (``model.inertias``)
                           ``(njoints, 3, 3)``
``frame_joint``            ``(nframes,)``        parent joint of each frame (``model.frames[f].parentJoint``)
``fR fp``                  ``(nframes, 3, 3)``,  frame placement in its parent joint
                           ``(nframes, 3)``
``armature``               ``(nv,)``             rotor inertia added to the diagonal of the mass matrix
``gravity``                ``(6,)``              ``model.gravity`` (linear, then angular)
=========================  ====================  ===================================================================
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .joint_types import NV, NotLowerable, joint_arrays


class RigidBodyModel(NamedTuple):
    """The arrays of a lowered ``pinocchio.Model`` (see the module docstring)."""

    nq: int
    nv: int
    njoints: int
    nframes: int
    jtype: np.ndarray
    idx_q: np.ndarray
    idx_v: np.ndarray
    nvj: np.ndarray
    axis: np.ndarray
    parent: np.ndarray
    subtree_end: np.ndarray
    depth: np.ndarray
    dof_joint: np.ndarray
    dof_parent: np.ndarray
    jR: np.ndarray
    jp: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    frame_joint: np.ndarray
    fR: np.ndarray
    fp: np.ndarray
    armature: np.ndarray
    gravity: np.ndarray


class RigidBodyWorkspace(NamedTuple):
    """Preallocated arrays the kernels write into; every spatial quantity is in the world frame.

    ``oR (njoints, 3, 3)``, ``op (njoints, 3)``: joint placements ``oMi``.  ``oS (nv, 6)``: motion subspace
    columns, one row per velocity index.  ``ov oa (njoints, 6)``: spatial velocities and accelerations (at the
    world origin).  ``ow (njoints, 6)``: joint motion ``oS_i v_i``.  ``oI (njoints, 6, 6)``: body spatial
    inertias.  ``oh (njoints, 6)``: momenta ``oI ov``; ``oIa (njoints, 6)``: ``oI oa``.  ``of (njoints, 6)``:
    after a RNEA pass, the force each joint transmits (its subtree's net force).  ``oIc oBc (njoints, 6, 6)``:
    composite inertias and composite Coriolis maps; ``IcS BcS (nv, 6)``: ``Ic S`` and ``Bcᵀ S`` per dof (the
    last two for the derivatives).  ``M (nv, nv)``: mass matrix, armature included (as ``pinocchio.crba``);
    ``L (nv, nv)``: lower triangular, ``M = Lᵀ L``; ``dinv (nv,)``: ``1 / diag(L)``.  ``tau zero (nv,)``:
    scratch and a zero vector.  ``tmp (6, 6)``, ``Rf (3, 3)``, ``pf (3,)``: scratch (``Rf, pf``: the last frame
    placement a frame kernel computed).
    """

    oR: np.ndarray
    op: np.ndarray
    oS: np.ndarray
    ov: np.ndarray
    oa: np.ndarray
    ow: np.ndarray
    oI: np.ndarray
    oh: np.ndarray
    oIa: np.ndarray
    of: np.ndarray
    oIc: np.ndarray
    oBc: np.ndarray
    IcS: np.ndarray
    BcS: np.ndarray
    M: np.ndarray
    L: np.ndarray
    dinv: np.ndarray
    tau: np.ndarray
    zero: np.ndarray
    tmp: np.ndarray
    Rf: np.ndarray
    pf: np.ndarray


def lower_model(model: object) -> RigidBodyModel:
    """The :class:`RigidBodyModel` of a ``pinocchio.Model``.

    Raises
    ------
    NotLowerable
        If a joint type is not supported (see :func:`.joint_types.joint_arrays`) or a subtree is not a
        contiguous range of joint indices.
    """
    jtype, idx_q, idx_v, axis = joint_arrays(model)
    njoints, nv = model.njoints, model.nv
    parent = np.array([model.parents[i] for i in range(njoints)], dtype=np.int64)
    nvj = np.array([0] + [NV[int(t)] for t in jtype[1:]], dtype=np.int64)
    subtree_end = np.arange(1, njoints + 1, dtype=np.int64)
    for i in range(njoints - 1, 0, -1):
        subtree_end[parent[i]] = max(subtree_end[parent[i]], subtree_end[i])
    depth = np.zeros(njoints, dtype=np.int64)
    for i in range(1, njoints):
        if parent[i] >= i:
            raise NotLowerable(f"joint {model.names[i]!r} comes before its parent")
        depth[i] = depth[parent[i]] + 1
    for i in range(1, njoints):
        inside = [k for k in range(njoints) if _is_ancestor(parent, i, k)]
        if inside != list(range(i, subtree_end[i])):
            raise NotLowerable(f"the subtree of joint {model.names[i]!r} is not a contiguous range of joints")
    dof_joint = np.zeros(nv, dtype=np.int64)
    dof_parent = np.full(nv, -1, dtype=np.int64)
    for i in range(1, njoints):
        dof_joint[idx_v[i] : idx_v[i] + nvj[i]] = i
        dof_parent[idx_v[i] + 1 : idx_v[i] + nvj[i]] = np.arange(idx_v[i], idx_v[i] + nvj[i] - 1)
        if parent[i] > 0:
            dof_parent[idx_v[i]] = idx_v[parent[i]] + nvj[parent[i]] - 1
        if dof_parent[idx_v[i]] >= idx_v[i]:
            raise NotLowerable(f"joint {model.names[i]!r} has a velocity index before its parent's")
    placements = list(model.jointPlacements)
    inertias = list(model.inertias)
    frames = list(model.frames)
    return RigidBodyModel(
        nq=int(model.nq),
        nv=int(nv),
        njoints=int(njoints),
        nframes=len(frames),
        jtype=jtype,
        idx_q=idx_q,
        idx_v=idx_v,
        nvj=nvj,
        axis=axis,
        parent=parent,
        subtree_end=subtree_end,
        depth=depth,
        dof_joint=dof_joint,
        dof_parent=dof_parent,
        jR=np.array([m.rotation for m in placements], dtype=float).reshape(njoints, 3, 3),
        jp=np.array([m.translation for m in placements], dtype=float).reshape(njoints, 3),
        mass=np.array([b.mass for b in inertias], dtype=float),
        com=np.array([b.lever for b in inertias], dtype=float).reshape(njoints, 3),
        inertia=np.array([b.inertia for b in inertias], dtype=float).reshape(njoints, 3, 3),
        frame_joint=np.array([f.parentJoint for f in frames], dtype=np.int64),
        fR=np.array([f.placement.rotation for f in frames], dtype=float).reshape(len(frames), 3, 3),
        fp=np.array([f.placement.translation for f in frames], dtype=float).reshape(len(frames), 3),
        armature=np.array(model.armature, dtype=float).reshape(nv),
        gravity=np.array(model.gravity.vector, dtype=float).reshape(6),
    )


def _is_ancestor(parent: np.ndarray, i: int, k: int) -> bool:
    """True when joint ``i`` is ``k`` or one of its ancestors."""
    while k > i:
        k = parent[k]
    return k == i


def make_workspace(rb: RigidBodyModel) -> RigidBodyWorkspace:
    """A zeroed :class:`RigidBodyWorkspace` sized for ``rb``."""
    n, nv = rb.njoints, rb.nv
    return RigidBodyWorkspace(
        oR=np.zeros((n, 3, 3)),
        op=np.zeros((n, 3)),
        oS=np.zeros((nv, 6)),
        ov=np.zeros((n, 6)),
        oa=np.zeros((n, 6)),
        ow=np.zeros((n, 6)),
        oI=np.zeros((n, 6, 6)),
        oh=np.zeros((n, 6)),
        oIa=np.zeros((n, 6)),
        of=np.zeros((n, 6)),
        oIc=np.zeros((n, 6, 6)),
        oBc=np.zeros((n, 6, 6)),
        IcS=np.zeros((nv, 6)),
        BcS=np.zeros((nv, 6)),
        M=np.zeros((nv, nv)),
        L=np.zeros((nv, nv)),
        dinv=np.zeros(nv),
        tau=np.zeros(nv),
        zero=np.zeros(nv),
        tmp=np.zeros((6, 6)),
        Rf=np.zeros((3, 3)),
        pf=np.zeros(3),
    )


def declaring(base: type, name: str) -> tuple[type, ...]:
    """The classes derived from ``base`` in crocopy that define ``name`` themselves: the models that carry their own
    lowering (a subclass inherits none: it may override the maths)."""
    found, stack = [], [base]
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        if name in cls.__dict__ and cls.__module__.startswith("crocopy."):
            found.append(cls)
    return tuple(found)
