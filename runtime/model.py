"""A compiled model of one scene, with numpy-friendly access to every generated kernel.

    from runtime import load_model
    model = load_model("paper-case1")
    qdd = model.forward_dynamics(model.q0, model.qd0)
"""
from __future__ import annotations

import os
import reprlib
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import interface
from codegen.cache import generate_cached
from codegen.options import BuildOptions, build_options
from codegen.artifact import GeneratedModel
from codegen.scene import Chains
from codegen.scene import Scene, load_scene, scene_file

from .compile import compile_model


class ImpactError(RuntimeError):
    """The generated impact solver returned an error code (message from the C side)."""


# The impact laws at walls with friction by name, and the library's constant of each (gac.h, GAC_IMPACT_LAW_*)
IMPACT_LAWS = {"frictionless": "GAC_IMPACT_LAW_FRICTIONLESS", "gdi": "GAC_IMPACT_LAW_GDI",
               "newton-coulomb": "GAC_IMPACT_LAW_NEWTON_COULOMB", "gdi-common-e": "GAC_IMPACT_LAW_GDI_COMMON_E",
               "gdi-tangential": "GAC_IMPACT_LAW_GDI_TANGENTIAL"}
# The parts an impact's measured accuracy is made of by name (Impact.roundoff_cause), and the library's constant of
# each (gac.h, GAC_ROUNDOFF_*)
ROUNDOFF_CAUSES = {"floor": "GAC_ROUNDOFF_FLOOR", "stored": "GAC_ROUNDOFF_STORED",
                   "evaluation": "GAC_ROUNDOFF_EVALUATION", "law": "GAC_ROUNDOFF_LAW",
                   "identity": "GAC_ROUNDOFF_IDENTITY", "rounds-energy": "GAC_ROUNDOFF_ROUNDS_ENERGY",
                   "hold": "GAC_ROUNDOFF_HOLD", "link": "GAC_ROUNDOFF_LINK"}
# The checks that can refuse an impact by name (record.refusal), and the library's constant of each (GAC_REFUSED_*)
REFUSALS = {"none": "GAC_REFUSED_NONE", "accuracy": "GAC_REFUSED_ACCURACY", "elastic-rounds": "GAC_REFUSED_ELASTIC_ROUNDS",
            "elastic-change": "GAC_REFUSED_ELASTIC_CHANGE", "pull": "GAC_REFUSED_PULL", "gain": "GAC_REFUSED_GAIN",
            "approach": "GAC_REFUSED_APPROACH"}
CHOSEN_LAWS = ("gdi", "newton-coulomb", "frictionless")     # what a user may ask for; gdi-common-e and
                                                            # gdi-tangential: a record's only


@dataclass(frozen=True)
class FrictionalImpact:
    """What CompiledModel.impact_friction returns."""

    qd_plus: np.ndarray       # velocities after the impact (nq)
    impulse: np.ndarray       # N s along each contact's inward normal (>= 0)
    impulse_t: np.ndarray     # (ncontact_set, 2) N s along each wall's two tangential axes, ascending (a link
    #                           pair's or an obstacle's: along its contact frame's t1, t2)
    law: str                  # the law applied ('gdi', 'gdi-common-e', 'newton-coulomb', 'frictionless')
    residual: float           # the law's largest relative violation of its conditions


_DEFINED: dict[int, set] = {}      # id(compiled module) -> the callbacks defined in it


