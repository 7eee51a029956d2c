"""The compiled rows of a node's constraint manager (see :mod:`.constraint_rows`).

A node with constraint rows lists, in its table (:mod:`.node_table`), a *constraint table*: ``c_ints``, a copy of
the node's integers whose residual items are the constraints' residuals (rows in ``cr``, Jacobians in ``cJx``,
``cJu``, every row with its ``u`` columns: ``U_START = 0``) and whose entries ``E_R``, ``E_JX``, ``E_JU`` have those
arrays' dimensions; and ``c_tbl``, the node's own buffer that :func:`constraint_table` fills with the node's
addresses, those three entries replaced by ``cr``, ``cJx``, ``cJu``.  The residual kernels of the cost items
(:func:`.residual_kernel.residual_rows`, ``residual_jacobians``) then evaluate the constraints' residuals on that
table, and :func:`stack_rows` stacks them as the manager does: the program ``c_rows`` (three integers per constraint,
in the manager's order of names: equality or not, first row in ``cr``, rows) puts each constraint's rows at the next
rows of ``g`` (inequality) or ``h`` (equality), the rows after the last zero; ``Gx, Gu`` and ``Hx, Hu`` likewise,
``Gu``/``Hu`` zero at the terminal node.  The rows go to the action data's arrays and to the differential data's
(which the manager's data shares).

The constraint table is rebuilt at every call from the node's own table (a node evaluated on another thread reads
that thread's workspace and scratch, :mod:`.node_threads`); a node is evaluated by one thread at a time, so its
buffer ``c_tbl`` is its own to write.
"""

from __future__ import annotations

from crocopy.kernels import compiled

from .node_table import (
    E_C_INTS,
    E_C_ROWS,
    E_C_TBL,
    E_CJU,
    E_CJX,
    E_CR,
    E_DG,
    E_DGU,
    E_DGX,
    E_DH,
    E_DHU,
    E_DHX,
    E_G,
    E_GU,
    E_GX,
    E_H,
    E_HU,
    E_HX,
    E_JU,
    E_JX,
    E_R,
    SHAPES,
    TERMINAL,
    ivec,
    mat,
    vec,
)


@compiled
def has_rows(ints) -> bool:
    """Whether the node has constraint rows to write (``g`` or ``h`` not empty; at the terminal node, maybe none of
    them a ``T_constraint`` one: then the program is empty and the rows are zero)."""
    return ints[SHAPES + 3 * E_G] + ints[SHAPES + 3 * E_H] > 0


@compiled
def constraint_table(tbl, ints):
    """``(c_tbl, c_ints)``: the node's constraint table, ``c_tbl`` filled from ``tbl`` (see the module docstring);
    both empty when the node has no constraint to evaluate."""
    ctbl, cints = ivec(tbl, ints, E_C_TBL), ivec(tbl, ints, E_C_INTS)
    if cints.shape[0]:
        for k in range(ctbl.shape[0]):
            ctbl[k] = tbl[k]
        ctbl[E_R], ctbl[E_JX], ctbl[E_JU] = tbl[E_CR], tbl[E_CJX], tbl[E_CJU]
    return ctbl, cints


@compiled
def _rows(src, dst, also, start, row, nr):
    """``dst[row:row+nr] = also[row:row+nr] = src[start:start+nr]`` (vectors or matrices' rows)."""
    for i in range(nr):
        dst[row + i] = src[start + i]
        also[row + i] = src[start + i]


@compiled
def _zero_after(a, b, row):
    """Rows ``row`` on of ``a`` and ``b`` set to zero."""
    for i in range(row, a.shape[0]):
        a[i] = 0.0
        b[i] = 0.0


@compiled
def stack_rows(tbl, ints, derivatives):
    """Stack the constraints' residual rows (and, if ``derivatives``, Jacobians) into ``g, h`` (``Gx, Gu, Hx, Hu``)
    of both datas by the program ``c_rows``; the rows after the last constraint's are zero."""
    prog, cr, cJx, cJu = ivec(tbl, ints, E_C_ROWS), vec(tbl, ints, E_CR), mat(tbl, ints, E_CJX), mat(tbl, ints, E_CJU)
    g, dg, h, dh = vec(tbl, ints, E_G), vec(tbl, ints, E_DG), vec(tbl, ints, E_H), vec(tbl, ints, E_DH)
    Gx, dGx, Gu, dGu = mat(tbl, ints, E_GX), mat(tbl, ints, E_DGX), mat(tbl, ints, E_GU), mat(tbl, ints, E_DGU)
    Hx, dHx, Hu, dHu = mat(tbl, ints, E_HX), mat(tbl, ints, E_DHX), mat(tbl, ints, E_HU), mat(tbl, ints, E_DHU)
    terminal = ints[TERMINAL] != 0
    ig = ih = 0
    for n in range(prog.shape[0] // 3):
        equality, start, nr = prog[3 * n] != 0, prog[3 * n + 1], prog[3 * n + 2]
        if equality:
            _rows(cr, h, dh, start, ih, nr)
            if derivatives:
                _rows(cJx, Hx, dHx, start, ih, nr)
                _rows(cJu, Hu, dHu, start, ih, nr)
            ih += nr
        else:
            _rows(cr, g, dg, start, ig, nr)
            if derivatives:
                _rows(cJx, Gx, dGx, start, ig, nr)
                _rows(cJu, Gu, dGu, start, ig, nr)
            ig += nr
    _zero_after(g, dg, ig)
    _zero_after(h, dh, ih)
    if derivatives:
        _zero_after(Gx, dGx, ig)
        _zero_after(Hx, dHx, ih)
        _zero_after(Gu, dGu, 0 if terminal else ig)
        _zero_after(Hu, dHu, 0 if terminal else ih)
