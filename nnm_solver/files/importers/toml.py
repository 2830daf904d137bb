"""The model description file (TOML): which matrix files, the nonlinear springs, the units, a display mesh.

::

    name = "cantilever"                  # optional (default: the file name)
    units = "mm-t-s"                     # SI (default), mm-t-s, mm-kg-ms, in-lbf-s, ft-lbf-s,
                                         # or a table: units = {length = "mm", mass = "t", time = "s"}
    [matrices]
    format = "matrixmarket"              # matrixmarket | abaqus | ansys | matlab | nastran (default: from the files)
    mass = "beam_M.mtx"                  # matrixmarket, abaqus: a pair of files
    stiffness = "beam_K.mtx"
    # file = "beam.full"                 # ansys, matlab: one file (matlab: variables M, K [, springs])
    # dof_map = "beam_dofs.txt"          # node and direction of each DOF, for formats without one
    # nastran: file = "model.op4" (or .op2), stiffness = "KAA", mass = "MAA" (matrix names, these by default),
    #          dof_map = "model.bdf" (its ASET/QSET cards) or a 'grid component' text file (nastran.py)

    [[springs]]                          # one table per nonlinear element
    type = "cubic"                       # default; the element type (see SPRING_TYPES); "polynomial" takes
                                         # coefficients = {2 = k2, 3 = k3, ...} (force sum k_p d^p);
                                         # "piecewise_linear" takes stiffnesses = [k0, k1, ...] (force /
                                         # length), breakpoints = [d1, ...] (length), optional eps and, for
                                         # an asymmetric law, stiffnesses_negative + breakpoints_negative;
                                         # "polynomial_stiffness" takes exponents, coefficients and dofs or
                                         # nodes (toml_coupled.py); the springs are built in toml_springs.py
    node = 6                             # by node and direction (needs a DOF map) ...
    direction = "uz"
    k3 = 1e9                             # in the description's units (force / length^3)
    # dof = 33                           # ... or by 0-based DOF index; other / other_node (+ other_direction)
                                         # make a relative spring on x[dof] - x[other]
    [mesh]                               # optional display mesh (any format meshio reads; a Nastran
    file = "beam.msh"                    # .bdf by pyNastran: nastran_mesh.py)
    # first_node = 1 | nodes = [...] | dofs_per_node = 6 | recovery = "R.mtx"   (see meshfile.py)
    # format = "gmsh"                    # meshio's format name, when the suffix is ambiguous

Every number (matrices, k3, mesh coordinates) is in the description's units; the model is built in
SI.  Relative paths are relative to the description file.  Errors name the file and the table.
"""
from __future__ import annotations

import sys
from pathlib import Path
import numpy as np

from ...errors import NNMFileError, NNMInputError
from ...model.model import Model
from .common import DofMap, Units, existing, read_dof_map_file
from .toml_springs import SPRING_TYPES, SpringType, _unknown, build_springs, to_si  # noqa: F401 (public here too)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

FORMATS = ("matrixmarket", "abaqus", "ansys", "matlab", "nastran")
TOP_KEYS = {"name", "description", "units", "matrices", "springs", "mesh"}
MATRIX_KEYS = {"format", "mass", "stiffness", "file", "dof_map"}
MESH_KEYS = {"file", "format", "nodes", "first_node", "dofs_per_node", "recovery"}


def _table(data, key, where, kind=dict, required=False):
    v = data.get(key)
    if v is None:
        if required:
            raise NNMInputError(f"{where}: missing [{key}]")
        return None
    if not isinstance(v, kind):
        raise NNMInputError(f"{where}: '{key}' must be a {'table' if kind is dict else 'list of tables'}")
    return v


def _sniff(path):
    """'matrixmarket' if the file starts like one, else 'abaqus'."""
    with open(path, "rb") as fh:
        head = fh.read(64)
    return "matrixmarket" if head.lstrip().lower().startswith(b"%%matrixmarket") else "abaqus"