class CInterface:
    """The one edge between Python and a compiled model, bound from its description (codegen.interface): every
    function NAME_<f> as ``c.<f>`` (``c.sim_init`` is NAME_sim_init), the model's descriptor NAME_model as
    ``c.model``, new C objects of its types by their short names (``c.new("sim")``), and the definition of the
    Python callbacks the loop calls (``c.define_callback("python_clock", function)``, once per module)."""

    def __init__(self, ffi, lib, name: str):
        self.ffi, self.lib, self.name = ffi, lib, name
        for f in interface.ALL_FUNCTIONS + interface.CALLBACKS:
            setattr(self, f.name, getattr(lib, f"{name}_{f.name}"))
        self.model = getattr(lib, f"{name}_model")

    def size(self, suffix: str) -> int:
        """The model's size NAME_<suffix> (one of codegen.interface.SIZES)."""
        if suffix not in {size.suffix for size in interface.SIZES}:
            raise ValueError(f"suffix: one of {', '.join(size.suffix for size in interface.SIZES)}, got {suffix!r}")
        return int(getattr(self.lib, f"{self.name.upper()}_{suffix}"))

    def new(self, type_name: str, init=None):
        """A new NAME_<type_name> (one of codegen.interface.TYPES), zeroed or from ``init``, owned by Python."""
        if type_name not in interface.TYPES:
            raise ValueError(f"type_name: one of {', '.join(interface.TYPES)}, got {type_name!r}")
        return self.ffi.new(f"{self.name}_{type_name} *", init)

    def define_callback(self, callback: str, function) -> None:
        """Define the extern "Python" function NAME_<callback> (one of codegen.interface.CALLBACKS) as ``function``,
        once per compiled module: cffi allows one definition, so ``function`` must find its run through the
        ``user`` handle it is passed."""
        if callback not in {f.name for f in interface.CALLBACKS}:
            raise ValueError(f"callback: one of {', '.join(f.name for f in interface.CALLBACKS)}, got {callback!r}")
        defined = _DEFINED.setdefault(id(self.lib), set())
        if callback not in defined:
            self.ffi.def_extern(name=f"{self.name}_{callback}")(function)
            defined.add(callback)


