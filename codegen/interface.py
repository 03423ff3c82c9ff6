"""The C interface of a generated model, described once as plain data.

Every generated model NAME has the same functions: its kernels (straight-line code, generated per scene)
and thin wrappers around the hand-written library in ``runtime/c`` (``gac.h``), which does the hybrid loop
for any model through the const descriptor ``NAME_model``.  This module lists them, with their C types and
the meaning and size of every argument, and the sizes a model exports.  From it come the declarations
of ``NAME.h`` (templates/model.h.j2), the model's cffi declarations (templates/cdef.h.j2), the function table of
``runtime.model.CompiledModel`` and the function table of docs/generated-c.md.  Plain data: no sympy, no jinja2,
no runtime import.

The library's own interface (its codes, types, storage formulas and functions) is described in one place, gac.h:
the build layer gives its declarations to cffi (runtime.header), and Python reads a code's value from a compiled
module (``lib.GAC_OK``) or from that parse, never from a list of its own.

In C types, ``{name}`` stands for the model's name (``paper_case1``) and ``{NAME}`` for it in capitals.
"""
from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Arg:
    """One argument: its name, its C type (without restrict) and what it holds (size, units)."""

    name: str
    ctype: str
    doc: str
    restrict: bool = False          # declared restrict in C (its memory is not reached through another)


@dataclass(frozen=True)
class Function:
    """One function NAME_<name>."""

    name: str
    returns: str
    args: tuple[Arg, ...]
    summary: str                    # what it does, one line
    doc: str = ""                   # more, for the header comment (lines joined by spaces)
    kernel: bool = False            # a generated kernel (its body is the scene's straight-line code)
    dense: bool = False             # a dense kernel (O(n^2) code): generated, or formed by the library
    fused: bool = False             # two kernels on one tape: generated where forward_dynamics is straight-line
                                    # code, otherwise formed by the library from the two
    tangent: bool = False           # a kernel's directional derivative (codegen.tangent): generated where
                                    # forward_dynamics is straight-line code (unless options.tangent is False);
                                    # otherwise NAME_<name> writes NaN and the descriptor's pointer is NULL
    extended: bool = False          # a long-double variant of a kernel (NAME_<kernel>_ld), printed from the same
                                    # flattened program as the kernel (codegen.emit.render_extended): generated
                                    # unless options.extended is False; otherwise NAME_<name> writes NaN and the
                                    # descriptor's pointer is NULL
    out_size: str = "NQ"            # the size macro of the output (without NAME_): what the NaN stub writes

    def c_type(self, arg: Arg, name: str, restrict: str = "") -> str:
        ctype = arg.ctype.format(name=name, NAME=name.upper())
        if arg.restrict and restrict:
            return f"{ctype}{restrict} {arg.name}" if ctype.endswith("*") else f"{ctype} {restrict} {arg.name}"
        return f"{ctype}{arg.name}" if ctype.endswith("*") else f"{ctype} {arg.name}"

    def declaration(self, name: str, restrict: str = "") -> str:
        """``returns name_fn(args)`` for model ``name``; ``restrict``: the macro that spells restrict
        (the header's), or '' (cffi's declarations)."""
        args = ", ".join(self.c_type(a, name, restrict) for a in self.args) or "void"
        returns = self.returns.format(name=name, NAME=name.upper())
        space = "" if returns.endswith("*") else " "
        return f"{returns}{space}{name}_{self.name}({args})"


def _q(doc="generalised coordinates Theta (NQ; rad for angles, m for X1..X3)"):
    return Arg("q", "const double *", doc, restrict=True)


def _qd(doc="generalised velocities Theta_dot (NQ; rad/s, m/s)"):
    return Arg("qd", "const double *", doc, restrict=True)


def _p(doc="parameters (NPARAM, layout in the header)"):
    return Arg("p", "const double *", doc, restrict=True)


def _u(doc="inputs (NU, layout in the header; N m on an angle, N on a translation; NULL when NU = 0)"):
    return Arg("u", "const double *", doc, restrict=True)


def _seed(name, doc):
    return Arg(name, "const double *", doc, restrict=True)


def _out(name, doc):
    return Arg(name, "double *", doc, restrict=True)


def _out_ld(name, doc):
    return Arg(name, "long double *", doc, restrict=True)


_LD_DOC = ("The same flattened program as NAME_{kernel}, every intermediate a long double (inputs double): what the "
           "impact's accuracy measure evaluates its residuals with (gac_impact_accuracy), about 11 more bits than "
           "the double kernel.  A model built with extended=False has none: this function then writes NaN and "
           "NAME_model.{name} is NULL.")


