"""Print flattened programs as C99 and render them through the Jinja templates in templates/."""
from __future__ import annotations

from importlib import resources

import jinja2
import numpy as np
import sympy as sp
from sympy.codegen.ast import float80, real
from sympy.printing.c import C99CodePrinter

from . import interface
from .flatten import Program
from .artifact import GeneratedModel, RenderedFunction, scene_hash, text_digest  # noqa: F401
from .ops import count_ops
from .options import BuildOptions
from .parameters import parameter_rules
from .scene import DEFAULT_GRAVITY_DIRECTION, OBSTACLE_GEOMETRY_KINDS, WALL_NAMES, JointStop, ObstacleContact, Scene, \
    parameter_name, split_parameter_name
from .version import __version__


class ChainCPrinter(C99CodePrinter):
    """C99 printer for straight-line kernels.

    Doubles are printed with 17 significant digits (round-trip exact), integer powers are
    expanded into products, rationals become double literals, and a product is printed as
    numerator / denominator, matching the counting rule of :mod:`codegen.ops`.
    """

    def _print_Float(self, expr):
        return _double_literal(float(expr))

    def _print_Integer(self, expr):
        return f"{int(expr)}.0"

    def _print_Rational(self, expr):
        return _double_literal(float(expr))

    def _print_Pow(self, expr):
        base, exponent = expr.args
        if exponent.is_Integer:
            k = abs(int(exponent))
            factor = self.parenthesize(base, 50)      # bases are atoms after flatten
            product = "*".join([factor] * k)
            return product if exponent > 0 else f"1.0/({product})"
        if exponent == sp.Rational(1, 2):
            return f"sqrt({self._print(base)})"
        if exponent == sp.Rational(-1, 2):
            return f"1.0/sqrt({self._print(base)})"
        return f"pow({self._print(base)}, {self._print(exponent)})"

    def _print_Mul(self, expr):
        coefficient, factors = expr.as_coeff_mul()
        sign = ""
        if coefficient < 0:
            sign, coefficient = "-", -coefficient
        numerator, denominator = [], []
        if coefficient != 1:
            numerator.append(self._print(coefficient))
        for factor in factors:
            if factor.is_Pow and factor.exp.is_Number and factor.exp < 0:
                denominator.append(sp.Pow(factor.base, -factor.exp))
            else:
                numerator.append(self._factor(factor))
        text = "*".join(numerator) if numerator else "1.0"
        if denominator:
            parts = [self._factor(d) for d in denominator]
            text += "/" + (parts[0] if len(parts) == 1 and denominator[0].is_Atom else f"({'*'.join(parts)})")
        return sign + text

    def _factor(self, expr):
        text = self._print(expr)
        return f"({text})" if (expr.is_Add or expr.is_Pow) else text

    def _print_Add(self, expr):
        terms = [self._print(term) for term in expr.args]
        out = terms[0]
        for term in terms[1:]:
            out += f" - {term[1:]}" if term.startswith("-") else f" + {term}"
        return out


def _double_literal(value: float) -> str:
    text = repr(value)
    if "e" not in text and "." not in text and "inf" not in text and "nan" not in text:
        text += ".0"
    return text


class LongDoubleCPrinter(ChainCPrinter):
    """ChainCPrinter for long double: the inputs' elements widened where they are read ((long double)q[0], so that
    no product or sum of two inputs is rounded to double), literals with an L suffix, the math functions'
    long-double forms (sinl, cosl, fabsl: C99CodePrinter's real type float80) and sqrtl, powl.  A number that is a double (a Float: the scene's
    values and twists) is printed with 21 significant digits of that double, which reads back as the same double in
    long double (64-bit significand); a rational with 21 digits of its exact value."""

    def __init__(self):
        super().__init__({"type_aliases": {real: float80}})

    def _print_Symbol(self, expr):
        name = super()._print_Symbol(expr)
        return f"(long double){name}" if "[" in name else name    # an input (q[0], p[3]): widened before use

    def _print_Float(self, expr):
        return _long_double_literal(f"{float(expr):.21g}")

    def _print_Integer(self, expr):
        return f"{int(expr)}.0L"

    def _print_Rational(self, expr):
        return _long_double_literal(str(sp.N(expr, 21)))

    def _print_Pow(self, expr):
        base, exponent = expr.args
        if exponent.is_Integer:
            k = abs(int(exponent))
            factor = self.parenthesize(base, 50)
            product = "*".join([factor] * k)
            return product if exponent > 0 else f"1.0L/({product})"
        if exponent == sp.Rational(1, 2):
            return f"sqrtl({self._print(base)})"
        if exponent == sp.Rational(-1, 2):
            return f"1.0L/sqrtl({self._print(base)})"
        return f"powl({self._print(base)}, {self._print(exponent)})"


