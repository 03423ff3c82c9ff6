"""The forward dynamics as loops over the links (rolled) instead of one straight line per link (unrolled).

The unrolled kernel (codegen.kernels.forward_dynamics_kernel) writes every link's step of the recursion out,
so its code grows with n (about 190 operations, 6 lines of machine code per operation, per link): past a few
dozen links it no longer fits the instruction cache and the compiler's time grows with it.  The rolled kernel
runs the same three passes of the articulated-body recursion (codegen.articulated) with the links of a run of
identical links as the iterations of a C loop:

    velocities  omega_k, omega_dot_v_k, r_ddot_Ov_k                    base -> tip   (Eq. 18, 20)
    backward    the loads (S_k, T_k), articulated inertia and force,
                joint pivots                                           tip -> base   (Eq. 38-41)
    forward     joint accelerations theta_ddot_k                       base -> tip

The links before the run (the imaginary links -1, 0 and link 1 at least) and after it (the tip at least) stay
straight-line code.  Each loop body is derived once, symbolically, for a generic link k: the link's parameters
are read as p[a k + b] and its coordinate as q[k + c] (index maps checked affine over the run), so a run is a
range of links with the same link kind, twists, joint springs, dampers and inputs, and the same parameters built
in as zero.  Values cross from one pass to the next through per-link arrays on the kernel's stack (cos and sin of
theta_k, the velocities, the pivots: at most 17 doubles per link) and from one iteration to the next through
small carried arrays.  An entry that is an exact constant (a structural zero) is not stored but kept as the
constant where it is the same constant at every iteration (entries that differ, say zero only at the tip, are
stored: a fixed point between the block before a loop and its body), and a carried entry that nothing after the
loop needs through any number of iterations is not carried at all (a liveness fixed point: in a planar model the
out-of-plane inertia).

The operations per link are those of the unrolled kernel (the link's moments are formed once, in the backward
pass, where the loads and the inertia both need them).  What it saves is code: the kernel's size no longer grows
with n.
"""
from __future__ import annotations

import copy
import re
from dataclasses import dataclass, field

import sympy as sp

from . import articulated, gibbs_appell, kinematics
from .artifact import OpCount, RenderedFunction
from .emit import c_expression
from .flatten import flatten
from .kernels import Kernel
from .ops import count_ops
from .kinematics import ChainSymbols, Motion
from .scene import parameter_name, split_parameter_name
from .tape import ZERO, Tape, index_name

ROLL_MIN_RUN = 4          # the fewest links a loop covers


class NotRollable(Exception):
    """The scene's links do not form a run the loops can cover (the unrolled kernel is used instead)."""


# --- where a value lives between blocks ------------------------------------------------------------------------
def _affine(stride: int, offset: int) -> str:
    """C text of stride * k + offset."""
    text = "k" if stride == 1 else f"{stride}*k"
    return text if offset == 0 else f"{text} {'+' if offset > 0 else '-'} {abs(offset)}"


@dataclass(frozen=True)
class Generic:
    """The loop's link index k plus a shift."""
    shift: int = 0


def _pattern(values, forced: tuple | None = None) -> tuple:
    """Which entries of a stored vector are constants (kept as such) and which are stored: per entry the
    constant, or None; an entry equal to an earlier stored one is ('same', index).  ``forced``: a pattern to
    follow instead (an entry it stores is stored even when constant), which the values must fit."""
    seen, natural = {}, []
    for i, v in enumerate(values):
        v = sp.sympify(v)
        if v.is_Number:
            natural.append(v)
        elif v in seen:
            natural.append(("same", seen[v]))
        else:
            seen[v] = i
            natural.append(None)
    if forced is None:
        return tuple(natural)
    if len(forced) != len(natural) or any(f is not None and f != m for f, m in zip(forced, natural)):
        raise Mismatch(None, forced, tuple(natural))
    return forced


