"""The optics package's layout rules (issue 22): sizes, one reader of the environment."""

from __future__ import annotations

import ast
from pathlib import Path

import nirglucose.optics

_ROOT = Path(nirglucose.optics.__file__).parent
_MODULES = sorted(_ROOT.rglob("*.py"))

#: Limits of the issue: lines per module, code lines per function (docstring excluded)
#: unless its docstring says why it is longer ("on purpose").
_MAX_MODULE_LINES = 800
_MAX_FUNCTION_LINES = 60


def test_the_package_has_its_parts():
    names = {p.relative_to(_ROOT).as_posix() for p in _MODULES}
    for part in ("lut/grid.py", "lut/build.py", "lut/cache.py", "lut/interpolate.py",
                 "kernels/mc_white.py"):
        assert part in names
    # the validation solvers are the repository's, not the installed package's (issue 42)
    assert not any(n.startswith("reference/") for n in names)
    validation = _ROOT.parents[2] / "validation" / "nirglucose_reference"
    assert {"photon_engine.py", "lut_checks.py"} <= {p.name for p in validation.glob("*.py")}


def test_no_module_is_too_long():
    long = {p.name: n for p in _MODULES
            if (n := len(p.read_text().splitlines())) > _MAX_MODULE_LINES}
    assert long == {}


def test_no_function_is_too_long_without_a_reason():
    long = []
    for path in _MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            doc = ast.get_docstring(node) or ""
            first = node.body[0]
            skip = first.end_lineno - first.lineno + 1 if doc else 0
            code = node.end_lineno - node.lineno + 1 - skip
            if code > _MAX_FUNCTION_LINES and "on purpose" not in doc:
                long.append(f"{path.name}:{node.name} ({code} lines)")
    assert long == []


def test_only_the_environment_module_reads_the_environment():
    readers = []
    for path in _MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in ("environ", "getenv"):
                readers.append(path.relative_to(_ROOT).as_posix())
    assert sorted(set(readers)) == ["_environment.py"]
