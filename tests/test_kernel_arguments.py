"""Kernels take bundles, not long argument lists: no function of psph/kernels takes more
than 12 positional arguments (the fields and parameters beyond that travel as the named
tuples of `psph/kernels/bundles.py`)."""

import ast
from pathlib import Path

KERNELS = Path(__file__).resolve().parents[1] / "psph" / "kernels"
MOST = 12


def long_signatures(source: str, name: str = "<source>") -> list[str]:
    """'name:line function (count)' of each function with more than MOST positional
    arguments."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef):
            count = len(node.args.posonlyargs) + len(node.args.args)
            if count > MOST:
                out.append(f"{name}:{node.lineno} {node.name} ({count})")
    return out


def test_no_kernel_over_twelve_positional_arguments():
    found = [hit for path in sorted(KERNELS.glob("*.py"))
             for hit in long_signatures(path.read_text(), path.name)]
    assert found == [], "\n".join(found)


def test_the_check_sees_a_long_signature():
    args = ", ".join(f"a{i}" for i in range(13))
    assert long_signatures(f"def f({args}):\n    pass\n") == ["<source>:1 f (13)"]
    assert long_signatures("def g(a, b, *, c, d, e, f, g, h, i, j, k, l, m, n):\n  pass\n") == []