def _expand(pattern: tuple, stored) -> tuple:
    """The values a pattern stands for: its constants, its aliases, and ``stored(i)`` for each stored entry."""
    out = []
    for i, entry in enumerate(pattern):
        out.append(stored(i) if entry is None else out[entry[1]] if isinstance(entry, tuple) else entry)
    return tuple(out)


def _meet(a: tuple, b: tuple) -> tuple:
    """The pattern that fits both: an entry stays constant (or an alias) only where both agree."""
    if a is None or len(a) != len(b):
        return b
    return tuple(x if x == y else None for x, y in zip(a, b))


class Mismatch(NotRollable):
    """Two writers (the block before a loop and the loop body, or two links) leave different constants in a
    carried or stored vector: build again with a pattern that stores the differing entries."""

    def __init__(self, name, old, new):
        super().__init__(f"{name}: entries constant in one place are not in another")
        self.name, self.old, self.new = name, old, new


@dataclass
class Store:
    """A per-link array name[width * (k - first) + i] in the kernel's stack frame."""

    name: str
    width: int
    first: int
    last: int
    comment: str
    patterns: dict = field(default_factory=dict)      # k -> pattern of what was written
    forced: tuple | None = None                       # the pattern every write follows, if set

    @property
    def size(self) -> int:
        return self.width * (self.last - self.first + 1)

    def _index(self, k, i: int) -> str:
        if isinstance(k, Generic):
            return f"{self.name}[{_affine(self.width, self.width * (k.shift - self.first) + i)}]"
        return f"{self.name}[{self.width * (k - self.first) + i}]"

    def write(self, k, values, ks=None) -> list[tuple[str, sp.Expr]]:
        """(lvalue, value) pairs storing ``values`` for link k; ``ks``: the links a generic k stands for."""
        try:
            pattern = _pattern(values, self.forced)
        except Mismatch as error:
            raise Mismatch(self.name, error.old, error.new) from None
        for kk in (ks if isinstance(k, Generic) else [k]):
            self.patterns[kk + (k.shift if isinstance(k, Generic) else 0)] = pattern
        return [(self._index(k, i), v) for i, (v, entry) in enumerate(zip(values, pattern)) if entry is None]

    def read(self, k, ks=None) -> tuple:
        """The values of link k: constants as they were, stored entries as symbols reading the array."""
        links = [kk + k.shift for kk in ks] if isinstance(k, Generic) else [k]
        patterns = {self.patterns.get(kk) for kk in links}
        if None in patterns:
            raise NotRollable(f"{self.name}: links {links[0]}..{links[-1]} read before they are written")
        if len(patterns) != 1:
            met = None
            for pattern in patterns:
                met = _meet(met, pattern)
            raise Mismatch(self.name, met, met)
        return _expand(patterns.pop(), lambda i: sp.Symbol(self._index(k, i), real=True))


@dataclass
class Carry:
    """Values handed from one block (or loop iteration) to the next, in the array name[]: read at a block's
    start into constants cin_NAME_i, so the block may overwrite the array at its end."""

    name: str
    comment: str
    pattern: tuple = None
    size: int = 0

    def write(self, values) -> list[tuple[str, sp.Expr]]:
        try:
            pattern = _pattern(values, self.pattern)
        except Mismatch as error:
            raise Mismatch(self.name, error.old, error.new) from None
        self.pattern = pattern
        self.size = max(self.size, len(values))
        return [(f"{self.name}[{i}]", v) for i, (v, entry) in enumerate(zip(values, pattern)) if entry is None]

    def read(self) -> tuple[tuple, list[str]]:
        """(values, the lines declaring the stored ones)."""
        lines = []

        def stored(i):
            lines.append(f"const double cin_{self.name}_{i} = {self.name}[{i}];")
            return sp.Symbol(f"cin_{self.name}_{i}", real=True)
        return _expand(self.pattern, stored), lines


