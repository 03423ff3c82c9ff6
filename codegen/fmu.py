"""The texts of an FMI 2.0 Co-Simulation FMU of a generated model: its modelDescription.xml and the small C file
that tells the FMI slave (runtime/c/fmi2/gac_fmi2.c) which model it runs.

The variables are described once, by the rows of gac_fmi2.h (the coordinates q and rates qd (outputs), the inputs
u, the parameters p, the initial state q0, qd0 and the solver settings (parameters), the energy terms and the
impact count (outputs)); the tools layer reads them (runtime.header.fmi2_rows) and hands them here, and
``variable_table`` renders them as docs/fmi.md's table.  Everything here is plain text; building the binary and
zipping the FMU is ``runtime.fmu``'s job.
"""
from __future__ import annotations

import re
import uuid
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from .artifact import GeneratedModel
from .emit import _double_literal, _environment, param_doc
from .parameters import parameter_rules
from .scene import Scene
from .version import __version__

FMI_VERSION = "2.0"

# The units the variables use, as FMI 2.0 <Unit> elements: exponents of the SI base units (and rad).
UNITS = {
    "s": {"s": 1}, "m": {"m": 1}, "rad": {"rad": 1}, "kg": {"kg": 1},
    "m/s": {"m": 1, "s": -1}, "rad/s": {"rad": 1, "s": -1}, "m/s2": {"m": 1, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2}, "J": {"kg": 1, "m": 2, "s": -2},
    "kg/m": {"kg": 1, "m": -1}, "kg.m": {"kg": 1, "m": 1}, "kg.m2": {"kg": 1, "m": 2},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1}, "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
}

# The unit written in a parameter's description (codegen.emit.param_doc) -> its FMI unit name.
DOC_UNITS = {"m": "m", "rad": "rad", "kg": "kg", "kg/m": "kg/m", "kg m": "kg.m", "kg m^2": "kg.m2",
             "m/s^2": "m/s2", "N m/rad": "N.m/rad", "N m s/rad": "N.m.s/rad", "-": None}

@dataclass(frozen=True)
class Variable:
    """One ScalarVariable of modelDescription.xml."""

    name: str
    value_reference: int
    type: str                       # Real or Integer
    causality: str                  # output, input or parameter
    variability: str                # continuous, discrete or fixed
    description: str
    unit: str | None = None
    start: str | None = None        # the start value as text (inputs and parameters)
    initial: str | None = None      # calculated for outputs
    min: str | None = None
    max: str | None = None

    def attributes(self) -> str:
        """The element's attributes, quoted."""
        pairs = [("name", self.name), ("valueReference", str(self.value_reference)),
                 ("description", self.description), ("causality", self.causality),
                 ("variability", self.variability)]
        if self.initial:
            pairs.append(("initial", self.initial))
        return " ".join(f"{key}={quoteattr(value)}" for key, value in pairs)

    def type_attributes(self) -> str:
        pairs = [(key, value) for key, value in (("unit", self.unit), ("min", self.min), ("max", self.max),
                                                 ("start", self.start)) if value is not None]
        return " ".join(f"{key}={quoteattr(value)}" for key, value in pairs)


def coordinate_unit(name: str, rate: bool = False, force: bool = False) -> str:
    angle = (name.partition(".")[2] or name).startswith("theta")      # a chain's prefix ('c2.theta_1') dropped
    if force:
        return "N.m" if angle else "N"
    return ("rad/s" if angle else "m/s") if rate else ("rad" if angle else "m")


def _parameter_unit(pname: str) -> str | None:
    doc = param_doc(pname)
    match = re.search(r"\(([^()]*)\)\s*$", doc)
    return DOC_UNITS[match.group(1)] if match else None


def library_text(text: str, constants: dict) -> str:
    """A row's text with the library's constants (GAC_METHOD_DOPRI5) written as their values."""
    return re.sub(r"\bGAC_\w+\b", lambda m: f"{constants[m.group(0)]:g}", text)