# ---------------------------------------------------------------------------------------------------
# kernels: generated per scene (codegen.kernels builds them in this order; codegen.emit checks it)
# ---------------------------------------------------------------------------------------------------
KERNELS = (
    Function("mass_matrix", "void", (_q(), _p(), _out("M", "I_f, NQ x NQ row-major, symmetric")),
             "Flight inertia matrix I_f (Eq. 12).", kernel=True, dense=True),
    Function("bias", "void", (_q(), _qd(), _u(), _p(), _out("R", "R (NQ): I_f qdd = R in flight")),
             "Right-hand side R of I_f qdd = R (Eq. 12, 38-41), inputs, springs and dampers included.", kernel=True,
             dense=True),
    Function("forward_dynamics", "void", (_q(), _qd(), _u(), _p(), _out("qdd", "qdd (NQ; rad/s^2, m/s^2)")),
             "Accelerations solving I_f qdd = R.", kernel=True),
    Function("inertia_solve", "void",
             (_q(), Arg("Q", "const double *", "generalised forces (NQ; N m on an angle, N on a translation)", True),
              _p(), _out("x", "I_f^-1 Q (NQ; rad/s^2, m/s^2)")),
             "I_f^-1 Q: the accelerations generalised forces Q alone give (articulated-body recursion, O(n)).",
             kernel=True),
    Function("generalized_momentum", "void", (_q(), _qd(), _p(), _out("h", "I_f qd (NQ; N m s, N s)")),
             "Generalised momentum I_f qd = dT/dqd (composite momenta, O(n)).", kernel=True),
    Function("contact_points", "void", (_q(), _p(), _out("r", "O_1..O_NPOINT, NPOINT x 3 (m)")),
             "Contact points O_1..O_(n+1) in the reference frame.", kernel=True),
    Function("contact_velocities", "void",
             (_q(), _qd(), _p(), _out("v", "their velocities, NPOINT x 3 (m/s)")),
             "Velocities of the contact points (Eq. 42).", kernel=True),
    Function("contact_jacobian", "void", (_q(), _p(), _out("J", "NJROW x NQ, row r = d(O_i . X_a)/dq")),
             "Rows of the contact Jacobian (Eq. 42) that the walls need.", kernel=True, dense=True),
    Function("contact_generalized_force", "void",
             (_q(), Arg("f", "const double *", "force along each contact Jacobian row (NJROW; N, N m on a stop)",
                        True), _p(), _out("Q", "J^T f (NQ; N m on an angle, N on a translation)")),
             "Generalised force J^T f of forces along the contact Jacobian rows (O(n)).", kernel=True),
    Function("contact_gaps", "void", (_q(), _p(), _out("gap", "NCONTACT gaps (m), >= 0 inside the box")),
             "Gap of each contact (point, wall).", kernel=True),
    Function("energy", "void", (_q(), _qd(), _p(), _out("E", "E[0] kinetic, E[1] potential energy (J)")),
             "Kinetic and potential energy.", kernel=True),
    Function("contact_bias", "void",
             (_q(), _qd(), _p(), _out("a", "Jdot qd (NJROW; m/s^2): the rows' accelerations at qdd = 0")),
             "Contact row accelerations at qdd = 0.", kernel=True),
    Function("power", "void",
             (_q(), _qd(), _u(), _p(), _out("P", "P[0] power of the inputs, P[1] dissipation of the dampers (W)")),
             "Rates of the energy balance: dE/dt = P[0] - P[1] in flight.", kernel=True),
    Function("forward_dynamics_energy", "void",
             (_q(), _qd(), _u(), _p(), _out("y", "NQ + 2: qdd (NQ; rad/s^2, m/s^2), then T and V (J)")),
             "forward_dynamics and energy at one state in one call (the rotations computed once).", kernel=True,
             fused=True),
    Function("forward_dynamics_tangent", "void",
             (_q(), _qd(), _u(), _p(),
              _seed("dq", "direction of q (NQ; rad, m)"), _seed("dqd", "direction of qd (NQ; rad/s, m/s)"),
              _seed("du", "direction of u (NU; N m, N; NULL when NU = 0)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dqdd", "d qdd along (dq, dqd, du, dp) (NQ; rad/s^2, m/s^2 per unit of the direction)")),
             "Directional derivative of forward_dynamics (forward mode, exact: the tangent of its tape).",
             "dqdd = (d qdd/dq) dq + (d qdd/dqd) dqd + (d qdd/du) du + (d qdd/dp) dp at (q, qd, u, p), O(n) per "
             "direction; gac_linearize calls it once per column of A and B.  A model whose forward dynamics is "
             "rolled code, or built with tangent=False, has none: this function then writes NaN and "
             "NAME_model.forward_dynamics_tangent is NULL.", kernel=True, tangent=True),
    Function("forward_dynamics_tangent_block", "void",
             (_q(), _qd(), _u(), _p(),
              _seed("dq", "GAC_TANGENT_BLOCK directions of q, one after the other (GAC_TANGENT_BLOCK x NQ)"),
              _seed("dqd", "the same directions of qd (GAC_TANGENT_BLOCK x NQ)"),
              _seed("du", "the same directions of u (GAC_TANGENT_BLOCK x NU; NULL when NU = 0)"),
              _seed("dp", "the same directions of p (GAC_TANGENT_BLOCK x NPARAM; ignored with baked parameters)"),
              _out("dqdd", "d qdd along each direction (GAC_TANGENT_BLOCK x NQ)")),
             "forward_dynamics_tangent along GAC_TANGENT_BLOCK directions at once (its primal part computed once).",
             "The same numbers as GAC_TANGENT_BLOCK calls of forward_dynamics_tangent, the part of its tape that "
             "reads no direction computed once: each further direction costs its tangent part alone (the "
             "sensitivities' flight, gac_sens.c).  Without a tangent kernel: NaN, and "
             "NAME_model.forward_dynamics_tangent_block is NULL.", kernel=True, tangent=True,
             out_size="NQ * GAC_TANGENT_BLOCK"),
    Function("inertia_solve_tangent", "void",
             (_q(), Arg("Q", "const double *", "generalised forces (NQ; N m on an angle, N on a translation)", True),
              _p(), _seed("dq", "direction of q (NQ; rad, m)"), _seed("dQ", "direction of Q (NQ)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dx", "d(I_f^-1 Q) along (dq, dQ, dp) (NQ)")),
             "Directional derivative of inertia_solve (forward mode, exact: the tangent of its tape).",
             "dx = d(I_f^-1 Q) = -I_f^-1 (dI_f) I_f^-1 Q + I_f^-1 dQ along (dq, dQ, dp), O(n); the sensitivities of "
             "an impact (gac_sens.c).  Without a tangent kernel (as forward_dynamics_tangent): NaN, and "
             "NAME_model.inertia_solve_tangent is NULL.", kernel=True, tangent=True),
    Function("contact_generalized_force_tangent", "void",
             (_q(), Arg("f", "const double *", "force along each contact Jacobian row (NJROW; N, N m on a stop)",
                        True), _p(), _seed("dq", "direction of q (NQ; rad, m)"), _seed("df", "direction of f (NJROW)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dQ", "d(J^T f) along (dq, df, dp) (NQ)")),
             "Directional derivative of contact_generalized_force (forward mode, exact).",
             "dQ = (dJ)^T f + J^T df along (dq, df, dp), O(n); with f a unit row, dJ's row along dq.  Without a "
             "tangent kernel: NaN, and NAME_model.contact_generalized_force_tangent is NULL.", kernel=True,
             tangent=True),
    Function("contact_gaps_tangent", "void",
             (_q(), _p(), _seed("dq", "direction of q (NQ; rad, m)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dgap", "d gap along (dq, dp) (NCONTACT; m, rad on a stop)")),
             "Directional derivative of contact_gaps (forward mode, exact).",
             "dgap = (d gap/dq) dq + (d gap/dp) dp, O(n): an event time's sensitivity (gac_sens.c).  Without a "
             "tangent kernel: NaN, and NAME_model.contact_gaps_tangent is NULL.", kernel=True, tangent=True,
             out_size="NCONTACT"),
    Function("contact_bias_tangent", "void",
             (_q(), _qd(), _p(), _seed("dq", "direction of q (NQ; rad, m)"),
              _seed("dqd", "direction of qd (NQ; rad/s, m/s)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("da", "d(Jdot qd) along (dq, dqd, dp) (NJROW; m/s^2)")),
             "Directional derivative of contact_bias (forward mode, exact).",
             "da = (d(Jdot qd)/dq) dq + (d(Jdot qd)/dqd) dqd + (d(Jdot qd)/dp) dp, O(n): the sensitivities of the "
             "resting contacts' forces in flight (gac_sens.c).  Without a tangent kernel: NaN, and "
             "NAME_model.contact_bias_tangent is NULL.", kernel=True, tangent=True, out_size="NJROW"),
    Function("contact_points_tangent", "void",
             (_q(), _p(), _seed("dq", "direction of q (NQ; rad, m)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dr", "d O_1..O_NPOINT along (dq, dp) (NPOINT x 3; m)")),
             "Directional derivative of contact_points (forward mode, exact).",
             "dr = (d r/dq) dq + (d r/dp) dp, O(n): the joint points' motion that moves a link pair's or an "
             "obstacle's closest points (gac_contact_normal_tangent).  Without a tangent kernel: NaN, and "
             "NAME_model.contact_points_tangent is NULL.", kernel=True, tangent=True, out_size="NPOINT * 3"),
    Function("contact_velocities_tangent", "void",
             (_q(), _qd(), _p(), _seed("dq", "direction of q (NQ; rad, m)"),
              _seed("dqd", "direction of qd (NQ; rad/s, m/s)"),
              _seed("dp", "direction of p (NPARAM; ignored with baked parameters)"),
              _out("dv", "d(contact_velocities) along (dq, dqd, dp) (NPOINT x 3; m/s)")),
             "Directional derivative of contact_velocities (forward mode, exact).",
             "dv = (d v/dq) dq + (d v/dqd) dqd + (d v/dp) dp, O(n); with qd = e_k and dqd = 0, the change of the "
             "points' Jacobian column k along (dq, dp): a link pair's or an obstacle's row's derivative "
             "(gac_contact_normal_tangent).  Without a tangent kernel: NaN, and "
             "NAME_model.contact_velocities_tangent is NULL.", kernel=True, tangent=True, out_size="NPOINT * 3"),
    Function("generalized_momentum_ld", "void", (_q(), _qd(), _p(), _out_ld("h", "I_f qd (NQ; N m s, N s)")),
             "generalized_momentum in long double: I_f qd.",
             _LD_DOC.format(kernel="generalized_momentum", name="generalized_momentum_ld"), kernel=True,
             extended=True),
    Function("contact_generalized_force_ld", "void",
             (_q(), Arg("f", "const double *", "force along each contact Jacobian row (NJROW; N, N m on a stop)",
                        True), _p(), _out_ld("Q", "J^T f (NQ; N m on an angle, N on a translation)")),
             "contact_generalized_force in long double: J^T f.",
             _LD_DOC.format(kernel="contact_generalized_force", name="contact_generalized_force_ld"), kernel=True,
             extended=True),
    Function("energy_ld", "void", (_q(), _qd(), _p(), _out_ld("E", "E[0] kinetic, E[1] potential energy (J)")),
             "energy in long double: kinetic and potential energy.",
             _LD_DOC.format(kernel="energy", name="energy_ld"), kernel=True, extended=True, out_size="2"),
)

DENSE_KERNELS = tuple(f.name for f in KERNELS if f.dense)
FUSED_KERNELS = tuple(f.name for f in KERNELS if f.fused)
TANGENT_KERNELS = tuple(f.name for f in KERNELS if f.tangent)
EXTENDED_KERNELS = tuple(f.name for f in KERNELS if f.extended)
EXTENDED_OF = {name.removesuffix("_ld"): name for name in EXTENDED_KERNELS}   # kernel -> its long-double variant
DENSE_MAX_LINKS = 12        # up to this n the dense kernels are generated unless told otherwise


def wants_dense(n: int, dense: bool | None) -> bool:
    """Whether a model of n links gets its dense kernels generated: ``dense`` if given, else n <= DENSE_MAX_LINKS.
    Without them NAME_mass_matrix, NAME_bias and NAME_contact_jacobian form the matrices at run time from the
    O(n) kernels (gac_mass_matrix, gac_bias, gac_contact_jacobian)."""
    return n <= DENSE_MAX_LINKS if dense is None else bool(dense)


TANGENT_BLOCK = 4           # directions of forward_dynamics_tangent_block (gac.h's GAC_TANGENT_BLOCK)
SPLIT_LINES = 600           # a kernel longer than this is cut into parts (codegen.emit.render_function) ...
SPLIT_LINES_HOT = 8000      # ... the hot kernels longer than this (parts cost 2-9 % per call)
HOT_KERNELS = ("forward_dynamics", "forward_dynamics_tangent")   # (the tangent: at every stage per direction)

ROLLED_MIN_LINKS = 8        # from this n on, forward_dynamics is emitted with loops over the links (codegen.rolled)


def wants_rolled(n: int, rolled: bool | None) -> bool:
    """Whether a model of n links gets the rolled forward dynamics (loops over its links, codegen.rolled):
    ``rolled`` if given, else n >= ROLLED_MIN_LINKS.  Where the scene has no run of identical links to loop over,
    the kernel stays unrolled."""
    return n >= ROLLED_MIN_LINKS if rolled is None else bool(rolled)


_WORK = Arg("work", "double *", "scratch, {NAME}_IMPACT_NWORK doubles", restrict=True)
_CONTACT_SET = (Arg("ncontact_set", "int", "number of contacts taking part in the impact"),
                Arg("contact_set", "const int *", "their indices 0..NCONTACT-1", restrict=True))
_RESTING = (Arg("nresting", "int", "number of resting contacts, held at their walls"),
            Arg("resting", "const int *", "their indices 0..NCONTACT-1", restrict=True))

# ---------------------------------------------------------------------------------------------------
# the rest of the per-model API: NAME_rhs and the wrappers of the library (runtime/c/gac.h)
# ---------------------------------------------------------------------------------------------------
FUNCTIONS = (
    Function("rhs", "void",
             (Arg("t", "double", "time (s), unused"), Arg("x", "const double *", "state [q, qd] (NX)", True),
              _u(), _p(), _out("xdot", "[qd, qdd] (NX)")),
             "ODE right-hand side of the flight phase."),
    Function("impact", "int",
             (_q(), _qd(), _p(), *_CONTACT_SET, _out("qd_plus", "velocities after (NQ)"),
              _out("impulse", "impulse of each contact of the set along its inward normal (ncontact_set; N s)"), _WORK),
             "Impact law, Eq. 44-48, all contacts of the set together (gac_impact).",
             "Solved as (J I_f^-1 J^T) F = -(1 + e) J qd, qd_plus = qd + I_f^-1 J^T F (Eq. 48 with the "
             "velocity unknowns eliminated); impulse[k] > 0 pushes contact contact_set[k] away from its wall. "
             "Returns GAC_OK or GAC_ERR_*."),
    Function("impact_complementarity", "int",
             (_q(), _qd(), _p(), *_CONTACT_SET, _out("qd_plus", "velocities after (NQ)"),
              _out("impulse", "total impulse of each contact of the set (ncontact_set; N s, >= 0)"), _WORK),
             "Newton's law (Eq. 47) with complementarity, in rounds (gac_impact_complementarity).",
             "No contact pulls or approaches its wall afterwards, the kinetic energy never grows; the law the "
             "hybrid loop applies.  Returns GAC_OK or GAC_ERR_*."),
    Function("constrained_dynamics", "int",
             (_q(), _qd(), _u(), _p(), *_RESTING, _out("qdd", "accelerations (NQ)"),
              _out("lambda", "force of each resting contact along its inward normal (nresting; N)"), _WORK),
             "Accelerations with the resting contacts held at their walls (gac_constrained_dynamics).",
             "I_f qdd = R + N^T lambda, N qdd = -Ndot qd; nresting = 0 gives forward_dynamics.  Returns GAC_OK or "
             "GAC_ERR_*."),
    Function("contact_info", "void",
             (Arg("c", "int", "contact index 0..NCONTACT-1"),
              Arg("point", "int *", "out: point index, 1-based (O_1 = 1)"),
              Arg("axis", "int *", "out: wall axis, 0..2 for X1..X3"),
              Arg("normal_sign", "int *", "out: inward normal sign, +1 or -1")),
             "Point, wall axis and inward normal of contact c (0, -1, 0 outside the range)."),
    Function("contact_name", "const char *", (Arg("c", "int", "contact index 0..NCONTACT-1"),),
             "Contact c's name: \"O3/x2_min\" (point O_3 on the wall x2_min) or \"theta_2_upper\" (a joint stop); "
             "\"\" outside the range."),
    Function("default_parameters", "void", (Arg("p", "double *", "out: the scene's parameters (NPARAM)"),),
             "The scene's parameter vector."),
    Function("initial_state", "void",
             (Arg("q", "double *", "out: the scene's initial coordinates (NQ)"),
              Arg("qd", "double *", "out: the scene's initial velocities (NQ)")),
             "The scene's initial state."),
    Function("check_parameters", "int",
             (Arg("p", "const double *", "parameters (NPARAM)"),
              Arg("bad_index", "int *", "out: the parameter that fails, if any (NULL: not written)")),
             "Every parameter in its allowed range and the relations between them (what the scene loader checks).",
             "Each p[i] finite, within [lo, hi] of the descriptor's parameter_info[i] (which names it and says what it "
             "allows in words), and 0 or at least DBL_MIN in magnitude; then the relations: a wall's max above its "
             "min, a joint's upper limit above its lower one, a rigid link's inertia physical (reported on Ixx of "
             "the link).  sim_init calls it.  Returns GAC_OK or GAC_ERR_BAD_PARAMETER."),
    Function("error_message", "const char *", (Arg("code", "int", "a return code"),),
             "Message for a return code (gac_error_message)."),
    Function("default_options", "void", (Arg("opt", "{name}_options *", "out (NULL: nothing is done)"),),
             "Default options: DOPRI5, rtol 1e-8, atol 1e-10, resting contact on."),
    Function("sim_init", "int",
             (Arg("sim", "{name}_sim *", "the simulation (not NULL)"),
              Arg("t0", "double", "start time (s)"),
              Arg("q", "const double *", "start coordinates (NQ; not NULL)"),
              Arg("qd", "const double *", "start velocities (NQ; not NULL)"),
              Arg("p", "const double *", "parameters (NPARAM, copied; NULL: the scene's)"),
              Arg("opt", "const {name}_options *", "options (copied; NULL: the defaults)")),
             "Start a simulation (gac_sim_init); on an error *sim is left unchanged.",
             "Returns GAC_OK, GAC_ERR_NULL_ARGUMENT, GAC_ERR_BAD_OPTION, GAC_ERR_BAD_PARAMETER (check_parameters says "
             "which), GAC_ERR_START_OUTSIDE or another error."),
    Function("sim_advance", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("t_end", "double", "integrate up to this time (s), finite, >= sim->base.t"),
              Arg("t_eval", "const double *", "ascending sample times (n_eval; may be NULL if n_eval = 0)"),
              Arg("n_eval", "int", "number of samples, >= 0"),
              Arg("i_eval", "int *", "in/out: the next sample, 0 <= *i_eval <= n_eval"),
              Arg("x_eval", "double *", "out: state [q, qd] at each sample passed (n_eval x NX)"),
              Arg("record", "{name}_impact_record *", "out: the impact or contact change (not NULL)")),
             "Integrate until t_end, the next impact or the next contact release (gac_sim_advance).",
             "Returns GAC_SIM_END, GAC_SIM_IMPACT, GAC_SIM_CONTACT or an error (< 0)."),
    Function("sim_set_input", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("u", "const double *", "the inputs (NU, copied; finite; may be NULL when NU = 0)")),
             "Hold the inputs u from now on (gac_sim_set_input): a zero-order hold over the next sim_advance calls.",
             "Returns GAC_OK, GAC_ERR_NULL_ARGUMENT or GAC_ERR_BAD_INPUT."),
    Function("sim_set_controller", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("controller", "gac_controller", "controller(t, q, qd, u, user) writes u (NU); NULL: the held inputs"),
              Arg("user", "void *", "passed to the controller as it is")),
             "Let a controller give the inputs at every stage (gac_sim_set_controller).",
             "Returns GAC_OK or GAC_ERR_NULL_ARGUMENT."),
    Function("sim_set_controller_jacobian", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation with a controller (sim_set_controller)"),
              Arg("jacobian", "gac_controller_jacobian", "jacobian(t, q, qd, du_dq, du_dqd, user) writes du/dq and "
                  "du/dqd (NU x NQ each, row-major) with the controller's user pointer; NULL: none")),
             "Give the controller its Jacobian, so that the sensitivities follow its state feedback "
             "(gac_sim_set_controller_jacobian; without it a controller ends them, GAC_SENS_CONTROLLER).",
             "Returns GAC_OK, GAC_ERR_NULL_ARGUMENT or GAC_ERR_BAD_OPTION (no controller set, or a schedule's)."),
    Function("sim_set_clock", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("clock", "gac_clock", "clock(user): seconds from a fixed origin, never decreasing; NULL: C's clock() "
                  "(processor time)"),
              Arg("user", "void *", "passed to the clock as it is")),
             "Measure the wall-time budget (options.max_wall_time) with this clock from now on (gac_sim_set_clock).",
             "Returns GAC_OK or GAC_ERR_NULL_ARGUMENT."),
    Function("sim_set_progress", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("progress", "gac_progress", "progress(t, n_steps, n_impacts, user), every GAC_LOOK_STEPS steps and "
                  "at each sim_advance; nonzero stops the run (GAC_ERR_STOPPED); NULL: none"),
              Arg("user", "void *", "passed to the callback as it is")),
             "Follow the run and let a callback stop it (gac_sim_set_progress).",
             "Returns GAC_OK or GAC_ERR_NULL_ARGUMENT."),
    Function("sim_set_schedule", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("schedule", "const gac_schedule *", "inputs at times, held or linear (kept alive by the caller); "
                  "NULL: none")),
             "Drive the run by an input schedule, each of its times a step boundary (gac_sim_set_schedule).",
             "Returns GAC_OK, GAC_ERR_NULL_ARGUMENT, or GAC_ERR_BAD_OPTION / GAC_ERR_BAD_INPUT for a schedule that "
             "gac_schedule_check refuses or whose nu is not NU."),
    Function("sim_run", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("t_end", "double", "integrate up to this time (s)"),
              Arg("record", "{name}_impact_record *", "out: the last impact (not NULL)"),
              Arg("summary", "gac_run_summary *", "out: impacts, first impact time, losses, contact events")),
             "Run to t_end in one call, counting the impacts (gac_sim_run): for studies of many runs.",
             "Returns GAC_SIM_END or an error (< 0; GAC_ERR_MAX_IMPACTS after options.max_impacts impacts)."),
    Function("sim_state", "void",
             (Arg("sim", "const {name}_sim *", "the simulation (NULL: nothing is written)"),
              Arg("t", "double *", "out: current time (s), or NULL"),
              Arg("q", "double *", "out: current coordinates (NQ), or NULL"),
              Arg("qd", "double *", "out: current velocities (NQ), or NULL")),
             "The current time and state, in chart A's coordinates whichever base chart is integrated (gac_sim_state)."),
    Function("sens_attach", "int",
             (Arg("sim", "{name}_sim *", "an initialised simulation"),
              Arg("sens", "gac_sens *", "the sensitivities (caller-owned, alive for the run; NULL detaches them)"),
              Arg("k", "int", "directions, >= 1"),
              Arg("seed_x", "const double *", "the directions' seeds of the state, k x NX direction-major: "
                  "seed_x[j*NX + i] = d x_i / d direction j at the current time"),
              Arg("seed_p", "const double *", "their seeds of the parameters, k x NPARAM (NULL: 0): "
                  "seed_p[j*NPARAM + {NAME}_P_G] = 1 for d/dg"),
              Arg("dwork", "double *", "storage, {NAME}_SENS_NDOUBLE(k) doubles (caller-owned, alive for the run)")),
             "Carry forward sensitivities of the run along k directions from its current time on (gac_sens_attach).",
             "sens->status stays GAC_SENS_VALID while every event is differentiated; the first that is not ends "
             "them (sens->status, t_status, contact_status).  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT, "
             "GAC_ERR_BAD_OPTION (k < 1, a seed not finite) or GAC_ERR_BAD_MODEL (the model has no tangent kernels)."),
    Function("sens_state", "int",
             (Arg("sim", "const {name}_sim *", "a simulation with sensitivities attached"),
              Arg("S", "double *", "out: k x NX, S[j*NX + i] = d x_i / d direction j at the current time, in chart "
                  "A's coordinates (like sim_state)")),
             "The sensitivities at the current time (gac_sens_state).",
             "NaN once sens->status is not GAC_SENS_VALID.  Returns GAC_OK or GAC_ERR_NULL_ARGUMENT (sim or S NULL, "
             "or no sensitivities attached)."),
    Function("sim_copy", "void",
             (Arg("dst", "{name}_sim *", "the copy"), Arg("src", "const {name}_sim *", "an initialised simulation")),
             "Copy a simulation, its arrays bound to the copy's own storage."),
    Function("impact_record_copy", "void",
             (Arg("dst", "{name}_impact_record *", "the copy"),
              Arg("src", "const {name}_impact_record *", "a record filled by sim_advance")),
             "Copy an impact record, its arrays bound to the copy's own storage."),
)

