"""Independent numerical reference model of a floating open chain: the yardstick of the tests and of the
chart-switching report (studies.charts_report).

Plain numpy, written to be read top to bottom.  Nothing here is generated; it
is the yardstick the generated code is compared against.  At the end: the model
of a scene (``reference_of``) and an integration of it through the gimbal lock
(``integrate_reference``).

The system
----------
An open chain of ``n >= 1`` real rigid links floating in 3D, preceded by two
massless, zero-length "imaginary" links -1 and 0 that give the base its
orientation.  Generalised coordinates, length ``N = n + 5``::

    q = [th_{-1}, th_0, th_1, ..., th_n, X1, X2, X3]

so ``th_k`` sits at index ``k + 1`` and ``X_a`` (a = 1, 2, 3) at ``n + 1 + a``.

Frames (rotation matrices map link-frame components to reference components)::

    R_{-1} = T_{-1} @ Rz(th_{-1})
    R_k    = R_{k-1} @ T_k @ Rz(th_k)          k = 0..n

``T_k`` are constant "twist" rotations.  Joint axis ``z_k = R_k[:, 2]``, link
direction ``x_k = R_k[:, 0]``.  Points: ``O_{-1} = O_0 = O_1 = X`` and
``O_{i+1} = O_i + l_i x_i`` for ``i = 1..n``; the "contact points" are
``O_1 .. O_{n+1}``.

Link ``i`` (1..n) carries, in its own frame and relative to its origin
``O_i``: length ``l``, mass ``m``, first moment ``h = m c`` and the inertia
tensor ``K`` about ``O_i`` (not about the centre of mass).  Gravity of
magnitude ``g`` acts along the unit vector ``d`` (default ``-X2``).

Equations of motion: ``M(q) qdd = R(q, qd)``.
"""

import numpy as np


# ---------------------------------------------------------------------------
# Small rotation helpers
# ---------------------------------------------------------------------------

