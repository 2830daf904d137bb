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


def _module_imports(root):
    """{module: set of nnm_solver modules it imports at module level} from the source (ast)."""
    import ast
    from pathlib import Path

    pkg = Path(root)
    graph = {}
    for path in pkg.rglob("*.py"):
        rel = path.relative_to(pkg.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        name = ".".join(parts)
        base = parts if path.name == "__init__.py" else parts[:-1]
        deps = set()
        for node in ast.parse(path.read_text()).body:          # module level only: lazy imports are fine
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    target = base[:len(base) - node.level + 1] + (node.module.split(".") if node.module else [])
                else:
                    target = (node.module or "").split(".")
                if target and target[0] == "nnm_solver":
                    deps.add(".".join(target))
                    deps.update(".".join(target + [a.name]) for a in node.names)
            elif isinstance(node, ast.Import):
                deps.update(a.name for a in node.names if a.name.startswith("nnm_solver"))
        graph[name] = deps
    return {m: {d for d in deps if d in graph and d != m} for m, deps in graph.items()}


def test_no_import_cycle_inside_the_solver():
    from pathlib import Path

    graph = _module_imports(Path(__file__).resolve().parents[1] / "nnm_solver")
    graph = {m: {d for d in deps if not m.startswith(d + ".")} for m, deps in graph.items()}  # parents' __init__
    state, cycle = {}, []

    def visit(m, stack):
        state[m] = 1
        for d in sorted(graph[m]):
            if d == "nnm_solver" or m == "nnm_solver":
                continue
            if state.get(d) == 1:
                cycle.append(stack[stack.index(d):] + [d] if d in stack else [m, d])
            elif d not in state:
                visit(d, stack + [d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycle, f"import cycles: {cycle[:3]}"
