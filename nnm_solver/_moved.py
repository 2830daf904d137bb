"""Old module paths of nnm_solver (before its subpackages, issue 27) kept importable.

``import nnm_solver.newmark`` or ``from nnm_solver.io import load_model`` still work: each old path
below is the same module object as its new one (``nnm_solver.integrators.newmark``, ...), so an
attribute set through either is seen by both.  The old modules whose names are now subpackages
(``model``, ``integrators``, ``continuation``, ``driver``, ``sweeps``, ``cli``) re-export their
public names from the subpackage itself.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys

#: old path (under nnm_solver) -> new path
MOVED = {
    "elements": "model.elements",
    "element_set": "model.element_set",
    "laws": "model.laws",
    "mesh": "model.mesh",
    "modal": "model.modal",
    "scaling": "model.scaling",
    "reduction": "model.reduction",
    "sparse": "model.sparse",
    "variants": "model.variants",
    "newmark": "integrators.newmark",
    "newmark_monodromy": "integrators.newmark_monodromy",
    "gauss": "integrators.gauss",
    "gauss_monodromy": "integrators.gauss_monodromy",
    "lowrank": "integrators.lowrank",
    "engine_driver": "continuation.engine_driver",
    "floquet": "stability.floquet",
    "locator": "stability.locator",
    "krein": "stability.krein",
    "events": "stability.events",
    "branch": "results.branch",
    "settings": "results.settings",
    "stops": "results.stops",
    "plotting": "results.plotting",
    "iterator": "driver.iterator",
    "refinement": "driver.refinement",
    "tongue_skip": "backbone.content",
    "switching": "driver.switching",
    "jobs": "driver.jobs",
    "io": "files.io",
    "h5file": "files.h5file",
    "exports": "files.exports",
    "importers": "files.importers",
    "importers.abaqus": "files.importers.abaqus",
    "importers.ansys": "files.importers.ansys",
    "importers.common": "files.importers.common",
    "importers.matlab": "files.importers.matlab",
    "importers.matrixmarket": "files.importers.matrixmarket",
    "importers.meshfile": "files.importers.meshfile",
    "importers.toml": "files.importers.toml",
    "sweep_files": "sweeps.sweep_files",
    "sweep_progress": "sweeps.progress",
    "cli_exchange": "cli.exchange",
}


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``nnm_solver.<old>`` and hands out the module at its new path."""

    prefix = __package__ + "."

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith(self.prefix) or fullname[len(self.prefix):] not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        module = importlib.import_module(self.prefix + MOVED[spec.name[len(self.prefix):]])
        spec.loader_state = module.__spec__          # the module's own spec, set back by exec_module
        return module

    def exec_module(self, module):
        # the import machinery has set the module's __spec__ to the old path's: give it back its own
        module.__spec__ = module.__spec__.loader_state


def install():
    if not any(isinstance(f, _MovedModules) for f in sys.meta_path):
        sys.meta_path.insert(0, _MovedModules())   # before the path finder: it would load an old
        # package's submodules (nnm_solver.importers.abaqus) a second time, under the old name
