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
    #          dof_map = "model.bdf" (its ASET/ASET1 cards) or a 'grid component' text file (nastran.py)

    [[springs]]                          # one table per nonlinear element
    type = "cubic"                       # default; the element type (see SPRING_TYPES); "polynomial" takes
                                         # coefficients = {2 = k2, 3 = k3, ...} (force sum k_p d^p);
                                         # "piecewise_linear" takes stiffnesses = [k0, k1, ...] (force /
                                         # length), breakpoints = [d1, ...] (length), optional eps and, for
                                         # an asymmetric law, stiffnesses_negative + breakpoints_negative
    node = 6                             # by node and direction (needs a DOF map) ...
    direction = "uz"
    k3 = 1e9                             # in the description's units (force / length^3)
    # dof = 33                           # ... or by 0-based DOF index; other / other_node (+ other_direction)
                                         # make a relative spring on x[dof] - x[other]
    [mesh]                               # optional display mesh (any format meshio reads)
    file = "beam.msh"
    # first_node = 1 | nodes = [...] | dofs_per_node = 6 | recovery = "R.mtx"   (see meshfile.py)
    # format = "gmsh"                    # meshio's format name, when the suffix is ambiguous

Every number (matrices, k3, mesh coordinates) is in the description's units; the model is built in
SI.  Relative paths are relative to the description file.  Errors name the file and the table.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ...model.elements import CubicSpring
from ...errors import NNMFileError, NNMInputError
from ...model.model import Model
from .common import Units, direction_name, existing, read_dof_map_file

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

FORMATS = ("matrixmarket", "abaqus", "ansys", "matlab", "nastran")
TOP_KEYS = {"name", "description", "units", "matrices", "springs", "mesh"}
MATRIX_KEYS = {"format", "mass", "stiffness", "file", "dof_map"}
MESH_KEYS = {"file", "format", "nodes", "first_node", "dofs_per_node", "recovery"}
LOCATION_KEYS = {"type", "dof", "other", "node", "direction", "other_node", "other_direction"}


@dataclass(frozen=True)
class SpringType:
    """A nonlinear element type of the ``[[springs]]`` tables.

    parameters : its required keys (in the description's units);
    build(dof, other, params, scale) -> element, where scale(p) converts the coefficient of d^p
    of a force law to SI;
    parse(key, value, where) -> the parameter's value (default: a finite number);
    optional : keys that may be given (passed to build only when present).
    """

    parameters: tuple
    build: Callable
    parse: Callable | None = None
    optional: tuple = ()


def _cubic(dof, other, params, scale):
    return CubicSpring(dof=dof, other=other, k3=params["k3"] * scale(3))


def _law_table(key, value, where):
    """{power: coefficient} from a TOML table such as {2 = 1e5, 3 = 1e9}."""
    if not isinstance(value, dict) or not value:
        raise NNMInputError(f"{where}: {key} must be a table of powers and coefficients, e.g. {{2 = 1e5, 3 = 1e9}}")
    law = {}
    for p, c in value.items():
        if not str(p).isdigit() or int(p) < 2:
            raise NNMInputError(f"{where}: {key}: power {p!r} is not an integer >= 2 (the linear stiffness is in K)")
        law[int(p)] = _number(c, f"{key}.{p}", where)
    return law


def _polynomial(dof, other, params, scale):
    from ...model.elements import PolynomialSpring
    return PolynomialSpring(dof=dof, other=other, coefficients={p: c * scale(p) for p, c in
                                                                params["coefficients"].items()})


def _pwl_parse(key, value, where):
    """A list of numbers (stiffnesses, breakpoints) or one number (eps)."""
    if key == "eps":
        return _number(value, key, where)
    if not isinstance(value, list):
        raise NNMInputError(f"{where}: {key} must be a list of numbers, e.g. {key} = [1e5, 2e4]")
    return [_number(v, f"{key}[{i}]", where) for i, v in enumerate(value)]


def _piecewise(dof, other, params, scale):
    """PiecewiseLinearSpring: stiffnesses are coefficients of d^1 (force / length), breakpoints lengths."""
    from ...model.elements import PiecewiseLinearSpring
    law = {k: params[k] for k in ("stiffnesses", "breakpoints", "stiffnesses_negative", "breakpoints_negative", "eps")
           if k in params}
    return to_si(PiecewiseLinearSpring(dof=dof, other=other, **law), scale)


def to_si(spring, scale):
    """The element ``spring`` given in file units, in SI; scale(p) converts the coefficient of d^p (E / s^(p+1),
    s the DOF's unit), so a stiffness scales by scale(1) and a length (breakpoint) by scale(0) / scale(1) = s."""
    from ...model.elements import PiecewiseLinearSpring, PolynomialSpring
    if isinstance(spring, CubicSpring):
        return spring.scaled(scale(3))
    if isinstance(spring, PolynomialSpring):
        return PolynomialSpring(dof=spring.dof, other=spring.other,
                                coefficients={p: c * scale(p) for p, c in spring.coefficients.items()})
    if isinstance(spring, PiecewiseLinearSpring):
        k, s = scale(1), scale(0) / scale(1)
        if k == 1.0 and s == 1.0:
            return spring
        neg = {} if spring.symmetric else dict(stiffnesses_negative=[c * k for c in spring.stiffnesses_negative],
                                               breakpoints_negative=[b * s for b in spring.breakpoints_negative])
        return PiecewiseLinearSpring(dof=spring.dof, other=spring.other, stiffnesses=[c * k for c in spring.stiffnesses],
                                     breakpoints=[b * s for b in spring.breakpoints], eps=spring.eps, **neg)
    raise NNMInputError(f"no unit conversion for {type(spring).__name__}")


