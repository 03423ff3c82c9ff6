"""The C library's interface as Python reads it: gac.h, its one description.

gac.h declares the library's codes, constants, types, storage formulas and functions once.  This module reads it
for the build: ``library_cdef`` turns its declarations into cffi's (every model's module is built with them, so
cffi checks each struct against the compiled C; of its functions, the checks and storage sizes PYTHON_FUNCTIONS:
Python reaches the rest through the model's own NAME_* functions, and a wrapper for each would cost every model's
build time), and ``library_constants`` gives its numeric constants by name
(``GAC_ERR_BAD_PARAMETER``, ``GAC_RTOL_MIN``) where Python needs one before a model is compiled.  The reading is
a small preprocessor of what gac.h uses: include guards, ``#if``/``#ifdef`` on ``__cplusplus`` (taken as a C
compiler does), constant ``#define``s and function-like macros (left to C).
"""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

LIBRARY_HEADER = Path(__file__).resolve().parent / "c" / "gac.h"
FMI2_HEADER = Path(__file__).resolve().parent / "c" / "fmi2" / "gac_fmi2.h"
FMI2_FIELDS = ("id", "name", "count", "causality", "variability", "unit", "start", "what")   # a row of X(...)

# The library functions a compiled module offers Python as lib.gac_*: the checks of options, descriptor and inertia,
# the storage sizes, the frictional impact law, inverse dynamics, the contact of two capsule links and of a link and
# an obstacle (and of any contact of the table), an obstacle's shape at p and the obstacle a parameter moves (with the checks of a box's rotation and a
# plane's normal), a contact's J^T n and a link contact's derivative of it and of its frame's rows, the
# linearisation, the base charts' conversion and its derivative, and the sensitivities of a run (they take the
# model's descriptor; no per-model wrapper).  Their signatures come from gac.h like everything else.
PYTHON_FUNCTIONS = ("gac_chart_convert", "gac_chart_convert_tangent", "gac_check_options", "gac_impact_friction",
                    "gac_impact_nwork", "gac_inertia_admissible",
                    "gac_contact_frame_tangent", "gac_contact_geometry", "gac_contact_normal",
                    "gac_contact_normal_tangent",
                    "gac_inverse_dynamics", "gac_link_gap", "gac_link_impact", "gac_linearize", "gac_model_check",
                    "gac_obstacle_gap", "gac_obstacle_parameter", "gac_obstacle_shape", "gac_rotation_admissible",
                    "gac_unit_admissible",
                    "gac_record_ndouble", "gac_record_nint",
                    "gac_sens_attach", "gac_sens_ndouble", "gac_sens_state", "gac_sim_ndouble", "gac_sim_nint")

_NUMBER = r"-?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?"
_DEFINE = re.compile(rf"#\s*define\s+(\w+)(\(?)\s*(.*)$")


