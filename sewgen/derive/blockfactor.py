"""Φ_q factored block by block, as C lines of the motion and rates kernels, their SIMD twins and Newton's LU.

Φ_q is block lower triangular in the loops' solving order (:func:`sewgen.derive.branches.blocks`: each loop reads
the coordinates of its own and of earlier loops). A mechanism that Newton solves (no closed form) factors each
diagonal block alone and solves by forward block substitution, reading only Φ_q's structural non-zeros, where
the runtime's dense factor (``sg_factor_eq_inl``) took all n × n entries: the JB1-3 feed's 7 × 7 (blocks 3, 2,
1, 1) is most of the machine's analysis. The SIMD twins print the same lines lane by lane (``vector=True``),
so they give the scalar kernels' values to the bit.

The scaling is the dense factor's (csrc/sg_runtime.h): E = R A C, rows by ``rs`` (each loop's size), each column
to its largest entry 1. A 1 × 1 block is its reciprocal; a larger one the runtime's pivoted LU
(``sg_lu_bound_inl``: pivots below SG_PIVOT_RTOL are singular, with its comparison-matrix bound of
||D_k^-1||_inf). Since det E is the product of the blocks' determinants, a block singular to the tolerance is
the position's singularity. The condition estimate stays an upper bound of ||E||_inf ||E^-1||_inf: for
x = E^-1 b with ||b||_inf <= 1, block k's x_k = D_k^-1 (b_k - sum_{j<k} E_kj x_j), so by induction
||x_k||_inf <= t_k = ||D_k^-1|| (1 + max_{r in block k} sum_c |E_rc| t_{block(c)}) (the bound of block forward
substitution, e.g. Higham, *Accuracy and Stability of Numerical Algorithms*, §13.1), and ||E^-1||_inf <= max_k
t_k. For a single block this is the dense factor's own bound.
"""
from __future__ import annotations

from dataclasses import dataclass


def _block_of_col(pairs) -> dict:
    """Each coordinate's block (its index in ``pairs``, (rows, cols) pairs in solving order)."""
    return {c: k for k, (_rows, cols) in enumerate(pairs) for c in cols}


