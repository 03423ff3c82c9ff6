"""Symbols of a scene and the recursive kinematics of the chain (paper Sect. 2 and Eq. 15-23).

Frame convention (docs/model.md, "Frame convention"): ^{ref}R_{-1} = T_{-1} Rz(theta_-1) and
^{k-1}R_k = T_k Rz(theta_k) for k = 0..n.  Links -1 and 0 are massless and of zero length;
link k spans O_k -> O_{k+1} = O_k + l_k x_{k,1}, and O_{-1} = O_0 = O_1 = (X1, X2, X3).

Everything is expressed in the frame of the link it belongs to ("^k v" in the paper).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import sympy as sp

from .scene import Scene, parameter_name
from .specialise import Layout, layout_for
from .tape import (E_X, E_Z, ZERO, Tape, Vec, Mat, add, column, cross, dot, index_name, matmul,
                   mat_t_vec, matvec, scale, to_exact)


@dataclass
class LinkSymbols:
    """Parameter symbols of one real link and its moments B0..B3 (Eq. 4-7).

    B1 = skew(h) with h the first moment of mass about O_i (so B1 v = h x v), and
    K = B2 + B3 is the inertia tensor about O_i; only B2 + B3 enters the equations.
    """

    length: sp.Expr
    B0: sp.Expr            # mass, Eq. 4
    h: Vec                 # first moment, B1 = skew(h), Eq. 5
    K: Mat                 # B2 + B3, Eq. 6 + 7 (symmetric)


class ChainSymbols:
    """Inputs (q, qd, p) of the generated functions, as sympy symbols named like the C arrays.

    ``q`` and ``qd`` are indexed in the full layout of Eq. 13 (n + 5 entries); coordinates the layout
    holds fixed are numbers (exact multiples of pi/2 for angles where they are one, zero velocity), the free ones are the
    symbols q[j], qd[j] of the model's own (reduced) input arrays.
    """

    def __init__(self, scene: Scene, bake_params: bool = False, layout: Layout | None = None):
        self.scene = scene
        self.layout = layout or layout_for(scene, specialise=False)
        self.n = scene.n
        self.nq = scene.nq                       # full layout size
        self.q = [None] * self.nq
        self.qd = [None] * self.nq
        for j, i in enumerate(self.layout.free):
            self.q[i] = sp.Symbol(f"q[{j}]", real=True)
            self.qd[i] = sp.Symbol(f"qd[{j}]", real=True)
        for i, value in self.layout.fixed:
            self.q[i] = _angle(value) if i < 3 else _number(value)
            self.qd[i] = sp.Integer(0)
        names = scene.parameter_names()
        values = scene.parameter_vector()
        zeros = set(self.layout.zero_params)
        if bake_params:
            self.p = [_number(v) for v in values]
        else:
            self.p = [sp.Integer(0) if name in zeros else sp.Symbol(f"p[{i}]", real=True)
                      for i, name in enumerate(names)]
        self.param_index = {name: i for i, name in enumerate(names)}
        self.twists = [to_exact(T) for T in scene.all_twists]
        self.up = tuple(to_exact([[-x for x in scene.gravity_direction]])[0])  # -d: (0, 1, 0) exactly by default
        self.u = [sp.Symbol(f"u[{i}]", real=True) for i in range(scene.nu)]    # inputs, scene.inputs order
        self.input_coordinate = scene.input_coordinates()                      # full-layout index of each

    # -- generalised forces (Eq. 10-11: dS/dq_ddot_j = Q_j) -------------------------------------------
    def spring_torque(self, k: int) -> sp.Expr:
        """-K_k (theta_k - rest_k): the torque of joint k's spring (0 without one)."""
        if k < 2 or self.scene.joints[k - 2].stiffness is None:
            return sp.Integer(0)
        stretch = self.theta(k) - self.param(parameter_name("rest_angle", k))
        return -self.param(parameter_name("stiffness", k)) * stretch

    def damper_torque(self, k: int) -> sp.Expr:
        """-C_k theta_dot_k: the torque of joint k's damper (0 without one)."""
        if k < 2 or self.scene.joints[k - 2].damping is None:
            return sp.Integer(0)
        return -self.param(parameter_name("damping", k)) * self.theta_dot(k)

    def input_force(self, index: int) -> sp.Expr:
        """The inputs acting on coordinate ``index`` (full layout): u_i for inputs[i] naming it."""
        return sp.Add(*[u for u, c in zip(self.u, self.input_coordinate) if c == index])

    def generalized_force(self, index: int, springs: bool = True) -> sp.Expr:
        """Q of coordinate ``index`` (full layout): inputs, damper and (springs=True) spring torques.  A
        Lagrangian derivation takes the springs from their potential instead (springs=False)."""
        Q = self.input_force(index)
        k = index - 1                                   # theta_k is q[k + 1]
        if 2 <= k <= self.n:
            Q += self.damper_torque(k) + (self.spring_torque(k) if springs else 0)
        return Q

    def spring_potential(self) -> sp.Expr:
        """sum_k 1/2 K_k (theta_k - rest_k)^2 over the joints with a spring (J)."""
        V = sp.Integer(0)
        for k in range(2, self.n + 1):
            if self.scene.joints[k - 2].stiffness is not None:
                stretch = self.theta(k) - self.param(parameter_name("rest_angle", k))
                V += self.param(parameter_name("stiffness", k)) * stretch * stretch / 2
        return V

    def power(self) -> tuple[sp.Expr, sp.Expr]:
        """(input power sum_i u_i qd_(c_i), damper dissipation sum_k C_k theta_dot_k^2 >= 0), W."""
        P_in = sp.Add(*[u * self.qd[c] for u, c in zip(self.u, self.input_coordinate)])
        P_damp = sp.Add(*[-self.damper_torque(k) * self.theta_dot(k) for k in range(2, self.n + 1)])
        return P_in, P_damp

    def param(self, name: str) -> sp.Expr:
        return self.p[self.param_index[name]]

    @property
    def gravity(self) -> sp.Expr:
        return self.param("g")

    def frame_acceleration(self) -> Vec:
        """The reference frame's acceleration that stands for gravity: -g d = g up (g X2 by default, Eq. 18)."""
        return scale(self.gravity, self.up)

    def height(self, r: Vec) -> sp.Expr:
        """up . r, the height of a point r against gravity (X2 by default): V = g sum_i m_i height(r_Gi)."""
        return dot(self.up, r)

    def theta(self, k: int) -> sp.Symbol:
        return self.q[k + 1]

    def theta_dot(self, k: int) -> sp.Symbol:
        return self.qd[k + 1]

    def base_position(self) -> Vec:
        return tuple(self.q[self.n + 2: self.n + 5])

    def base_velocity(self) -> Vec:
        return tuple(self.qd[self.n + 2: self.n + 5])


