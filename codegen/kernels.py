"""The straight-line kernels of one scene: what each generated C function computes.

Each kernel is derived on its own tape (so it carries only what it needs), then flattened and
CSE'd by :mod:`codegen.flatten`.  The kernels and their C signatures:

    mass_matrix(q, p, M)                 I_f, full and symmetric, row-major nq x nq   (Eq. 12)
    bias(q, qd, u, p, R)                 R(Theta, Theta_dot) + Q (inputs u, joint springs and dampers)
                                                                                        (Eq. 10-12, 38-41)
    forward_dynamics(q, qd, u, p, qdd)   Theta_ddot = I_f^-1 R by the O(n) articulated-body recursion
                                         (codegen.articulated; I_f is never formed)
    contact_points(q, p, r)              O_1..O_{n+1}, (n+1) x 3
    contact_velocities(q, qd, p, v)      their velocities, (n+1) x 3                    (Eq. 42)
    contact_jacobian(q, p, J)            rows of Eq. 42 that the walls need, nrow x nq
    contact_gaps(q, p, gap)              signed distance of each (point, wall) pair, >= 0 inside (less the
                                         point's capsule radius, Scene.point_radius), then of each
                                         joint stop (rad: theta_k - lower, upper - theta_k)
    contact_bias(q, qd, p, a)            J_dot qd: contact row accelerations at Theta_ddot = 0
    energy(q, qd, p, E)                  E[0] kinetic, E[1] potential (gravity and joint springs)
    power(q, qd, u, p, P)                P[0] power of the inputs, P[1] dissipation of the dampers (>= 0)
    inertia_solve(q, Q, p, x)            x = I_f^-1 Q for generalised forces Q, by the articulated recursion
    generalized_momentum(q, qd, p, h)    h = I_f qd = dT/dqd, by composite momenta
    contact_generalized_force(q, f, p, Q)  Q = J^T f for forces f along the contact Jacobian's rows
    forward_dynamics_energy(q, qd, u, p, y)  forward_dynamics and energy on one tape: y = [qdd, T, V]; generated
                                         where forward_dynamics is straight-line code, otherwise formed by the
                                         library from the two (gac_forward_dynamics_energy)
    forward_dynamics_tangent(q, qd, u, p, dq, dqd, du, dp, dqdd)  d Theta_ddot along (dq, dqd, du, dp): the
                                         forward-mode tangent of forward_dynamics' tape (codegen.tangent), O(n);
                                         generated where forward_dynamics is straight-line code (gac_linearize)
    inertia_solve_tangent(q, Q, p, dq, dQ, dp, dx), contact_generalized_force_tangent(q, f, p, dq, df, dp, dQ),
    contact_gaps_tangent(q, p, dq, dp, dgap),
    contact_bias_tangent(q, qd, p, dq, dqd, dp, da)  the same tangents of four more kernels (the sensitivities
                                         of an impact, of its event time and of the resting contacts' forces,
                                         gac_sens.c)
    contact_points_tangent(q, p, dq, dp, dr),
    contact_velocities_tangent(q, qd, p, dq, dqd, dp, dv)  and of the points and their velocities (a link pair's
                                         or an obstacle's row and its derivative, gac_contact_normal_tangent)
    forward_dynamics_tangent_block(q, qd, u, p, dq, dqd, du, dp, dqdd)  forward_dynamics_tangent along
                                         interface.TANGENT_BLOCK directions at once, its primal part computed once
                                         (the sensitivities' flight, gac_sens.c)

Every kernel but three costs O(n) for n links.  mass_matrix, bias and contact_jacobian form dense matrices
(O(n^2) code); the hybrid loop does not use them (it applies I_f^-1, I_f and J^T through the three operators
above), so they are generated only where they are small (interface.DENSE_MAX_LINKS) or when asked for, and otherwise
formed at run time from the operators (gac_mass_matrix, gac_bias, gac_contact_jacobian of the C library).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from . import articulated, gibbs_appell, interface, kinematics, tangent
from .kinematics import ChainSymbols
from .linalg import ldlt_solve
from .scene import JointStop, Scene, parameter_name
from .tape import Tape, add, cross, dot, mat_t_vec, matvec, scale, column


@dataclass
class Kernel:
    """A function to generate: its tape, and the outputs as (C array name, flat index, value)."""

    name: str
    summary: str
    inputs: tuple[str, ...]                       # the arrays it reads, in C signature order: q, then qd, u,
                                                  # Q or f, then p
    output: str                                   # name of the output array
    output_size: int
    tape: Tape
    values: list[sp.Expr] = field(default_factory=list)   # output[i] = values[i]
    block: int = 0                                # > 0: a tangent kernel of `block` directions at once (its seeds
                                                  # and output hold `block` directions, one after the other):
                                                  # the primal part once, the tangent part in a loop over them
    strides: dict = field(default_factory=dict)   # block: each seed array's and the output's length per direction


def _new(chain: ChainSymbols, name: str, summary: str, inputs, output: str, size: int) -> Kernel:
    return Kernel(name, summary, tuple(inputs), output, size, Tape())


def mass_matrix_kernel(chain: ChainSymbols) -> Kernel:
    free = chain.layout.free
    k = _new(chain, "mass_matrix", "Flight inertia matrix I_f(Theta) (Eq. 12, Fig. 2), full, row-major.",
             ("q", "p"), "M", len(free) ** 2)
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    lower = gibbs_appell.inertia_matrix(k.tape, chain, rotations, moments)
    k.values = [lower[(max(i, j), min(i, j))] for i in free for j in free]
    return k


def bias_kernel(chain: ChainSymbols) -> Kernel:
    free = chain.layout.free
    k = _new(chain, "bias", "Right-hand side R(Theta, Theta_dot) of I_f Theta_ddot = R (Eq. 12, 38-41, Fig. 3), "
             "generalised forces of inputs, springs and dampers included.", ("q", "qd", "u", "p"), "R", len(free))
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    motion = kinematics.velocity_products(k.tape, chain, rotations, moments)
    R = gibbs_appell.right_hand_side(k.tape, chain, rotations, moments, motion)
    k.values = [R[i] for i in free]
    return k


def forward_dynamics_kernel(chain: ChainSymbols, solver: str = "articulated") -> Kernel:
    """Theta_ddot = I_f^-1 R.  ``solver``: 'articulated' (default) factors I_f recursively at O(n)
    cost without forming it (codegen.articulated); 'dense' forms I_f (Eq. I, II) and runs a
    straight-line LDL^T (codegen.linalg), O(n^3)."""
    free = chain.layout.free
    how = {"articulated": "an O(n) articulated-body recursion", "dense": "a straight-line LDL^T of I_f"}
    k = _new(chain, "forward_dynamics", f"Theta_ddot solving I_f Theta_ddot = R, by {how[solver]}.",
             ("q", "qd", "u", "p"), "qdd", len(free))
    if solver == "articulated":
        k.values = articulated_accelerations(k.tape, chain)
        return k
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    motion = kinematics.velocity_products(k.tape, chain, rotations, moments)
    R = gibbs_appell.right_hand_side(k.tape, chain, rotations, moments, motion)
    lower = gibbs_appell.inertia_matrix(k.tape, chain, rotations, moments)
    # the model's own (reduced) system: rows and columns of the free coordinates
    reduced = {(a, b): lower[(max(free[a], free[b]), min(free[a], free[b]))]
               for a in range(len(free)) for b in range(a + 1)}
    n = chain.n
    translations = [a for a, i in enumerate(free) if i >= n + 2]
    order = translations + [a for a in range(len(free)) if a not in translations]   # X first (Eq. II block)
    k.values = ldlt_solve(k.tape, reduced, [R[i] for i in free], order)
    return k


def articulated_accelerations(tape: Tape, chain: ChainSymbols) -> list[sp.Expr]:
    """Theta_ddot of the free coordinates by the O(n) articulated-body recursion (codegen.articulated)."""
    rotations = kinematics.joint_rotations(tape, chain)
    moments = kinematics.link_moments_all(tape, chain)
    motion = kinematics.velocity_products(tape, chain, rotations, moments)
    qdd = articulated.forward_dynamics(tape, chain, moments, motion)
    return [qdd[i] for i in chain.layout.free]


def contact_points_kernel(chain: ChainSymbols) -> Kernel:
    k = _new(chain, "contact_points", "Positions of O_1..O_{n+1} in the reference frame, row i-1 = O_i.",
             ("q", "p"), "r", 3 * (chain.n + 1))
    points = _points(k.tape, chain)
    k.values = [x for point in points for x in point]
    return k


def contact_velocities_kernel(chain: ChainSymbols) -> Kernel:
    k = _new(chain, "contact_velocities", "Velocities of O_1..O_{n+1} in the reference frame (Eq. 42).",
             ("q", "qd", "p"), "v", 3 * (chain.n + 1))
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    frames = kinematics.reference_frames(k.tape, chain, rotations)
    velocities, _ = kinematics.point_velocities(k.tape, chain, frames, moments)
    k.values = [x for v in velocities for x in v]
    return k


def contact_jacobian_kernel(chain: ChainSymbols) -> Kernel:
    rows = chain.layout.contact_rows
    free = chain.layout.free
    k = _new(chain, "contact_jacobian",
             "Rows d(O_i . X_a)/dTheta of the contact Jacobian (Eq. 42, Fig. 4) for the (point, axis) "
             "pairs the walls need, row-major.", ("q", "p"), "J", len(rows) * len(free))
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    frames = kinematics.reference_frames(k.tape, chain, rotations)
    points = kinematics.point_positions(k.tape, chain, frames, moments)
    n = chain.n
    values = []
    for point, axis in rows:
        row = [sp.Integer(0)] * chain.nq
        if axis == "theta":                  # a joint stop: d(theta_k)/dq, a row of the identity
            row[point + 1] = sp.Integer(1)
            values += [row[i] for i in free]
            continue
        for j in range(-1, point):           # joints -1 .. point-1 move O_point
            origin = points[max(j, 1) - 1]   # O_-1 = O_0 = O_1
            arm = tuple(a - b for a, b in zip(points[point - 1], origin))
            row[j + 1] = cross(column(frames[j], 2), arm)[axis]
        row[n + 2 + axis] = sp.Integer(1)
        values += [row[i] for i in free]
    k.values = values
    return k


def contact_bias_kernel(chain: ChainSymbols) -> Kernel:
    """J_dot qd: the accelerations of the contact Jacobian's (point, axis) rows at Theta_ddot = 0, so that
    the point accelerations are J Theta_ddot + J_dot qd (the resting-contact constraint of the runtime).
    World-frame recursion: omega_k = omega_{k-1} + theta_dot_k z_k, omega_dot_k = omega_dot_{k-1} +
    theta_dot_k omega_{k-1} x z_k (z_k turns with frame k-1), and
    r_ddot_{O_{i+1}} = r_ddot_{O_i} + l_i (omega_dot_i x x_i + omega_i x (omega_i x x_i)), r_ddot_{O_1} = 0."""
    rows = chain.layout.contact_rows
    k = _new(chain, "contact_bias",
             "J_dot qd: accelerations of the contact Jacobian rows' (point, axis) at Theta_ddot = 0, row order "
             "of contact_jacobian.", ("q", "qd", "p"), "a", len(rows))
    tape = k.tape
    rotations = kinematics.joint_rotations(tape, chain)
    moments = kinematics.link_moments_all(tape, chain)
    frames = kinematics.reference_frames(tape, chain, rotations)
    zero = (sp.Integer(0),) * 3
    w, wd = zero, zero
    omega, omega_dot = {}, {}
    for j in range(-1, chain.n + 1):
        z = column(frames[j], 2)
        wd = tape.let_vec(add(wd, scale(chain.theta_dot(j), cross(w, z))), f"wdb_{j + 1}")
        w = tape.let_vec(add(w, scale(chain.theta_dot(j), z)), f"wb_{j + 1}")
        omega[j], omega_dot[j] = w, wd
    acc = [zero]
    for i in range(1, chain.n + 1):
        x = column(frames[i], 0)
        a_rel = add(cross(omega_dot[i], x), cross(omega[i], cross(omega[i], x)))
        acc.append(tape.let_vec(add(acc[-1], scale(moments[i].length, a_rel)), f"aO_{i + 1}"))
    k.values = [sp.Integer(0) if axis == "theta" else acc[point - 1][axis] for point, axis in rows]   # stops: 0
    return k


def contact_gaps_kernel(chain: ChainSymbols) -> Kernel:
    contacts = chain.layout.contacts
    capsules = any(link.radius > 0.0 for link in chain.scene.links)
    k = _new(chain, "contact_gaps",
             "Gap of each (point, wall) pair: distance of the point inside its wall"
             + (" less its capsule radius" if capsules else "") + " (negative = beyond it).",
             ("q", "p"), "gap", len(contacts))
    points = _points(k.tape, chain)
    values = []
    for point, wall in contacts:
        if isinstance(wall, JointStop):      # theta_k - lower, or upper - theta_k (rad)
            values.append(wall.normal_sign * (chain.theta(point) - chain.param(wall.parameter)))
            continue
        position = chain.param(parameter_name("wall", wall.name))
        gap = wall.normal_sign * (points[point - 1][wall.axis] - position)
        radius = chain.scene.point_radius(point)        # a capsule's end sphere reaches the wall first
        values.append(gap - sp.Float(radius) if radius > 0.0 else gap)
    k.values = values
    return k


def energy_expressions(tape, chain: ChainSymbols):
    """Kinetic and potential energy (T, V) from point velocities, a velocity-level path independent of I_f.
    With a tape that records nothing (codegen.lagrange.InlineTape) they come out as explicit expressions."""
    rotations = kinematics.joint_rotations(tape, chain)
    moments = kinematics.link_moments_all(tape, chain)
    frames = kinematics.reference_frames(tape, chain, rotations)
    points = kinematics.point_positions(tape, chain, frames, moments)
    velocities, omega_ref = kinematics.point_velocities(tape, chain, frames, moments)
    T = V = sp.Integer(0)
    for i in range(1, chain.n + 1):
        B, R = moments[i], frames[i]
        v, w = velocities[i - 1], omega_ref[i]
        h_ref = tape.let_vec(matvec(R, B.h), f"href_{i}")
        w_loc = tape.let_vec(mat_t_vec(R, w), f"wloc_{i}")
        T += B.B0 * dot(v, v) / 2 + dot(v, cross(w, h_ref)) + dot(w_loc, matvec(B.K, w_loc)) / 2
        V += chain.gravity * (B.B0 * chain.height(points[i - 1]) + chain.height(h_ref))    # -g d . m r_G
    return T, V + chain.spring_potential()


def energy_kernel(chain: ChainSymbols) -> Kernel:
    k = _new(chain, "energy", "E[0] = kinetic energy T, E[1] = potential energy V, gravity and joint springs (J).",
             ("q", "qd", "p"), "E", 2)
    k.values = list(energy_expressions(k.tape, chain))
    return k


def forward_dynamics_energy_kernel(chain: ChainSymbols) -> Kernel:
    """forward_dynamics and energy at one state, on one tape: the rotations, the link moments and the parameters'
    products are computed once for both (the hybrid loop wants the energy wherever it takes a step's end
    derivative)."""
    free = chain.layout.free
    k = _new(chain, "forward_dynamics_energy", "y[0..NQ-1] = Theta_ddot (as forward_dynamics), y[NQ] = T, "
             "y[NQ+1] = V (as energy).", ("q", "qd", "u", "p"), "y", len(free) + 2)
    k.values = articulated_accelerations(k.tape, chain) + list(energy_expressions(k.tape, chain))
    return k


def power_kernel(chain: ChainSymbols) -> Kernel:
    """The rates of the energy balance that are not potential: dE/dt = P_in - P_damp in flight."""
    k = _new(chain, "power", "P[0] = power of the inputs sum u_i qd_(c_i), P[1] = dissipation of the joint "
             "dampers sum C_k theta_dot_k^2 >= 0 (W).", ("q", "qd", "u", "p"), "P", 2)
    k.values = list(chain.power())
    return k


def inertia_solve_kernel(chain: ChainSymbols) -> Kernel:
    free = chain.layout.free
    k = _new(chain, "inertia_solve", "x = I_f^-1 Q: the accelerations that generalised forces Q alone give "
             "(no motion, no gravity), by the O(n) articulated-body recursion.", ("q", "Q", "p"), "x", len(free))
    Q = [sp.Integer(0)] * chain.nq
    for j, i in enumerate(free):
        Q[i] = sp.Symbol(f"Q[{j}]", real=True)
    moments = kinematics.link_moments_all(k.tape, chain)
    x = articulated.inertia_solve(k.tape, chain, moments, Q)
    k.values = [x[i] for i in free]
    return k


def generalized_momentum_kernel(chain: ChainSymbols) -> Kernel:
    k = _new(chain, "generalized_momentum", "h = I_f qd = dT/dqd: the generalised momentum, by composite "
             "momenta at O(n) cost (I_f times any vector).", ("q", "qd", "p"), "h", len(chain.layout.free))
    rotations = kinematics.joint_rotations(k.tape, chain)
    moments = kinematics.link_moments_all(k.tape, chain)
    velocities = kinematics.link_velocities(k.tape, chain, rotations, moments)
    h = articulated.generalized_momentum(k.tape, chain, moments, velocities)
    k.values = [h[i] for i in chain.layout.free]
    return k


def contact_generalized_force_kernel(chain: ChainSymbols) -> Kernel:
    """Q = J^T f: f[r] is a force along row r of contact_jacobian (N along X_a on point O_i, or N m on a stop's
    joint).  Joint j (origin O_max(j,1)) moves the points beyond it, so Q_j = z_j . M_j with M_j the moment
    about its origin of the forces on those points; M is accumulated from the tip,
    M_i = M_{i+1} + (O_{i+1} - O_i) x F_{>i}, in the reference frame; X1..X3 take the total force."""
    rows = chain.layout.contact_rows
    free = chain.layout.free
    k = _new(chain, "contact_generalized_force", "Q = J^T f: the generalised force of forces f along the contact "
             "Jacobian rows (N on a point's axis, N m on a stop's joint).", ("q", "f", "p"), "Q", len(free))
    tape, n = k.tape, chain.n
    rotations = kinematics.joint_rotations(tape, chain)
    moments = kinematics.link_moments_all(tape, chain)
    frames = kinematics.reference_frames(tape, chain, rotations)
    point_force = {i: [sp.Integer(0)] * 3 for i in range(1, n + 2)}
    Q = [sp.Integer(0)] * chain.nq
    for r, (point, axis) in enumerate(rows):
        f = sp.Symbol(f"f[{r}]", real=True)
        if axis == "theta":                  # a stop: a torque on its joint angle
            Q[point + 1] += f
        else:
            point_force[point][axis] += f
    beyond = tuple(point_force[n + 1])       # total force on the points beyond O_i
    moment = (sp.Integer(0),) * 3            # their moment about O_i
    for i in range(n, 0, -1):
        arm = scale(moments[i].length, column(frames[i], 0))          # O_{i+1} - O_i
        moment = tape.let_vec(add(moment, cross(arm, beyond)), f"Mf_{i}")
        Q[i + 1] += dot(column(frames[i], 2), moment)
        beyond = tape.let_vec(add(beyond, tuple(point_force[i])), f"Ff_{i}")
    for j in (-1, 0):                        # the imaginary joints turn about O_1 too
        Q[j + 1] += dot(column(frames[j], 2), moment)
    for a in range(3):
        Q[n + 2 + a] += beyond[a]
    k.values = [Q[i] for i in free]
    return k


def _points(tape: Tape, chain: ChainSymbols):
    rotations = kinematics.joint_rotations(tape, chain)
    moments = kinematics.link_moments_all(tape, chain)
    frames = kinematics.reference_frames(tape, chain, rotations)
    return kinematics.point_positions(tape, chain, frames, moments)


def forward_dynamics_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d Theta_ddot along a direction (dq, dqd, du, dp): the forward-mode tangent (codegen.tangent) of the
    articulated forward dynamics' tape, O(n) like it."""
    primal = forward_dynamics_kernel(chain)
    tape, values, inputs, _ = tangent.tangent(primal.tape, primal.values, primal.inputs)
    return Kernel("forward_dynamics_tangent", "Directional derivative of Theta_ddot (forward dynamics) along (dq, "
                  "dqd, du, dp): the forward-mode tangent of its O(n) tape.", inputs, "dqdd", primal.output_size,
                  tape, values)