def _long_double_literal(text: str) -> str:
    """A decimal number as a long-double literal: its trailing zeros after the point dropped (0.5L, not
    0.500000000000000000000L), an L appended."""
    mantissa, e, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    else:
        mantissa = mantissa.rstrip("0")
        mantissa += "0" if mantissa.endswith(".") else ""
    return mantissa + e + exponent + "L"


PRINTER = ChainCPrinter()
LONG_DOUBLE_PRINTER = LongDoubleCPrinter()


def c_expression(expr: sp.Expr) -> str:
    return PRINTER.doprint(expr)


def c_expression_ld(expr: sp.Expr) -> str:
    return LONG_DOUBLE_PRINTER.doprint(expr)


# A kernel longer than this is emitted as parts of at most this many lines.  Parts compile about 1.5 times
# faster per line at n = 64 but run 2-9 % slower, so the right-hand side's forward_dynamics (called at every
# integrator stage) is cut only when it is very long.


def render_function(program: Program, split_lines: int | None = interface.SPLIT_LINES) -> RenderedFunction:
    """The C lines of one kernel, and its operation count.  A kernel of more than ``split_lines`` lines (None:
    never) is also cut into parts of at most that many lines, called one after the other: the compiler's
    register allocation and scheduling grow faster than a function's length, so parts compile faster (at a
    cost of 2-9 % per call, measured: hence interface.SPLIT_LINES_HOT for the right-hand side; docs/performance.md)."""
    kernel = program.kernel
    if kernel.block:
        return _render_block(program)
    lines = [f"const double {symbol.name} = {c_expression(expr)};" for symbol, expr in program.assignments]
    for i, expr in enumerate(program.outputs):
        lines.append(f"{kernel.output}[{i}] = {c_expression(expr)};")
    ops = count_ops([e for _, e in program.assignments] + list(program.outputs))
    function = RenderedFunction(kernel.name, kernel.summary, kernel.inputs, kernel.output, kernel.output_size,
                                lines, ops)
    if split_lines is not None and len(lines) > split_lines:
        function.parts, function.scratch = split(program, lines, split_lines)
    return function


def render_extended(program: Program) -> RenderedFunction:
    """The long-double variant NAME_<kernel>_ld of a kernel (interface.EXTENDED_KERNELS) from the kernel's own
    flattened program: inputs double, every intermediate and the output long double.  Never cut into parts (the
    three kernels are O(n) and short)."""
    kernel = program.kernel
    name = interface.EXTENDED_OF[kernel.name]
    summary = next(f.summary for f in interface.KERNELS if f.name == name)
    lines = [f"const long double {symbol.name} = {c_expression_ld(expr)};" for symbol, expr in program.assignments]
    for i, expr in enumerate(program.outputs):
        lines.append(f"{kernel.output}[{i}] = {c_expression_ld(expr)};")
    ops = count_ops([e for _, e in program.assignments] + list(program.outputs))
    return RenderedFunction(name, summary, kernel.inputs, kernel.output, kernel.output_size, lines, ops,
                            out_type="long double")