def _lines(text: str) -> list[str]:
    """gac.h without comments, continuation lines joined, and with the branches a C (not C++) compiler skips
    removed."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"\\\n", " ", text)
    kept, skipping = [], []                    # skipping: one flag per open #if, True where its branch is skipped
    for line in text.splitlines():
        directive = line.strip()
        if directive.startswith("#"):
            word = directive[1:].strip().split(maxsplit=1)[0] if directive[1:].strip() else ""
            if word in ("if", "ifdef", "ifndef"):
                skipping.append("__cplusplus" in directive and word != "ifndef")
                continue
            if word == "else":
                skipping[-1] = not skipping[-1]
                continue
            if word == "endif":
                skipping.pop()
                continue
        if not any(skipping):
            kept.append(line)
    return kept


def parse_header(text: str) -> tuple[dict[str, int | float], str]:
    """(the numeric constants of ``text`` by name, its declarations for cffi)."""
    constants: dict[str, int | float] = {}
    declarations = []
    for line in _lines(text):
        match = _DEFINE.match(line.strip())
        if match is None:
            declarations.append(line.replace("GAC_RESTRICT", "").rstrip())
            continue
        name, function_like, value = match.groups()
        value = value.strip()
        if function_like or not re.fullmatch(_NUMBER, value):
            continue                           # a macro of arguments, a guard or GAC_RESTRICT: C's own
        if re.fullmatch(r"-?\d+", value):
            constants[name] = int(value)
            declarations.append(f"#define {name} ...")
        else:
            constants[name] = float(value)
            declarations.append(f"static const double {name};")
    cdef = "\n".join(line for line in declarations if line.strip()) + "\n"
    return constants, cdef


@lru_cache(maxsize=1)
def _library(text: str) -> tuple[dict[str, int | float], str]:
    return parse_header(text)


def library_constants() -> dict[str, int | float]:
    """Every numeric constant of gac.h by name (``GAC_OK``, ``GAC_ERR_*``, ``GAC_SIM_*``, ``GAC_METHOD_*``, the
    limits; GAC_RTOL_MIN and the other doubles as floats)."""
    return dict(_library(LIBRARY_HEADER.read_text())[0])


def library_cdef(functions=PYTHON_FUNCTIONS) -> str:
    """gac.h's declarations as cffi takes them: its typedefs, structs (complete: cffi checks their layout), its
    integer constants as ``#define NAME ...``, its doubles as ``static const double NAME;``, and the declarations
    of the named ``functions`` (all of gac.h's with ``functions=None``)."""
    cdef = _library(LIBRARY_HEADER.read_text())[1]
    if functions is None:
        return cdef
    missing = set(functions) - set(library_functions(cdef))
    if missing:
        raise ValueError(f"gac.h declares no function {sorted(missing)}")
    return "".join(statement for statement in _statements(cdef)
                   if _function_name(statement) in (None, *functions))


def _statements(cdef: str) -> list[str]:
    """cdef cut after each top-level ';' (a struct's fields stay inside its statement) and after each line of the
    preprocessor (a #define is a statement of its own, not the start of the declaration that follows it)."""
    statements, depth, start = [], 0, 0
    for i, ch in enumerate(cdef):
        depth += (ch == "{") - (ch == "}")
        line_start = i == 0 or cdef[i - 1] == "\n"
        if depth == 0 and line_start and ch == "#" and cdef[start:i].strip() == "":
            end = cdef.find("\n", i)
            end = len(cdef) if end < 0 else end + 1
            statements.append(cdef[start:end])
            start = end
        elif ch == ";" and depth == 0 and i >= start:
            end = cdef.find("\n", i)
            end = len(cdef) if end < 0 else end + 1
            statements.append(cdef[start:end])
            start = end
    return statements + [cdef[start:]]


def _function_name(statement: str) -> str | None:
    """The name a function declaration declares; None for a typedef, a struct or a constant."""
    text = statement.strip()
    if text.startswith(("typedef", "struct", "#define", "static const")) or "{" in text:
        return None
    match = re.search(r"(\w+)\s*\(", text)
    return None if match is None else match.group(1)


def library_functions(cdef: str | None = None) -> list[str]:
    """The functions gac.h declares, in order."""
    cdef = _library(LIBRARY_HEADER.read_text())[1] if cdef is None else cdef
    return [name for name in map(_function_name, _statements(cdef)) if name is not None]


def return_codes(constants: dict[str, int | float] | None = None) -> dict[str, int]:
    """The library's return codes by name: GAC_OK and every GAC_ERR_*."""
    constants = library_constants() if constants is None else constants
    return {name: int(value) for name, value in constants.items()
            if name == "GAC_OK" or name.startswith("GAC_ERR_")}


def _arguments(text: str) -> list[str]:
    """The comma-separated arguments of a macro call's text (between its parentheses), strings kept whole."""
    args, current, quoted = [], "", False
    for ch in text:
        if ch == '"':
            quoted = not quoted
        if ch == "," and not quoted:
            args.append(current.strip())
            current = ""
        else:
            current += ch
    return args + [current.strip()]


def parse_rows(text: str, macro: str) -> list[dict[str, str]]:
    """The rows X(id, name, ...) of the X-macro ``macro`` of a header (gac_fmi2.h's GAC_FMI2_REALS), each as
    {field: text} by FMI2_FIELDS, strings unquoted."""
    text = re.sub(r"\\\n", " ", re.sub(r"/\*.*?\*/", "", text, flags=re.S))
    match = re.search(rf"^#define {macro}\(X\)(.*)$", text, flags=re.M)
    if match is None:
        raise ValueError(f"{macro}: no such X-macro in the header")
    rows = []
    for call in re.findall(r'X\(((?:[^()"]|"[^"]*")*)\)', match.group(1)):
        values = [value[1:-1] if value.startswith('"') else value for value in _arguments(call)]
        if len(values) != len(FMI2_FIELDS):
            raise ValueError(f"{macro}: a row has {len(values)} fields, not {len(FMI2_FIELDS)}: X({call})")
        rows.append(dict(zip(FMI2_FIELDS, values)))
    return rows


def fmi2_rows() -> dict[str, list[dict[str, str]]]:
    """The FMU's variables as gac_fmi2.h describes them: {"Real": rows, "Integer": rows}, in value-reference order."""
    text = FMI2_HEADER.read_text()
    return {"Real": parse_rows(text, "GAC_FMI2_REALS"), "Integer": parse_rows(text, "GAC_FMI2_INTEGERS")}