@dataclass
class Block:
    """Straight-line code (loop None) or a loop body over links first..last (step +1 or -1)."""

    comment: str
    tape: Tape
    reads: list[str]                                   # lines declaring carried-in values
    writes: list[tuple[str, sp.Expr]]                  # lvalue = value, at the block's end
    loop: tuple[int, int, int] | None = None           # (first, last, step)

    def kernel(self) -> Kernel:
        k = Kernel("block", self.comment, (), "", len(self.writes), self.tape)
        k.values = [v for _, v in self.writes]
        return k


# --- which links the loops cover ---------------------------------------------------------------------------------
def _link_params(chain: ChainSymbols, i: int) -> list[str]:
    """Base names of the parameters of link i and joint i (name_i), in parameter order."""
    return [kind for kind, owner in map(split_parameter_name, chain.param_index) if owner == i]


def _signature(chain: ChainSymbols, k: int):
    """What the loop bodies at link k depend on beyond the indices of its parameters and coordinate: kinds and
    parameters (and which are built-in zeros or baked numbers) of links k - 1 and k and of joint k, the twists
    T_k and T_{k+1}, whether theta_k is free, and how many inputs act on it."""
    scene = chain.scene
    parts = []
    for i in (k - 1, k):
        names = _link_params(chain, i)
        parts.append((scene.links[i - 1].kind, tuple(names),
                      tuple(v if v.is_Number else None for v in (chain.param(parameter_name(b, i)) for b in names))))
    parts.append((chain.twists[k + 1], chain.twists[k + 2], (k + 1) in chain.layout.free,
                  sum(c == k + 1 for c in chain.input_coordinate)))
    return tuple(parts)


def _affine_map(values: list[int]) -> tuple[int, int] | None:
    """(stride, offset) with values[j] = stride * j + offset for every j, or None."""
    stride = values[1] - values[0] if len(values) > 1 else 0
    if all(v == values[0] + stride * j for j, v in enumerate(values)):
        return stride, values[0]
    return None


def find_run(chain: ChainSymbols) -> tuple[int, int] | None:
    """The longest range k0..k1 (2 <= k0, k1 <= n - 1, at least ROLL_MIN_RUN links) of links the loop bodies
    cover, or None."""
    n = chain.n
    best, start = None, 2
    for k in range(2, n + 1):
        if k == n or _signature(chain, k) != _signature(chain, start):
            if k - start >= ROLL_MIN_RUN and (best is None or k - start > best[1] - best[0] + 1):
                best = (start, k - 1)
            start = k
    return best


def generic_chain(chain: ChainSymbols, run: tuple[int, int]) -> ChainSymbols:
    """A copy of ``chain`` whose symbols of link k* = run[0] (its coordinate, its parameters and those of link
    k* - 1 and joint k*, the inputs on theta_k*) read the arrays at the loop index k instead."""
    k0, k1 = run
    ks = list(range(k0, k1 + 1))
    g = copy.copy(chain)
    g.q, g.qd, g.p, g.u = list(chain.q), list(chain.qd), list(chain.p), list(chain.u)
    free = chain.layout.free
    if k0 + 1 in free:
        m = _affine_map([free.index(k + 1) for k in ks])
        if m is None or m[0] != 1:
            raise NotRollable("the joint angles of the run are not consecutive coordinates")
        g.q[k0 + 1] = sp.Symbol(f"q[{_affine(1, m[1] - k0)}]", real=True)
        g.qd[k0 + 1] = sp.Symbol(f"qd[{_affine(1, m[1] - k0)}]", real=True)
    for d in (-1, 0):
        for base in _link_params(chain, k0 + d):
            index = chain.param_index[f"{base}_{k0 + d}"]
            if g.p[index].is_Number:
                continue                                   # built in (a zero, or a baked value): same all along
            m = _affine_map([chain.param_index[f"{base}_{k + d}"] for k in ks])
            if m is None:
                raise NotRollable(f"parameter {base}: its index is not affine along the run")
            g.p[index] = sp.Symbol(f"p[{_affine(m[0], m[1] - m[0] * k0)}]", real=True)
    inputs = [[i for i, c in enumerate(chain.input_coordinate) if c == k + 1] for k in ks]
    for slot in range(len(inputs[0])):
        m = _affine_map([row[slot] for row in inputs])
        if m is None:
            raise NotRollable("the inputs on the run's joints are not in link order")
        g.u[inputs[0][slot]] = sp.Symbol(f"u[{_affine(m[0], m[1] - m[0] * k0)}]", real=True)
    return g


