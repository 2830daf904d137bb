"""What the page says about the model: its nonlinear elements (type, DOFs, parameters), for the
Modes tab and the title line."""
from __future__ import annotations


#: elements listed in the table at most
MAX_ELEMENTS_LISTED = 60


def _num(v):
    return f"{float(v):.4g}"


def dof_text(model, d):
    """'12' or '12 (wing tip z)' with the model's DOF label."""
    labels = getattr(model, "dof_labels", None)
    if labels is not None and 0 <= d < len(labels):
        return f"{d} ({labels[d]})"
    return str(d)


def element_dofs(model, el):
    """The element's deformation in words: 'x[3]' (grounded) or 'x[3] - x[8]' (relative), with labels."""
    if not hasattr(el, "dof"):                       # an element in several coordinates (PolynomialStiffness)
        dofs = getattr(el, "dofs", None)
        dofs = range(model.n) if dofs is None else dofs
        return ", ".join(f"x[{dof_text(model, d)}]" for d in list(dofs)[:6]) + (" ..." if len(list(dofs)) > 6 else "")
    other = getattr(el, "other", None)
    text = f"x[{dof_text(model, el.dof)}]"
    return text if other is None else f"{text} − x[{dof_text(model, other)}]"


def element_parameters(el):
    """The element's parameters in SI units (CubicSpring, PolynomialSpring, PiecewiseLinearSpring; any
    other element: its law, else its fields)."""
    kind = type(el).__name__
    if kind == "CubicSpring":
        return f"k3 = {_num(el.k3)} N/m³"
    if kind == "PolynomialSpring":
        return ", ".join(f"k{p} = {_num(c)} N/m^{p}" for p, c in sorted(el.coefficients.items()))
    if kind == "PiecewiseLinearSpring":
        slopes = ", ".join(_num(k) for k in el.stiffnesses)
        bps = ", ".join(_num(b) for b in el.breakpoints)
        return f"slopes [{slopes}] N/m at breakpoints [{bps}] m (kinks smoothed over eps = {_num(el.eps)} x d1)"
    try:
        law = el.law()
        if law:
            return ", ".join(f"k{p} = {_num(c)}" for p, c in sorted(law.items()))
    except Exception:
        pass
    fields = {k: v for k, v in vars(el).items() if k not in ("dof", "other")} if hasattr(el, "__dict__") else {}
    return ", ".join(f"{k} = {v}" for k, v in fields.items()) or repr(el)


ELEMENT_NAMES = {"CubicSpring": "cubic spring", "PolynomialSpring": "polynomial spring",
                 "PiecewiseLinearSpring": "piecewise-linear spring"}


def elements_summary(model):
    """'4 cubic springs', '1 cubic spring, 2 piecewise-linear springs', 'no nonlinear element'."""
    counts = {}
    for el in model.springs:
        name = ELEMENT_NAMES.get(type(el).__name__, type(el).__name__)
        counts[name] = counts.get(name, 0) + 1
    if not counts:
        return "no nonlinear element"
    return ", ".join(f"{n} {name}{'s' if n > 1 else ''}" for name, n in counts.items())


def elements_markdown(model):
    """Markdown table of the model's nonlinear elements: type, deformation (DOFs), parameters."""
    els = list(model.springs)
    head = f"**Nonlinear elements** ({elements_summary(model)})"
    if not els:
        return head
    rows = [head, "", "| # | element | deformation d | parameters |", "|---|---|---|---|"]
    for i, el in enumerate(els[:MAX_ELEMENTS_LISTED]):
        rows.append(f"| {i + 1} | {ELEMENT_NAMES.get(type(el).__name__, type(el).__name__)} | "
                    f"{element_dofs(model, el)} | {element_parameters(el)} |")
    if len(els) > MAX_ELEMENTS_LISTED:
        rows.append(f"\n({len(els) - MAX_ELEMENTS_LISTED} more elements not listed)")
    return "\n".join(rows)


def model_markdown(model):
    """The model in a few lines (Modes tab): name, DOFs, mass, then its nonlinear elements."""
    name = getattr(model, "name", "") or "model"
    mesh = getattr(model, "mesh", None)
    mesh_text = f", display mesh of {len(mesh.vertices)} vertices" if mesh is not None else ""
    return f"**Model:** {name}, {model.n} DOFs{mesh_text}\n\n" + elements_markdown(model)