ALL_FUNCTIONS = KERNELS + FUNCTIONS

# The functions a model's cffi module declares extern "Python" (NAME_python_<name>): the front end defines them, the
# loop calls them through the pointers given to sim_set_controller, sim_set_controller_jacobian, sim_set_clock and
# sim_set_progress.
CALLBACKS = (
    Function("python_controller", "void",
             (Arg("t", "double", "time (s)"), Arg("q", "const double *", "NQ"), Arg("qd", "const double *", "NQ"),
              Arg("u", "double *", "out: the inputs (NU)"), Arg("user", "void *", "the run's handle")),
             "The inputs of a run driven by a Python function u(t, q, qd) (a gac_controller)."),
    Function("python_controller_jacobian", "void",
             (Arg("t", "double", "time (s)"), Arg("q", "const double *", "NQ"), Arg("qd", "const double *", "NQ"),
              Arg("du_dq", "double *", "out: d u / d q (NU x NQ)"),
              Arg("du_dqd", "double *", "out: d u / d qd (NU x NQ)"), Arg("user", "void *", "the run's handle")),
             "The Jacobian of a Python controller (runtime.inputs.Controller; a gac_controller_jacobian)."),
    Function("python_clock", "double", (Arg("user", "void *", "unused"),),
             "Seconds of the Python process's monotonic clock (a gac_clock)."),
    Function("python_progress", "int",
             (Arg("t", "double", "simulated time (s)"), Arg("n_steps", "long", "steps so far"),
              Arg("n_impacts", "long", "impacts so far"), Arg("user", "void *", "the run's handle")),
             "The run's Python progress callback; nonzero stops the run (a gac_progress)."),
)