_CONCRETE = re.compile(r"^(q|qd|u|p)\[(\d+)\]$")


def _check_generic(chain: ChainSymbols, block: Block) -> None:
    """A loop body must not read a concrete link's coordinate, input or parameter (only g and the walls')."""
    symbols = set()
    for s, e in block.tape.assignments:
        symbols |= e.free_symbols
    for _, v in block.writes:
        symbols |= sp.sympify(v).free_symbols
    names = {i: name for name, i in chain.param_index.items()}
    for s in symbols:
        m = _CONCRETE.match(s.name)
        if m and (m.group(1) != "p" or names[int(m.group(2))].rsplit("_", 1)[-1].isdigit()):
            raise NotRollable(f"a loop body reads {s.name}, which belongs to one link")


# --- the blocks ----------------------------------------------------------------------------------------------
def _velocity(tape: Tape, chain: ChainSymbols, k: int, previous):
    """Link k's step of the velocity pass: (omega, omega_dot_v, r_ddot_Ov) of frame k (Eq. 18, 20) and
    (cos, sin) of theta_k."""
    tag = index_name(k)
    theta = chain.theta(k)
    c, s = tape.let(sp.cos(theta), f"c_{tag}"), tape.let(sp.sin(theta), f"s_{tag}")
    R = kinematics.joint_rotation(tape, chain.twists[k + 1], c, s, tag)
    r_prev = (kinematics.link_offset(chain, {k - 1: kinematics.link_moments(tape, chain, k - 1)}, k - 1)
              if k >= 2 else (ZERO, ZERO, ZERO))
    return kinematics.velocity_step(tape, R, chain.theta_dot(k), previous, r_prev, tag), (c, s)


def _backward(tape: Tape, chain: ChainSymbols, k: int, child, cs_child, motion):
    """Link k's step of the backward pass (articulated.backward_step) with joint k + 1's (cos, sin) ``cs_child``
    and link k's load (T_k, S_k) of Eq. 39-40 from its ``motion`` (omega, omega_dot_v, r_ddot_Ov)."""
    moments = {k: kinematics.link_moments(tape, chain, k)} if k >= 1 else {}
    load = None
    if k >= 1:
        S, T = gibbs_appell.link_loads(tape, moments, Motion({k: motion[0]}, {k: motion[1]}, {k: motion[2]}), k)
        load = (T, S)
    joint = None
    if child is not None:
        joint = articulated.JointTransform(tape, chain, moments, k + 1, cs_child)
    tau = chain.generalized_force(k + 1) if k + 1 in chain.layout.free else None
    return articulated.backward_step(tape, moments, joint, k, child, load, tau)


def _forward(tape: Tape, chain: ChainSymbols, k: int, motion, cs_k, pivot):
    """Link k's step of the forward pass (articulated.forward_step) with joint k's (cos, sin) ``cs_k``."""
    moments = {k - 1: kinematics.link_moments(tape, chain, k - 1)} if k >= 2 else {}
    joint = articulated.JointTransform(tape, chain, moments, k, cs_k)
    return articulated.forward_step(tape, joint, pivot, motion, k)


LOCKED = ("locked",)


def _flat(parts) -> tuple:
    return tuple(v for part in parts for v in part)


