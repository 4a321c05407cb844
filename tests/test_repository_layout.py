"""The repository's script folders keep one job each (issue 42): ``benchmarks/`` holds
speed checks that print one JSON object, ``studies/`` research scripts and their
records, ``tools/`` what writes the package's data; the reference solvers
(``validation/``) ship with none of them in the installed package."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _scripts(folder: str) -> list[Path]:
    return sorted(p for p in (ROOT / folder).glob("*.py") if not p.name.startswith("_"))


def test_every_speed_benchmark_prints_one_json_object():
    scripts = _scripts("benchmarks")
    assert len(scripts) >= 5
    for path in scripts:
        tree = ast.parse(path.read_text())
        dumps = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
                 and getattr(n.func, "attr", None) == "dumps"
                 and getattr(n.func.value, "id", None) == "json"]
        assert dumps, f"{path.name} prints no JSON object: a speed check belongs in benchmarks/"


def _code_strings(path: Path) -> set[str]:
    """The string constants of a script's code (docstrings left out)."""
    tree = ast.parse(path.read_text())
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, ast.Module | ast.FunctionDef | ast.ClassDef) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    return {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
            and isinstance(n.value, str) and id(n) not in docs}


def test_only_tools_write_the_package_data():
    # the package's data files are named in code only by the tools that write them
    data = {p.name for p in (ROOT / "src" / "nirglucose" / "data").glob("*.json")}
    assert "tuned_params.json" in data
    for folder in ("benchmarks", "studies"):
        for path in _scripts(folder):
            named = {s for s in _code_strings(path) if any(d in s for d in data)}
            assert not named, f"{folder}/{path.name} names package data {named}: a tool"
    assert any("tuned_params.json" in s for s in _code_strings(ROOT / "tools" / "tune.py"))


def test_the_records_are_with_the_studies():
    assert (ROOT / "studies" / "records").is_dir()
    assert not (ROOT / "benchmarks" / "records").exists()
    for path in [*ROOT.glob("docs/**/*.md"), ROOT / "README.md", ROOT / "Makefile"]:
        text = path.read_text()
        assert "benchmarks/records" not in text, path
        for moved in (*_scripts("studies"), *_scripts("tools")):
            assert f"benchmarks/{moved.name}" not in text, (path, moved.name)


def test_the_reference_solvers_are_outside_the_installed_package():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["tool"]["setuptools"]["packages"]["find"]["where"] == ["src"]
    assert (ROOT / "validation" / "nirglucose_reference" / "photon_engine.py").is_file()
    assert not (ROOT / "src" / "nirglucose" / "optics" / "reference").exists()
    assert "validation" in pyproject["tool"]["pytest"]["ini_options"]["pythonpath"]
