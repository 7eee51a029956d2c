"""The compiled node's table is declared once (:mod:`crocopy.models.rbd.node_table`): indices, scratch and checks
come from the declaration, and every kernel reads each entry with an accessor of its dimension and dtype."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from crocopy.models.rbd import node_table as table
from crocopy.models.rbd.contact_kernel import ContactWorkspace

KERNELS = sorted(Path(table.__file__).parent.glob("*.py"))
ACCESSOR = re.compile(r"\b(vec|mat|cube|ivec)\(\s*tbl\s*,\s*ints\s*,\s*(?:table\.)?(E_[A-Z0-9_]+)\s*\)")
"""An accessor applied to an entry, ``mat(tbl, ints, E_FX)`` (or ``table.mat(tbl, ints, table.E_FX)``)."""
DIMENSION = {"vec": (1, np.float64), "mat": (2, np.float64), "cube": (3, np.float64), "ivec": (1, np.int64)}
SIZES = {"nq": 7, "nv": 6, "nx": 13, "ndx": 12, "nu": 4, "nr": 9, "nr_u": 4, "n_stack": 3, "nc": 6, "n_contacts": 2,
         "n_kin": 40, "nr_user": 1, "n_stamp": 19, "ng": 5, "nh": 3, "nrc": 8, "n_tbl": 120, "n_c_ints": 500,
         "n_c_rows": 6, "n_cols": 16}


def test_every_entry_has_one_generated_index():
    entries = table.NODE_ARRAYS + table.SCRATCH_ARRAYS
    assert len({e.name for e in entries}) == len(entries)
    assert [table.ENTRIES[e.name] for e in entries] == list(range(table.NODE, table.NODE + len(entries)))
    for e in entries:
        assert getattr(table, "E_" + e.name.upper()) == table.ENTRIES[e.name]
    assert [e.name[1:] for e in entries if e.owner == "contact workspace"] == list(ContactWorkspace._fields)


def test_every_accessor_a_kernel_applies_has_the_entry_dimension_and_dtype():
    declared = {"E_" + e.name.upper(): e for e in table.NODE_ARRAYS + table.SCRATCH_ARRAYS}
    uses = []
    for path in KERNELS:
        for accessor, name in ACCESSOR.findall(path.read_text()):
            entry = declared[name]  # an undeclared name raises KeyError here
            uses.append((path.name, accessor, name))
            assert (len(entry.shape), entry.dtype) == DIMENSION[accessor], (path.name, accessor, name)
    assert len(uses) > 40
    assert any(path == "rk_node_kernel.py" for path, _, _ in uses)


def test_the_scratch_is_made_from_the_declaration():
    arrays = table.make_arrays(table.SCRATCH_ARRAYS, SIZES)
    assert arrays["rows"].shape == (6, 16) and arrays["cY"].shape == (6, 6) and arrays["cG"].shape == (6, 6)
    assert table.make_arrays(table.SCRATCH_ARRAYS, {**SIZES, "nc": 0})["cG"].shape == (1, 1)
    table.check_arrays(table.SCRATCH_ARRAYS, [arrays[e.name] for e in table.SCRATCH_ARRAYS], SIZES)


@pytest.mark.parametrize(("name", "bad", "given"), [
    ("Fx", np.zeros((12, 11)), r"float64 array of shape \(12, 11\)"),
    ("Lu", np.zeros(4, dtype=np.int64), r"int64 array of shape \(4,\)"),
    ("Lxx", np.zeros((12, 24))[:, ::2], r"float64 array of shape \(12, 12\), not C-contiguous"),
    ("user_dims", np.zeros(5), r"float64 array of shape \(5,\)"),
    ("ref_R", [[0.0]], "list"),
])
def test_a_wrong_node_array_is_refused_naming_its_entry(name, bad, given):
    arrays = table.make_arrays(table.NODE_ARRAYS, SIZES)
    arrays[name] = bad
    entry = next(e for e in table.NODE_ARRAYS if e.name == name)
    with pytest.raises(ValueError, match=rf"entry '{name}' \({entry.owner}\) must be .*got a {given}"):
        table.check_arrays(table.NODE_ARRAYS, [arrays[e.name] for e in table.NODE_ARRAYS], SIZES)