# The per-model C types NAME_<type>: a front end creates them by these names.
TYPES = ("options", "sim", "impact_record")


# ---------------------------------------------------------------------------------------------------
# per-model size macros NAME_<suffix>: the counts are the model's; the storage sizes are gac.h's macros of them
# (GAC_SIM_NDOUBLE(NAME_NQ, ...)), the one formula the library's gac_sim_ndouble(m) etc. apply too
# ---------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Size:
    suffix: str
    doc: str
    storage: str = ""               # a storage size: the gac.h macro and its arguments; "" for a count


SIZES = (
    Size("N", "real links"),
    Size("NQ", "generalised coordinates"),
    Size("NX", "ODE state [q, qd]"),
    Size("NPARAM", "parameters"),
    Size("NU", "inputs"),
    Size("NPOINT", "contact points O_1..O_NPOINT"),
    Size("NCONTACT", "contacts (point, wall)"),
    Size("NJROW", "contact Jacobian rows"),
    Size("IMPACT_NWORK", "doubles of the work array of impact, impact_complementarity, constrained_dynamics "
         "(last argument: 1 if a wall has friction)",
         "GAC_IMPACT_NWORK(NQ, NPOINT, NJROW, FRICTION)"),
    Size("SIM_NDOUBLE", "doubles of a simulation's storage (gac_sim_ndouble; last argument: 1 if a wall has friction)",
         "GAC_SIM_NDOUBLE(NQ, NPARAM, NU, NPOINT, NCONTACT, NJROW, FRICTION)"),
    Size("SIM_NINT", "ints of a simulation's storage (gac_sim_nint)", "GAC_SIM_NINT(NQ, NCONTACT)"),
    Size("RECORD_NDOUBLE", "doubles of an impact record's storage (gac_record_ndouble)", "GAC_RECORD_NDOUBLE(NQ)"),
    Size("RECORD_NINT", "ints of an impact record's storage (gac_record_nint)", "GAC_RECORD_NINT(NQ)"),
)