def forward_dynamics_tangent_block_kernel(chain: ChainSymbols) -> Kernel:
    """forward_dynamics_tangent along interface.TANGENT_BLOCK directions at once: the same tangent program, emitted
    with its primal part (no seed in it) once and its tangent part in a loop over the directions
    (codegen.emit.render_function), so that each direction costs the tangent part alone."""
    single = forward_dynamics_tangent_kernel(chain)
    nq = len(chain.layout.free)
    strides = {"dq": nq, "dqd": nq, "du": len(chain.u), "dp": len(chain.p), single.output: single.output_size}
    return Kernel("forward_dynamics_tangent_block", f"forward_dynamics_tangent along {interface.TANGENT_BLOCK} "
                  "directions at once (the primal part computed once).", single.inputs, single.output,
                  interface.TANGENT_BLOCK * single.output_size, single.tape, single.values,
                  block=interface.TANGENT_BLOCK, strides=strides)


def _tangent_of(primal: Kernel, name: str, summary: str) -> Kernel:
    tape, values, inputs, _ = tangent.tangent(primal.tape, primal.values, primal.inputs)
    return Kernel(name, summary, inputs, "d" + primal.output, primal.output_size, tape, values)


def inertia_solve_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d(I_f^-1 Q) along (dq, dQ, dp): the tangent of inertia_solve's O(n) tape (an impact's sensitivity)."""
    return _tangent_of(inertia_solve_kernel(chain), "inertia_solve_tangent",
                       "Directional derivative of I_f^-1 Q along (dq, dQ, dp): the tangent of its O(n) tape.")


def contact_generalized_force_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d(J^T f) along (dq, df, dp): the tangent of contact_generalized_force's O(n) tape."""
    return _tangent_of(contact_generalized_force_kernel(chain), "contact_generalized_force_tangent",
                       "Directional derivative of J^T f along (dq, df, dp): the tangent of its O(n) tape.")