def _flat_articulated(x) -> tuple:
    (A, B, C), (N, F) = x
    return tuple(v for M in (A, B, C) for row in M for v in row) + tuple(N) + tuple(F)


def _articulated(v):
    mats = tuple(tuple(tuple(v[9 * m + 3 * i + j] for j in range(3)) for i in range(3)) for m in range(3))
    return mats, (tuple(v[27:30]), tuple(v[30:33]))


def _pivot_values(pivot) -> tuple:
    W, ud = pivot
    return tuple(W[i] for i in (0, 1, 3, 4, 5)) + (ud,)


def _pivot(values):
    return (values[0], values[1], sp.Integer(1), values[2], values[3], values[4]), values[5]


def build_blocks(chain: ChainSymbols, run: tuple[int, int], forced: dict | None = None):
    """The rolled forward dynamics of ``chain``, links run[0]..run[1] in loops, as (blocks, stores, carries).
    ``forced``: patterns (name -> pattern) the stored and carried vectors follow (see rolled_kernel)."""
    forced = forced or {}
    n = chain.n
    k0, k1 = run
    ks = list(range(k0, k1 + 1))
    free = chain.layout.free
    g = generic_chain(chain, run)
    here = Generic()
    cs = Store("cs", 2, -1, n, "cos theta_k, sin theta_k")
    mv = Store("mv", 9, 1, n, "omega, omega_dot_v, r_ddot_Ov of link k (Eq. 18, 20)")
    pv = Store("pv", 6, -1, n, "pivot of joint k: W = U / D (entries 0, 1, 3, 4, 5), u / D")
    vel = Carry("vel", "omega, omega_dot_v, r_ddot_Ov of the last link done (Eq. 18, 20)")
    art = Carry("art", "articulated inertia (A, B, C) and force (N, F) of the links done, about their first joint")
    mot = Carry("mot", "acceleration (alpha, a) of the last link done")
    for store in (cs, mv, pv):
        store.forced = forced.get(store.name)
    for carry in (vel, art, mot):
        carry.pattern = forced.get(carry.name)
    out = []

    def store_pivot(k, pivot, links=None):
        if pivot is None:
            for kk in (links or [k]):
                pv.patterns[kk] = LOCKED
            return []
        return pv.write(k, _pivot_values(pivot), links)

    def read_pivot(k, links=None):
        first = links[0] + k.shift if links else k
        if pv.patterns.get(first) == LOCKED:
            return None
        return _pivot(pv.read(k, links))

    def qdd_write(k, value, generic=False):
        if value is None:
            return []
        j = free.index(k + 1)
        return [(f"qdd[{_affine(1, j - k0)}]" if generic else f"qdd[{j}]", value)]

    # 1. velocities, links -1 .. k0 - 1
    tape, writes = Tape(), []
    motion = ((ZERO, ZERO, ZERO), (ZERO, ZERO, ZERO), chain.frame_acceleration())
    for k in range(-1, k0):
        motion, cs_k = _velocity(tape, chain, k, motion)
        writes += cs.write(k, cs_k) + (mv.write(k, _flat(motion)) if k >= 1 else [])
    writes += vel.write(_flat(motion))
    out.append(Block(f"velocities of links -1..{k0 - 1} (Eq. 18, 20)", tape, [], writes))

    # 2. loop: velocities of the run
    tape = Tape()
    values, reads = vel.read()
    motion, cs_k = _velocity(tape, g, k0, _motion(values))
    writes = cs.write(here, cs_k, ks) + mv.write(here, _flat(motion), ks) + vel.write(_flat(motion))
    out.append(Block("velocities of link k", tape, reads, writes, (k0, k1, 1)))

    # 3. velocities after the run, then the backward pass from the tip to k1 + 1
    tape = Tape()
    values, reads = vel.read()
    motion, local_cs, local_motion, writes = _motion(values), {}, {}, []
    for k in range(k1 + 1, n + 1):
        motion, local_cs[k] = _velocity(tape, chain, k, motion)
        local_motion[k] = motion
        writes += cs.write(k, local_cs[k])
    child = None
    for k in range(n, k1, -1):
        child, pivot = _backward(tape, chain, k, child, local_cs.get(k + 1), local_motion[k])
        writes += store_pivot(k, pivot)
    writes += art.write(_flat_articulated(child))
    out.append(Block(f"velocities of links {k1 + 1}..{n}; backward pass over links {n}..{k1 + 1} "
                     "(Eq. 38-41)", tape, reads, writes))

    # 4. loop: backward pass over the run, tip to base
    tape = Tape()
    values, reads = art.read()
    child, pivot = _backward(tape, g, k0, _articulated(values), cs.read(Generic(1), ks),
                             _motion(mv.read(here, ks)))
    writes = store_pivot(here, pivot, ks) + art.write(_flat_articulated(child))
    out.append(Block("backward pass at link k", tape, reads, writes, (k1, k0, -1)))

    # 5. backward pass over links k0 - 1 .. -1, the root's translations, forward pass over links -1 .. k0 - 1
    tape = Tape()
    values, reads = art.read()
    child, pivots = _articulated(values), {}
    for k in range(k0 - 1, -2, -1):
        motion = _motion(mv.read(k)) if k >= 1 else None
        child, pivots[k] = _backward(tape, chain, k, child, cs.read(k + 1), motion)
    inertia, force = child
    root = articulated.JointTransform(tape, chain, {}, -1, cs.read(-1))
    X_ddot = articulated._root_translations(tape, chain, root, inertia, force, set(free), chain.generalized_force)
    writes = [(f"qdd[{free.index(n + 2 + a)}]", X_ddot[a]) for a in range(3) if n + 2 + a in free]
    motion = ((ZERO, ZERO, ZERO), X_ddot)
    for k in range(-1, k0):
        motion, value = _forward(tape, chain, k, motion, cs.read(k), pivots[k])
        writes += qdd_write(k, value)
    writes += mot.write(_flat(motion))
    out.append(Block(f"backward pass over links {k0 - 1}..-1, the base's translations (Eq. 41), forward pass "
                     f"over links -1..{k0 - 1}", tape, reads, writes))

    # 6. loop: forward pass over the run
    tape = Tape()
    values, reads = mot.read()
    motion, value = _forward(tape, g, k0, (values[0:3], values[3:6]), cs.read(here, ks), read_pivot(here, ks))
    writes = qdd_write(k0, value, generic=True) + mot.write(_flat(motion))
    out.append(Block("forward pass at link k", tape, reads, writes, (k0, k1, 1)))

    # 7. forward pass over the links after the run
    tape = Tape()
    values, reads = mot.read()
    motion, writes = (values[0:3], values[3:6]), []
    for k in range(k1 + 1, n + 1):
        motion, value = _forward(tape, chain, k, motion, cs.read(k), read_pivot(k))
        writes += qdd_write(k, value)
    out.append(Block(f"forward pass over links {k1 + 1}..{n}", tape, reads, writes))
    for block in out:
        if block.loop is not None:
            _check_generic(chain, block)
    for carry, body, consumer in ((vel, out[1], out[2]), (art, out[3], out[4]), (mot, out[5], out[6])):
        _drop_dead_entries(carry, out, body, consumer)
    return out, [cs, mv, pv], [vel, art, mot]