def _render_block(program: Program) -> RenderedFunction:
    """A tangent kernel of kernel.block directions (codegen.kernels.forward_dynamics_tangent_block_kernel): the
    assignments that read no seed (the primal part) once, then a loop over the directions j with the others, each
    seed array a read at a + j * stride (its j-th direction, as a_j) and the output written at j * stride.  Not cut
    into parts (a loop does not cross them); its operation count is the primal part's plus block times the rest's."""
    kernel = program.kernel
    seeds = {a for a in kernel.inputs if a in kernel.strides}
    seeded, primal, tangent = set(), [], []
    for symbol, expr in program.assignments:
        reads = expr.free_symbols
        if reads & seeded or any(s.name.partition("[")[0] in seeds for s in reads):
            seeded.add(symbol)
            tangent.append((symbol, expr))
        else:
            primal.append((symbol, expr))
    local = {}                                       # a[i] -> a_j[i]
    for expr in [e for _, e in tangent] + list(program.outputs):
        for s in expr.free_symbols:
            array, bracket, rest = s.name.partition("[")
            if bracket and array in seeds:
                local[s] = sp.Symbol(f"{array}_j[{rest}", real=True)
    out, size = kernel.output, kernel.strides[kernel.output]
    lines = [f"const double {symbol.name} = {c_expression(expr)};" for symbol, expr in primal]
    lines.append(f"for (int j = 0; j < {kernel.block}; ++j) {{")
    lines += [f"    const double *{a}_j = {a} != 0 ? {a} + j * {kernel.strides[a]} : 0;" for a in sorted(seeds)]
    lines += [f"    (void){a}_j;" for a in sorted(seeds)]
    lines += [f"    const double {symbol.name} = {c_expression(expr.xreplace(local))};" for symbol, expr in tangent]
    lines += [f"    {out}[j * {size} + {i}] = {c_expression(expr.xreplace(local))};"
              for i, expr in enumerate(program.outputs)]
    lines.append("}")
    ops = count_ops([e for _, e in primal])
    once = count_ops([e for _, e in tangent] + list(program.outputs))
    for _ in range(kernel.block):
        ops = ops + once
    return RenderedFunction(kernel.name, kernel.summary, kernel.inputs, kernel.output, kernel.output_size, lines, ops)


