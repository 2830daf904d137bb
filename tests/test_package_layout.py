"""Package layout: the solver does not pull in the FE kit, the aircraft example or the viewer."""
import subprocess
import sys

FORBIDDEN = ["nnm_fem", "paris_aircraft", "viser", "trimesh", "nnm_viewer", "dask", "distributed"]


def test_import_nnm_solver_does_not_import_fem_aircraft_or_viewer():
    code = ("import sys\n"
            "import nnm_solver\n"
            f"bad = sorted(m for m in sys.modules if m.split('.')[0] in {FORBIDDEN!r})\n"
            "print(','.join(bad))\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    bad = [m for m in run.stdout.strip().split(",") if m]
    assert not bad, f"import nnm_solver imported {bad}"


#: the solver's layers, lowest first: a module may import its own layer and the layers before it.  The base
#: modules (errors, jit, threads, fourier) sit below everything; hb and matio are facades at the top.
LAYERS = ["errors", "jit", "threads", "fourier", "_moved", "model", "integrators", "continuation", "stability",
          "orbits", "results", "analysis", "backbone", "driver", "files", "identification", "sweeps", "cli", "hb",
          "matio"]
#: at most this many modules at the top level of nnm_solver (besides __init__.py): the folders say the layers
TOP_LEVEL_MAX = 10


def import_graph(root):
    """{module: set of modules of the same package it imports}, from the source of the package at ``root``
    (a folder), counting imports at any depth (module level and inside functions).  An import of one of a
    module's own parent packages is left out (a package's __init__ imports its modules)."""
    import ast
    from pathlib import Path

    pkg = Path(root)
    mods = {}
    for path in sorted(pkg.rglob("*.py")):
        parts = list(path.relative_to(pkg.parent).with_suffix("").parts)
        is_init = parts[-1] == "__init__"
        if is_init:
            parts = parts[:-1]
        base = parts if is_init else parts[:-1]
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    target = base[:len(base) - node.level + 1] + (node.module.split(".") if node.module else [])
                else:
                    target = (node.module or "").split(".")
                if target and target[0] == pkg.name:
                    deps.add(".".join(target))
                    deps.update(".".join(target + [a.name]) for a in node.names)
            elif isinstance(node, ast.Import):
                deps.update(a.name for a in node.names if a.name.split(".")[0] == pkg.name)
        mods[".".join(parts)] = deps

    def resolve(name):                     # a name -> the module that defines it (a.b.func -> a.b)
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name

    return {m: {r for r in map(resolve, deps) if r and r != m and not m.startswith(r + ".")}
            for m, deps in mods.items()}


def find_cycles(graph):
    """Import cycles of a graph {module: imported modules}, each as [m1, m2, ..., m1]."""
    state, cycles = {}, []

    def visit(m, stack):
        state[m] = 1
        stack.append(m)
        for d in sorted(graph.get(m, ())):
            if state.get(d) == 1:
                cycles.append(stack[stack.index(d):] + [d])
            elif d not in state:
                visit(d, stack)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [])
    return cycles


def _root(name):
    from pathlib import Path
    return Path(__file__).resolve().parents[1] / name


def test_no_import_cycle_in_the_solver_or_the_viewer():
    for pkg in ("nnm_solver", "nnm_viewer"):
        cycles = find_cycles(import_graph(_root(pkg)))
        assert not cycles, f"{pkg}: import cycles {[' -> '.join(c) for c in cycles[:3]]}"


def test_the_cycle_check_finds_a_cycle_through_a_function_level_import(tmp_path):
    pkg = tmp_path / "demo_pkg"
    (pkg / "low").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "low" / "__init__.py").write_text("")
    (pkg / "low" / "a.py").write_text("from ..high import b\n")
    (pkg / "high.py").write_text("def f():\n    from .low.a import g\n    return g\n")
    (pkg / "other.py").write_text("import demo_pkg.high\n")
    graph = import_graph(pkg)
    assert graph["demo_pkg.other"] == {"demo_pkg.high"}
    assert find_cycles(graph) == [["demo_pkg.high", "demo_pkg.low.a", "demo_pkg.high"]]
    (pkg / "high.py").write_text("def f():\n    return 1\n")
    assert find_cycles(import_graph(pkg)) == []


def test_layers_import_only_the_layers_below_them():
    graph = import_graph(_root("nnm_solver"))
    layer = {m: m.split(".")[1] for m in graph if m != "nnm_solver"}
    assert set(layer.values()) <= set(LAYERS), f"modules outside the known layers: {set(layer.values()) - set(LAYERS)}"
    upward = sorted(f"{m} -> {d}" for m, deps in graph.items() if m in layer for d in deps
                    if d in layer and LAYERS.index(layer[d]) > LAYERS.index(layer[m]))
    assert not upward, f"imports of a higher layer: {upward[:5]}"