def _angle(value: float) -> sp.Expr:
    """A held angle: an exact multiple of pi/2 where it is one (to 1e-12; its sine and cosine then vanish or are
    +-1 symbolically), else the number."""
    quarter = round(value / (math.pi / 2))
    if abs(value - quarter * math.pi / 2) < 1e-12:
        return sp.Integer(quarter) * sp.pi / 2
    return _number(value)


def _number(value: float) -> sp.Expr:
    value = float(value)
    return sp.Integer(int(value)) if value == int(value) else sp.Float(repr(value), 17)


def link_moments(tape: Tape, chain: ChainSymbols, i: int) -> LinkSymbols:
    """B0..B3 of real link i (Eq. 4-7), as symbols of the runtime parameters."""
    link = chain.scene.links[i - 1]
    P = lambda kind: chain.param(parameter_name(kind, i))
    if link.kind == "line":
        l, mu = P("l"), P("mu")
        B0 = tape.let(mu * l, f"B0_{i}")                               # Eq. 4: int mu
        hx = tape.let(mu * l * l / 2, f"h_{i}_x")                      # Eq. 5: int mu eta x
        b2 = tape.let(mu * l * l * l / 3, f"B2_{i}")                   # Eq. 6: int mu eta^2 (yy, zz)
        K = ((tape.let(l * P("Jxx"), f"K_{i}_xx"), ZERO, ZERO),        # Eq. 7: B3 = l J
             (ZERO, tape.let(b2 + l * P("Jyy"), f"K_{i}_yy"), ZERO),
             (ZERO, ZERO, tape.let(b2 + l * P("Jzz"), f"K_{i}_zz")))
        return LinkSymbols(l, B0, (hx, ZERO, ZERO), K)
    # general rigid link: mass m, centre of mass c, inertia Ic about c
    l, m = P("l"), P("m")
    c = (P("cx"), P("cy"), P("cz"))
    h = tape.let_vec(scale(m, c), f"h_{i}")
    Ic = ((P("Ixx"), P("Ixy"), P("Ixz")), (P("Ixy"), P("Iyy"), P("Iyz")), (P("Ixz"), P("Iyz"), P("Izz")))
    cc = c[0] ** 2 + c[1] ** 2 + c[2] ** 2
    K = [[None] * 3 for _ in range(3)]
    for a in range(3):                       # parallel-axis theorem, about O_i
        for b in range(a, 3):
            value = Ic[a][b] + m * ((cc if a == b else 0) - c[a] * c[b])
            K[a][b] = K[b][a] = tape.let(value, f"K_{i}_{'xyz'[a]}{'xyz'[b]}")
    return LinkSymbols(l, m, h, tuple(tuple(r) for r in K))