def split(program: Program, lines: list[str], size: int) -> tuple[list[list[str]], int]:
    """Cut straight-line code into parts of at most ``size`` lines (the outputs go with the last part).  A value
    one part defines and a later part uses is stored in the scratch array s[] at the end of the first and
    read back at the start of the other; a slot is reused once the last part reading it has started."""
    symbols = [symbol for symbol, _ in program.assignments]
    expressions = [expr for _, expr in program.assignments] + list(program.outputs)
    bounds = list(range(0, len(lines), size))
    part_of_line = [i // size for i in range(len(lines))]
    defined_in = {symbol: part_of_line[i] for i, symbol in enumerate(symbols)}
    last_use = {}                                    # symbol -> last part that reads it from another part
    imports = [{} for _ in bounds]                   # per part, an ordered set of the symbols it reads in
    for i, expr in enumerate(expressions):
        part = part_of_line[i]
        for symbol in expr.free_symbols:
            home = defined_in.get(symbol)
            if home is not None and home < part:
                imports[part][symbol] = None
                last_use[symbol] = max(last_use.get(symbol, part), part)
    released = [[] for _ in bounds]                  # per part, the symbols whose slot is free from its start on
    for symbol, part in last_use.items():
        released[part].append(symbol)
    slot, free, scratch = {}, [], 0
    exports = [[] for _ in bounds]
    for part in range(len(bounds)):
        free.extend(slot[symbol] for symbol in released[part])     # read at this part's start: reusable
        for symbol in symbols[bounds[part]:bounds[part] + size]:
            if symbol in last_use:
                slot[symbol] = free.pop() if free else scratch
                scratch += slot[symbol] == scratch
                exports[part].append(symbol)
    parts = []
    for part, start in enumerate(bounds):
        body = [f"const double {symbol.name} = s[{slot[symbol]}];"
                for symbol in sorted(imports[part], key=lambda s: slot[s])]
        body += lines[start:start + size]
        body += [f"s[{slot[symbol]}] = {symbol.name};" for symbol in exports[part]]
        parts.append(body)
    return parts, max(scratch, 1)


def _environment() -> jinja2.Environment:
    loader = jinja2.FunctionLoader(lambda name: resources.files("templates").joinpath(name).read_text())
    return jinja2.Environment(loader=loader, undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
                              trim_blocks=True, lstrip_blocks=True)


def _weight_scale_expression(scene: Scene, bake_params: bool) -> str:
    """C expression of M |g| L from the parameter vector p (with bake_params, from the scene's values, as every
    kernel of such a model): the work to lift the whole chain by its own length (the energy scale of a chain at
    rest on the floor, where T + V can be exactly 0)."""
    values = scene.parameter_vector()

    def value(kind, owner=None):
        index = scene.parameter_index(kind, owner)
        return _double_literal(float(values[index])) if bake_params else f"p[{index}]"
    masses, lengths = [], []
    for i, link in enumerate(scene.links, start=1):
        masses.append(f"{value('mu', i)} * {value('l', i)}" if link.kind == "line" else value("m", i))
        lengths.append(value("l", i))
    return f"({' + '.join(masses)}) * fabs({value('g')}) * ({' + '.join(lengths)})"


def assemble_model(scene: Scene, name: str, functions: list[RenderedFunction], options: BuildOptions,
                   layout, chart_b=None, timings=None, chains=None, chart_models=None) -> GeneratedModel:
    """The model's header, source and cffi declarations from its rendered kernels (in interface order).
    ``chart_b``: (the scene on chart B, its rendered loop kernels) for a second base chart (codegen.charts), or None;
    ``timings``: seconds per stage so far; ``chains``: for several chains (codegen.combine), each chain's prefix, its
    rendered kernels (emitted static, the model's kernels wrapping them), its parameters' places in p and whether
    the model gathers them (chart B's kernels share chart A's); ``chart_models``: for several chains, (suffix, the
    scene on those charts, its loop kernels) of each combination of the turning chains' charts but chart A's, the
    last every one on chart B (chart_b then unused)."""
    if chart_b is not None:
        chart_models = [("b", *chart_b)]
    bake_params = options.bake_params
    dense = _check_kernels(functions)
    generated = {f.name: f for f in functions}
    env = _environment()
    params = list(zip(scene.parameter_names(), scene.parameter_vector().tolist()))
    pnames = [pname for pname, _ in params]
    names = scene.full_coordinate_names()
    zeros = set(layout.zero_params)
    rules = parameter_rules(scene, layout.zero_params, bake_params, layout.held_params)
    contact_table = [_contact_entry(c, point, wall, layout, scene, bake_params)
                     for c, (point, wall) in enumerate(layout.contacts)]
    contact_table += [_link_entry(len(contact_table) + k, pair, scene, bake_params)
                      for k, pair in enumerate(scene.rowless_contacts())]
    sizes = interface.size_definitions(name, n=scene.n, nq=layout.nq, nparam=len(params), nu=scene.nu,
                                       npoint=scene.npoint, ncontact=len(contact_table),
                                       njrow=len(layout.contact_rows), friction=any(entry["has_friction"] for entry in contact_table))
    context = dict(
        NAME=name.upper(), name=name, version=__version__, scene=scene, scene_hash=scene_hash(scene),
        bake_params=bake_params, functions=functions, nq=layout.nq,
        coordinates=[names[i] for i in layout.free], fixed=[(names[i], _double_literal(v)) for i, v in layout.fixed],
        notes=layout.notes, gravity_along=gravity_text(scene),
        params=[(i, pname, param_doc(pname, scene) + (" [built in as 0]" if pname in zeros else ""), _double_literal(value),
                 f"[{rule.lo:g}, {rule.hi:g}]") for i, ((pname, value), rule) in enumerate(zip(params, rules))],
        parameter_info=[(rule.name, _double_literal(rule.lo), _double_literal(rule.hi), _c_string(rule.text))
                        for rule in rules],
        relations=parameter_relations(rules),
        weight_scale=_weight_scale_expression(scene, bake_params),
        contacts=[(c, point, wall) for c, (point, wall) in enumerate(layout.contacts)]
                 + [(len(layout.contacts) + k, pair.i, pair) for k, pair in enumerate(scene.rowless_contacts())],
        contact_table=contact_table,
        link_radius=[_double_literal(float(scene.capsule_radius(pair.i) if isinstance(pair, ObstacleContact)
                                           else pair.radius)) for pair in scene.rowless_contacts()],
        obstacles=[dict(name=o.name, kind=o.kind, radius=o.radius, restitution=o.restitution,
                        shape=[_double_literal(x) for x in o.shape],
                        param=-1 if bake_params else pnames.index(o.geometry_names[0]))
                   for o in scene.obstacles],
        row_labels=[f"(theta_{point})" if axis == "theta" else f"(O_{point},X{axis + 1})"
                    for point, axis in layout.contact_rows],
        rows=list(layout.contact_rows), twists=scene.all_twists,
        chart=_chart_context(scene, layout), base=_base_context(scene, layout), layout_free=list(layout.free),
        bases=_bases_context(scene, layout),
        fused=any(name in generated for name in interface.FUSED_KERNELS),
        tangent=any(name in generated for name in interface.TANGENT_KERNELS),
        extended=any(name in generated for name in interface.EXTENDED_KERNELS),
        chart_models=[_chart_model_context(suffix, scene_m, kernels, layout)
                      for suffix, scene_m, kernels in chart_models or ()],
        q0=[_double_literal(float(x)) for x in layout.reduce(scene.q0)],
        qd0=[_double_literal(float(x)) for x in layout.reduce(scene.qd0)],
        literal=_double_literal,

        inputs=[(i, coordinate, macro_name(coordinate), "N m" if coordinate.startswith("theta") else "N")
                for i, coordinate in enumerate(scene.inputs)],
        param_macros=[(i, macro_name(pname)) for i, pname in enumerate(pnames)],
        coordinate_macros=[(i, macro_name(names[full]), names[full]) for i, full in enumerate(layout.free)],
        has_power=scene.driven, friction_velocity=_double_literal(float(scene.friction_velocity)),
        sizes=interface.SIZES, size_values=sizes,
        kernels=[(f, generated.get(f.name)) for f in interface.KERNELS], dense=dense,
        formed=[f for f in interface.KERNELS if f.name not in generated], all_functions=interface.ALL_FUNCTIONS,
        api_functions=interface.FUNCTIONS, callbacks=interface.CALLBACKS,
        chains=[dict(chain, nparam=len(chain["pmap"])) for chain in chains or ()],
    )
    context["chart_b"] = context["chart_models"][-1] if context["chart_models"] else None
    header = env.get_template("model.h.j2").render(**context)
    source = env.get_template("model.c.j2").render(**context)
    cdef = env.get_template("cdef.h.j2").render(**context)
    return GeneratedModel(name, header, source, cdef, functions, options, layout, text_digest(header, source, cdef),
                          dict(timings or {}))


PARAM_DOC = {
    "g": "gravity along -X2 (m/s^2)", "l": "length (m)", "mu": "mass per unit length (kg/m)",
    "Jxx": "moment of inertia per unit length about x (kg m)",
    "Jyy": "moment of inertia per unit length about y (kg m)",
    "Jzz": "moment of inertia per unit length about z (kg m)",
    "m": "mass (kg)", "cx": "centre of mass x (m)", "cy": "centre of mass y (m)", "cz": "centre of mass z (m)",
    "Ixx": "inertia about the centre of mass, xx (kg m^2)", "Iyy": "inertia about the centre of mass, yy (kg m^2)",
    "Izz": "inertia about the centre of mass, zz (kg m^2)", "Ixy": "inertia about the centre of mass, xy (kg m^2)",
    "Ixz": "inertia about the centre of mass, xz (kg m^2)", "Iyz": "inertia about the centre of mass, yz (kg m^2)",
}


JOINT_DOC = {"stiffness": "spring stiffness K (N m/rad)", "rest_angle": "spring rest angle (rad)",
             "damping": "damper coefficient C (N m s/rad)", "lower": "lower limit (rad)", "upper": "upper limit (rad)",
             "e_limit": "restitution of the limits (-)"}


def parameter_relations(rules) -> list[tuple[str, int, str]]:
    """The relations of the parameter rules (codegen.parameters) as C: (condition on p, the index a failure is
    reported on, what it says), in the order of the vector."""
    relations = []
    for rule in rules:
        if rule.above >= 0:
            relations.append((f"p[{rule.index}] > p[{rule.above}]", rule.index, f"{rule.name} > {rule.above_name}"))
        if rule.inertia_of:
            i = rule.inertia_of
            relations.append((f"gac_inertia_admissible(p + {rule.index})", rule.index,
                              f"{parameter_name('Ixx', i)} .. {parameter_name('Iyz', i)}: a physical inertia"))
        if rule.rotation_of:
            o = rule.rotation_of
            relations.append((f"gac_rotation_admissible(p + {rule.index})", rule.index,
                              f"{parameter_name('rotation_11', o)} .. {parameter_name('rotation_33', o)}: a rotation"))
        if rule.unit_of:
            o = rule.unit_of
            relations.append((f"gac_unit_admissible(p + {rule.index})", rule.index,
                              f"{parameter_name('normal_x', o)} .. {parameter_name('normal_z', o)}: a unit vector"))
    return relations


def _c_string(text: str) -> str:
    """A text as a C string literal's contents (the rules' words are plain ASCII without quotes)."""
    if not text.isascii() or '"' in text or "\\" in text:
        raise AssertionError(f"not a plain C string: {text!r}")
    return text


def _check_kernels(functions: list[RenderedFunction]) -> bool:
    """The generated kernels are those codegen.interface declares (all, or all but some of the dense, fused,
    tangent and long-double ones): same names, order, inputs and output.  Returns whether the dense kernels are among them."""
    names = {f.name for f in functions}
    dense = "mass_matrix" in names
    fused = any(name in names for name in interface.FUSED_KERNELS)
    tangent = any(name in names for name in interface.TANGENT_KERNELS)
    extended = any(name in names for name in interface.EXTENDED_KERNELS)
    declared = [(f.name, tuple(a.name for a in f.args[:-1]), f.args[-1].name) for f in interface.KERNELS
                if (dense or not f.dense) and (fused or not f.fused) and (tangent or not f.tangent)
                and (extended or not f.extended)]
    generated = [(f.name, tuple(f.inputs), f.output) for f in functions]
    if declared != generated:
        raise AssertionError(f"kernels {generated} differ from codegen.interface.KERNELS {declared}")
    return dense


def _chart_model_context(suffix: str, scene, functions: list[RenderedFunction], layout) -> dict:
    """One model on other base charts (NAME_model_<suffix>): its loop kernels, its bases and its start."""
    return dict(suffix=suffix, functions=functions, fused=any(f.name in interface.FUSED_KERNELS for f in functions),
                tangent=any(f.name in interface.TANGENT_KERNELS for f in functions),
                extended=any(f.name in interface.EXTENDED_KERNELS for f in functions), base=_base_context(scene, layout),
                bases=_bases_context(scene, layout),
                rows=[[_double_literal(float(x)) for x in row] for row in scene.base_twists[0]]
                if isinstance(scene, Scene) else None,
                q0=[_double_literal(float(x)) for x in layout.reduce(scene.q0)],
                qd0=[_double_literal(float(x)) for x in layout.reduce(scene.qd0)])


def _chart_context(scene: Scene, layout) -> dict:
    """What the C loop needs for the base chart's measure |det E| = |a . (e_z x Rz(theta_0) b)|, a = T_0^T e_z,
    b = T_1 e_z (the three base joint axes' triple product): a, b, and where theta_0 is (an index into q, or
    its fixed value)."""
    return _chart_of(*_turning_chain(scene, layout), layout)


def _chart_of(scene: Scene, offset: int, layout) -> dict:
    """_chart_context of the chain ``scene`` whose state starts at ``offset`` in the full layout."""
    T0, T1 = (np.array(T, dtype=float) for T in scene.base_twists[1:])
    if offset + 1 not in layout.free:
        # theta_0 held (a planar model, a revolute or fixed base): theta_-1 is held with it, and the rates of the
        # base angles left map to omega through one unit column, never singular: the measure of a chart at its best
        # (|cos 0| with a = e_y, b = e_x), whatever the held angle (a revolute base about X2 holds theta_0 = pi/2)
        return {"a": ["0.0", "1.0", "0.0"], "b": ["1.0", "0.0", "0.0"], "index": -1, "value": "0.0"}
    return {"a": [_double_literal(float(x)) for x in T0[2, :]], "b": [_double_literal(float(x)) for x in T1[:, 2]],
            "index": layout.free.index(offset + 1), "value": "0.0"}


def _bases_context(scene, layout) -> list[dict]:
    """Of several chains two or more of which turn their base (theta_0 a coordinate): each one's base and measure
    (gac_model.bases, charts), in chain order; else none (the one base is gac_model.base)."""
    if isinstance(scene, Scene):
        return []
    turning = [(chain, scene.state_offset(k)) for k, chain in enumerate(scene.chains, start=1)
               if scene.state_offset(k) + 1 in layout.free]
    if len(turning) < 2:
        return []
    return [dict(base=_base_of(chain, offset, layout), chart=_chart_of(chain, offset, layout))
            for chain, offset in turning]


def _turning_chain(scene, layout) -> tuple:
    """(the chain whose base chart the model watches, its offset in the full layout): the scene itself at 0; of
    several chains (codegen.scene.Chains), the one whose theta_0 is a coordinate (at most one), else chain 1."""
    if isinstance(scene, Scene):
        return scene, 0
    for k, chain in enumerate(scene.chains, start=1):
        if scene.state_offset(k) + 1 in layout.free:
            return chain, scene.state_offset(k)
    return scene.chains[0], 0


def _base_context(scene: Scene, layout) -> dict:
    """The base chart's twists T_-1, T_0, T_1 (row-major, 9 numbers each) and the indices in q of theta_-1, theta_0,
    theta_1 (-1 for one the model holds fixed): gac_model.base, for the conversion between two charts."""
    return _base_of(*_turning_chain(scene, layout), layout)


def _base_of(scene: Scene, offset: int, layout) -> dict:
    """_base_context of the chain ``scene`` whose state starts at ``offset`` in the full layout."""
    T = [[_double_literal(float(x)) for row in M for x in row] for M in scene.base_twists]
    return {"T_m1": T[0], "T_0": T[1], "T_1": T[2],
            "index": [layout.free.index(offset + i) if offset + i in layout.free else -1 for i in range(3)]}


def _contact_entry(c: int, point: int, wall, layout, scene: Scene, bake_params: bool) -> dict:
    """One row of the model's gac_contact table, and its description for the header."""
    stop = isinstance(wall, JointStop)
    row = layout.contact_rows.index((point, "theta" if stop else wall.axis))
    restitution = ("e_limit", point) if stop else ("e", wall.name)          # the parameter of its e
    e_index = -1 if bake_params else (scene.stop_parameter_index(*restitution) if stop and hasattr(
        scene, "stop_parameter_index") else scene.parameter_index(*restitution))   # several chains: its chain's
    sign = int(wall.normal_sign)
    if stop:
        label = wall.name
        doc = (f"joint {point} {'lower' if wall.side < 0 else 'upper'} limit, theta_{point} "
               f"{'>=' if wall.side < 0 else '<='} {wall.parameter} (e = {wall.restitution}), Jacobian row {row}")
    else:
        label = f"O{point}/{wall.name}"
        doc = (f"O_{point} / {wall.name} (e = {wall.restitution}), Jacobian row {row}, normal "
               f"{'+' if sign > 0 else '-'}X{wall.axis + 1}")
    friction = 0.0 if stop else float(wall.friction)
    tangents = [a for a in range(3) if not stop and a != wall.axis]
    trow = [layout.contact_rows.index((point, a)) if friction > 0.0 and (point, a) in layout.contact_rows else -1
            for a in tangents] if tangents else [-1, -1]
    if friction > 0.0:
        doc += f", Coulomb friction coefficient c_f = {friction} (tangential rows {', '.join(str(r) for r in trow if r >= 0)})"
    return dict(c=c, point=point, axis=-1 if stop else wall.axis, sign=sign, row=row,
                e_index=e_index, e_value=_double_literal(float(wall.restitution)),
                kind="GAC_CONTACT_STOP" if stop else "GAC_CONTACT_WALL",
                coordinate=layout.free.index(point + 1) if stop else -1, label=label, doc=doc,
                has_friction=int(friction > 0.0),
                friction_index=(-1 if bake_params or friction == 0.0
                                else scene.parameter_index("friction", wall.name)),
                friction_value=_double_literal(friction), trow=trow, end=0)


def _link_entry(c: int, pair, scene: Scene, bake_params: bool) -> dict:
    """One row of the model's gac_contact table for two capsule links (GAC_CONTACT_LINK): links i, j in point and
    coordinate, a constant e and Coulomb coefficient (friction.links); or for a link and a fixed obstacle
    (GAC_CONTACT_OBSTACLE): link i in point, the obstacle's index in coordinate, its e the parameter e_<name> and its
    friction coefficient, where > 0, the parameter friction_<name>.  No Jacobian row (row 0 unused; their frictional
    impacts act along their contact frame, gac_rowless_frame); the radius sum of a link pair, or the link's radius
    of an obstacle contact (the obstacle's own is its geometry), goes to the model's link_radius."""
    friction = float(pair.friction)
    rough = (f"Coulomb friction coefficient c_f = {friction:g} at impacts (along its contact frame)"
             if friction > 0.0 else "frictionless")
    if isinstance(pair, ObstacleContact):
        o = pair.obstacle
        part = f"link {pair.i}" if pair.end == 0 else f"O_{pair.joint} (an end of link {pair.i})"
        return dict(c=c, point=pair.i, axis=-1, sign=1, row=0,
                    e_index=-1 if bake_params else scene.parameter_index("e", o.name),
                    e_value=_double_literal(float(o.restitution)), kind="GAC_CONTACT_OBSTACLE", coordinate=pair.index,
                    label=pair.name, doc=f"{part} on the fixed {o.kind} {o.name} (radii {pair.radius:g} m "
                    f"together, e = {o.restitution}), {rough}", has_friction=int(friction > 0.0),
                    friction_index=(-1 if bake_params or friction == 0.0 else scene.parameter_index("friction", o.name)),
                    friction_value=_double_literal(friction), trow=[-1, -1], end=pair.end)
    part = f"links {pair.i} and {pair.j}" if pair.end == 0 else \
        f"O_{pair.joint} (an end of link {pair.i}) and link {pair.j}"
    return dict(c=c, point=pair.i, axis=-1, sign=1, row=0, e_index=-1,
                e_value=_double_literal(float(pair.restitution)), kind="GAC_CONTACT_LINK", coordinate=pair.j,
                label=pair.name, doc=f"{part} as capsules (radii {pair.radius:g} m together, "
                f"e = {pair.restitution}), {rough}", has_friction=int(friction > 0.0), friction_index=-1,
                friction_value=_double_literal(friction), trow=[-1, -1], end=pair.end)


def macro_name(name: str) -> str:
    """A parameter or coordinate name as part of a C macro name: 'e_x2_min' -> 'E_X2_MIN', 'theta_-1' -> 'THETA_M1'."""
    return name.replace("-", "M").replace(".", "_").upper()


def gravity_text(scene: Scene) -> str:
    """Where gravity acts, in words: '-X2' (the default), else the scene's gravity_direction d."""
    d = scene.gravity_direction
    if d == DEFAULT_GRAVITY_DIRECTION:
        return "-X2"
    return f"d = ({', '.join(repr(x) for x in d)}) of the box frame (gravity_direction)"


def param_doc(pname: str, scene: Scene | None = None) -> str:
    """The description of parameter ``pname`` (its unit last, in parentheses); ``scene``: says where g acts when the
    scene's gravity is not along -X2."""
    chain, dot, own = pname.partition(".")
    if dot:                                         # a chain's own parameter in a scene of several chains ('c2.l_1')
        return f"chain {chain[1:]}, {param_doc(own)}"
    kind, owner = split_parameter_name(pname)
    if kind == "g" and scene is not None and scene.gravity_direction != DEFAULT_GRAVITY_DIRECTION:
        return f"gravity's magnitude, along {gravity_text(scene)} (m/s^2)"
    if kind in JOINT_DOC:
        return f"joint {owner}: {JOINT_DOC[kind]}"
    if kind == "wall":
        return f"position of wall {owner} (m)"
    if kind == "e":
        return f"restitution of {'wall' if owner in WALL_NAMES else 'obstacle'} {owner} (-)"
    if kind == "friction":
        return f"Coulomb friction coefficient of {'wall' if owner in WALL_NAMES else 'obstacle'} {owner} (-)"
    if kind == "g":
        return PARAM_DOC["g"]
    if kind in OBSTACLE_GEOMETRY_KINDS:
        return f"obstacle {owner}: {_obstacle_doc(kind)}"
    return f"link {owner}: {PARAM_DOC[kind]}"


def _obstacle_doc(kind: str) -> str:
    """The description of an obstacle's geometry parameter (codegen.scene.OBSTACLE_PARAMETERS)."""
    what, _, axis = kind.rpartition("_")
    if what == "rotation":
        return f"rotation entry R[{axis[0]}][{axis[1]}] (row, column; its columns the box's axes) (-)"
    words = {"center": "centre", "a": "end a", "b": "end b", "point": "point on the plane", "half": "half extent",
             "normal": "unit normal (into the free side)"}
    if kind == "radius":
        return "radius (m)"
    return f"{words[what]}, {axis} (m)" if what != "normal" else f"{words[what]}, {axis} (-)"


STANDALONE_TEMPLATES = {"{name}_example.c": "example_main.c.j2", "Makefile": "Makefile.j2",
                        "CMakeLists.txt": "CMakeLists.txt.j2"}


def render_standalone(scene: Scene, name: str, library_sources: list[str], layout) -> dict[str, str]:
    """The example program and build files that go beside NAME.h / NAME.c and the library's files
    (``--standalone``); ``library_sources``: the library's .c file names; ``layout``: the model's."""
    env = _environment()
    full = scene.input_coordinates()
    context = dict(NAME=name.upper(), name=name, version=__version__, scene=scene, library_sources=library_sources,
                   inputs=[(i, coordinate, layout.free.index(full[i])) for i, coordinate in enumerate(scene.inputs)],
                   friction=any(w.friction > 0.0 for w in scene.walls))
    return {filename.format(name=name): env.get_template(template).render(**context)
            for filename, template in STANDALONE_TEMPLATES.items()}