def read_matrices(mt, folder, where):
    """(M, K, dof_map or None, format) of the [matrices] table."""
    _unknown(mt, MATRIX_KEYS, where)
    fmt = mt.get("format")
    if fmt is not None and str(fmt).lower() not in FORMATS:
        raise NNMInputError(f"{where}: format {fmt!r} is not one of {', '.join(FORMATS)}")
    fmt = None if fmt is None else str(fmt).lower()
    single = mt.get("file")
    if fmt == "nastran" or fmt is None and Path(str(single)).suffix.lower() in (".op4", ".op2"):
        from .nastran import read_nastran_table
        return read_nastran_table(mt, folder, where)
    if single is not None:
        if "mass" in mt or "stiffness" in mt:
            raise NNMInputError(f"{where}: give either file or the pair mass, stiffness, not both")
        f = existing(folder / str(single), f"{where} file")
        fmt = fmt or {".full": "ansys", ".mat": "matlab"}.get(f.suffix.lower())
        if fmt not in ("ansys", "matlab"):
            raise NNMInputError(f"{where}: a single matrix file is an ANSYS .full or a MATLAB .mat file; "
                                f"set format = 'ansys' or 'matlab', or give mass and stiffness files")
    else:
        for key in ("mass", "stiffness"):
            if key not in mt:
                raise NNMInputError(f"{where}: missing '{key}' (the {key} matrix file), or give file = ...")
        fm = existing(folder / str(mt["mass"]), f"{where} mass")
        fk = existing(folder / str(mt["stiffness"]), f"{where} stiffness")
        fmt = fmt or _sniff(fm)
        if fmt not in ("matrixmarket", "abaqus"):
            raise NNMInputError(f"{where}: format {fmt!r} takes one file (file = ...), not mass and stiffness")
    springs = []
    if fmt == "matrixmarket":
        from .matrixmarket import read_mtx_pair
        M, K = read_mtx_pair(fm, fk)
        dof_map = None
    elif fmt == "abaqus":
        from .abaqus import read_abaqus_pair
        M, K, dof_map = read_abaqus_pair(fm, fk)
    elif fmt == "ansys":
        from .ansys import read_full
        M, K, dof_map = read_full(f)
    else:
        from .matlab import SPRING_VARIABLES, read_mat, springs_from_mat, strings_of
        data = read_mat(f, ["M", "K", "dof_labels", "springs_version", *SPRING_VARIABLES])
        for key in ("M", "K"):
            if key not in data:
                raise NNMFileError(f"{f}: no variable '{key}'")
        M, K = data["M"], data["K"]
        # the file's dof_labels ('node 12 uz') are its DOF map, as when the .mat is loaded alone (they were dropped
        # here: springs by node refused, rotations scaled as translations); the description's dof_map wins
        dof_map = (DofMap.from_labels(strings_of(data["dof_labels"]))
                   if "dof_labels" in data and "dof_map" not in mt else None)
        springs = springs_from_mat(data, M.shape[0], f)
    if M.shape != K.shape:
        raise NNMFileError(f"{where}: M is {M.shape[0]}x{M.shape[1]} but K is {K.shape[0]}x{K.shape[1]}; "
                           f"they must have the same size")
    if "dof_map" in mt:
        if dof_map is not None:
            raise NNMInputError(f"{where}: {fmt} files carry their own DOF map; remove dof_map")
        dof_map = read_dof_map_file(folder / str(mt["dof_map"]), f"{where} dof_map: ")
        if len(dof_map) != M.shape[0]:
            raise NNMFileError(f"{folder / str(mt['dof_map'])}: {len(dof_map)} DOFs listed, the matrices have "
                               f"{M.shape[0]}")
    return M, K, dof_map, fmt, springs