def contact_bias_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d(J_dot qd) along (dq, dqd, dp): the tangent of contact_bias' tape (the sensitivities of the resting
    contacts' forces in flight)."""
    return _tangent_of(contact_bias_kernel(chain), "contact_bias_tangent",
                       "Directional derivative of J_dot qd along (dq, dqd, dp): the tangent of its tape.")


def contact_points_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d O_i along (dq, dp): the tangent of contact_points' tape (a link pair's or an obstacle's geometry)."""
    return _tangent_of(contact_points_kernel(chain), "contact_points_tangent",
                       "Directional derivative of the points O_1..O_{n+1} along (dq, dp): the tangent of their tape.")


def contact_velocities_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d v_O_i along (dq, dqd, dp): the tangent of contact_velocities' tape; at qd = e_k, dqd = 0 the change of the
    points' Jacobian column k (the second derivatives of the kinematics a link pair's row needs)."""
    return _tangent_of(contact_velocities_kernel(chain), "contact_velocities_tangent",
                       "Directional derivative of the velocities of O_1..O_{n+1} along (dq, dqd, dp): the tangent of "
                       "their tape.")


def contact_gaps_tangent_kernel(chain: ChainSymbols) -> Kernel:
    """d gap along (dq, dp): the tangent of contact_gaps' tape (an event time's sensitivity)."""
    return _tangent_of(contact_gaps_kernel(chain), "contact_gaps_tangent",
                       "Directional derivative of the contact gaps along (dq, dp): the tangent of their tape.")


KERNEL_BUILDERS = (mass_matrix_kernel, bias_kernel, forward_dynamics_kernel, inertia_solve_kernel,
                   generalized_momentum_kernel, contact_points_kernel, contact_velocities_kernel,
                   contact_jacobian_kernel, contact_generalized_force_kernel, contact_gaps_kernel, energy_kernel,
                   contact_bias_kernel, power_kernel, forward_dynamics_energy_kernel, forward_dynamics_tangent_kernel,
                   forward_dynamics_tangent_block_kernel,
                   inertia_solve_tangent_kernel, contact_generalized_force_tangent_kernel, contact_gaps_tangent_kernel,
                   contact_bias_tangent_kernel, contact_points_tangent_kernel, contact_velocities_tangent_kernel)


def builders(dense: bool, fused: bool = True, tangent: bool = True):
    """The kernel builders of a model, in the order of codegen.interface.KERNELS: the dense ones
    (interface.DENSE_KERNELS) if ``dense``, the fused ones (interface.FUSED_KERNELS) if ``fused``, the tangent ones
    (interface.TANGENT_KERNELS) if ``tangent``."""
    def wanted(builder) -> bool:
        name = builder.__name__.removesuffix("_kernel")
        return ((dense or name not in interface.DENSE_KERNELS) and (fused or name not in interface.FUSED_KERNELS)
                and (tangent or name not in interface.TANGENT_KERNELS))
    return [b for b in KERNEL_BUILDERS if wanted(b)]


def build_kernels(scene: Scene, bake_params: bool = False, progress=None, layout=None,
                  dense: bool | None = None, skip=(), fused: bool = True, tangent: bool = True) -> list[Kernel]:
    """Derive every kernel of the scene (symbolic, per-intermediate symbols; no CSE yet); the dense ones
    (codegen.interface.DENSE_KERNELS) only if ``interface.wants_dense(n, dense)``, the fused ones
    (codegen.interface.FUSED_KERNELS) only if ``fused``, the tangent ones (interface.TANGENT_KERNELS) only if
    ``tangent``; none named in ``skip``."""
    chain = ChainSymbols(scene, bake_params, layout)
    kernels = []
    for builder in builders(interface.wants_dense(scene.n, dense), fused, tangent):
        if builder.__name__.removesuffix("_kernel") in skip:
            continue
        if progress:
            progress(builder.__name__.removesuffix("_kernel"))
        kernels.append(builder(chain))
    return kernels
