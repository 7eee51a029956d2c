"""Pickling the Pinocchio objects that crocopy's data hold (registered with :mod:`copyreg`).

* ``pinocchio.ProximalSettings`` (contact dynamics settings) has no pickle support: it is
  pickled by its four parameters.
* ``pinocchio.Data`` pickles, but an unpickled ``Data`` lacks work buffers that the Cholesky
  factorisation of the mass matrix uses (``cholesky.decompose``, ``impulseDynamics`` and the
  contact dynamics then crash; measured with pin 4.0 and 4.1).  A ``Data`` is therefore unpickled
  into ``model.createData()`` of a model with the same structure: the models of crocopy's states
  are remembered (weakly) for that, and the model travels in the pickle.  A ``Data`` of a model
  crocopy has not seen keeps Pinocchio's own pickling.

``copy.deepcopy`` of a ``Data`` uses Pinocchio's copy constructor and needs none of this.
"""

from __future__ import annotations

import copyreg
import weakref

import pinocchio as pin

_models: list[list] = []  # [weakref to a pin.Model, structure of its datas or None until needed]


def remember_model(model: pin.Model) -> None:
    """Remember ``model`` (weakly) so that its datas can be pickled safely."""
    _models[:] = [entry for entry in _models if entry[0]() is not None]
    if not any(entry[0]() is model for entry in _models):
        _models.append([weakref.ref(model), None])


def _structure(data: pin.Data) -> tuple:
    """What the allocation of a ``Data`` depends on: joint types, tree shape and frame count."""
    kinds = tuple(j.shortname().removeprefix("JointData") for j in data.joints)
    return kinds, tuple(data.lastChild), tuple(data.nvSubtree), len(data.oMf), data.M.shape[0]


def _model_of(data: pin.Data) -> pin.Model | None:
    """A remembered model whose datas have ``data``'s structure, or ``None``."""
    wanted = _structure(data)
    for entry in _models:
        model = entry[0]()
        if model is None:
            continue
        if entry[1] is None:
            entry[1] = _structure(model.createData())
        if entry[1] == wanted:
            return model
    return None


def _restore_data(model: pin.Model, state: tuple) -> pin.Data:
    """A ``Data`` allocated by ``model`` holding the pickled values ``state``."""
    remember_model(model)
    data = model.createData()
    data.__setstate__(state)
    return data


def _reduce_data(data: pin.Data) -> tuple:
    model = _model_of(data)
    reduced = data.__reduce__()
    if model is None:
        return reduced
    return _restore_data, (model, reduced[2])


def _reduce_proximal_settings(settings: pin.ProximalSettings) -> tuple:
    return pin.ProximalSettings, (
        settings.absolute_accuracy,
        settings.relative_accuracy,
        settings.mu,
        settings.max_iter,
    )


copyreg.pickle(pin.Data, _reduce_data)
copyreg.pickle(pin.ProximalSettings, _reduce_proximal_settings)