def test_top_level_holds_few_modules_and_each_subpackage_says_its_layer():
    root = _root("nnm_solver")
    top = sorted(p.name for p in root.glob("*.py") if p.name != "__init__.py")
    assert len(top) <= TOP_LEVEL_MAX, f"{len(top)} modules at the top of nnm_solver: {top}"
    for sub in sorted(p for p in root.iterdir() if (p / "__init__.py").exists()):
        doc = (sub / "__init__.py").read_text()
        assert "Layer:" in doc, f"nnm_solver/{sub.name}/__init__.py does not say what its layer may import"


def test_old_module_paths_still_import_as_the_same_modules():
    code = ("import nnm_solver.newmark as a, nnm_solver.integrators.newmark as b\n"
            "import nnm_solver.importers.abaqus as c, nnm_solver.files.importers.abaqus as d\n"
            "from nnm_solver.model import CubicSpring\n"
            "from nnm_solver.io import load_model\n"
            "from nnm_solver.matio import load_mat_model\n"
            "from nnm_solver.hb import continue_nnm_hb\n"
            "from nnm_solver.continuation import pseudo_arclength\n"
            "assert a is b and c is d and a.__spec__.name == 'nnm_solver.integrators.newmark'\n"
            "print('ok')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr


def _loops(path, predicate):
    """Line numbers of the for/while loops of a module whose body makes calls satisfying predicate(names)."""
    import ast
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.For, ast.While)):
            names = set()
            for n in ast.walk(node):
                if isinstance(n, ast.Call):
                    f = n.func
                    names.add(f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", ""))
            if predicate(names):
                out.append(node.lineno)
    return out


def _newton_loop(names):
    """A Newton loop: a Jacobian (or, for chord Newton, a residual) evaluated and a linear system solved in the same
    loop (also a compiled one: a residual kernel, e.g. ``residual_jacobian``, and the compiled QR solve)."""
    return (bool({"jacobian", "jacobian_of", "residual", "residual_parts"} & names
                 or any(n.startswith("residual_") for n in names))
            and bool({"solve", "lstsq", "lu_solve", "solve_triangular", "_qr_solve"} & names))


#: the places a Newton loop may live: the engine's corrector and the fixed-parameter Newton (continuation/), and the
#: events' bracketing root finder (stability/roots.py); every other module corrects with these (no exemption)
NEWTON_PLACES = ("continuation/", "stability/roots.py")

def _loops_outside(predicate, places):
    """{module: line numbers} of the solver's loops satisfying predicate outside the allowed places."""
    root = _root("nnm_solver")
    found = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        lines = _loops(path, predicate)
        if lines and not rel.startswith(places):
            found[rel] = lines
    return found


def test_newton_loops_live_in_the_continuation_engine_and_the_root_finder():
    found = _loops_outside(_newton_loop, NEWTON_PLACES)
    assert not found, f"Newton loops outside continuation/ and stability/roots.py: {found}"


def test_the_check_finds_a_newton_loop(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("def f(prob, u):\n    for _ in range(9):\n        r, J = prob.jacobian(u)\n"
                 "        u = u - np.linalg.solve(J, r)\n    return u\n")
    assert _loops(p, _newton_loop) == [2]
    p.write_text("def f(prob, u, lu):\n    while True:\n        r = prob.residual(u)\n"
                 "        u = u - lu_solve(lu, r)\n    return u\n")
    assert _loops(p, _newton_loop) == [2]                   # chord Newton: an old factorisation, a new residual
    p.write_text("def f(prob, u):\n    for _ in range(9):\n        u = newton(prob, u)\n    return u\n")
    assert _loops(p, _newton_loop) == []
    # a compiled chord loop around one residual kernel (orbits/condensed_chord.py before round 5 of issue 52: the
    # loop now lives in continuation/chord.py, the kernel passed to it)
    p.write_text("def f(u, Q, R, c):\n    while True:\n        res = residual_jacobian(u, False, *c)[0]\n"
                 "        u = u + _qr_solve(Q, R, -res)\n    return u\n")
    assert _loops(p, _newton_loop) == [2]


def _stepping_loop(names):
    """An arclength stepping loop of its own: the engine's corrector (or its tangent) called inside a loop, i.e. a
    loop doing what continuation/engine.pseudo_arclength does (single corrections, e.g. onto an energy level set,
    and the root finder's trial points are not loops over it)."""
    return bool({"correct", "correct_factored", "tangent", "tangent_factored"} & names)


#: the places a stepping loop may live: the engine (pseudo-arclength) and the natural-parameter stepper
#: (continuation/natural.py); the backbone and the driver iterate over these generators and steppers
STEPPING_PLACES = ("continuation/",)


def test_stepping_loops_live_in_the_continuation_engine():
    found = _loops_outside(_stepping_loop, STEPPING_PLACES)
    assert not found, f"stepping loops outside continuation/: {found}"


def test_the_check_finds_a_stepping_loop(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("def f(prob, u, t, h):\n    for _ in range(9):\n        v = correct(prob, u + h * t, t, s, 1e-9)[0]\n"
                 "        t, u = v - u, v\n    return u\n")
    assert _loops(p, _stepping_loop) == [2]
    p.write_text("def f(prob, u, t, s):\n    for point in pseudo_arclength(prob, u, t, s, 1e-9):\n        u = point.u\n"
                 "    return u\n")
    assert _loops(p, _stepping_loop) == []


#: the modules where numbers may be written at module level: the settings modules (each holds typed frozen dataclasses
#: with every default written once, and the instance its layer reads, e.g. ``ORBITS = OrbitSettings()``)
SETTINGS_MODULES = ["analysis/settings.py", "backbone/settings.py", "driver/settings.py", "files/settings.py",
                    "identification/settings.py", "integrators/settings.py", "model/settings.py", "orbits/settings.py",
                    "results/settings.py", "stability/settings.py", "sweeps/settings.py"]
#: module-level numbers elsewhere that are not thresholds, tolerances or sizes of the solver, each with what it is
NOT_THRESHOLDS = {
    "files/h5file.py": {"FORMAT_VERSION": "the version of the .h5 file format (a format's number)"},
    "files/importers/matlab.py": {"SPRINGS_VERSION": "the newest spring-table version the reader knows (a format's)"},
    "files/importers/measured_units.py": {"G0": "a physical constant: standard gravity (m/s^2)"},
    "files/importers/nastran.py": {"_SMALLEST": "the range of a FORMATTED OUTPUT4 field (two-digit exponents)"},
    "integrators/newmark.py": {"_STATE": "an enumeration: what a sweep records", "_RECORD": "(the same enumeration)",
                               "_TANGENTS": "(the same enumeration)"},
    "continuation/chord.py": {"JUDGE": "an enumeration: why the compiled chord iterations returned",
                                  "SINGULAR": "(the same enumeration)", "REFRESH": "(the same enumeration)"},
    "threads.py": {"BLAS_THREADS": "a process setting a user assigns at run time (None: BLAS left alone), read at "
                                   "each call; it changes no result",
                   "_open": "state, not a setting: the count of BLAS-limited regions open now (0 at import)"},
}


def _numeric(node):
    """True for a number, a signed number, arithmetic of numbers (``1.0 / 3.0``, ``0.03 + 0.03j``) or a tuple, list
    or set of such: what a threshold, a tolerance or a size written as a constant looks like.  Not: strings,
    booleans, None, tables keyed by names (dicts: unit conversions, enumerations), values computed from other names
    (an alias of a settings field, ``FOLD_SLOPE = ORBITS.fold_slope``)."""
    import ast
    if isinstance(node, ast.Constant):
        return isinstance(node.value, (int, float, complex)) and not isinstance(node.value, bool)
    if isinstance(node, ast.UnaryOp):
        return _numeric(node.operand)
    if isinstance(node, ast.BinOp):
        return _numeric(node.left) and _numeric(node.right)
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return bool(node.elts) and all(_numeric(e) for e in node.elts)
    return False


def _module_thresholds(path):
    """The names a module binds at module level (plain or annotated assignment, one name or a tuple of names) to a
    numeric value (_numeric): its module-level thresholds."""
    import ast
    out = []
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None and _numeric(node.value):
            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                out += [e.id for e in (t.elts if isinstance(t, (ast.Tuple, ast.List)) else [t])
                        if isinstance(e, ast.Name)]
    return out


def _thresholds_outside_settings(root, settings_modules=SETTINGS_MODULES):
    """{module: [names]} of the module-level thresholds of the package at ``root`` outside its settings modules
    (paths relative to root) and NOT_THRESHOLDS."""
    found = {}
    for p in sorted(root.rglob("*.py")):
        rel = p.relative_to(root).as_posix()
        if rel in settings_modules:
            continue
        names = [n for n in _module_thresholds(p) if n not in NOT_THRESHOLDS.get(rel, {})]
        if names:
            found[rel] = names
    return found


def test_no_module_level_threshold_outside_the_settings_objects():
    """Every threshold, tolerance and size of the solver (all of nnm_solver/) is a field of a typed frozen settings
    object in a settings module (SETTINGS_MODULES; continuation/'s are ContinuationSettings and NewtonSettings) or an
    argument whose default is read from one, written once.  Module-level numbers elsewhere are the few that are not
    thresholds (NOT_THRESHOLDS: format versions, a physical constant, an enumeration, a process setting)."""
    root = _root("nnm_solver")
    found = _thresholds_outside_settings(root)
    assert not found, f"module-level thresholds outside the settings modules: {found}"
    for rel, names in NOT_THRESHOLDS.items():      # the exceptions exist (a stale one would hide a new threshold)
        assert set(names) <= set(_module_thresholds(root / rel)), rel
    assert all((root / rel).is_file() for rel in SETTINGS_MODULES)


def test_the_settings_modules_hold_frozen_dataclasses():
    """Each settings module's classes are frozen dataclasses (changed with dataclasses.replace, never in place)."""
    import ast
    root = _root("nnm_solver")
    for rel in SETTINGS_MODULES:
        for node in ast.parse((root / rel).read_text()).body:
            if isinstance(node, ast.ClassDef):
                decorators = [ast.unparse(d) for d in node.decorator_list]
                assert any(d.startswith("dataclass(") and "frozen=True" in d for d in decorators), (rel, node.name)


def test_the_threshold_check_finds_a_planted_threshold(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "layer").mkdir(parents=True)
    (pkg / "layer" / "kernel.py").write_text(
        "from .settings import LAYER\n"
        "TOL = 1e-9\n"
        "STEPS: int = 40\n"
        "FLOOR = -1\n"
        "SHARE = 1.0 / 3.0\n"
        "SHIFT = 0.03 + 0.03j\n"
        "RADII = (0.02, 0.012)\n"
        "LO, HI = 1e-3, 1e3\n"
        "ALIAS = LAYER.tol\n"                      # an alias of a settings field: not a threshold of its own
        "NAME = 'newmark'\n"
        "UNITS = {'mm': 1e-3}\n"
        "ON = True\n"
        "def f(x, tol=1e-6):\n"                    # an argument's default: allowed
        "    local = 1e-12\n"
        "    return x < tol + local\n")
    (pkg / "layer" / "settings.py").write_text("TOL = 1e-9\n")
    found = _thresholds_outside_settings(pkg, ["layer/settings.py"])
    assert found == {"layer/kernel.py": ["TOL", "STEPS", "FLOOR", "SHARE", "SHIFT", "RADII", "LO", "HI"]}
    # a settings module not named as one is checked like any other
    assert _thresholds_outside_settings(pkg, [])["layer/settings.py"] == ["TOL"]
    (pkg / "layer" / "kernel.py").write_text("from .settings import LAYER\nALIAS = LAYER.tol\n")
    assert _thresholds_outside_settings(pkg, ["layer/settings.py"]) == {}


def _foreign_private_assignments(path):
    """``obj._name = ...`` assignments of a module where obj is not self or cls (a private attribute hung on
    another object)."""
    import ast
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        targets = node.targets if isinstance(node, ast.Assign) else (
            [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else [])
        for t in targets:
            for e in (t.elts if isinstance(t, ast.Tuple) else [t]):
                if (isinstance(e, ast.Attribute) and e.attr.startswith("_") and not e.attr.startswith("__")
                        and not (isinstance(e.value, ast.Name) and e.value.id in ("self", "cls"))):
                    out.append((node.lineno, ast.unparse(e)))
        # getattr / hasattr / setattr of a private name on another object (a side channel read or written)
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in ("getattr", "hasattr", "setattr") and len(node.args) >= 2
                and isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value, str)
                and node.args[1].value.startswith("_") and not node.args[1].value.startswith("__")
                and not (isinstance(node.args[0], ast.Name) and node.args[0].id in ("self", "cls"))):
            out.append((node.lineno, ast.unparse(node)))
    return out


def test_no_private_attribute_is_hung_on_another_object():
    """Working data about a point or a problem lives beside it (driver/candidate.py, orbits/hill_shared.py's warm
    starts, the locator's spectra), not as private attributes set on it or read from it from outside."""
    root = _root("nnm_solver")
    found = {p.relative_to(root).as_posix(): _foreign_private_assignments(p) for p in sorted(root.rglob("*.py"))}
    found = {k: v for k, v in found.items() if v}
    assert not found, f"private attributes set on other objects: {found}"


def test_the_check_finds_a_private_attribute_on_another_object(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("def f(point, x):\n    point._seen = x\n    self._ok = x\n    a, point._b = 1, 2\n"
                 "    c = getattr(point, '_c', None)\n    d = getattr(self, '_d', None)\n")
    assert [name for _, name in _foreign_private_assignments(p)] == ["point._seen", "point._b",
                                                                     "getattr(point, '_c', None)"]
