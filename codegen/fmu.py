"""The texts of an FMI 2.0 Co-Simulation FMU of a generated model: its modelDescription.xml and the small C file
that tells the FMI slave (runtime/c/fmi2/gac_fmi2.c) which model it runs.

The variables follow the value references of gac_fmi2.h: the coordinates q and rates qd (outputs), the inputs u,
the parameters p, the initial state q0, qd0 and the solver settings (parameters), the energy terms and the
impact count (outputs).  Everything here is plain text; building the binary and zipping the FMU is
``runtime.fmu``'s job.
"""
from __future__ import annotations

import re
import uuid
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from .artifact import GeneratedModel
from .emit import _double_literal, _environment, param_doc
from .parameters import parameter_rules
from .scene import Scene, coordinate_names
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

# Solver settings and energy outputs, in the order of gac_fmi2.h (GAC_FMI2_NSOLVER_REAL, GAC_FMI2_NOUT_REAL);
# the solver's start values are gac_default_options' (a test reads them back from a built FMU).
SOLVER_REALS = (("solver.rtol", 1e-8, None, "relative tolerance of DOPRI5/DOP853 (default: the experiment's "
                 "tolerance if one is given)"),
                ("solver.atol", 1e-10, None, "absolute tolerance of DOPRI5/DOP853 (default: the experiment's "
                 "tolerance / 100 if one is given)"),
                ("solver.dt", 0.0, "s", "RK4 step; the first step of DOPRI5/DOP853 (0: automatic)"),
                ("solver.h_max", 0.0, "s", "largest step (0: unbounded)"))
ENERGY_OUTPUTS = (("energy.kinetic", "kinetic energy T"),
                  ("energy.potential", "potential energy V (gravity and joint springs)"),
                  ("energy.work_input", "work of the inputs since the start"),
                  ("energy.dissipated", "energy the joint dampers took since the start"),
                  ("energy.impact_loss", "kinetic energy the impacts took since the start"),
                  ("energy.friction", "energy sliding friction took at resting contacts since the start"))


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
    angle = name.startswith("theta")
    if force:
        return "N.m" if angle else "N"
    return ("rad/s" if angle else "m/s") if rate else ("rad" if angle else "m")


def _parameter_unit(pname: str) -> str | None:
    doc = param_doc(pname)
    match = re.search(r"\(([^()]*)\)\s*$", doc)
    return DOC_UNITS[match.group(1)] if match else None


def fmi2_variables(model: GeneratedModel, scene: Scene, constants: dict) -> list[Variable]:
    """Every variable of the FMU, in the order of gac_fmi2.h's value references (Real, then Integer).  ``constants``:
    the library's (gac.h, as runtime.header reads it): the smallest rtol and the integrators' codes."""
    layout = model.layout
    names = coordinate_names(scene.n)
    coordinates = [names[i] for i in layout.free]
    q0 = layout.reduce(scene.q0)
    qd0 = layout.reduce(scene.qd0)
    real: list[tuple] = []
    for c in coordinates:
        real.append((f"q.{c}", "output", "continuous", f"coordinate {c}", coordinate_unit(c), None))
    for c in coordinates:
        real.append((f"qd.{c}", "output", "continuous", f"rate of {c}", coordinate_unit(c, rate=True), None))
    for c in scene.inputs:
        real.append((f"u.{c}", "input", "continuous", f"generalised force on {c}, held over each step",
                     coordinate_unit(c, force=True), 0.0))
    bounds = {}                                     # the parameters' allowed ranges (codegen.parameters), as min, max
    for rule, value in zip(parameter_rules(scene, layout.zero_params, model.bake_params),
                           scene.parameter_vector().tolist()):
        real.append((f"p.{rule.name}", "parameter", "fixed", param_doc(rule.name), _parameter_unit(rule.name), value))
        bounds[f"p.{rule.name}"] = (_double_literal(rule.lo), _double_literal(rule.hi))
    bounds["solver.dt"] = bounds["solver.h_max"] = ("0", None)
    bounds["solver.rtol"] = (_double_literal(constants["GAC_RTOL_MIN"]), "1.0")     # below 1 too: fmi2SetReal refuses rtol = 1
    for c, value in zip(coordinates, q0):
        real.append((f"q0.{c}", "parameter", "fixed", f"initial {c}", coordinate_unit(c), float(value)))
    for c, value in zip(coordinates, qd0):
        real.append((f"qd0.{c}", "parameter", "fixed", f"initial rate of {c}", coordinate_unit(c, rate=True),
                     float(value)))
    for vname, value, unit, doc in SOLVER_REALS:
        real.append((vname, "parameter", "fixed", doc, unit, value))
    for vname, doc in ENERGY_OUTPUTS:
        real.append((vname, "output", "continuous", doc, "J", None))

    methods = rk4, dopri5, dop853 = (constants[f"GAC_METHOD_{m}"] for m in ("RK4", "DOPRI5", "DOP853"))
    variables = []
    for vr, (vname, causality, variability, doc, unit, start) in enumerate(real):
        if causality == "parameter" and vname.startswith("p.") and model.bake_params:
            continue                                # built into the code: nothing to set
        variables.append(Variable(vname, vr, "Real", causality, variability, doc, unit,
                                  None if start is None else _double_literal(start),
                                  "calculated" if causality == "output" else None, *bounds.get(vname, (None, None))))
    variables += [
        Variable("solver.method", 0, "Integer", "parameter", "fixed",
                 f"integrator: {rk4} RK4 (fixed step solver.dt), {dopri5} DOPRI5, {dop853} DOP853",
                 start=str(dopri5), min=str(min(methods)), max=str(max(methods))),
        Variable("impacts", 1, "Integer", "output", "discrete", "impacts since the start", initial="calculated"),
        Variable("resting_contacts", 2, "Integer", "output", "discrete", "contacts resting on their wall now",
                 initial="calculated"),
    ]
    return variables


def fmu_guid(model: GeneratedModel) -> str:
    """The FMU's GUID: fixed by the model's text, so the same model always gives the same FMU."""
    return "{" + str(uuid.UUID(hex=model.text_digest()[:32])) + "}"


def fmu_texts(model: GeneratedModel, scene: Scene, sources: list[str], stop_time: float,
              step_size: float, constants: dict) -> dict[str, str]:
    """modelDescription.xml and NAME_fmi2.c of the model's FMU; ``sources``: the C files shipped in sources/;
    ``constants``: the library's (runtime.header.library_constants)."""
    variables = fmi2_variables(model, scene, constants)
    outputs = [index for index, v in enumerate(variables, start=1) if v.causality == "output"]
    used = sorted({v.unit for v in variables if v.unit})
    context = dict(name=model.name, guid=fmu_guid(model), version=__version__, fmi_version=FMI_VERSION,
                   description=f"{scene.name}: {scene.n}-link chain confined in a box (flight, impacts, resting "
                               "contact), recursive Gibbs-Appell", variables=variables, outputs=outputs,
                   units=[(unit, UNITS[unit]) for unit in used], sources=sources,
                   stop_time=_double_literal(stop_time), step_size=_double_literal(step_size),
                   bake_params=model.bake_params, quote=quoteattr)
    env = _environment()
    return {"modelDescription.xml": env.get_template("modelDescription.xml.j2").render(**context),
            f"{model.name}_fmi2.c": env.get_template("fmi2_model.c.j2").render(**context)}