#: element types by name; a new element type registers its builder here (``type = "<name>"``)
SPRING_TYPES = {"cubic": SpringType(("k3",), _cubic),
                "polynomial": SpringType(("coefficients",), _polynomial, _law_table),
                "piecewise_linear": SpringType(("stiffnesses", "breakpoints"), _piecewise, _pwl_parse,
                                               ("eps", "stiffnesses_negative", "breakpoints_negative"))}


def _table(data, key, where, kind=dict, required=False):
    v = data.get(key)
    if v is None:
        if required:
            raise NNMInputError(f"{where}: missing [{key}]")
        return None
    if not isinstance(v, kind):
        raise NNMInputError(f"{where}: '{key}' must be a {'table' if kind is dict else 'list of tables'}")
    return v


def _unknown(table, allowed, where):
    extra = sorted(set(table) - set(allowed))
    if extra:
        raise NNMInputError(f"{where}: unknown key(s) {', '.join(extra)}; known: {', '.join(sorted(allowed))}")


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
        from .matlab import SPRING_VARIABLES, read_mat, springs_from_mat
        data = read_mat(f, ["M", "K", "springs_version", *SPRING_VARIABLES])
        for key in ("M", "K"):
            if key not in data:
                raise NNMFileError(f"{f}: no variable '{key}'")
        M, K = data["M"], data["K"]
        dof_map = None
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


def _number(value, key, where):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise NNMInputError(f"{where}: {key} = {value!r} is not a number")
    if not np.isfinite(value):
        raise NNMInputError(f"{where}: {key} = {value} is not finite")
    return float(value)


def _dof(row, prefix, n, dof_map, where):
    """0-based DOF of a spring end: '<prefix>' index or '<prefix>node' + direction; None if absent."""
    idx_key = "dof" if prefix == "" else "other"
    node_key = "node" if prefix == "" else "other_node"
    if idx_key in row and node_key in row:
        raise NNMInputError(f"{where}: give {idx_key} or {node_key}, not both")
    if idx_key in row:
        d = row[idx_key]
        if isinstance(d, bool) or not isinstance(d, int) or not 0 <= d < n:
            raise NNMInputError(f"{where}: {idx_key} = {d!r} is not a DOF of the model (0-based, 0..{n - 1})")
        return d
    if node_key in row:
        if dof_map is None:
            raise NNMInputError(f"{where}: springs by node need a DOF map; these matrix files have none: give "
                                f"{idx_key} = <0-based index>, or [matrices] dof_map = <file>")
        direction = row.get("other_direction", row.get("direction")) if prefix else row.get("direction")
        if direction is None:
            raise NNMInputError(f"{where}: {node_key} needs a direction (ux, uy, uz, rx, ry, rz)")
        return dof_map.index(row[node_key], direction, f"{where}: ")
    return None


def build_springs(rows, n, dof_map, units, where):
    rotations = dof_map.rotations() if dof_map is not None else np.zeros(n, bool)
    out = []
    for i, row in enumerate(rows, 1):
        w = f"{where} [[springs]] #{i}"
        if not isinstance(row, dict):
            raise NNMInputError(f"{w}: must be a table")
        kind = str(row.get("type", "cubic")).lower()
        if kind not in SPRING_TYPES:
            raise NNMInputError(f"{w}: unknown type {row.get('type')!r}; known: {', '.join(SPRING_TYPES)}")
        st = SPRING_TYPES[kind]
        _unknown(row, LOCATION_KEYS | set(st.parameters) | set(st.optional), w)
        if "direction" in row:
            direction_name(row["direction"], f"{w}: ")
        dof = _dof(row, "", n, dof_map, w)
        if dof is None:
            raise NNMInputError(f"{w}: give dof = <0-based index> or node = <node> with direction = <ux..rz>")
        other = _dof(row, "other", n, dof_map, w)
        if other is not None and rotations[other] != rotations[dof]:
            raise NNMInputError(f"{w}: a relative spring joins a rotation and a translation")
        missing = [k for k in st.parameters if k not in row]
        if missing:
            raise NNMInputError(f"{w}: missing {', '.join(missing)} (a {kind} spring needs "
                                f"{', '.join(st.parameters)})")
        params = {k: st.parse(k, row[k], w) if st.parse else _number(row[k], k, w)
                  for k in (*st.parameters, *st.optional) if k in row}
        try:
            element = st.build(dof, other, params, units.coefficient_scale(bool(rotations[dof])))
        except (TypeError, ValueError) as exc:
            raise NNMInputError(f"{w}: {exc}") from None
        out.append(element)
    return out


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
        M, K = units.to_si(M, K, rotations)
        springs = [to_si(s, units.coefficient_scale(bool(rotations[s.dof]))) for s in springs]
        springs += build_springs(_table(data, "springs", where, list) or [], n, dof_map, units, where)
        mesh = None
        ms = _table(data, "mesh", where)
        if ms is not None:
            _unknown(ms, MESH_KEYS, f"{where} [mesh]")
            if "file" not in ms:
                raise NNMInputError(f"{where} [mesh]: missing file (a mesh file meshio reads)")
            from .meshfile import read_display_mesh
            mesh = read_display_mesh(folder / str(ms["file"]), n, dof_map, nodes=ms.get("nodes"),
                                     first_node=ms.get("first_node", 1), dofs_per_node=ms.get("dofs_per_node"),
                                     recovery=None if "recovery" not in ms else folder / str(ms["recovery"]),
                                     scale=units.L, file_format=ms.get("format"), where=f"{where} [mesh]: ")
            if not units.is_si:  # map from SI model coordinates to vertex displacements in m
                mesh.displacement_map = units.L * mesh.displacement_map / units.dof_scale(rotations)[None, :]
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