def _leaves(block: Block) -> list[set[str]]:
    """Per write of a block, the names of the symbols it reads (through the block's tape)."""
    definitions = dict(block.tape.assignments)
    memo = {}

    def of(symbol) -> frozenset:
        if symbol not in memo:
            if symbol in definitions:
                memo[symbol] = frozenset().union(*(of(x) for x in definitions[symbol].free_symbols))
            else:
                memo[symbol] = frozenset([symbol.name])
        return memo[symbol]
    return [set().union(*(of(x) for x in sp.sympify(v).free_symbols)) for _, v in block.writes]


def _drop_dead_entries(carry: Carry, blocks: list[Block], body: Block, consumer: Block) -> None:
    """Stop carrying entries nothing needs: an entry is live if the block after the loop reads it, or if the
    body computes a live entry or anything it stores from it (a fixed point over the iterations); the writes
    of the others are removed (in planar models, for instance, the out-of-plane inertia)."""
    prefix = f"cin_{carry.name}_"
    mine = re.compile(rf"^{carry.name}\[(\d+)\]$")

    def entries(names):
        return {int(name[len(prefix):]) for name in names if name.startswith(prefix)}
    live = set().union(*[entries(x) for x in _leaves(consumer)]) if consumer.writes else set()
    body_leaves = _leaves(body)
    while True:
        grown = set(live)
        for (lvalue, _), names in zip(body.writes, body_leaves):
            m = mine.match(lvalue)
            if m is None or int(m.group(1)) in live:
                grown |= entries(names)
        if grown == live:
            break
        live = grown
    for block in blocks:
        block.writes = [(lvalue, v) for lvalue, v in block.writes
                        if not (mine.match(lvalue) and int(mine.match(lvalue).group(1)) not in live)]


