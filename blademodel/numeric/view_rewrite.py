"""Write the per-contact kernel's buffer views out as offsets into the flat buffers.

The kernel's templates read their tables through *views* of four flat buffers
(``vec(R, I, R_GN, 4 * nc)``, ``wvec(WI, nc, WC_AC)``, ``R[I[R_KV]:]`` ...: see
:mod:`.contact_flow`), which document the layout. Compiled as written, each view is
an array slice, and Numba lowers a slice to bounds-normalizing code that costs
about 16 ms of compile time apiece (a template holds over 200). :func:`direct_views`
rewrites a template's source before it is compiled:

* a variable bound to a view and used only by subscripting (``X[i]``, ``X[i] = v``,
  ``X[i] += v``) becomes its offset, ``X_o = <offset> & NONNEG``, and every
  ``X[i]`` becomes ``buf[(X_o + i) & NONNEG]``;
* a view subscripted in place (``wvec(WI, nc, WC_MARK)[z]``) likewise;
* any other view (passed on as an argument, its ``shape`` read) stays a slice;
* ``law_offset(I, j)``, the offset of a contact's law states, is written out.

The masks (``& NONNEG``) let the compiler see that the indices are not negative
(:data:`~blademodel.numeric.contract.NONNEG`); every index in the templates is a
valid, non-negative position, so they change no value. The rewritten functions
compute what the templates say, element for element.
"""

from __future__ import annotations

import ast

#: The view helpers and their arguments: the buffer, then what fixes the offset and the length.
_HELPERS = {"vec": ("a", "I", "key", "size"), "wvec": ("WI", "nc", "k"), "wdof": ("WI", "nc", "n", "k"),
            "wrow": ("WI", "nc", "n", "ns", "k")}


def _expr(text: str) -> ast.expr:
    return ast.parse(text, mode="eval").body


def _view(node: ast.AST):
    """``(buffer, offset, length)`` of a view expression (length None for an open slice), or None."""
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _HELPERS:
        names = _HELPERS[node.func.id]
        if len(node.args) != len(names) or node.keywords:
            raise ValueError(f"view {ast.unparse(node)}: expected the arguments {', '.join(names)}")
        arg = dict(zip(names, (ast.unparse(a) for a in node.args)))
        kind = node.func.id
        if kind == "vec":
            return arg["a"], f"{arg['I']}[{arg['key']}]", arg["size"]
        base = "W_HEAD" if kind == "wvec" else f"W_HEAD + WC_COUNT * ({arg['nc']})"
        if kind == "wvec":
            return arg["WI"], f"{base} + ({arg['k']}) * ({arg['nc']})", arg["nc"]
        if kind == "wdof":
            return arg["WI"], f"{base} + ({arg['k']}) * ({arg['n']})", arg["n"]
        return arg["WI"], f"{base} + WD_COUNT * ({arg['n']}) + ({arg['k']}) * ({arg['ns']})", arg["ns"]
    if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and isinstance(node.slice, ast.Slice)
            and node.slice.lower is not None and node.slice.upper is None and node.slice.step is None):
        return node.value.id, ast.unparse(node.slice.lower), None
    return None


def _indexed(buffer: str, offset: str, index: ast.expr, ctx) -> ast.Subscript:
    """``buffer[(offset + index) & NONNEG]``."""
    if isinstance(index, ast.UnaryOp) and isinstance(index.op, ast.USub):
        raise ValueError(f"negative index {ast.unparse(index)} into a view of {buffer}")
    sub = _expr(f"{buffer}[({offset} + (__i)) & NONNEG]")
    sub.slice.left.right = index
    sub.ctx = ctx
    return sub


class _Parents(ast.NodeVisitor):
    def __init__(self):
        self.parent: dict = {}

    def generic_visit(self, node):
        for child in ast.iter_child_nodes(node):
            self.parent[child] = node
        super().generic_visit(node)


def _bound_views(fn: ast.FunctionDef) -> dict:
    """Variables of ``fn`` bound once, to a view: name -> (buffer, offset, length)."""
    bound: dict = {}
    count: dict = {}
    for node in ast.walk(fn):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            count[node.id] = count.get(node.id, 0) + 1
        if not isinstance(node, ast.Assign) or len(node.targets) != 1:
            continue
        tgt, val = node.targets[0], node.value
        pairs = (list(zip(tgt.elts, val.elts)) if isinstance(tgt, ast.Tuple) and isinstance(val, ast.Tuple)
                 and len(tgt.elts) == len(val.elts) else [(tgt, val)])
        for t, v in pairs:
            view = _view(v)
            if isinstance(t, ast.Name) and view is not None:
                bound[t.id] = view
    return {k: v for k, v in bound.items() if count.get(k) == 1}


def _rewrite_function(fn: ast.FunctionDef) -> None:
    parents = _Parents()
    parents.visit(fn)
    parent = parents.parent
    views = _bound_views(fn)
    # a view variable used other than by subscripting stays a view
    for node in ast.walk(fn):
        if isinstance(node, ast.Name) and node.id in views and isinstance(node.ctx, ast.Load):
            up = parent.get(node)
            if not (isinstance(up, ast.Subscript) and up.value is node and not isinstance(up.slice, ast.Slice)):
                views.pop(node.id)

    class Rewrite(ast.NodeTransformer):
        def visit_Assign(self, node):
            self.generic_visit(node)
            tgt, val = node.targets[0], node.value
            if isinstance(tgt, ast.Tuple) and isinstance(val, ast.Tuple) and len(tgt.elts) == len(val.elts):
                for k, t in enumerate(tgt.elts):
                    if isinstance(t, ast.Name) and t.id in views:
                        tgt.elts[k] = ast.Name(f"{t.id}_o", ast.Store())
                        val.elts[k] = _expr(f"({views[t.id][1]}) & NONNEG")
            elif isinstance(tgt, ast.Name) and tgt.id in views:
                node.targets[0] = ast.Name(f"{tgt.id}_o", ast.Store())
                node.value = _expr(f"({views[tgt.id][1]}) & NONNEG")
            return node

        def visit_Subscript(self, node):
            self.generic_visit(node)
            if isinstance(node.slice, ast.Slice):
                return node
            if isinstance(node.value, ast.Name) and node.value.id in views:
                return _indexed(views[node.value.id][0], f"{node.value.id}_o", node.slice, node.ctx)
            inner = _view(node.value)
            if inner is not None:
                return _indexed(inner[0], f"(({inner[1]}) & NONNEG)", node.slice, node.ctx)
            return node

        def visit_Call(self, node):
            self.generic_visit(node)
            if isinstance(node.func, ast.Name) and node.func.id == "law_offset":
                I, j = (ast.unparse(a) for a in node.args)
                return _expr(f"(2 * {I}[H_N] + {I}[({I}[O_CSO] + {j}) & NONNEG])")
            view = _view(node)
            if view is not None:   # passed on: the slice it returns
                buf, off, size = view
                return _expr(f"{buf}[{off}:{off} + ({size})]")
            return node

    Rewrite().visit(fn)


def direct_views(source: str) -> str:
    """``source`` (a template module) with its functions' views written out as offsets (see the module)."""
    tree = ast.parse(source)
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name not in (*_HELPERS, "law_offset"):
            _rewrite_function(node)
    ast.fix_missing_locations(tree)
    return ast.unparse(tree)
