"""The package's layout rules (issues 22 and 33): no import circles, every lazy import
named, no oversized modules or functions.

The import graph is built from the source with :mod:`ast` (nothing is imported):
every ``import`` / ``from ... import`` of a ``nirglucose`` module, relative imports
resolved, imports under ``if TYPE_CHECKING:`` not counted. Importing ``a.b.c`` runs
``a``, ``a.b`` and ``a.b.c``, so an edge goes to each of them except the importing
module's own ancestor packages (those are always initialised first) -- unless the
module reads a name from one (``from . import __version__``): that is an edge to a
package ``__init__`` that may still be initialising. The circle test counts imports
inside functions too (they run on the first call, and a circle they close is hidden,
not gone); those are allowed only for a named reason (a heavy library deferred, a
module slow to import, the command line), the rest stand on a ratchet list. Imports of
another module's private names stand on a ratchet count.

The size rules are the optics package's (tests/optics/test_optics_layout.py): at most
800 lines a module and 60 code lines a function (docstring excluded) unless its
docstring says why it is longer ("on purpose"). Today's offenders sit in explicit
allow-lists below with the reason; the lists can only shrink (an entry that no longer
offends fails the test, so fixing one means deleting its line).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import nirglucose

_ROOT = Path(nirglucose.__file__).parent
_PACKAGE = "nirglucose"
_MAX_MODULE_LINES = 800
_MAX_FUNCTION_LINES = 60
_REASON = "on purpose"

#: Modules over 800 lines, path -> reason; empty: every module complies. An entry
#: must go once its module is split (the test says so).
ALLOWED_LONG_MODULES: dict[str, str] = {}

#: Outside libraries slow to import (or optional) that a module may load lazily, inside
#: the function that needs them, so that ``import nirglucose`` and the modules that do
#: not need them stay light: name -> why.
HEAVY_LIBRARIES: dict[str, str] = {
    "torch": "PyTorch: the networks only; about a second to import",
    "safetensors": "the networks' weight files only",
    "matplotlib": "figures only",
    "numba": "the compiled kernels only (optics; the UVA/Padova RK4)",
    "dask": "sweeps on a cluster only",
    "distributed": "sweeps on a cluster only",
    "onnx": "an optional extra (export-onnx)",
    "onnxruntime": "an optional extra (export-onnx)",
    "iadpython": "the adding-doubling reference solver only",
    "sbi": "the device twin's posterior estimator only (nirglucose.twin); about 5 s to import",
}

#: The package's own modules slow to import for a reason of their own: name -> why.
SLOW_MODULES: dict[str, str] = {
    "optics.kernels.lut_kernel": "compiles (or loads from numba's cache) its "
    "signature-typed kernels when imported",
    # measured with ``python -X importtime`` after ``import nirglucose`` (issue 33)
    "simulation.simulator": "loads scipy.special (normal quantiles of its random streams), "
    "about 0.2 s, which `import nirglucose` defers until the first ng.simulate call",
    "twin.twin": "loads the simulator (through the twin's parameters), which `import "
    "nirglucose` defers until a twin is read",
    "simulation.wear": "loads scipy.signal (the interstitial lag filter), about 0.8 s, "
    "which `import nirglucose` defers until the first ng.simulate_wear call",
}

#: Imports of the package's own modules inside functions that no reason above covers
#: (``module:function -> target``): a ratchet, now empty (issue 33) and to stay so. Such
#: an import hides a dependency from the reader of the module's header: move it to the
#: top (or the code to a leaf module). A new one fails the test.
UNREASONED_FUNCTION_IMPORTS: frozenset[str] = frozenset()

#: Imports of another module's private (``_x``) names: a ratchet at this count, which
#: may only fall (lower it when you remove some).
MAX_UNDERSCORE_IMPORTS = 139

#: The package's layers, lowest first (issue 42): a module imports modules of its own
#: layer or lower ones, never a higher one, so no arrow runs back up. By top-level name
#: under ``nirglucose`` (``""``: the package's ``__init__``); a new subpackage fails
#: :func:`test_every_module_has_a_layer` until it is placed here.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("_version", "exceptions", "constants", "portable", "libm", "resources", "formatting",
     "data", "_renamed"),
    ("config",),
    ("dataset", "optics", "metrics"),  # the data boundary, the physics, the scores
    ("simulation", "fitted"),  # the simulator; the estimators' side of the schema
    ("api", "features"),
    ("", "models", "design"),
    ("twin",),  # the simulator fitted to a device file (estimators and the bound inside)
    ("calibration",),  # intervals and calibration of a fitted model
    ("prediction", "export"),  # using a fitted model
    ("evaluation",),  # judging the models
    ("plots",),
    ("report",),
    ("cli",),
)
#: The evaluation's own floors, lowest first (``""``: its ``__init__``, which imports
#: nothing): the task engine, the pieces both verbs share, the benchmark, then what
#: runs benchmarks (sweeps, the worn-device study).
EVALUATION_LAYERS: tuple[tuple[str, ...], ...] = (
    ("", "engine"),
    ("splits", "protocol", "reference", "estimators", "cohorts"),
    ("benchmark",),
    ("sweep", "wear"),
)


def layer_of(module: str) -> tuple[int, int]:
    """``(layer, evaluation floor)`` of a dotted module name (the floor is 0 outside
    :mod:`nirglucose.evaluation`); a KeyError for a module no layer names."""
    parts = module.split(".")
    top = parts[1] if len(parts) > 1 else ""
    rank = next(i for i, names in enumerate(LAYERS) if top in names)
    if top != "evaluation":
        return rank, 0
    sub = parts[2] if len(parts) > 2 else ""
    return rank, next(i for i, names in enumerate(EVALUATION_LAYERS) if sub in names)


def arrows_back_up(graph: dict[str, set[str]], layer=layer_of) -> list[str]:
    """Every import ``a -> b`` with ``b`` on a higher layer (or evaluation floor) than
    ``a``."""
    return sorted(f"{a} -> {b}" for a, targets in graph.items() for b in targets
                  if layer(b) > layer(a))


#: Functions over 60 code lines without the reason in their docstring, qualname ->
#: reason; empty: every function is short or says why it is not.
ALLOWED_LONG_FUNCTIONS: dict[str, str] = {}


def _modules(root: Path = _ROOT, package: str = _PACKAGE) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = [package, *path.relative_to(root).with_suffix("").parts]
        is_pkg = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_pkg else parts)] = (path, is_pkg)
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(node: ast.AST, function: str = "", typing: bool = False):
    """``(import statement, enclosing function's qualname or "")`` for every import that
    can run (not under ``if TYPE_CHECKING``, unless ``typing``: then those too);
    ``""``: it runs when the module loads."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.Import | ast.ImportFrom):
            yield child, function
        elif isinstance(child, ast.If) and _is_type_checking(child.test):
            for sub in (*child.body, *child.orelse) if typing else child.orelse:
                yield from _imports(ast.Module(body=[sub], type_ignores=[]), function, typing)
        elif isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
            yield from _imports(child, f"{function}.{child.name}" if function else child.name,
                                typing)
        elif isinstance(child, ast.ClassDef) and function:
            yield from _imports(child, f"{function}.{child.name}", typing)
        else:
            yield from _imports(child, function, typing)


def _named(node: ast.Import | ast.ImportFrom, name: str, is_pkg: bool,
           mods) -> list[tuple[str, str | None]]:
    """``(module, name read from it or None)`` for each alias of an import statement: the
    name is None where the alias is itself a module (``import a.b``, ``from a import b``
    with ``b`` a submodule), so ``from . import __version__`` reads a package's
    ``__init__`` while ``from . import sibling`` does not."""
    if isinstance(node, ast.Import):
        return [(a.name, None) for a in node.names if a.name in mods]
    if node.level:
        base = (name if is_pkg else name.rpartition(".")[0]).split(".")
        base = base[: len(base) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    out = []
    for alias in node.names:
        sub = f"{target}.{alias.name}"
        if sub in mods:
            out.append((sub, None))
        elif target in mods:
            out.append((target, alias.name))
    return out


def import_graph(*, functions: bool = False, typing: bool = False, root: Path = _ROOT,
                 package: str = _PACKAGE) -> dict[str, set[str]]:
    """Module -> the package's modules its imports run (see the module docstring).

    ``functions``: imports inside functions count too (they run when the function is
    first called, so a circle closed by one is a circle all the same). ``typing``:
    imports under ``if TYPE_CHECKING:`` count too (a circle of types is a circle for
    the reader and the type checker). A name read from one of the module's own
    ancestor packages (``from . import __version__``) is an edge to that package's
    ``__init__``, which may still be initialising.
    """
    mods = _modules(root, package)
    graph = {}
    for name, (path, is_pkg) in mods.items():
        ancestors = {".".join(name.split(".")[:k]) for k in range(1, name.count(".") + 2)}
        edges = set()
        for node, function in _imports(ast.parse(path.read_text()), typing=typing):
            if function and not functions:
                continue
            for target, read in _named(node, name, is_pkg, mods):
                parts = target.split(".")
                edges |= {".".join(parts[:k]) for k in range(1, len(parts) + 1)} - ancestors
                if read is not None and target in ancestors and target != name:
                    edges.add(target)  # a name read from a package still initialising
        graph[name] = {m for m in edges if m in mods}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every import circle: the strongly connected groups of more than one module
    (Tarjan's algorithm, iterative), each sorted, the groups sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                group = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    group.append(w)
                    if w == v:
                        break
                if len(group) > 1:
                    found.append(sorted(group))
    return sorted(found)


def _third_party(node: ast.Import | ast.ImportFrom) -> set[str]:
    """Top-level names of the outside libraries an import statement loads."""
    if isinstance(node, ast.Import):
        return {a.name.split(".")[0] for a in node.names}
    return set() if node.level else {(node.module or "").split(".")[0]}


def heavy_libraries() -> dict[str, set[str]]:
    """Module -> the :data:`HEAVY_LIBRARIES` that importing it loads (through the
    package's module-level imports)."""
    mods = _modules()
    own = {name: set() for name in mods}
    for name, (path, _) in mods.items():
        for node, function in _imports(ast.parse(path.read_text())):
            if not function:
                own[name] |= _third_party(node) & set(HEAVY_LIBRARIES)
    graph = import_graph()
    return {name: set().union(own[name], *(own[m] for m in _closure(graph, name)))
            for name in mods}


def function_imports() -> dict[str, str]:
    """Every import of the package's own modules inside a function, as
    ``"module:function -> target"``, with its reason (``""``: none applies).

    Reasons: the target loads a heavy library the importing module does not (see
    :data:`HEAVY_LIBRARIES`); the target is slow to import (:data:`SLOW_MODULES`); or
    the importer is the command line, which imports a command's library only when that
    command runs (``nirglucose --help`` stays fast).
    A lazy attribute of a package ``__init__`` uses :func:`importlib.import_module`,
    which is no import statement and is not listed.
    """
    mods = _modules()
    heavy = heavy_libraries()
    out = {}
    for name, (path, is_pkg) in mods.items():
        for node, function in _imports(ast.parse(path.read_text())):
            if not function:
                continue
            for target, _ in _named(node, name, is_pkg, mods):
                key = f"{name.removeprefix(_PACKAGE + '.')}:{function} -> " \
                      f"{target.removeprefix(_PACKAGE + '.')}"
                deferred = heavy[target] - heavy[name]
                slow = target.removeprefix(_PACKAGE + ".")
                if deferred:
                    reason = "defers " + ", ".join(sorted(deferred))
                elif slow in SLOW_MODULES:
                    reason = SLOW_MODULES[slow]
                elif name.startswith(f"{_PACKAGE}.cli"):
                    reason = "command line: imported when the command runs"
                else:
                    reason = ""
                out[key] = reason
    return out


def underscore_imports() -> list[str]:
    """Private names (``_x``, not dunders) imported from another of the package's
    modules, as ``"module -> target._name"``, one per import."""
    mods = _modules()
    out = []
    for name, (path, is_pkg) in mods.items():
        for node, _ in _imports(ast.parse(path.read_text())):
            for target, read in _named(node, name, is_pkg, mods):
                if read and read.startswith("_") and not read.startswith("__") \
                        and target != name:
                    out.append(f"{name} -> {target}.{read}")
    return sorted(out)



def _function_lengths():
    """(``path:Class.function``, code lines, docstring) of every function in the package."""
    for path in sorted(_ROOT.rglob("*.py")):
        rel = path.relative_to(_ROOT).as_posix()

        def visit(node, prefix, rel=rel):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                    doc = ast.get_docstring(child) or ""
                    first = child.body[0]
                    skip = first.end_lineno - first.lineno + 1 if doc else 0
                    code = child.end_lineno - child.lineno + 1 - skip
                    yield f"{rel}:{prefix}{child.name}", code, doc
                    yield from visit(child, f"{prefix}{child.name}.")
                elif isinstance(child, ast.ClassDef):
                    yield from visit(child, f"{prefix}{child.name}.")
                else:
                    yield from visit(child, prefix)

        yield from visit(ast.parse(path.read_text()), "")


# --------------------------------------------------------------------------- tests
def test_no_import_circle_at_any_depth():
    # imports inside functions count (a circle they close is a circle all the same), and
    # so does a name read from a package's __init__ that imports the reader
    found = circles(import_graph(functions=True))
    assert found == [], "import circles: " + "; ".join(" <-> ".join(c) for c in found)


def test_no_import_circle_even_through_type_only_imports():
    # ``if TYPE_CHECKING:`` imports count too: a circle of types is a circle to read
    # (the report's figure sections once shared a class that way)
    found = circles(import_graph(functions=True, typing=True))
    assert found == [], "import circles: " + "; ".join(" <-> ".join(c) for c in found)


def test_every_module_has_a_layer():
    unplaced = []
    for module in _modules():
        try:
            layer_of(module)
        except StopIteration:
            unplaced.append(module)
    assert not unplaced, f"place these in LAYERS / EVALUATION_LAYERS: {unplaced}"


def test_no_import_runs_back_up_the_layers():
    # at run time, imports inside functions included (they run all the same)
    found = arrows_back_up(import_graph(functions=True))
    assert not found, "imports of a higher layer: " + "; ".join(found)


def test_the_layer_check_finds_an_arrow_back_up():
    graph = {"nirglucose.dataset.schema": {"nirglucose.models.registry"},
             "nirglucose.evaluation.engine.tasks": {"nirglucose.evaluation.benchmark.run"},
             "nirglucose.models.registry": {"nirglucose.dataset.schema"},
             "nirglucose.evaluation.sweep.run": {"nirglucose.evaluation.benchmark.run"}}
    assert arrows_back_up(graph) == [
        "nirglucose.dataset.schema -> nirglucose.models.registry",
        "nirglucose.evaluation.engine.tasks -> nirglucose.evaluation.benchmark.run",
    ]
    assert layer_of("nirglucose") == layer_of("nirglucose.models") > layer_of("nirglucose.api")


def test_prediction_imports_only_models_dataset_and_calibration():
    # using a fitted model never loads the study engine (issue 42)
    reached = _closure(import_graph(functions=True), "nirglucose.prediction")
    tops = {m.split(".")[1] for m in reached if m.count(".")}
    assert {"models", "dataset", "calibration"} <= tops
    assert not tops & {"evaluation", "report", "plots", "cli", "export"}, tops
    calibration = _closure(import_graph(functions=True), "nirglucose.calibration.conformal")
    assert not any(m.startswith("nirglucose.evaluation") for m in calibration)


def test_the_circle_finder_finds_every_circle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"e"}, "e": {"d", "a"}, "f": {"a"}}
    assert circles(graph) == [["a", "b", "c"], ["d", "e"]]
    assert circles({"a": {"b"}, "b": set()}) == []


def test_a_circle_through_a_package_init_and_a_function_is_found(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .data import Data\n__version__ = '1'\n")
    (pkg / "data.py").write_text("class Data:\n    def __init__(self):\n"
                                 "        from . import __version__\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "a.py").write_text("def f():\n    from .b import g\n")
    (pkg / "sub" / "b.py").write_text("from . import a\nfrom .. import data  # a module\n")
    loose = import_graph(root=pkg, package="pkg")
    assert circles(loose) == []  # module level only: both circles close inside functions
    found = circles(import_graph(functions=True, root=pkg, package="pkg"))
    assert found == [["pkg", "pkg.data"], ["pkg.sub.a", "pkg.sub.b"]]


def test_function_level_imports_have_a_reason_or_are_on_the_ratchet():
    found = function_imports()
    unreasoned = {k for k, why in found.items() if not why}
    new = unreasoned - UNREASONED_FUNCTION_IMPORTS
    assert not new, ("imports inside functions with no reason (move them to the module's "
                     f"top, or the code to a leaf module): {sorted(new)}")
    gone = UNREASONED_FUNCTION_IMPORTS - unreasoned
    assert not gone, f"no longer imported inside a function: delete from the list: {sorted(gone)}"


def test_the_function_import_census_sees_lazy_heavy_imports():
    found = function_imports()
    # plots load matplotlib: the report's figure helpers import them when drawing
    assert any(k.startswith("report.") and why == "defers matplotlib"
               for k, why in found.items())
    assert all(why for k, why in found.items() if k.startswith("cli."))
    assert "matplotlib" in heavy_libraries()["nirglucose.plots.style"]
    assert "torch" not in heavy_libraries()["nirglucose"]


def test_the_slow_modules_are_deferred_by_import_nirglucose():
    # the stated reasons hold: ``import nirglucose`` loads none of SLOW_MODULES (nor the
    # scipy parts that make the simulators slow), in a fresh interpreter
    slow = [f"{_PACKAGE}.{m}" for m in SLOW_MODULES] + ["scipy.special", "scipy.signal"]
    run = subprocess.run([sys.executable, "-c", "import sys, nirglucose; print(sorted(m for m "
                          f"in {slow!r} if m in sys.modules))"],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == "[]"


def test_private_names_imported_across_modules_do_not_grow():
    found = underscore_imports()
    assert len(found) <= MAX_UNDERSCORE_IMPORTS, (
        f"{len(found)} imports of another module's private names (at most "
        f"{MAX_UNDERSCORE_IMPORTS}): make the name public where it is shared, or keep it "
        "in its module")
    assert all(" -> " in f and "._" in f for f in found)


def test_the_graph_resolves_relative_imports_and_packages():
    graph = import_graph()
    assert "nirglucose.dataset.container" in graph["nirglucose.dataset.schema"]
    # importing models.registry runs the models package too (an edge to each) ...
    assert {"nirglucose.models", "nirglucose.models.registry"} <= graph[
        "nirglucose.evaluation.benchmark.run"
    ]
    # ... but a module's own ancestors are no edges (they are initialised first)
    assert "nirglucose.models" not in graph["nirglucose.models.linear"]
    # features reads the fitted-state helper from the leaf module, not the models package
    assert "nirglucose.fitted" in graph["nirglucose.features.transform"]
    reached = _closure(graph, "nirglucose.features")
    assert not any(m.startswith("nirglucose.models") for m in reached)


def _closure(graph: dict[str, set[str]], start: str) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        for m in graph[todo.pop()] - seen:
            seen.add(m)
            todo.append(m)
    return seen


def test_the_data_container_does_not_need_the_simulator():
    graph = import_graph()
    for module in ("nirglucose.dataset", "nirglucose.dataset.schema", "nirglucose.features"):
        reached = _closure(graph, module)
        assert not any(m.startswith("nirglucose.simulation") for m in reached), (module, reached)
    assert "nirglucose.simulation.partitioned" not in _closure(graph, "nirglucose.dataset")


def test_the_evaluation_modules_import_in_any_order():
    # a fresh interpreter per entry point: a hidden cycle shows as an ImportError
    for module in ("nirglucose.evaluation.engine.tasks", "nirglucose.evaluation.sweep",
                   "nirglucose.evaluation.benchmark.aggregate", "nirglucose.features",
                   "nirglucose.fitted", "nirglucose.simulation.partitioned"):
        run = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True,
                             text=True, check=False)
        assert run.returncode == 0, (module, run.stderr[-2000:])


def test_no_module_is_too_long():
    long = {
        p.relative_to(_ROOT).as_posix(): n
        for p in sorted(_ROOT.rglob("*.py"))
        if (n := len(p.read_text().splitlines())) > _MAX_MODULE_LINES
    }
    assert set(long) - set(ALLOWED_LONG_MODULES) == set(), long
    assert set(ALLOWED_LONG_MODULES) - set(long) == set(), "now short: drop from the list"


def test_no_function_is_too_long_without_a_reason():
    long = {
        name: n
        for name, n, doc in _function_lengths()
        if n > _MAX_FUNCTION_LINES and _REASON not in doc
    }
    assert set(long) - set(ALLOWED_LONG_FUNCTIONS) == set(), long
    assert set(ALLOWED_LONG_FUNCTIONS) - set(long) == set(), "now short: drop from the list"