def size_definitions(name: str, n: int, nq: int, nparam: int, nu: int, npoint: int, ncontact: int, njrow: int,
                     friction: bool = False) -> dict[str, str]:
    """The C definition of every NAME_<suffix> of SIZES for model ``name``: a count's value, or a storage size's
    gac.h macro over the model's counts (FRICTION: 1 if some wall has friction, else 0)."""
    counts = {"N": n, "NQ": nq, "NX": 2 * nq, "NPARAM": nparam, "NU": nu, "NPOINT": npoint, "NCONTACT": ncontact,
              "NJROW": njrow}
    NAME = name.upper()

    def argument(match) -> str:
        word = match.group(0)
        return str(int(friction)) if word == "FRICTION" else f"{NAME}_{word}"
    definitions = {}
    for size in SIZES:
        if size.storage:
            macro, args = size.storage.split("(", 1)
            definitions[size.suffix] = macro + "(" + re.sub(r"[A-Z_]+", argument, args)
        else:
            definitions[size.suffix] = str(counts[size.suffix])
    return definitions


def function_table() -> str:
    """The per-model functions as a markdown table (docs/generated-c.md renders it between its markers): each
    function's call, its kind and what it does."""
    lines = ["| function | kind | computes |", "|---|---|---|"]
    for f in ALL_FUNCTIONS:
        call = f"NAME_{f.name}({', '.join(a.name for a in f.args)})"
        kind = ("fused kernel" if f.fused else "dense kernel" if f.dense else "tangent kernel" if f.tangent
                else "long-double kernel" if f.extended else "kernel") if f.kernel else "wrapper"
        summary = f.summary.replace("|", "/").replace("*", "\\*")
        lines.append(f"| `{call}` | {kind} | {summary} |")
    return "\n".join(lines) + "\n"
