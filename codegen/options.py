"""How a scene becomes a model: every choice of the generator and of the build, made once.

``build_options`` turns what a caller asked for (the command line, ``runtime.load_model``, ``codegen.generate``)
into a frozen ``BuildOptions`` with every default decided from the scene's size; derivation, emission, the caches'
keys and the compile then read it as it is, and no stage decides again.  The generated model carries it
(``GeneratedModel.options``).  Plain data: no sympy, no jinja2.
"""
from __future__ import annotations

from dataclasses import dataclass

from . import interface

FORMULATIONS = ("gibbs_appell", "lagrange")
DEFAULT_FLAGS = ("-O2",)


@dataclass(frozen=True)
class BuildOptions:
    """Every choice that shapes a model's C text and its compiled module."""

    bake_params: bool = False             # the scene's numbers built into the code as constants (p is ignored)
    specialise: bool = True               # leave out what the scene does not need (codegen.specialise)
    dense: bool = True                    # generate mass_matrix, bias, contact_jacobian (O(n^2) code); else the
                                          # library forms them at run time from the O(n) kernels
    rolled: bool = False                  # emit forward_dynamics with loops over the scene's run of identical links
    rolled_required: bool = False         # ... and refuse a scene without such a run (asked for, not the default,
                                          # which falls back to straight-line code)
    chart_b: bool = True                  # a free base's second chart (codegen.charts), for the loop near the gimbal
                                          # lock; False: none (a run that reaches the lock stops there with
                                          # GAC_ERR_GIMBAL_LOCK) and half the code of such a model
    tangent: bool = False                 # generate the tangent kernels (codegen.tangent: gac_linearize and the
                                          # run's sensitivities need them); straight-line forward dynamics only
    extended: bool = True                 # generate the long-double variants of generalized_momentum,
                                          # contact_generalized_force and energy (interface.EXTENDED_KERNELS): the
                                          # impact's accuracy measure evaluates its residuals with them; False: the
                                          # double ones (a smaller build, a coarser measure on ill-conditioned chains)
    formulation: str = "gibbs_appell"     # the dynamics kernels: the paper's recursion, or "lagrange" (an explicit
                                          # Euler-Lagrange expansion, for comparison)
    split_lines: int = interface.SPLIT_LINES          # a kernel longer than this is cut into parts ...
    split_lines_hot: int = interface.SPLIT_LINES_HOT  # ... the hot kernels (interface.HOT_KERNELS) longer than this
    flags: tuple[str, ...] = DEFAULT_FLAGS            # the C compiler's flags for the compiled module

    def generation_text(self) -> str:
        """The choices that shape the C text (not the compiler's flags), for the generated text's cache key."""
        return (f"{self.bake_params}|{self.specialise}|{self.dense}|{self.rolled}|{self.rolled_required}|"
                f"{self.chart_b}|{self.tangent}|{self.extended}|{self.formulation}|{self.split_lines}|"
                f"{self.split_lines_hot}")

    def split_size(self, kernel_name: str) -> int:
        """The part length of a kernel (split_lines_hot for the right-hand side's forward_dynamics)."""
        return self.split_lines_hot if kernel_name in interface.HOT_KERNELS else self.split_lines


def build_options(scene, *, bake_params: bool = False, specialise: bool = True, dense: bool | None = None,
                  rolled: bool | None = None, chart_b: bool = True, tangent: bool = False,
                  extended: bool = True, formulation: str = "gibbs_appell",
                  split_lines: int | None = None, flags=None) -> BuildOptions:
    """The options of a model of ``scene`` (n links): ``dense`` None generates the dense kernels up to
    interface.DENSE_MAX_LINKS links (always for the Lagrangian formulation), ``rolled`` None loops from
    interface.ROLLED_MIN_LINKS links on where the scene has a run (the Gibbs-Appell formulation only; True
    requires a run), ``chart_b`` False leaves a free base's second chart out, ``tangent`` True generates the tangent
    kernels (the exact derivatives of gac_linearize and of a run's sensitivities; about twice the derivation time and
    1.5-2x the C) with straight-line forward dynamics (``rolled`` None then means no loops; rolled=True is refused:
    the loops have no tangent), ``extended`` False leaves out the long-double variants of three kernels
    (interface.EXTENDED_KERNELS; the impact's accuracy is then measured in double), ``split_lines`` None keeps the emitter's part lengths (one value sets both),
    ``flags`` None is DEFAULT_FLAGS."""
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation: must be one of {', '.join(FORMULATIONS)}, got {formulation!r}")
    if formulation == "lagrange":
        if dense is False:
            raise ValueError("dense: the Lagrangian formulation always generates the dense kernels")
        dense = True
    if split_lines is not None and (not isinstance(split_lines, int) or split_lines < 1):
        raise ValueError(f"split_lines: must be a whole number of lines >= 1, got {split_lines!r}")
    n = scene.n
    if not isinstance(tangent, bool):
        raise TypeError(f"tangent: expected True or False, got {tangent!r}")
    if not isinstance(extended, bool):
        raise TypeError(f"extended: expected True or False, got {extended!r}")
    if tangent and rolled is True:
        raise ValueError("tangent: the rolled forward dynamics (rolled=True: loops over the links) has no tangent "
                         "kernel; leave rolled out (or False) to build the derivatives with straight-line code")
    loops = formulation == "gibbs_appell" and not tangent and interface.wants_rolled(n, rolled)
    if tangent and formulation == "lagrange":
        raise ValueError("tangent: the Lagrangian formulation has no tangent kernel; use the gibbs_appell one")
    return BuildOptions(
        bake_params=bool(bake_params), specialise=bool(specialise), dense=interface.wants_dense(n, dense),
        rolled=loops, rolled_required=loops and rolled is True, chart_b=bool(chart_b),
        tangent=tangent, extended=extended, formulation=formulation,
        split_lines=interface.SPLIT_LINES if split_lines is None else split_lines,
        split_lines_hot=interface.SPLIT_LINES_HOT if split_lines is None else split_lines,
        flags=DEFAULT_FLAGS if flags is None else tuple(str(f) for f in flags))
