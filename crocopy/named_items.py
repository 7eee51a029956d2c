"""Registries of named items with an ``active`` flag (costs, constraints, contacts, impulses).

A registry keeps ``self._items`` (name → item with an ``active`` attribute), reports
``active_set``/``inactive_set``, and calls ``_recount()`` after every change so it can refresh its
dimensions.  ``_kind`` names the items in error messages; ``_sorted`` keeps them ordered by name.
"""

from __future__ import annotations

from typing import Any


class NamedItems:
    """Shared bookkeeping of Crocoddyl's ``CostModelSum``/``ConstraintModelManager``/``Contact...Multiple``."""

    _kind = "item"
    _sorted = True
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
        """The item ``name`` (``KeyError`` if unknown)."""
        try:
            return self._items[name]
        except KeyError:
            raise KeyError(f"no {self._kind} named {name!r}") from None

    def _check_new_name(self, name: str) -> None:
        if name in self._items:
            article = "an" if self._kind[0] in "aeiou" else "a"
            raise ValueError(f"{article} {self._kind} named {name!r} already exists")

    def _insert(self, name: str, item: Any) -> None:
        self._check_new_name(name)
        self._items[name] = item
        if self._sorted:
            self._items = dict(sorted(self._items.items()))
        self._recount()

    def _remove(self, name: str) -> None:
        self._get(name)
        del self._items[name]
        self._recount()

    def _set_active(self, name: str, active: bool) -> None:
        self._get(name).active = bool(active)
        self._recount()