def _motion(values):
    return tuple(values[0:3]), tuple(values[3:6]), tuple(values[6:9])


# --- C text ----------------------------------------------------------------------------------------------------
def rolled_kernel(chain: ChainSymbols):
    """(blocks, stores, carries) of the rolled forward dynamics, or None when no run of ROLL_MIN_RUN links."""
    run = find_run(chain)
    if run is None:
        return None
    forced = {}
    for _ in range(12):
        try:
            return build_blocks(chain, run, forced)
        except Mismatch as error:          # store the entries that differ, and build again
            forced[error.name] = _meet(error.old, error.new)
        except NotRollable:
            return None
    return None


def summary(built) -> str:
    blocks = built[0]
    loops = [b.loop for b in blocks if b.loop is not None]
    first, last = loops[0][0], loops[0][1]
    return ("Theta_ddot solving I_f Theta_ddot = R, by an O(n) articulated-body recursion with links "
            f"{first}..{last} in loops.")


def render(name: str, summary: str, inputs, output: str, size: int, built) -> RenderedFunction:
    """The kernel's C lines (each block flattened and CSE'd on its own) and its operations per call."""
    blocks, stores, carries = built
    lines = []
    for store in stores:
        if store.patterns:
            lines.append(f"double {store.name}[{store.size}];   /* {store.comment} */")
    for carry in carries:
        lines.append(f"double {carry.name}[{carry.size}];   /* {carry.comment} */")
    ops = OpCount()
    for block in blocks:
        program = flatten(block.kernel())
        used = set().union(*[e.free_symbols for _, e in program.assignments], *[sp.sympify(e).free_symbols
                                                                                   for e in program.outputs])
        used = {symbol.name for symbol in used}
        body = [line for line in block.reads if line.split()[2] in used]
        body += [f"const double {s.name} = {c_expression(e)};" for s, e in program.assignments]
        body += [f"{lvalue} = {c_expression(e)};" for (lvalue, _), e in zip(block.writes, program.outputs)]
        block_ops = count_ops([e for _, e in program.assignments] + list(program.outputs))
        if block.loop is None:
            lines.append(f"{{   /* {block.comment} */")
        else:
            first, last, step = block.loop
            head = (f"for (int k = {first}; k <= {last}; ++k)" if step > 0 else
                    f"for (int k = {first}; k >= {last}; --k)")
            lines.append(f"{head} {{   /* {block.comment} */")
            block_ops = OpCount(*(x * (abs(last - first) + 1) for x in block_ops.as_tuple()))
        lines += ["    " + line for line in body]
        lines.append("}")
        ops = ops + block_ops
    return RenderedFunction(name, summary, tuple(inputs), output, size, lines, ops)
