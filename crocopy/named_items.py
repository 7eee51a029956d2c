"""Registries of named items with an ``active`` flag (costs, constraints, contacts, impulses).

A registry keeps ``self._items`` (name → item with an ``active`` attribute), reports
``active_set``/``inactive_set``, and calls ``_recount()`` after every change so it can refresh its
dimensions; every change also touches the registry (:func:`crocopy.versioning.touch`) for the data
that cache what it holds.  ``_kind`` names the items in error messages; items are kept ordered by
name, as in Crocoddyl.
"""

from __future__ import annotations

from typing import Any

from .state import StateAbstract
from .validation import ArgumentTypeError, as_bool, as_name
from .versioning import Parametrized, structure_changed, touch


def article(word: str) -> str:
    """The indefinite article of ``word`` ("a" or "an")."""
    return "an" if word[0].lower() in "aeiou" else "a"


class NamedItems:
    """Shared bookkeeping of Crocoddyl's ``CostModelSum``/``ConstraintModelManager``/``Contact...Multiple``."""

    _kind = "item"
    _items: dict[str, Any]

    @property
    def active_set(self) -> set[str]:
        """Names of the active items."""
        return {n for n, item in self._items.items() if item.active}

    @property
    def inactive_set(self) -> set[str]:
        """Names of the inactive items."""
        return {n for n, item in self._items.items() if not item.active}

    def _recount(self) -> None:
        raise NotImplementedError

    def _get(self, name: str) -> Any:
        """The item ``name`` (``KeyError`` if unknown, :class:`ArgumentTypeError` if not a str)."""
        as_name(name, "name")
        try:
            return self._items[name]
        except KeyError:
            raise KeyError(f"no {self._kind} named {name!r}") from None

    def _check_new_name(self, name: str) -> None:
        if not isinstance(name, str):
            raise ArgumentTypeError(f"name of the {self._kind} must be a str, got {type(name).__name__}")
        if name in self._items:
            raise ValueError(f"{article(self._kind)} {self._kind} named {name!r} already exists")

    def _insert(self, name: str, item: Any) -> None:
        self._check_new_name(name)
        self._items[name] = item
        self._items = dict(sorted(self._items.items()))
        self._changed()

    def _remove(self, name: str) -> None:
        self._get(name)
        del self._items[name]
        self._changed()

    def _set_active(self, name: str, active: bool) -> None:
        self._get(name).active = as_bool(active, "active")
        self._changed()

    def _changed(self, structural: bool = True) -> None:
        """Recount and touch; ``structural``: the datas made before have the wrong shape (see
        :func:`crocopy.versioning.structure_changed`)."""
        self._recount()
        touch(self)
        if structural:
            structure_changed(self)


class ModelItems(Parametrized, NamedItems):
    """Named models on one state and control dimension ``nu`` (cost sums, constraint managers, contact
    and impulse sets).

    Subclasses set ``_kind``, ``_model_type`` (the class every item's model derives from) and may
    narrow :meth:`_check_state` and :meth:`_state_mismatch`.

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension of every item (default ``state.nv``).
    """

    _read_only = frozenset({"state"})

    _model_type: type = object

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        self.state = self._check_state(state)
        self.nu = state.nv if nu is None else int(nu)
        if self.nu < 0:
            raise ValueError(f"nu must be non-negative, got {self.nu}")
        self._items = {}
        self._recount()

    @staticmethod
    def _check_state(state: StateAbstract) -> StateAbstract:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        return state

    def _state_mismatch(self, state: StateAbstract) -> str | None:
        """Why an item built on ``state`` does not fit here, or ``None``."""
        if state.nx != self.state.nx or state.ndx != self.state.ndx:
            return "a state of another dimension"
        return None

    def _check_model(self, name: str, model: Any) -> None:
        """Check that ``model`` may join under ``name``.

        Raises
        ------
        ValueError
            If ``model`` is not a ``_model_type``, ``name`` is taken, or ``model`` has another ``nu``
            or does not fit the state.
        """
        kind = self._kind
        if not isinstance(model, self._model_type):
            expected = self._model_type.__name__
            raise ValueError(f"{kind} must be {article(expected)} {expected}, got {type(model).__name__}")
        self._check_new_name(name)
        if model.nu != self.nu:
            raise ValueError(f"{kind} {name!r} has nu = {model.nu}, expected nu = {self.nu}")
        mismatch = self._state_mismatch(model.state)
        if mismatch is not None:
            raise ValueError(f"{kind} {name!r} was built on {mismatch}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(" + ", ".join(f"{n}: {item!r}" for n, item in self._items.items()) + ")"