def link_moments_all(tape: Tape, chain: ChainSymbols) -> dict[int, LinkSymbols]:
    return {i: link_moments(tape, chain, i) for i in range(1, chain.n + 1)}


def joint_rotations(tape: Tape, chain: ChainSymbols) -> dict[int, Mat]:
    """^{k-1}R_k = T_k Rz(theta_k) for k = -1..n (k = -1 maps to the reference frame)."""
    rotations = {}
    for k in range(-1, chain.n + 1):
        c = tape.let(sp.cos(chain.theta(k)), f"c_{index_name(k)}")
        s = tape.let(sp.sin(chain.theta(k)), f"s_{index_name(k)}")
        rotations[k] = joint_rotation(tape, chain.twists[k + 1], c, s, index_name(k))
    return rotations


def joint_rotation(tape: Tape, T: Mat, c, s, tag: str) -> Mat:
    """^{k-1}R_k = T_k Rz(theta_k) from the twist and c = cos theta_k, s = sin theta_k."""
    Rz = ((c, -s, ZERO), (s, c, ZERO), (ZERO, ZERO, sp.Integer(1)))
    return tape.let_mat(matmul(T, Rz), f"R_{tag}")


def link_offset(chain: ChainSymbols, moments: dict[int, LinkSymbols], k: int) -> Vec:
    """^k r_{O_{k+1}/O_k} = l_k x_{k,1}: zero for the imaginary links."""
    if k < 1:
        return (ZERO, ZERO, ZERO)
    return scale(moments[k].length, E_X)


@dataclass
class Motion:
    """Velocities and the velocity-product parts of the accelerations of every link, in its own frame."""

    omega: dict[int, Vec]          # ^k omega_k
    omega_dot_v: dict[int, Vec]    # ^k omega_dot_{v,k}, Eq. 20
    acc_v: dict[int, Vec]          # ^k r_ddot_{O_{v,k}}, Eq. 18 (includes gravity as +g X2 of the base)


def velocity_products(tape: Tape, chain: ChainSymbols, rotations: dict[int, Mat],
                      moments: dict[int, LinkSymbols]) -> Motion:
    """Forward recursion for omega_k, omega_dot_{v,k} and r_ddot_{O_{v,k}} (Eq. 18 and 20).

    Eq. 18 and 20 are sums over k' < k; written as a recursion over k they read
        omega_k          = ^kR_{k-1} omega_{k-1} + theta_dot_k z
        omega_dot_{v,k}  = ^kR_{k-1} omega_dot_{v,k-1} + (^kR_{k-1} omega_{k-1}) x z theta_dot_k
        r_ddot_{Ov,k}    = ^kR_{k-1} (r_ddot_{Ov,k-1} + omega_dot_{v,k-1} x r_{k-1}
                                       + omega_{k-1} x (omega_{k-1} x r_{k-1}))
    starting from the reference frame, which has omega = 0 and r_ddot_{Ov} = -g d (gravity along d; g X2 by
    default).
    """
    omega, omega_dot_v, acc_v = {}, {}, {}
    previous = ((ZERO, ZERO, ZERO), (ZERO, ZERO, ZERO), chain.frame_acceleration())
    r_prev = (ZERO, ZERO, ZERO)
    for k in range(-1, chain.n + 1):
        w, wd, a = velocity_step(tape, rotations[k], chain.theta_dot(k), previous, r_prev, index_name(k))
        omega[k], omega_dot_v[k], acc_v[k] = w, wd, a
        previous = (w, wd, a)
        r_prev = link_offset(chain, moments, k)
    return Motion(omega, omega_dot_v, acc_v)


