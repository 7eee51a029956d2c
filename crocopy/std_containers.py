"""Crocoddyl's C++ container types under their names, as the Python containers crocopy uses.

Crocoddyl exposes ``std::vector`` and ``std::map`` containers (``StdVec_ActionModel``,
``StdMap_CostItem``, ...).  crocopy holds the same things in Python lists, dicts and sets, so each
name is that Python type: ``crocopy.StdVec_ActionModel()`` is an empty list to ``append`` to,
``isinstance(costs.costs, crocopy.StdMap_CostItem)`` holds.  The vectors of models and datas are
lists with Crocoddyl's ``tolist()`` (a plain list of the same objects), as
``problem.runningModels`` and ``problem.runningDatas`` are.  The containers of arrays
(``StdVec_VectorXs``, ``StdVec_MatrixXs``, ``StdVec_RowMatrixX``) are lists with Crocoddyl's
``tolist()`` (:class:`~crocopy.solvers.std_vector.StdVec_VectorXs`).
"""

from __future__ import annotations

from .shooting import StdVec_ActionModel
from .solvers.std_vector import StdVec_VectorXs

StdVec_ActionData = StdVec_DiffActionModel = StdVec_DiffActionData = StdVec_ActionModel
StdVec_ControlParametrizationModel = StdVec_ControlParametrizationData = StdVec_ActionModel
StdVec_Callback = StdVec_Thruster = StdVec_ActionModel
StdVec_MatrixXs = StdVec_RowMatrixX = StdVec_VectorXs
StdMap_CostItem = StdMap_CostData = dict
StdMap_ConstraintItem = StdMap_ConstraintData = dict
StdMap_ContactItem = StdMap_ContactData = dict
StdMap_ImpulseItem = StdMap_ImpulseData = dict
StdSet_String = set
