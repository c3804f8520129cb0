"""Branch identity and loop sizes of a mechanism, from the structure of its loop-closure equations.

**Blocks.** Φ_q, permuted, is block lower-triangular: solve the first block's coordinates from its equations,
then the next block's given those, and so on (Dulmage–Mendelsohn: a perfect matching of equations to
coordinates, then the strongly connected components of the dependency graph, in topological order). A dyad is
one 2 × 2 block (its closing joint's two equations in its two links' coordinates), a slot or cam contact whose
pin is already placed a 1 × 1 block, a loop that does not split (the feed fork, cam and stitch block) one larger
block. Each block is a small problem with discrete solutions — the assembly branches of that closing triangle
— and the sign of its determinant tells them apart: it changes only where the block is singular, where two
branches meet. The runtime (csrc/sg_runtime.c) checks the signs of every block at every position Newton solves,
against those of the sweep's first position, so no loop flips unseen — det Φ_q alone, the product of the block
determinants, misses two blocks flipping together.

A block's value is its determinant over the product of its rows' norms in the whole Φ_q (Hadamard: in
[-1, 1]; near 0 means near a singular position of that loop), so it also measures how far the position is
from the toggle of that loop.

**Loop sizes.** Each equation's own size: the sum of the magnitudes of its terms, with every cos and sin taken
as 1 — the lengths (and the slider travels) of the loop that equation closes, nothing outside it. Newton stops
when every equation's residual is below a relative tolerance times its own size (angle equations: 1 rad).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .kinematics import Kinematics


@dataclass
class Block:
    rows: list  # closure equation indices
    cols: list  # coordinate indices, matched to rows in order
    joints: list  # closing joints of the rows, in order of first appearance


def _structure(kin: Kinematics) -> list[set]:
    n = len(kin.q)
    return [{j for j in range(n) if kin.jac_q[i, j] != 0} for i in range(n)]


def _matching(struct: list[set], n: int) -> list | None:
    """A perfect matching row -> column (augmenting paths), or None when Φ_q is structurally singular."""
    col_of_row = [-1] * n
    row_of_col = [-1] * n

    def augment(i, seen):
        for j in sorted(struct[i]):
            if j in seen:
                continue
            seen.add(j)
            if row_of_col[j] < 0 or augment(row_of_col[j], seen):
                row_of_col[j], col_of_row[i] = i, j
                return True
        return False

    for i in range(n):
        if not augment(i, set()):
            return None
    return col_of_row


def _components(struct: list[set], col_of_row: list) -> list[list]:
    """Strongly connected components of 'row i needs the row matched to column j' (Tarjan), in solving order."""
    n = len(struct)
    row_of_col = {j: i for i, j in enumerate(col_of_row)}
    succ = [sorted(row_of_col[j] for j in struct[i] if row_of_col[j] != i) for i in range(n)]
    index, low, on, stack, comps = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in succ[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(sorted(comp))

    for v in range(n):
        if v not in index:
            visit(v)
    return comps  # Tarjan emits a component after everything it needs: solving order


def blocks(kin: Kinematics) -> list[Block]:
    """The diagonal blocks of Φ_q in solving order (one block of everything if Φ_q is structurally singular)."""
    n = len(kin.q)
    if n == 0:
        return []
    struct = _structure(kin)
    match = _matching(struct, n)
    comps = _components(struct, match) if match is not None else [list(range(n))]
    out = []
    for rows in comps:
        cols = [match[i] for i in rows] if match is not None else list(range(n))
        joints = []
        for i in rows:
            j = kin.closure_names[i].rsplit(".", 1)[0]
            if j not in joints:
                joints.append(j)
        out.append(Block(rows, cols, joints))
    return out


def row_scales(kin: Kinematics) -> list[sp.Expr]:
    """Each closure equation's own size (see the module docstring): lengths in m; an angle equation 1 (rad)."""
    out = []
    for name, expr in zip(kin.closure_names, kin.closure):
        if name.endswith(".angle"):
            out.append(sp.S.One)
            continue
        total = sp.S.Zero
        for term in sp.Add.make_args(sp.expand(expr)):
            trig = {f: sp.S.One for f in term.atoms(sp.sin, sp.cos)}
            total += sp.Abs(term.xreplace(trig))
        out.append(total if total != 0 else sp.S.One)
    return out