class CompiledModel:
    """Calls into the compiled kernels of one scene.  Arrays in and out are float64 numpy arrays, in
    the model's own coordinates: ``layout.free`` of the full layout of Eq. 13 (all of it for the general
    model; ``layout.reduce`` / ``layout.expand`` convert)."""

    def __init__(self, scene: Scene, generated: GeneratedModel, module):
        self.scene = scene
        self.options = generated.options              # every choice it was generated and compiled with
        self.generated = generated
        self.layout = generated.layout
        self.ffi, self.lib = module.ffi, module.lib
        self.name = generated.name
        self.n, self.nq = scene.n, self.layout.nq          # nq: the model's own coordinates
        self.p = scene.parameter_vector()
        self.parameter_names = scene.parameter_names()
        self.input_names = list(scene.inputs)              # u[i] acts on coordinate input_names[i]
        self.nu = scene.nu
        self.q0, self.qd0 = self.layout.reduce(scene.q0), self.layout.reduce(scene.qd0)
        # the kernel's contacts (point, Wall or JointStop), then each capsule link pair (i, LinkPair), then each link
        # and obstacle (i, ObstacleContact): gac.h's table
        self.contacts = list(self.layout.contacts) + [(pair.i, pair) for pair in scene.rowless_contacts()]
        self.contact_rows = list(self.layout.contact_rows)
        self.c = CInterface(self.ffi, self.lib, self.name)   # every call into the compiled model goes through it
        self._work = np.zeros(self.size("IMPACT_NWORK"))

    def __reduce__(self):
        """Pickled as the scene and build options: another process (a Dask worker) loads the model from the
        shared build cache, once per process (runtime.model.model_of)."""
        return model_of, (self.scene, self.options)

    def size(self, suffix: str) -> int:
        """The model's size NAME_<suffix> (codegen.interface.SIZES), read from the compiled module."""
        return self.c.size(suffix)

    def error_message(self, code: int) -> str:
        """The C library's message for a return code."""
        return self.ffi.string(self.c.error_message(code)).decode()

    def parameter_problem(self, p=None) -> str:
        """The C check of a parameter vector (NAME_check_parameters, which NAME_sim_init and the FMU apply): '' if it
        passes, else 'p[NAME]: the rule in words, got VALUE' for the parameter it names, from the model's C table
        (NAME_model.parameter_info)."""
        p = self._params(p)
        bad = self.ffi.new("int *", -1)
        if self.c.check_parameters(self._ptr(p), bad) == self.lib.GAC_OK:
            return ""
        info = self.c.model.parameter_info[bad[0]]
        value = float(p[bad[0]])
        subnormal = " (nonzero below the smallest normal double: give 0 or a larger magnitude)" \
            if value != 0.0 and abs(value) < sys.float_info.min else ""
        return (f"p[{self.ffi.string(info.name).decode()}]: {self.ffi.string(info.range).decode()}, "
                f"got {value!r}{subnormal}")

    # -- plumbing ---------------------------------------------------------------
    def _ptr(self, array: np.ndarray):
        return self.ffi.cast("double *", self.ffi.from_buffer(array))

    def _vec(self, x, size: int, what: str) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        if x.shape != (size,):
            raise ValueError(f"{what}: expected shape ({size},), got {x.shape}")
        return x

    def _params(self, p):
        return self.p if p is None else self._vec(p, len(self.p), "p")

    def _inputs(self, u):
        return np.zeros(max(self.nu, 1)) if u is None else self._vec(u, self.nu, "u")

    def parameters(self, overrides: dict | None = None, base=None) -> np.ndarray:
        """The parameter vector with ``overrides`` ({name: value}, names of ``parameter_names``) applied to
        ``base`` (default: the scene's own)."""
        p = np.array(self.p if base is None else base, dtype=float)
        for name, value in (overrides or {}).items():
            if name not in self.parameter_names:
                raise ValueError(f"p[{name}]: no such parameter; this model's parameters are "
                                 f"{', '.join(self.parameter_names)}")
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ValueError(f"p[{name}]: expected a number, got {value!r}")
            p[self.parameter_names.index(name)] = float(value)
        return p

    def _call(self, name: str, out_size: int, *inputs):
        out = np.zeros(out_size)
        getattr(self.c, name)(*(self._ptr(a) for a in inputs), self._ptr(out))
        return out

    # -- kernels ----------------------------------------------------------------
    def mass_matrix(self, q, p=None) -> np.ndarray:
        q = self._vec(q, self.nq, "q")
        return self._call("mass_matrix", self.nq ** 2, q, self._params(p)).reshape(self.nq, self.nq)

    def bias(self, q, qd, p=None, u=None) -> np.ndarray:
        """R of I_f qdd = R, with the generalised forces of the inputs u (default 0), springs and dampers."""
        return self._call("bias", self.nq, self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd"),
                          self._inputs(u), self._params(p))

    def forward_dynamics(self, q, qd, p=None, u=None) -> np.ndarray:
        return self._call("forward_dynamics", self.nq, self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._inputs(u), self._params(p))

    def forward_dynamics_energy(self, q, qd, p=None, u=None) -> tuple[np.ndarray, float, float]:
        """forward_dynamics and energy at one state in one call: (qdd, T, V)."""
        y = self._call("forward_dynamics_energy", self.nq + 2, self._vec(q, self.nq, "q"),
                       self._vec(qd, self.nq, "qd"), self._inputs(u), self._params(p))
        return y[:self.nq], float(y[self.nq]), float(y[self.nq + 1])

    def rhs(self, t: float, x, p=None, u=None) -> np.ndarray:
        x = self._vec(x, 2 * self.nq, "x")
        out = np.zeros(2 * self.nq)
        self.c.rhs(float(t), self._ptr(x), self._ptr(self._inputs(u)), self._ptr(self._params(p)),
                        self._ptr(out))
        return out

    def power(self, q, qd, p=None, u=None) -> tuple[float, float]:
        """(power of the inputs, dissipation of the dampers) in W: dE/dt = P_in - P_damp in flight."""
        P = self._call("power", 2, self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd"), self._inputs(u),
                       self._params(p))
        return float(P[0]), float(P[1])

    def inertia_solve(self, q, Q, p=None) -> np.ndarray:
        """I_f^-1 Q: the accelerations that generalised forces Q alone give (O(n), no matrix formed)."""
        return self._call("inertia_solve", self.nq, self._vec(q, self.nq, "q"), self._vec(Q, self.nq, "Q"),
                          self._params(p))

    def generalized_momentum(self, q, qd, p=None) -> np.ndarray:
        """I_f qd = dT/dqd (O(n), no matrix formed)."""
        return self._call("generalized_momentum", self.nq, self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._params(p))

    def contact_generalized_force(self, q, f, p=None) -> np.ndarray:
        """J^T f: the generalised force of forces f along the contact Jacobian rows (``contact_rows``; N, or
        N m on a joint stop's row)."""
        return self._call("contact_generalized_force", self.nq, self._vec(q, self.nq, "q"),
                          self._vec(f, len(self.contact_rows), "f"), self._params(p))

    def contact_points(self, q, p=None) -> np.ndarray:
        return self._call("contact_points", 3 * self.scene.npoint, self._vec(q, self.nq, "q"),
                          self._params(p)).reshape(self.scene.npoint, 3)

    def contact_velocities(self, q, qd, p=None) -> np.ndarray:
        return self._call("contact_velocities", 3 * self.scene.npoint, self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._params(p)).reshape(self.scene.npoint, 3)

    def contact_jacobian(self, q, p=None) -> np.ndarray:
        rows = len(self.contact_rows)
        if rows == 0:
            return np.zeros((0, self.nq))
        return self._call("contact_jacobian", rows * self.nq, self._vec(q, self.nq, "q"),
                          self._params(p)).reshape(rows, self.nq)

    def contact_bias(self, q, qd, p=None) -> np.ndarray:
        """J_dot qd: the contact Jacobian rows' accelerations at qdd = 0 (row order of contact_jacobian)."""
        return self._call("contact_bias", len(self.contact_rows), self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._params(p))

    def contact_gaps(self, q, p=None) -> np.ndarray:
        """Every contact's gap: the kernel's (walls, stops), then each link pair's and each obstacle contact's
        (gac_contact_geometry)."""
        gaps = self._call("contact_gaps", len(self.contacts), self._vec(q, self.nq, "q"), self._params(p))
        for c in range(len(self.layout.contacts), len(self.contacts)):
            gaps[c] = self.contact_geometry(q, c, p)[0]
        return gaps

    def contact_geometry(self, q, c: int, p=None) -> tuple[float, float, float, np.ndarray]:
        """The geometry of contact c, a link pair or an obstacle's contact (gac_contact_geometry): (gap, s, t, n),
        as link_gap's and obstacle_gap's; a plane's contact of one joint point has s = 0 or 1 along its link."""
        first = len(self.layout.contacts)
        if isinstance(c, bool) or not isinstance(c, (int, np.integer)) or not first <= c < len(self.contacts):
            raise ValueError(f"c: a link pair's or an obstacle's contact index in {first}..{len(self.contacts) - 1}, "
                             f"got {c!r}")
        out = np.zeros(6)
        code = self.lib.gac_contact_geometry(self.ffi.addressof(self.c.model), self._ptr(self._vec(q, self.nq, "q")),
                                             self._ptr(self._params(p)), int(c), self._ptr(out))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"contact {c} ({self.contacts[c][1].name}): {self.error_message(code)}")
        return float(out[0]), float(out[1]), float(out[2]), out[3:].copy()

    def obstacle_gap(self, q, i: int, obstacle: str, p=None) -> tuple[float, float, float, np.ndarray]:
        """The contact of link i and the fixed obstacle named ``obstacle`` (gac_obstacle_gap): (gap, s, t, n) with gap
        the distance of the link's segment from the obstacle's less their radii (m), s and t the closest points'
        fractions along the link and the obstacle's segment, n the unit normal from the obstacle to the link.  The
        obstacle's geometry is p's (its parameters center_x_<name>, ..., radius_<name>: parameter_names)."""
        names = [o.name for o in self.scene.obstacles]
        if obstacle not in names:
            raise ValueError(f"obstacle: one of this scene's obstacles ({', '.join(names) or 'none'}), got {obstacle!r}")
        last = self.scene.npoint - 1                    # links are numbered by their first point (codegen.scene.Chains)
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 1 <= i <= last:
            raise ValueError(f"i: a link index in 1..{last}, got {i!r}")
        o = names.index(obstacle)
        radius = self.scene.capsule_radius(i)           # the link's; the obstacle's is its geometry, read from p
        out = np.zeros(6)
        code = self.lib.gac_obstacle_gap(self.ffi.addressof(self.c.model), self._ptr(self._vec(q, self.nq, "q")),
                                         self._ptr(self._params(p)), int(i), o, radius, self._ptr(out))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"obstacle contact (link {i}, {obstacle}): {self.error_message(code)}")
        return float(out[0]), float(out[1]), float(out[2]), out[3:].copy()

    def contact_normal(self, q, c: int, p=None) -> np.ndarray:
        """J^T n of contact c (gac_contact_normal): the generalised force (nq) of a unit push along its normal, so
        that the gap's rate is contact_normal . qd."""
        if isinstance(c, bool) or not isinstance(c, (int, np.integer)) or not 0 <= c < len(self.contacts):
            raise ValueError(f"c: a contact index in 0..{len(self.contacts) - 1}, got {c!r}")
        g = np.zeros(self.nq)
        code = self.lib.gac_contact_normal(self.ffi.addressof(self.c.model), self._ptr(self._vec(q, self.nq, "q")),
                                           self._ptr(self._params(p)), int(c), self._ptr(g))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"contact {c}: {self.error_message(code)}")
        return g

    def energy(self, q, qd, p=None) -> tuple[float, float]:
        E = self._call("energy", 2, self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd"), self._params(p))
        return float(E[0]), float(E[1])

    def _link_pair(self, i: int, j: int, radius) -> float:
        """Check links i, j (1-based) and give the radius sum of their capsules (``radius`` if given)."""
        n = self.scene.npoint - 1                       # links are numbered by their first point (codegen.scene.Chains)
        for name, k in (("i", i), ("j", j)):
            if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= n:
                raise ValueError(f"{name}: a link index in 1..{n}, got {k!r}")
        if i == j:
            raise ValueError(f"j: a link other than i = {i}, got {j!r}")
        if radius is None:
            return self.scene.capsule_radius(i) + self.scene.capsule_radius(j)
        if not (isinstance(radius, (int, float, np.floating)) and 0.0 <= float(radius) < np.inf):
            raise ValueError(f"radius: a finite number >= 0 (m), got {radius!r}")
        return float(radius)

    def link_gap(self, q, i: int, j: int, p=None, radius=None) -> tuple[float, float, float, np.ndarray]:
        """The contact of links i and j as capsules (gac_link_gap): (gap, s, t, n) with gap the distance of their
        segments less the sum of their radii (``radius`` if given; m), s and t the closest points' fractions along
        links i and j, n the unit normal from link j's closest point to link i's."""
        radius = self._link_pair(i, j, radius)
        out = np.zeros(6)
        code = self.lib.gac_link_gap(self.ffi.addressof(self.c.model), self._ptr(self._vec(q, self.nq, "q")),
                                     self._ptr(self._params(p)), int(i), int(j), radius, self._ptr(out))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"link contact ({i}, {j}): {self.error_message(code)}")
        return float(out[0]), float(out[1]), float(out[2]), out[3:].copy()

    def link_impact(self, q, qd, i: int, j: int, e: float, p=None, radius=None) -> tuple[np.ndarray, float, float]:
        """Newton's law with restitution e on the relative normal velocity of links i and j at their closest points
        (gac_link_impact): (qd_plus, impulse >= 0 in N s, the normal velocity before)."""
        radius = self._link_pair(i, j, radius)
        q, qd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd")
        qd_plus, out = np.zeros(self.nq), np.zeros(2)
        code = self.lib.gac_link_impact(self.ffi.addressof(self.c.model), self._ptr(q), self._ptr(qd),
                                        self._ptr(self._params(p)), int(i), int(j), radius, float(e),
                                        self._ptr(qd_plus), self._ptr(out), self._ptr(out[1:]))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"link impact ({i}, {j}): {self.error_message(code)}")
        return qd_plus, float(out[0]), float(out[1])

    def impact(self, q, qd, contact_set, p=None, mode: str = "equality") -> tuple[np.ndarray, np.ndarray]:
        """Post-impact velocities and impulses for the contacts with indices ``contact_set``:
        mode 'equality' is Eq. 48 as printed, 'complementarity' forbids pulling impulses."""
        if mode not in ("equality", "complementarity"):
            raise ValueError(f"mode: must be 'equality' or 'complementarity', got {mode!r}")
        q, qd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd")
        contact_set = np.ascontiguousarray(contact_set, dtype=np.int32)
        qd_plus, impulse = np.zeros(self.nq), np.zeros(max(len(contact_set), 1))
        solve = self.c.impact if mode == "equality" else self.c.impact_complementarity
        code = solve(self._ptr(q), self._ptr(qd), self._ptr(self._params(p)), len(contact_set),
                                  self.ffi.cast("int *", self.ffi.from_buffer(contact_set)),
                                  self._ptr(qd_plus), self._ptr(impulse), self._ptr(self._work))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"impact with contacts {contact_set.tolist()}: {self.error_message(code)}")
        return qd_plus, impulse[:len(contact_set)]


    def inverse_dynamics(self, q, qd, qdd, p=None, u=None) -> np.ndarray:
        """tau: the generalised forces (N on X1..X3, N m on the angles) that, with the model's own (gravity, inputs
        u, joint springs and dampers), give the accelerations qdd at (q, qd) in flight: I_f qdd = R + tau
        (gac_inverse_dynamics: O(n), exact)."""
        q, qd, qdd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd"), self._vec(qdd, self.nq, "qdd")
        tau = np.zeros(self.nq)
        self.lib.gac_inverse_dynamics(self.ffi.addressof(self.c.model), self._ptr(q), self._ptr(qd), self._ptr(qdd),
                                      self._ptr(self._inputs(u)), self._ptr(self._params(p)), self._ptr(tau))
        return tau

    def require_tangents(self, what: str) -> None:
        """Refuse ``what`` (a ValueError naming it) when the model was built without its tangent kernels."""
        if not self.options.tangent:
            raise ValueError(f"{what}: this model has no tangent kernel (forward_dynamics_tangent); load it with "
                             "tangent=True (load_model(scene, tangent=True))")

    def forward_dynamics_tangent(self, q, qd, dq, dqd, p=None, u=None, du=None, dp=None) -> np.ndarray:
        """d qdd along the direction (dq, dqd, du, dp) at (q, qd, u, p): the directional derivative of
        forward_dynamics, exact (its generated forward-mode tangent, O(n)); du and dp default to 0.  dp along a
        parameter the model has built in (baked parameters, or a specialised model's zero) has no effect."""
        self.require_tangents("forward_dynamics_tangent")
        dq, dqd = self._vec(dq, self.nq, "dq"), self._vec(dqd, self.nq, "dqd")
        du = np.zeros(max(self.nu, 1)) if du is None else self._vec(du, self.nu, "du")
        dp = np.zeros(len(self.p)) if dp is None else self._vec(dp, len(self.p), "dp")
        return self._call("forward_dynamics_tangent", self.nq, self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._inputs(u), self._params(p), dq, dqd, du, dp)

    def contact_points_tangent(self, q, dq, p=None, dp=None) -> np.ndarray:
        """d O_1..O_npoint along (dq, dp) at (q, p) (npoint x 3, m per unit of the direction): the directional
        derivative of contact_points, exact (its generated tangent, O(n)); dp defaults to 0."""
        self.require_tangents("contact_points_tangent")
        dp = np.zeros(len(self.p)) if dp is None else self._vec(dp, len(self.p), "dp")
        return self._call("contact_points_tangent", 3 * self.scene.npoint, self._vec(q, self.nq, "q"),
                          self._params(p), self._vec(dq, self.nq, "dq"), dp).reshape(self.scene.npoint, 3)

    def contact_velocities_tangent(self, q, qd, dq, dqd, p=None, dp=None) -> np.ndarray:
        """d(velocities of O_1..O_npoint) along (dq, dqd, dp) at (q, qd, p) (npoint x 3): the directional
        derivative of contact_velocities, exact (its generated tangent, O(n)); dp defaults to 0."""
        self.require_tangents("contact_velocities_tangent")
        dp = np.zeros(len(self.p)) if dp is None else self._vec(dp, len(self.p), "dp")
        return self._call("contact_velocities_tangent", 3 * self.scene.npoint, self._vec(q, self.nq, "q"),
                          self._vec(qd, self.nq, "qd"), self._params(p), self._vec(dq, self.nq, "dq"),
                          self._vec(dqd, self.nq, "dqd"), dp).reshape(self.scene.npoint, 3)

    def linearize(self, q, qd, p=None, u=None, parameters=None):
        """The flight dynamics x_dot = f(x, u, p), x = [q, qd], linearised at (q, qd, u, p): (A, B) with
        A = df/dx (2 nq x 2 nq) and B = df/du (2 nq x nu), exact (gac_linearize: the tangent kernel once per
        column).  ``parameters``: names of ``parameter_names`` -> (A, B, P) with P = df/dp of those parameters
        (2 nq x len(parameters), column k for parameters[k]); a parameter the model has built in is refused."""
        self.require_tangents("linearize")
        q, qd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd")
        p, u = self._params(p), self._inputs(u)
        nx = 2 * self.nq
        A, B = np.zeros((nx, nx)), np.zeros((nx, max(self.nu, 1)))
        code = self.lib.gac_linearize(self.ffi.addressof(self.c.model), self._ptr(q), self._ptr(qd), self._ptr(u),
                                      self._ptr(p), self._ptr(A), self._ptr(B))
        if code != self.lib.GAC_OK:
            raise RuntimeError(f"linearize: {self.error_message(code)}")
        B = B[:, :self.nu].copy()
        if parameters is None:
            return A, B
        columns = [self._runtime_parameter(name) for name in parameters]
        P = np.zeros((nx, len(columns)))
        zero = np.zeros(self.nq)
        for k, index in enumerate(columns):
            dp = np.zeros(len(self.p))
            dp[index] = 1.0
            P[self.nq:, k] = self.forward_dynamics_tangent(q, qd, zero, zero, p, u if self.nu else None, dp=dp)
        return A, B, P

    def _runtime_parameter(self, name) -> int:
        """The index of a parameter the model reads from p (linearize's ``parameters``)."""
        if name not in self.parameter_names:
            raise ValueError(f"parameters: no parameter {name!r}; this model's parameters are "
                             f"{', '.join(self.parameter_names)}")
        if self.options.bake_params:
            raise ValueError(f"parameters: {name} is built into this model (bake_params): its derivative is not "
                             "available; load the model without bake_params")
        if name in self.layout.zero_params:
            raise ValueError(f"parameters: {name} is built in as 0 by this specialised model: its derivative is not "
                             "available; load the model with specialise=False")
        return self.parameter_names.index(name)

    def impact_law_code(self, law: str) -> int:
        """The library's code (GAC_IMPACT_LAW_*) of an impact law named in IMPACT_LAWS."""
        return int(getattr(self.lib, IMPACT_LAWS[law]))

    def impact_law_name(self, code: int) -> str:
        """The name (IMPACT_LAWS) of a library impact-law code."""
        return next(name for name in IMPACT_LAWS if self.impact_law_code(name) == code)

    def roundoff_cause_name(self, code: int) -> str:
        """The name (ROUNDOFF_CAUSES) of a library code GAC_ROUNDOFF_*: an impact's accuracy's largest part."""
        return next(name for name, constant in ROUNDOFF_CAUSES.items() if int(getattr(self.lib, constant)) == code)

    def refusal_name(self, code: int) -> str:
        """The name (REFUSALS) of a library code GAC_REFUSED_*: the check that refused an impact."""
        return next(name for name, constant in REFUSALS.items() if int(getattr(self.lib, constant)) == code)

    def impact_friction(self, q, qd, contact_set, p=None, law: str = "gdi") -> FrictionalImpact:
        """The impact law at walls with Coulomb friction (gac_impact_friction): the rounds of the complementarity
        law, each round with Coulomb's cone on gamma+ + e gamma- ('gdi', never gains energy), on the tangential
        velocity after the impact ('newton-coulomb', can gain energy), or without friction ('frictionless')."""
        if law not in CHOSEN_LAWS:
            raise ValueError(f"law: must be one of {CHOSEN_LAWS}, got {law!r}")
        q, qd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd")
        contact_set = np.ascontiguousarray(contact_set, dtype=np.int32)
        k = max(len(contact_set), 1)
        qd_plus, impulse, impulse_t = np.zeros(self.nq), np.zeros(k), np.zeros(2 * k)
        law_used, residual = self.ffi.new("int *"), self.ffi.new("double *")
        code = self.lib.gac_impact_friction(
            self.ffi.addressof(self.c.model), self._ptr(q), self._ptr(qd),
            self._ptr(self._params(p)), len(contact_set), self.ffi.cast("int *", self.ffi.from_buffer(contact_set)),
            self.impact_law_code(law), self._ptr(qd_plus), self._ptr(impulse), self._ptr(impulse_t), law_used,
            residual, self._ptr(self._work))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"impact with contacts {contact_set.tolist()}: {self.error_message(code)}")
        n = len(contact_set)
        return FrictionalImpact(qd_plus, impulse[:n], impulse_t[:2 * n].reshape(n, 2),
                                self.impact_law_name(law_used[0]), float(residual[0]))

    def constrained_dynamics(self, q, qd, resting, p=None, u=None) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations and contact forces with the contacts ``resting`` held at their walls (bilateral, with
        Coulomb friction on walls that have it): I_f qdd = R + N^T lambda + friction, N qdd = -Ndot qd (the
        runtime's resting contact)."""
        q, qd = self._vec(q, self.nq, "q"), self._vec(qd, self.nq, "qd")
        resting = np.ascontiguousarray(resting, dtype=np.int32)
        qdd, lam = np.zeros(self.nq), np.zeros(max(len(resting), 1))
        code = self.c.constrained_dynamics(self._ptr(q), self._ptr(qd), self._ptr(self._inputs(u)),
                                                self._ptr(self._params(p)), len(resting),
                                                self.ffi.cast("int *", self.ffi.from_buffer(resting)),
                                                self._ptr(qdd), self._ptr(lam), self._ptr(self._work))
        if code != self.lib.GAC_OK:
            raise ImpactError(f"constrained dynamics with contacts {resting.tolist()}: {self.error_message(code)}")
        return qdd, lam[:len(resting)]


def load_model(scene: Scene | str | Path, bake_params: bool = False, flags=None, progress=None,
               specialise: bool = True, dense: bool | None = None, rolled: bool | None = None,
               chart_b: bool = True, tangent: bool = False, extended: bool = True) -> CompiledModel:
    """Generate (cached) and compile (cached) the model of a scene, a shipped scene name or a scene
    file.  ``specialise`` (default) leaves out what the scene does not need; False gives the general
    model.  ``dense``: generate the dense kernels (mass_matrix, bias, contact_jacobian; O(n^2) code, not
    needed by simulations); None (default) does up to codegen.interface.DENSE_MAX_LINKS links, and otherwise
    they are formed at run time from the O(n) kernels.  ``rolled``: emit the forward dynamics with loops over the
    links (codegen.rolled); None (default) does from codegen.interface.ROLLED_MIN_LINKS links on.  ``chart_b``
    False leaves a free base's second chart out (a run that reaches the gimbal lock then stops there).  ``tangent``
    True generates the tangent kernels that ``linearize``, ``forward_dynamics_tangent`` and ``simulate(...,
    sensitivities=...)`` need (straight-line forward dynamics then; about twice the derivation).  ``extended``
    False leaves out the long-double variants of generalized_momentum, contact_generalized_force and energy that
    the impact's accuracy measure evaluates its residuals with (it then measures in double).  The choices
    are resolved once, here (codegen.options.build_options), into the model's ``options``.  For a name or a file,
    the same model object is returned again while the file is unchanged (same path, modification time and size)
    and the options are the same."""
    for option, value in (("dense", dense), ("rolled", rolled)):
        if value is not None and not isinstance(value, bool):
            raise TypeError(f"{option}: expected True, False or None, got {value!r}")
    for option, value in (("tangent", tangent), ("extended", extended)):
        if not isinstance(value, bool):
            raise TypeError(f"{option}: expected True or False, got {value!r}")
    choices = dict(bake_params=bake_params, specialise=specialise, dense=dense, rolled=rolled, chart_b=chart_b,
                   tangent=tangent, extended=extended, flags=flags)
    if isinstance(scene, (Scene, Chains)):
        return _build_model(scene, build_options(scene, **choices), progress)
    if not isinstance(scene, (str, os.PathLike)):
        raise TypeError("scene: expected a Scene, a shipped scene name or a path to a .toml/.json scene "
                        f"file, got {reprlib.repr(scene)} ({type(scene).__name__})")
    path = scene_file(scene)
    stat = path.stat()
    key = (path, stat.st_mtime_ns, stat.st_size, bool(bake_params), tuple(flags or ()), bool(specialise), dense,
           rolled, bool(chart_b), tangent, extended)
    model = _MODELS.get(key)
    if model is None:
        loaded = load_scene(path)
        model = _build_model(loaded, build_options(loaded, **choices), progress)
        _MODELS[key] = model
    return model


_MODELS: dict[tuple, CompiledModel] = {}      # (scene file, mtime, size, what was asked) -> model


def _build_model(scene: Scene, options: BuildOptions, progress) -> CompiledModel:
    generated = generate_cached(scene, options, progress=progress)
    module = compile_model(generated.name, generated.header, generated.source, generated.cdef,
                           flags=options.flags, progress=progress, digest=generated.text_digest())
    return CompiledModel(scene, generated, module)


_BY_SCENE: dict[tuple, CompiledModel] = {}    # (scene, options) -> model, for model_of


def model_of(scene: Scene, options: BuildOptions) -> CompiledModel:
    """The model of a scene, built (or loaded from the build cache) once per process: what an unpickled
    CompiledModel is."""
    key = (scene, options)
    if key not in _BY_SCENE:
        _BY_SCENE[key] = _build_model(scene, options, None)
    return _BY_SCENE[key]