@dataclass(frozen=True)
class BlockFactor:
    """Φ_q's structure (``nonzero[i][j]``: entry (i, j) is not identically 0) and its diagonal blocks in solving
    order (``blocks``: (rows, cols) pairs, cols the coordinates each block solves for)."""

    n: int
    nonzero: tuple
    blocks: tuple

    @classmethod
    def of(cls, n: int, jacobian: list, blocks: list) -> "BlockFactor | None":
        """The block factor of Φ_q (``jacobian``: n × n entries, row-major, SymPy; ``blocks``: objects with
        ``rows`` and ``cols``), or None where it would gain nothing or does not apply: a single block, or a row
        that reads a coordinate of a later block (then the dense factor)."""
        if n == 0 or len(blocks) < 2:
            return None
        nonzero = tuple(tuple(jacobian[i * n + j] != 0 for j in range(n)) for i in range(n))
        if not all(any(row[j] for row in nonzero) for j in range(n)):
            return None  # a coordinate no loop reads: structurally singular (the dense factor says so per position)
        pairs = tuple((tuple(b.rows), tuple(b.cols)) for b in blocks)
        block_of_col = _block_of_col(pairs)
        if sorted(block_of_col) != list(range(n)) or sorted(r for rows, _ in pairs for r in rows) != list(range(n)):
            return None
        for k, (rows, _cols) in enumerate(pairs):
            for r in rows:
                if any(nonzero[r][c] and block_of_col[c] > k for c in range(n)):
                    return None
        return cls(n, nonzero, pairs)

    def _at(self, i: int, j: int) -> str:
        return f"J[{i * self.n + j}]"

    def _earlier(self, k: int) -> list[int]:
        """The coordinates of the blocks before block k."""
        return [c for _rows, cols in self.blocks[:k] for c in cols]

    def factor_lines(self, vector: bool = False) -> list[str]:
        """Scale J (rows by rs, columns into cs: 1/m_j, then m_j, as sg_factor_eq_inl), factor each diagonal block,
        set *cond; return SG_SINGULAR from the kernel where a column is empty or not finite, a block is singular or
        the bound is not finite.
        ``vector``: the SIMD twin's lines (csrc/sg_simd.h), the same operations lane by lane, so the same values
        to the bit; a lane that fails a test is cleared from the mask ``ok`` instead."""
        n, nz, at = self.n, self.nonzero, self._at
        real, fabs = ("sg_vd", "sgv_fabs") if vector else ("double", "fabs")
        zero = "sgv_set1(0.0)" if vector else "0.0"

        def fail_unless(test: str) -> str:
            return f"ok &= {test};" if vector else f"if (!({test})) return SG_SINGULAR;"

        def keep_max(m: str, v: str) -> str:  # m = v where v > m or v is NaN (NaN propagates)
            return f"{m} = sgv_select(~({v} <= {m}), {v}, {m});" if vector else f"if (!({v} <= {m})) {m} = {v};"

        lines = ["sg_vm ok = sgv_true();" if vector else "*cond = INFINITY;",
                 "/* Φ_q by its diagonal blocks (sewgen/derive/blockfactor.py) */"]
        lines += [f"{at(i, j)} *= rs[{i}];" for i in range(n) for j in range(n) if nz[i][j]]
        for j in range(n):
            col = [at(i, j) for i in range(n) if nz[i][j]]  # never empty (of)
            lines += ["{", f"    {real} m = {zero}, v;"]
            for e in col:
                lines.append(f"    v = {fabs}({e}); {keep_max('m', 'v')}")
            test = ("(m > sgv_set1(0.0)) & (m < sgv_set1(INFINITY))" if vector
                    else "m > 0.0 && m < INFINITY")
            lines += [f"    {fail_unless(test)}", f"    cs[{j}] = 1.0 / m;", f"    cs[{n + j}] = m;"]
            lines += [f"    {e} *= cs[{j}];" for e in col] + ["}"]
        lines.append(f"{real} anorm = {zero};")
        for i in range(n):
            terms = " + ".join(f"{fabs}({at(i, j)})" for j in range(n) if nz[i][j])
            lines.append(f"{{ const {real} s = {terms}; {keep_max('anorm', 's')} }}")
        block_of_col = _block_of_col(self.blocks)
        for k, (rows, cols) in enumerate(self.blocks):
            s = len(rows)
            lines.append(f"{real} bound{k};")
            lines.append("{")
            if s == 1:
                d = at(rows[0], cols[0])
                pivot = f"{fabs}({d}) > " + ("sgv_set1(SG_PIVOT_RTOL)" if vector else "SG_PIVOT_RTOL")
                lines += [f"    {fail_unless(pivot)}", f"    {d} = 1.0 / {d};", f"    const {real} inv = {fabs}({d});"]
            else:
                lines += [f"    F{k}[{a * s + b}] = {at(r, c) if nz[r][c] else zero};"
                          for a, r in enumerate(rows) for b, c in enumerate(cols)]
                lines.append(f"    {real} inv;")
                lines.append(f"    ok &= sgv_lu_bound({s}, F{k}, P{k}, &inv);" if vector else
                             f"    if (sg_lu_bound_inl({s}, F{k}, P{k}, &inv) != SG_OK) return SG_SINGULAR;")
            lines.append(f"    {real} u = {zero};")
            for r in rows:
                terms = [f"{fabs}({at(r, c)}) * bound{block_of_col[c]}" for c in self._earlier(k) if nz[r][c]]
                if terms:
                    lines.append(f"    {{ const {real} s = {' + '.join(terms)}; {keep_max('u', 's')} }}")
            lines += [f"    bound{k} = inv * (1.0 + u);", "}"]
        lines.append(f"{real} inorm = bound0;")
        lines += [keep_max("inorm", f"bound{k}") for k in range(1, len(self.blocks))]
        if vector:
            return lines + ["*cond = anorm * inorm;", "ok &= sgv_isfinite(*cond);"]
        return lines + ["*cond = anorm * inorm;", "if (!isfinite(*cond)) return SG_SINGULAR;"]

    def declarations(self, vector: bool = False) -> list[str]:
        """Each block's factor and interchanges (blocks of two or more rows)."""
        real, index = ("sg_vd", "sg_vm") if vector else ("double", "int")
        return [f"{real} F{k}[{len(rows) ** 2}]; {index} P{k}[{len(rows)}];"
                for k, (rows, _cols) in enumerate(self.blocks) if len(rows) > 1]

    def _substitution(self, a: str, b: str, row, block, result, real: str = "double") -> list[str]:
        """Forward block substitution over Φ_q's structure, the one loop of both solves: block after block, each
        row's right side ``row(r)`` less ``a``'s coupling entries (the stored Φ_q) times the earlier blocks' y; a
        1 × 1 block then times its stored reciprocal, a larger one by the lines ``block(k, rows, cols)`` gives
        (its declarations, the solve of v in place); b[c] = ``result(c)``."""
        n, nz = self.n, self.nonzero
        at = lambda i, j: f"{a}[{i * n + j}]"  # noqa: E731
        lines = [f"{real} y[{n}];"]
        for k, (rows, cols) in enumerate(self.blocks):
            earlier = self._earlier(k)
            rhs = [row(r) + "".join(f" - {at(r, c)} * y[{c}]" for c in earlier if nz[r][c]) for r in rows]
            if len(rows) == 1:
                lines.append(f"y[{cols[0]}] = ({rhs[0]}) * {at(rows[0], cols[0])};")
                continue
            setup, solve = block(k, rows, cols)
            lines += ["{", *setup, *(f"    v[{p}] = {e};" for p, e in enumerate(rhs)), solve]
            lines += [f"    y[{c}] = v[{p}];" for p, c in enumerate(cols)] + ["}"]
        return lines + [f"{b}[{c}] = {result(c)};" for c in range(self.n)]

    def solve_lines(self, b: str, vector: bool = False) -> list[str]:
        """``b`` (indexed by closure row) overwritten by Φ_q^-1 b (indexed by coordinate) with the factor above:
        y = E^-1 (R b) block after block, then b = C y (``vector``: the SIMD twin's, lane by lane)."""
        real, apply = ("sg_vd", "sgv_lu_apply") if vector else ("double", "sg_lu_apply_inl")
        lines = self._substitution(
            "J", b, lambda r: f"{b}[{r}] * rs[{r}]",
            lambda k, rows, _cols: ([f"    {real} v[{len(rows)}];"],
                                    f"    {apply}({len(rows)}, F{k}, P{k}, v);"),
            lambda c: f"y[{c}] * cs[{c}]", real)
        return ["{"] + [f"    {line}" for line in lines] + ["}"]

    def _offsets(self) -> list[int]:
        """Each block's first entry in the pivot vector."""
        out, k = [], 0
        for rows, _cols in self.blocks:
            out.append(k)
            k += len(rows)
        return out

    def newton_factor_lines(self, vector: bool = False) -> list[str]:
        """Newton's factor (kernel 'lu_factor': a, piv) of the raw Φ_q: each diagonal block in place by the
        runtime's pivoted LU, a pivot singular below SG_PIVOT_RTOL times the largest |entry| of its column in
        all of Φ_q (the dense factor's test); the coupling entries stay as they are. Block k's interchanges at
        piv[first row of k ...]. Each pivot is stored as its reciprocal (sg_lu_apply_inl's form), which the
        factor has computed anyway: the solve multiplies, no division on Newton's path. ``vector``: the SIMD
        twin (sgv_newton's), the same operations lane by lane; it returns the mask of the lanes the
        scalar factor accepts."""
        n, nz = self.n, self.nonzero
        a = lambda i, j: f"a[{i * n + j}]"  # noqa: E731
        real, fabs = ("sg_vd", "sgv_fabs") if vector else ("double", "fabs")
        lines = ["sg_vm ok = sgv_true();"] if vector else []
        for j in range(n):
            lines.append(f"{real} cm{j} = {'sgv_set1(0.0)' if vector else '0.0'};")
            keep = (f"cm{j} = sgv_select(v > cm{j}, v, cm{j});" if vector else f"if (v > cm{j}) cm{j} = v;")
            lines += [f"{{ const {real} v = {fabs}({a(i, j)}); {keep} }}" for i in range(n) if nz[i][j]]
        for (rows, cols), off in zip(self.blocks, self._offsets()):
            s = len(rows)
            if s == 1:
                d = a(rows[0], cols[0])
                test = f"{fabs}({d}) > SG_PIVOT_RTOL * cm{cols[0]}"
                lines += [f"ok &= {test};" if vector else f"if (!({test})) return SG_SINGULAR;", f"{d} = 1.0 / {d};"]
                continue
            columns = ", ".join(f"cm{c}" for c in cols)
            zero = "sgv_set1(0.0)" if vector else "0.0"
            lines += ["{", f"    {real} M[{s * s}];", f"    const {real} cm[{s}] = {{{columns}}};"]
            lines += [f"    M[{p * s + q}] = {a(r, c) if nz[r][c] else zero};"
                      for p, r in enumerate(rows) for q, c in enumerate(cols)]
            lines.append(f"    ok &= sgv_lu_factor_cm({s}, M, piv + {off}, cm);" if vector else
                         f"    if (sg_lu_factor_cm_inl({s}, M, piv + {off}, cm, NULL) != SG_OK) return SG_SINGULAR;")
            lines += [f"    {a(r, c)} = M[{p * s + q}];" if p != q else f"    {a(r, c)} = 1.0 / M[{p * s + q}];"
                      for p, r in enumerate(rows) for q, c in enumerate(cols)]
            lines.append("}")
        return lines + ["return ok;" if vector else "return SG_OK;"]

    def newton_solve_lines(self, vector: bool = False) -> list[str]:
        """Newton's solve (kernel 'lu_solve': lu, piv, b) with the factor above: forward block substitution, b
        (indexed by closure row) overwritten by the solution (indexed by coordinate). ``vector``: the SIMD
        twin's lines."""
        n, offsets = self.n, self._offsets()
        real, apply = ("sg_vd", "sgv_lu_apply") if vector else ("double", "sg_lu_apply_inl")

        def block(k, rows, cols):
            s = len(rows)
            gather = [f"    M[{p * s + q}] = lu[{r * n + c}];" for p, r in enumerate(rows) for q, c in enumerate(cols)]
            return [f"    {real} M[{s * s}], v[{s}];", *gather], f"    {apply}({s}, M, piv + {offsets[k]}, v);"

        return self._substitution("lu", "b", lambda r: f"b[{r}]", block, lambda c: f"y[{c}]", real)

    def ops(self) -> int:
        """Floating-point operations of the factor and two solves (the kernel's op count)."""
        nnz = sum(map(sum, self.nonzero))
        dense = sum(2 * len(rows) ** 3 // 3 + 2 * len(rows) ** 2 for rows, _c in self.blocks)
        return 5 * nnz + dense + 2 * (2 * nnz + 2 * self.n)