def fmi2_variables(model: GeneratedModel, scene: Scene, rows: dict, constants: dict) -> list[Variable]:
    """Every variable of the FMU, in the order of its value references (Real, then Integer), from the rows that
    describe them once (gac_fmi2.h's GAC_FMI2_REALS and GAC_FMI2_INTEGERS, read by runtime.header.fmi2_rows):
    a row of count 1 is one variable, a block (count nq, nu or nparam) one per coordinate, input or parameter, with
    its start from the scene.  ``constants``: the library's (gac.h), for the smallest rtol and the codes of the methods and impact laws."""
    layout = model.layout
    names = scene.full_coordinate_names()           # several chains: each with its prefix ('c2.theta_1')
    coordinates = [names[i] for i in layout.free]
    rules = parameter_rules(scene, layout.zero_params, model.bake_params, layout.held_params)
    blocks = {                                      # a block's members: (name, what %s stands for, scene's start)
        "Q": [(c, c, None) for c in coordinates],
        "QD": [(c, c, None) for c in coordinates],
        "U": [(c, c, None) for c in scene.inputs],
        "P": [(rule.name, param_doc(rule.name, scene), value)
              for rule, value in zip(rules, scene.parameter_vector().tolist())],
        "Q0": [(c, c, float(v)) for c, v in zip(coordinates, layout.reduce(scene.q0))],
        "QD0": [(c, c, float(v)) for c, v in zip(coordinates, layout.reduce(scene.qd0))],
    }
    bounds = {f"p.{rule.name}": (_double_literal(rule.lo), _double_literal(rule.hi)) for rule in rules}
    bounds["solver.dt"] = bounds["solver.h_max"] = ("0", None)
    bounds["solver.rtol"] = (_double_literal(float(constants["GAC_RTOL_MIN"])), "1.0")   # fmi2SetReal refuses 1
    methods = [int(constants[f"GAC_METHOD_{m}"]) for m in ("RK4", "DOPRI5", "DOP853")]
    bounds["solver.method"] = (str(min(methods)), str(max(methods)))
    laws = [int(constants[f"GAC_IMPACT_LAW_{law}"]) for law in ("FRICTIONLESS", "GDI", "NEWTON_COULOMB")]
    bounds["solver.impact_law"] = (str(min(laws)), str(max(laws)))
    bounds["solver.stick"] = ("0", "1")

    variables = []
    for vtype in ("Real", "Integer"):
        vr = 0
        for row in rows[vtype]:
            members = blocks[row["id"]] if row["count"] != "1" else [(None, None, None)]
            for member, said, scene_start in members:
                name = row["name"] if member is None else row["name"].rsplit(".", 1)[0] + "." + member
                unit = _unit(row["unit"], member)
                what = library_text(row["what"], constants).replace("%s", said or "")
                start = None
                if row["causality"] in ("parameter", "input"):
                    value = scene_start if scene_start is not None else library_text(row["start"], constants)
                    start = _double_literal(float(value)) if vtype == "Real" else str(int(float(value)))
                skip = row["id"] == "P" and model.bake_params         # built into the code: nothing to set
                if not skip:
                    variables.append(Variable(name, vr, vtype, row["causality"], row["variability"], what, unit, start,
                                              "calculated" if row["causality"] == "output" else None,
                                              *bounds.get(name, (None, None))))
                vr += 1
    return variables


def _unit(unit: str, member: str | None) -> str | None:
    """A row's unit for one of its variables: its own unit, or by the row's rule ("coordinate", "rate", "force",
    "parameter") from the variable's coordinate or parameter."""
    if unit == "parameter":
        return _parameter_unit(member)
    if unit in ("coordinate", "rate", "force"):
        return coordinate_unit(member, rate=unit == "rate", force=unit == "force")
    return unit or None


def fmu_guid(model: GeneratedModel) -> str:
    """The FMU's GUID: fixed by the model's text, so the same model always gives the same FMU."""
    return "{" + str(uuid.UUID(hex=model.text_digest()[:32])) + "}"


def fmu_texts(model: GeneratedModel, scene: Scene, sources: list[str], stop_time: float,
              step_size: float, rows: dict, constants: dict) -> dict[str, str]:
    """modelDescription.xml and NAME_fmi2.c of the model's FMU; ``sources``: the C files shipped in sources/;
    ``rows``: the FMU's variables as gac_fmi2.h describes them, ``constants``: the library's (runtime.header's
    fmi2_rows and library_constants: the emission layer does not read runtime/c itself)."""
    variables = fmi2_variables(model, scene, rows, constants)
    outputs = [index for index, v in enumerate(variables, start=1) if v.causality == "output"]
    used = sorted({v.unit for v in variables if v.unit})
    chains = getattr(scene, "chains", None)
    what = (f"{len(chains)} chains of {', '.join(str(c.n) for c in chains)} links" if chains
            else f"{scene.n}-link chain")
    context = dict(name=model.name, guid=fmu_guid(model), version=__version__, fmi_version=FMI_VERSION,
                   description=f"{scene.name}: {what} confined in a box (flight, impacts, resting contact), "
                               "recursive Gibbs-Appell", variables=variables, outputs=outputs,
                   units=[(unit, UNITS[unit]) for unit in used], sources=sources,
                   stop_time=_double_literal(stop_time), step_size=_double_literal(step_size),
                   bake_params=model.bake_params, quote=quoteattr)
    env = _environment()
    return {"modelDescription.xml": env.get_template("modelDescription.xml.j2").render(**context),
            f"{model.name}_fmi2.c": env.get_template("fmi2_model.c.j2").render(**context)}


UNIT_WORDS = {"coordinate": "m or rad", "rate": "m/s or rad/s", "force": "N or N m", "parameter": "per parameter"}


def variable_table(rows: dict, constants: dict) -> str:
    """The FMU's variables as a markdown table (docs/fmi.md renders it between its markers), one line per row of
    gac_fmi2.h: a block's name stands for one variable per coordinate C or parameter NAME."""
    lines = ["| name | type | causality | unit | start | what |", "|---|---|---|---|---|---|"]
    scene_start = {"P", "Q0", "QD0"}
    for vtype in ("Real", "Integer"):
        for row in rows[vtype]:
            block = row["count"] != "1"
            member = row["name"].rsplit(".", 1)[1] if block else ""
            causality = row["causality"] + (" (fixed)" if row["variability"] == "fixed" else "")
            unit = UNIT_WORDS.get(row["unit"], row["unit"])
            if row["causality"] == "output":
                start = ""
            elif row["id"] in scene_start:
                start = "the scene's"
            else:
                start = library_text(row["start"], constants)
            what = library_text(row["what"], constants)
            what = "its description" if what == "%s" else what.replace("%s", member)
            lines.append(f"| `{row['name']}` | {vtype} | {causality} | {unit} | {start} | {what} |")
    return "\n".join(lines) + "\n"
