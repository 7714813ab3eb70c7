"""Keys made of several id columns, each kept as wide as its data.

A leaf is named by its plant (or placement) and its leaf id, a vertex of a view by its vertex,
plant and leaf: grouping by such pairs must never pack them into one number (the plant id times
10,000 plus the leaf id attributes leaf 10,003 of plant 1 to plant 2, and a product of two
wide ranges overflows int64). :func:`groups` sorts the rows of the columns themselves, so any int64 ids
(negative ones, ids near 2^31, 10,000 leaves and more per plant) group exactly.
"""

from __future__ import annotations

import numpy as np


def groups(*columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of the id columns, and each row's group.

    Parameters
    ----------
    columns : each (N,) integers (any width; taken as int64)

    Returns
    -------
    keys : (K, len(columns)) int64, the distinct rows in lexicographic order (first column
        first)
    inverse : (N,) intp, the group (row of ``keys``) of each input row
    """
    cols = [np.asarray(c).astype(np.int64, copy=False).ravel() for c in columns]
    n = len(cols[0]) if cols else 0
    if any(len(c) != n for c in cols):
        raise ValueError("id columns of different lengths")
    if n == 0:
        return np.empty((0, len(cols)), np.int64), np.empty(0, np.intp)
    order = np.lexsort(cols[::-1])                   # the last key given is the primary one
    ranked = np.column_stack([c[order] for c in cols])
    new = np.ones(n, dtype=bool)
    new[1:] = np.any(ranked[1:] != ranked[:-1], axis=1)
    inverse = np.empty(n, dtype=np.intp)
    inverse[order] = np.cumsum(new) - 1
    return ranked[new], inverse


def group_rows(inverse: np.ndarray, n_groups: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each group's rows are: ``order[starts[k]:starts[k + 1]]`` are the rows of group k,
    in their input order.

    Returns
    -------
    order : (N,) intp, rows sorted by group (stable); starts : (K + 1,) intp
    """
    order = np.argsort(inverse, kind="stable")
    starts = np.searchsorted(inverse[order], np.arange(n_groups + 1))
    return order, starts