def display_mesh(path, n, dof_map, *, nodes=None, first_node=1, dofs_per_node=None, recovery=None, scale=1.0,
                 file_format=None, where=""):
    """The [mesh]'s DisplayMesh: a Nastran bulk data file (no format given) by pyNastran, its grids by ID
    (nastran_mesh.py); any other file by meshio (meshfile.py)."""
    from .nastran_mesh import BULK_SUFFIXES, read_bdf_mesh

    if Path(path).suffix.lower() in BULK_SUFFIXES and file_format is None:
        if nodes is not None or dofs_per_node is not None:
            raise NNMInputError(f"{where}a Nastran bulk data mesh is placed by grid ID (the DOF map); nodes and "
                                f"dofs_per_node are for other mesh files (or set format = \"nastran\" for meshio)")
        return read_bdf_mesh(path, n, dof_map, recovery=recovery, scale=scale, where=where)
    from .meshfile import read_display_mesh

    return read_display_mesh(path, n, dof_map, nodes=nodes, first_node=first_node, dofs_per_node=dofs_per_node,
                             recovery=recovery, scale=scale, file_format=file_format, where=where)


def read_description(path):
    """The parsed TOML of a description file (dict); one-line NNMFileError on a syntax error."""
    path = existing(path, "model description")
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise NNMFileError(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise NNMFileError(f"{path}: not a text (TOML) file") from None


def load_toml_model(path, name=None):
    """Model described by a TOML file (matrix files, springs, units, display mesh); see the module docstring."""
    path = Path(path)
    data = read_description(path)
    where = str(path)
    try:
        _unknown(data, TOP_KEYS, where)
        folder = path.parent
        units = Units.parse(data.get("units"), f"{where} units: ")
        mt = _table(data, "matrices", where, required=True)
        M, K, dof_map, fmt, springs = read_matrices(mt, folder, f"{where} [matrices]")
        n = M.shape[0]
        rotations = dof_map.rotations() if dof_map is not None else np.zeros(n, bool)
        if not units.is_si and dof_map is not None and dof_map.modal().any():
            raise NNMInputError(f"{where}: units {units}: a superelement's modal coordinates (QSET scalar points) "
                                f"have no length unit to convert; give its matrices in SI")
        M, K = units.to_si(M, K, rotations)
        springs = [to_si(s, units.coefficient_scale(bool(rotations[s.dof]))) for s in springs]
        springs += build_springs(_table(data, "springs", where, list) or [], n, dof_map, units, where)
        mesh = None
        ms = _table(data, "mesh", where)
        if ms is not None:
            _unknown(ms, MESH_KEYS, f"{where} [mesh]")
            if "file" not in ms:
                raise NNMInputError(f"{where} [mesh]: missing file (a mesh file meshio reads)")
            mesh = display_mesh(folder / str(ms["file"]), n, dof_map, nodes=ms.get("nodes"),
                                     first_node=ms.get("first_node", 1), dofs_per_node=ms.get("dofs_per_node"),
                                     recovery=None if "recovery" not in ms else folder / str(ms["recovery"]),
                                     scale=units.L, file_format=ms.get("format"), where=f"{where} [mesh]: ")
            if not units.is_si:  # map from SI model coordinates to vertex displacements in m
                per_dof = units.L / units.dof_scale(rotations)[None, :]
                D = mesh.displacement_map
                mesh.displacement_map = D.multiply(per_dof).tocsr() if hasattr(D, "multiply") else D * per_dof
        info = {"source": path.name, "format": fmt, "units": str(units)}
        if isinstance(data.get("description"), str):
            info["description"] = data["description"]
        model_name = name or str(data.get("name", path.stem))
    except NNMFileError:
        raise
    except NNMInputError as exc:
        msg = str(exc)
        raise NNMInputError(msg if msg.startswith(where) else f"{where}: {msg}") from None
    try:
        return Model(M, K, springs, dof_labels=None if dof_map is None else dof_map.labels(), mesh=mesh,
                     name=model_name, info=info)
    except NNMInputError as exc:
        raise NNMInputError(f"{where}: {exc}") from None