def velocity_step(tape: Tape, R: Mat, theta_dot, previous, r_prev: Vec, tag: str) -> tuple[Vec, Vec, Vec]:
    """One step of velocity_products: (omega, omega_dot_v, r_ddot_Ov) of frame k from those of frame k - 1
    (``previous``), the joint rotation R = ^{k-1}R_k, theta_dot_k and the offset r_{k-1} = O_k - O_{k-1}."""
    w_prev, wd_prev, a_prev = previous
    u = tape.let_vec(mat_t_vec(R, w_prev), f"wp_{tag}")                # ^kR_{k-1} omega_{k-1}
    w = tape.let_vec(add(u, scale(theta_dot, E_Z)), f"w_{tag}")
    wd = tape.let_vec(add(mat_t_vec(R, wd_prev), scale(theta_dot, cross(u, E_Z))), f"wdv_{tag}")
    a_local = add(a_prev, add(cross(wd_prev, r_prev), cross(w_prev, cross(w_prev, r_prev))))
    a = tape.let_vec(mat_t_vec(R, tape.let_vec(a_local, f"ap_{tag}")), f"av_{tag}")
    return w, wd, a


def link_velocities(tape: Tape, chain: ChainSymbols, rotations: dict[int, Mat],
                    moments: dict[int, LinkSymbols]) -> tuple[dict[int, Vec], dict[int, Vec]]:
    """omega_k and the velocity of O_k, both in frame k, for k = -1..n (Eq. 15-17 as a recursion):
        omega_k = ^kR_{k-1} omega_{k-1} + theta_dot_k z,   v_k = ^kR_{k-1} (v_{k-1} + omega_{k-1} x r_{k-1}),
    from the reference frame's omega = 0 and v = (X1_dot, X2_dot, X3_dot)."""
    omega, vel = {}, {}
    w_prev, v_prev, r_prev = (ZERO, ZERO, ZERO), chain.base_velocity(), (ZERO, ZERO, ZERO)
    for k in range(-1, chain.n + 1):
        R = rotations[k]
        tag = index_name(k)
        v = tape.let_vec(mat_t_vec(R, add(v_prev, cross(w_prev, r_prev))), f"vl_{tag}")
        w = tape.let_vec(add(mat_t_vec(R, w_prev), scale(chain.theta_dot(k), E_Z)), f"wl_{tag}")
        omega[k], vel[k] = w, v
        w_prev, v_prev, r_prev = w, v, link_offset(chain, moments, k)
    return omega, vel


def reference_frames(tape: Tape, chain: ChainSymbols, rotations: dict[int, Mat]) -> dict[int, Mat]:
    """^{ref}R_k for k = -1..n, by accumulating the joint rotations."""
    frames = {}
    current = None
    for k in range(-1, chain.n + 1):
        current = rotations[k] if current is None else tape.let_mat(matmul(current, rotations[k]),
                                                                     f"Rref_{index_name(k)}")
        frames[k] = current
    return frames


def point_positions(tape: Tape, chain: ChainSymbols, frames: dict[int, Mat],
                    moments: dict[int, LinkSymbols]) -> list[Vec]:
    """O_1 .. O_{n+1} in the reference frame: O_1 = (X1, X2, X3), O_{i+1} = O_i + l_i x_{i,1}."""
    points = [chain.base_position()]
    for i in range(1, chain.n + 1):
        step = scale(moments[i].length, column(frames[i], 0))
        points.append(tape.let_vec(add(points[-1], step), f"O_{i + 1}"))
    return points


def point_velocities(tape: Tape, chain: ChainSymbols, frames: dict[int, Mat],
                     moments: dict[int, LinkSymbols]) -> tuple[list[Vec], dict[int, Vec]]:
    """Velocities of O_1..O_{n+1} and angular velocities omega_k, all in the reference frame."""
    w = (ZERO, ZERO, ZERO)
    omega_ref = {}
    for k in range(-1, chain.n + 1):
        w = tape.let_vec(add(w, scale(chain.theta_dot(k), column(frames[k], 2))), f"wref_{index_name(k)}")
        omega_ref[k] = w
    velocities = [chain.base_velocity()]
    for i in range(1, chain.n + 1):
        arm = scale(moments[i].length, column(frames[i], 0))
        velocities.append(tape.let_vec(add(velocities[-1], cross(omega_ref[i], arm)), f"vO_{i + 1}"))
    return velocities, omega_ref


def to_parent(R: Mat, v: Vec) -> Vec:
    """^{k-1}R_k v: a vector of frame k expressed in frame k-1."""
    return matvec(R, v)
