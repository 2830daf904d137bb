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