def Rx(a):
    """Rotation by angle ``a`` about the x axis."""
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(a):
    """Rotation by angle ``a`` about the y axis."""
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def Rz(a):
    """Rotation by angle ``a`` about the z axis (every joint turns about z)."""
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def skew(v):
    """Matrix ``S`` with ``S @ w == np.cross(v, w)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def random_rotation(rng):
    """Uniformly distributed random rotation (from a normalised quaternion)."""
    quat = rng.normal(size=4)
    w, x, y, z = quat / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def default_twists(n):
    """The twists of the paper: a list of n + 2 matrices [T_{-1}, T_0, ..., T_n].

    With these, R_1 = Ry(th_{-1}) @ Rz(th_0) @ Rx(th_1) @ T_1, i.e. the base
    orientation is a yaw (about X2) / pitch (about X3) / roll (about X1)
    sequence.  T_1 maps the link-1 x axis onto the reference X2 axis.
    """
    T_minus1 = Rx(-np.pi / 2)
    T_0 = Rx(np.pi / 2)
    T_1 = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return [T_minus1, T_0, T_1] + [np.eye(3) for _ in range(n - 1)]


# ---------------------------------------------------------------------------
# Link inertia constructors; each returns (l, m, h, K), all in the link frame
# ---------------------------------------------------------------------------

def line_link(l, mu, J):
    """Uniform thin rod of the paper along the link x axis.

    ``mu`` is the mass per unit length, ``J = (Jxx, Jyy, Jzz)`` the moment of
    inertia of the cross-section per unit length.  K is about the origin O_i
    (the rod's end), hence the mu l^3 / 3 terms.
    """
    m = mu * l
    h = np.array([mu * l ** 2 / 2, 0.0, 0.0])
    K = np.diag([0.0, mu * l ** 3 / 3, mu * l ** 3 / 3]) + l * np.diag(J)
    return (float(l), float(m), h, K)


def rigid_link(l, mass, com, inertia_about_com):
    """General rigid link, shifting the inertia to the origin (parallel axes)."""
    c = np.asarray(com, dtype=float)
    h = mass * c
    K = np.asarray(inertia_about_com, dtype=float) + mass * (c @ c * np.eye(3) - np.outer(c, c))
    return (float(l), float(mass), h, K)


# ---------------------------------------------------------------------------
# The chain
# ---------------------------------------------------------------------------

class ReferenceChain:
    """Floating open chain; see the module docstring for all conventions.

    Parameters
    ----------
    links : list of (l, m, h, K), one per real link 1..n
    twists : list of n + 2 constant rotations [T_{-1}, T_0, T_1, ..., T_n]
    g : gravity magnitude, acting along d
    direction : d, the unit vector gravity acts along (default (0, -1, 0), i.e. -X2)
    """

    def __init__(self, links, twists, g, direction=(0.0, -1.0, 0.0)):
        self.n = len(links)
        assert self.n >= 1
        assert len(twists) == self.n + 2
        self.N = self.n + 5
        self.l = np.array([float(link[0]) for link in links])
        self.m = np.array([float(link[1]) for link in links])
        self.h = [np.asarray(link[2], dtype=float) for link in links]
        self.K = [np.asarray(link[3], dtype=float) for link in links]
        self.T = [np.asarray(T, dtype=float) for T in twists]
        self.g = float(g)
        self.up = -np.asarray(direction, dtype=float)     # -d: gravity acts against it

    # --- index bookkeeping -------------------------------------------------
    # Joints are numbered k = -1..n; Python lists indexed by k + 1.

    def theta(self, q):
        """Joint angles th_{-1}..th_n (length n + 2)."""
        return np.asarray(q, dtype=float)[: self.n + 2]

    def base(self, q):
        """Base position X = (X1, X2, X3)."""
        return np.asarray(q, dtype=float)[self.n + 2:]

    # --- kinematics ----------------------------------------------------------

    def frames(self, q):
        """[R_{-1}, R_0, ..., R_n]; R_k maps frame-k components to reference."""
        th = self.theta(q)
        R = self.T[0] @ Rz(th[0])
        frames = [R]
        for k in range(0, self.n + 1):
            R = R @ self.T[k + 1] @ Rz(th[k + 1])
            frames.append(R)
        return frames

    def origins(self, q):
        """Origins [O_{-1}, O_0, O_1, ..., O_{n+1}] (list index k + 1)."""
        frames = self.frames(q)
        X = self.base(q)
        O = [X.copy(), X.copy(), X.copy()]  # O_{-1} = O_0 = O_1 = X
        for i in range(1, self.n + 1):
            x_i = frames[i + 1][:, 0]
            O.append(O[-1] + self.l[i - 1] * x_i)
        return O

    def points(self, q):
        """Contact points O_1..O_{n+1} as an (n + 1, 3) array."""
        return np.array(self.origins(q)[2:])

    def joint_axes(self, q):
        """[z_{-1}, ..., z_n], the joint axes in the reference frame."""
        return [R[:, 2] for R in self.frames(q)]

    def point_jacobian(self, q):
        """d(O_j)/dq for j = 1..n+1, shape (n + 1, 3, N).

        Turning joint k (with everything else fixed) rotates every point
        beyond it about the axis z_k through O_k: column z_k x (O_j - O_k)
        for k < j.  Moving X translates every point: identity block.
        """
        z = self.joint_axes(q)
        O = self.origins(q)
        J = np.zeros((self.n + 1, 3, self.N))
        for j in range(1, self.n + 2):
            for k in range(-1, j):
                J[j - 1, :, k + 1] = np.cross(z[k + 1], O[j + 1] - O[k + 1])
            J[j - 1, :, self.n + 2:] = np.eye(3)
        return J

    def link_jacobians(self, q, i):
        """Geometric Jacobians (Jw, Jv) of real link i (1..n), each 3 x N.

        Jw maps qd to the angular velocity of link i, Jv to the velocity of
        its origin O_i.  Only joints k <= i move link i.
        """
        z = self.joint_axes(q)
        O = self.origins(q)
        Jw = np.zeros((3, self.N))
        Jv = np.zeros((3, self.N))
        for k in range(-1, i + 1):
            Jw[:, k + 1] = z[k + 1]
            Jv[:, k + 1] = np.cross(z[k + 1], O[i + 1] - O[k + 1])
        Jv[:, self.n + 2:] = np.eye(3)
        return Jw, Jv

    def velocities(self, q, qd):
        """Recursive velocities: lists w_k (k = -1..n) and v of O_{-1}..O_{n+1}.

        w_k = w_{k-1} + z_k thd_k;  v(O_{i+1}) = v(O_i) + w_i x (l_i x_i).
        (A different code path from the Jacobians, used for the energy.)
        """
        qd = np.asarray(qd, dtype=float)
        thd = self.theta(qd)
        Xd = self.base(qd)
        frames = self.frames(q)
        w = []
        w_prev = np.zeros(3)
        for k in range(-1, self.n + 1):
            w_prev = w_prev + frames[k + 1][:, 2] * thd[k + 1]
            w.append(w_prev)
        v = [Xd.copy(), Xd.copy(), Xd.copy()]
        for i in range(1, self.n + 1):
            r = self.l[i - 1] * frames[i + 1][:, 0]
            v.append(v[-1] + np.cross(w[i + 1], r))
        return w, v

    def point_velocities(self, q, qd):
        """Velocities of O_1..O_{n+1} as an (n + 1, 3) array."""
        _, v = self.velocities(q, qd)
        return np.array(v[2:])

    # --- energy and momentum -------------------------------------------------

    def energy(self, q, qd):
        """(T, V): kinetic and potential energy.

        Link i, with w its angular velocity, v the velocity of O_i and
        h_w = R_i h, K_w = R_i K R_i^T in reference components:
            T_i = 1/2 m v.v + v.(w x h_w) + 1/2 w.K_w w
            V_i = g up.(m O_i + R_i h)            (up = -d; up = X2 by default)
        """
        frames = self.frames(q)
        O = self.origins(q)
        w, v = self.velocities(q, qd)
        T = 0.0
        V = 0.0
        for i in range(1, self.n + 1):
            R = frames[i + 1]
            m, h_w, K_w = self.m[i - 1], R @ self.h[i - 1], R @ self.K[i - 1] @ R.T
            wi, vi = w[i + 1], v[i + 1]
            T += 0.5 * m * vi @ vi + vi @ np.cross(wi, h_w) + 0.5 * wi @ K_w @ wi
            V += self.g * self.up @ (m * O[i + 1] + h_w)
        return T, V

    def linear_momentum(self, q, qd):
        """Total linear momentum sum_i m_i v_com_i = sum_i (m v(O_i) + w_i x h_w)."""
        frames = self.frames(q)
        w, v = self.velocities(q, qd)
        p = np.zeros(3)
        for i in range(1, self.n + 1):
            h_w = frames[i + 1] @ self.h[i - 1]
            p += self.m[i - 1] * v[i + 1] + np.cross(w[i + 1], h_w)
        return p

    # --- generalised forces other than gravity ---------------------------------

    def relative_angle(self, q, k):
        """The angle of joint k read off the frames: T_k^T R_{k-1}^T R_k = Rz(angle) (k = 0..n)."""
        frames = self.frames(q)
        Rrel = self.T[k + 1].T @ frames[k].T @ frames[k + 1]
        return np.arctan2(Rrel[1, 0], Rrel[0, 0])

    def applied_forces(self, q, qd, u=(), inputs=(), springs=None, dampers=None):
        """Q of I_f qdd = R + Q, by virtual power, for:
        inputs[i] = "theta_k": a torque u[i] about z_k acting on frame k and -u[i] on frame k-1, so
            Q += u[i] (Jw_k - Jw_{k-1})^T z_k  (Jw_k: columns z_j, j <= k; Jw_{-2} = 0);
        inputs[i] = "Xa": a force u[i] e_a on the point O_1, Q += Jv(O_1)^T u[i] e_a;
        springs {k: (K, rest)}: the torque -K (angle_k - rest) of the same kind, the angle read off the
        frames; dampers {k: C}: the torque -C (w_k - w_{k-1}) . z_k, the relative rate from the velocities."""
        z = self.joint_axes(q)
        w, _ = self.velocities(q, qd)

        def torque_map(k):
            J = np.zeros((3, self.N))
            for j in range(-1, k + 1):
                J[:, j + 1] = z[j + 1]
            J_parent = np.zeros((3, self.N))
            for j in range(-1, k):
                J_parent[:, j + 1] = z[j + 1]
            return (J - J_parent).T @ z[k + 1]

        Q = np.zeros(self.N)
        for value, name in zip(u, inputs):
            if name.startswith("theta_"):
                Q += value * torque_map(int(name[len("theta_"):]))
            else:
                a = int(name[1]) - 1
                Q[self.n + 2 + a] += value          # Jv(O_1) = [0 | I] on the translations
        for k, (K, rest) in (springs or {}).items():
            Q += -K * (self.relative_angle(q, k) - rest) * torque_map(k)
        for k, C in (dampers or {}).items():
            rate = (w[k + 1] - w[k]) @ z[k + 1]
            Q += -C * rate * torque_map(k)
        return Q

    def spring_energy(self, q, springs):
        """sum_k 1/2 K (angle_k - rest)^2, the angles read off the frames."""
        return sum(0.5 * K * (self.relative_angle(q, k) - rest) ** 2 for k, (K, rest) in springs.items())

    def angular_momentum(self, q, qd):
        """Total angular momentum about the reference origin, sum_i (r_ci x m v_ci + I_ci w_i)."""
        frames = self.frames(q)
        O = self.origins(q)
        w, v = self.velocities(q, qd)
        L = np.zeros(3)
        for i in range(1, self.n + 1):
            R = frames[i + 1]
            m, h_w, K_w = self.m[i - 1], R @ self.h[i - 1], R @ self.K[i - 1] @ R.T
            c = h_w / m                                         # centre of mass from O_i
            r_c, v_c = O[i + 1] + c, v[i + 1] + np.cross(w[i + 1], c)
            I_c = K_w - m * (c @ c * np.eye(3) - np.outer(c, c))
            L += np.cross(r_c, m * v_c) + I_c @ w[i + 1]
        return L

    # --- dynamics ------------------------------------------------------------

    def mass_matrix(self, q):
        """M(q), N x N, assembled from the geometric Jacobians.

        With H = skew(h_w), the kinetic energy of link i is
            T_i = 1/2 m v.v - v.(H w) + 1/2 w.K_w w,
        a quadratic form in qd whose (symmetric) matrix is
            m Jv^T Jv - Jv^T H Jw + Jw^T H Jv + Jw^T K_w Jw
        (using H^T = -H).
        """
        frames = self.frames(q)
        M = np.zeros((self.N, self.N))
        for i in range(1, self.n + 1):
            R = frames[i + 1]
            m, h_w, K_w = self.m[i - 1], R @ self.h[i - 1], R @ self.K[i - 1] @ R.T
            H = skew(h_w)
            Jw, Jv = self.link_jacobians(q, i)
            M += m * Jv.T @ Jv - Jv.T @ H @ Jw + Jw.T @ H @ Jv + Jw.T @ K_w @ Jw
        return M

    def inverse_dynamics(self, q, qd, qdd):
        """Generalised forces tau = M qdd - R(q, qd), by recursive Newton-Euler.

        Everything is in reference (world) components.  Gravity is modelled by
        giving the base the acceleration -g d (g e2 by default).

        Forward pass (k = -1..n), z_k being fixed in frame k-1:
            w_k  = w_{k-1} + z_k thd_k
            wd_k = wd_{k-1} + z_k thdd_k + w_{k-1} x z_k thd_k
            a(O_1) = Xdd - g d,
            a(O_{i+1}) = a(O_i) + wd_i x r_i + w_i x (w_i x r_i),  r_i = l_i x_i
        Per link, the inertial force and moment about O_i are
            F_i = m a(O_i) + wd x h_w + w x (w x h_w)
            N_i = h_w x a(O_i) + K_w wd + w x (K_w w)
        Backward pass: f_i = F_i + f_{i+1},
            n_i = N_i + n_{i+1} + r_i x f_{i+1}   (moment about O_i),
        the imaginary links passing f, n through unchanged (O_{-1}=O_0=O_1).
        Then tau(th_k) = z_k . n_k and tau(X_a) = (f_1)_a.
        """
        q = np.asarray(q, dtype=float)
        thd, thdd = self.theta(qd), self.theta(qdd)
        Xdd = self.base(qdd)
        frames = self.frames(q)
        z = [R[:, 2] for R in frames]

        # forward pass: angular velocity and acceleration of links -1..n
        w, wd = [], []
        w_prev, wd_prev = np.zeros(3), np.zeros(3)
        for k in range(-1, self.n + 1):
            zk = z[k + 1]
            w_k = w_prev + zk * thd[k + 1]
            wd_k = wd_prev + zk * thdd[k + 1] + np.cross(w_prev, zk * thd[k + 1])
            w.append(w_k)
            wd.append(wd_k)
            w_prev, wd_prev = w_k, wd_k

        # forward pass: accelerations of the origins O_1..O_n
        a = [Xdd + self.g * self.up]  # a[0] = a(O_1)
        for i in range(1, self.n):
            r = self.l[i - 1] * frames[i + 1][:, 0]
            wi, wdi = w[i + 1], wd[i + 1]
            a.append(a[-1] + np.cross(wdi, r) + np.cross(wi, np.cross(wi, r)))

        # backward pass over the real links n..1
        f = np.zeros(3)  # force transmitted from link i+1 onwards
        nO = np.zeros(3)  # its moment about O_{i+1}
        tau = np.zeros(self.N)
        for i in range(self.n, 0, -1):
            R = frames[i + 1]
            m, h_w, K_w = self.m[i - 1], R @ self.h[i - 1], R @ self.K[i - 1] @ R.T
            wi, wdi, ai = w[i + 1], wd[i + 1], a[i - 1]
            r = self.l[i - 1] * R[:, 0]
            F = m * ai + np.cross(wdi, h_w) + np.cross(wi, np.cross(wi, h_w))
            N = np.cross(h_w, ai) + K_w @ wdi + np.cross(wi, K_w @ wi)
            nO = N + nO + np.cross(r, f)  # now about O_i
            f = F + f
            tau[i + 1] = z[i + 1] @ nO

        # imaginary links 0 and -1 sit at O_1 and carry no mass
        tau[1] = z[1] @ nO
        tau[0] = z[0] @ nO
        tau[self.n + 2:] = f
        return tau

    def bias(self, q, qd):
        """R(q, qd), the right-hand side of M qdd = R: minus the Coriolis,
        centrifugal and gravity generalised forces, R = -ID(q, qd, 0)."""
        return -self.inverse_dynamics(q, qd, np.zeros(self.N))

    def forward_dynamics(self, q, qd):
        """qdd = M^{-1} R."""
        return np.linalg.solve(self.mass_matrix(q), self.bias(q, qd))


# ---------------------------------------------------------------------------
# Random test cases
# ---------------------------------------------------------------------------

def random_link(rng):
    """A random, physically valid rigid link (l, m, h, K).

    The centre of mass lies along the link with a small lateral offset; the
    inertia about it comes from positive second moments s of a mass
    distribution (so it satisfies the triangle inequalities), rotated randomly.
    """
    l = rng.uniform(0.2, 2.0)
    mass = rng.uniform(0.1, 3.0)
    com = np.array([rng.uniform(0.0, l), rng.uniform(-0.1, 0.1) * l, rng.uniform(-0.1, 0.1) * l])
    s = rng.uniform(0.001, 0.1, size=3) * l ** 2  # second moments along principal axes
    principal = mass * np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
    Q = random_rotation(rng)
    return rigid_link(l, mass, com, Q @ np.diag(principal) @ Q.T)


def random_chain(n, rng, random_twists=False):
    """A ReferenceChain with n random links and g in [0, 12].

    With ``random_twists`` the twists T_2..T_n are random rotations; T_{-1},
    T_0, T_1 always keep their default values.
    """
    links = [random_link(rng) for _ in range(n)]
    twists = default_twists(n)
    if random_twists:
        for k in range(2, n + 1):
            twists[k + 1] = random_rotation(rng)
    g = rng.uniform(0.0, 12.0)
    return ReferenceChain(links, twists, g)


def random_state(n, rng):
    """Random (q, qd) with |th_0| <= 1.2, away from the gimbal lock th_0 = +-pi/2."""
    th = rng.uniform(-np.pi, np.pi, size=n + 2)
    th[1] = rng.uniform(-1.2, 1.2)
    X = rng.uniform(-1.0, 1.0, size=3)
    q = np.concatenate([th, X])
    qd = rng.normal(size=n + 5)
    return q, qd


# ---------------------------------------------------------------------------
# The model of a scene, and an integration of it through the gimbal lock
# ---------------------------------------------------------------------------

def reference_of(scene, p=None) -> ReferenceChain:
    """The independent numpy model of a codegen Scene (parameters from the vector p if given)."""
    from codegen.scene import LineLink
    if p is not None:
        scene = with_parameters(scene, p)
    links = []
    for link in scene.links:
        if isinstance(link, LineLink):
            links.append(line_link(link.length, link.mu, link.J))
        else:
            links.append(rigid_link(link.length, link.mass, link.com, link.inertia))
    return ReferenceChain(links, [np.array(T) for T in scene.all_twists], scene.gravity, scene.gravity_direction)


def with_parameters(scene, p):
    """The scene with the link parameters and gravity of the parameter vector p."""
    from codegen.scene import LineLink, RigidLink, Scene
    p = list(p)
    g, k = p[0], 1
    links = []
    for link in scene.links:
        values = p[k:k + len(link.param_names)]
        k += len(link.param_names)
        if isinstance(link, LineLink):
            links.append(LineLink(values[0], values[1], tuple(values[2:5])))
        else:
            l, m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = values
            links.append(RigidLink(l, m, (cx, cy, cz), ((ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz))))
    return Scene(name=scene.name, links=tuple(links), twists=scene.twists, gravity=g,
                 gravity_direction=scene.gravity_direction, walls=scene.walls,
                 q0=scene.q0, qd0=scene.qd0, base_twists=scene.base_twists, base=scene.base)


def integrate_reference(scene, t_eval, rtol=1e-12, atol=1e-12):
    """The numpy model of ``scene`` with the base orientation as a rotation matrix: at every right-hand
    side the chart is re-centred (T_-1 chosen so the base angles are 0, where the chart is perfectly
    conditioned), omega_1 is integrated instead of the angle rates, and scipy's DOP853 does the
    integration.  Returns the points O_1..O_{n+1} at t_eval."""
    from scipy.integrate import solve_ivp
    chain = reference_of(scene)
    T0, T1 = (np.array(T) for T in scene.base_twists[1:])
    q0, qd0 = np.array(scene.q0), np.array(scene.qd0)
    axes0 = np.stack(chain.joint_axes(q0)[:3], axis=1)
    y0 = np.r_[chain.frames(q0)[2].ravel(), axes0 @ qd0[:3], q0[3:], qd0[3:]]
    m = scene.nq - 3

    def centred(y):
        chain.T[0] = y[:9].reshape(3, 3) @ T1.T @ T0.T           # R_1 = T_-1 T_0 T_1 at zero angles
        return np.r_[0.0, 0.0, 0.0, y[12:12 + m]]

    def rhs(t, y):
        q, omega = centred(y), y[9:12]
        u = chain.joint_axes(q)[:3]
        thd = np.linalg.solve(np.stack(u, axis=1), omega)
        qdd = chain.forward_dynamics(q, np.r_[thd, y[12 + m:]])
        a, b, c = thd
        omega_dot = np.stack(u, axis=1) @ qdd[:3] + np.cross(u[0] * a, u[1]) * b \
            + np.cross(u[0] * a + u[1] * b, u[2]) * c
        return np.r_[(skew(omega) @ y[:9].reshape(3, 3)).ravel(), omega_dot, y[12 + m:], qdd[3:]]

    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=t_eval)
    if sol.status != 0:
        raise RuntimeError(f"integrate_reference: solve_ivp failed: {sol.message}")
    return np.array([chain.points(centred(y)) for y in sol.y.T])
