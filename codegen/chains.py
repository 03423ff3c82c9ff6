"""Several chains in one box: one model whose coordinates are the chains' stacked (docs/scenes.md, "Several chains").

A ``Chains`` holds one-chain scenes (codegen.scene.Scene) that share the box: its walls, gravity, restitution,
friction and obstacles; each chain has its own links, base, initial state and contact keys.  The model is the
chains' models side by side (codegen.combine): q = [q_1, q_2, ...], qd likewise, the flight inertia block-diagonal.
What the combined model numbers globally:

* **points**: chain 1's O_1..O_(n1+1), then chain 2's, ...: chain k's O_j is global point ``point_offset(k) + j``;
* **links**: a link is named by its first point, so chain k's link j is global link ``point_offset(k) + j`` (link i
  spans the global points O_i, O_(i+1), as in a one-chain model; the number after a chain's last link is no link);
* **coordinates**: the full layout is the chains' full layouts one after the other, each named with its chain's
  prefix ('c2.theta_1');
* **parameters**: the box's (g, the walls' positions, e and friction, the obstacles' e) once, in chain 1's order,
  then each chain's own (links, joints) with its prefix: 'c1.l_1', 'c2.mu_1', 'c2.e_limit_2'.

Capsule links of different chains strike each other (every pair whose radii add up to more than 0), with the box's
``restitution.links``.  Within a chain nothing changes.  Plain data: numpy only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import LinkPair, ObstacleContact, Scene, SceneError, coordinate_names, parameter_name, \
    split_parameter_name

BOX_KINDS = ("g", "wall", "friction")      # parameters of the box, shared by every chain (and every e but e_limit)
MAX_CHAINS = 16


def _box_value(chain: Scene, field: str):
    """What a chain has of the box's ``field``: its walls without the points each chain chooses, its obstacles
    without the links."""
    if field == "walls":
        return tuple((w.name, w.position, w.restitution, w.friction) for w in chain.walls)
    if field == "obstacles":
        return tuple((o.name, o.kind, o.segment, o.radius, o.restitution) for o in chain.obstacles)
    return getattr(chain, field)


def chain_prefix(k: int) -> str:
    """The prefix of chain k's (1-based) own names: 'c2.'."""
    return f"c{k}."


def is_box_parameter(name: str) -> bool:
    """Whether a one-chain scene's parameter belongs to the box (shared by every chain) rather than to the chain."""
    kind = split_parameter_name(name)[0]
    return kind in BOX_KINDS or kind == "e"


@dataclass(frozen=True)
class Chains:
    """Several one-chain scenes in one box (see the module's docstring).  Construction checks that they share the
    box and that the model can be built (SceneError naming the field)."""

    name: str
    chains: tuple[Scene, ...]
    description: str = ""
    link_restitution: float = 1.0         # e of two capsule links of different chains meeting

    def __post_init__(self):
        chains = tuple(self.chains)
        if not 2 <= len(chains) <= MAX_CHAINS:
            raise SceneError(f"chains: several chains means 2..{MAX_CHAINS} of them, got {len(chains)}")
        for k, chain in enumerate(chains, start=1):
            if not isinstance(chain, Scene):
                raise SceneError(f"chains[{k}]: expected a Scene, got {chain!r}")
        object.__setattr__(self, "chains", chains)
        first = chains[0]
        for k, chain in enumerate(chains[1:], start=2):
            for field in ("gravity", "gravity_direction", "walls", "obstacles", "friction_velocity"):
                if _box_value(chain, field) != _box_value(first, field):
                    raise SceneError(f"chains[{k}].{field}: the chains share the box's {field} (chain 1's), "
                                     f"got a different one")
        for k, chain in enumerate(chains, start=1):
            if chain.inputs:
                raise SceneError(f"chains[{k}].inputs: a scene of several chains takes no inputs (not supported "
                                 "yet); drive a one-chain scene instead")
        e = float(self.link_restitution)
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"restitution.links: must be in [0, 1], got {e!r}")
        object.__setattr__(self, "link_restitution", e)
        self._check_apart()

    def _check_apart(self) -> None:
        """No two chains' capsules overlap at the start (a gap below 0 would be an impact already passed)."""
        from .scene import contact_points, segment_distance
        ends = [contact_points(chain, np.asarray(chain.q0, dtype=float)) for chain in self.chains]
        for (k, a), (l, b) in ((x, y) for x in enumerate(ends, 1) for y in enumerate(ends, 1) if x[0] < y[0]):
            for i in range(len(a) - 1):
                for j in range(len(b) - 1):
                    r = self.chains[k - 1].links[i].radius + self.chains[l - 1].links[j].radius
                    if r > 0.0 and segment_distance(a[i], a[i + 1], b[j], b[j + 1]) < r:
                        raise SceneError(f"chains[{l}].initial.q: link {j + 1} of chain {l} overlaps link {i + 1} of "
                                         f"chain {k} as capsules at the start (their segments are closer than their "
                                         f"radii {r:g} m together)")

    # -- sizes and numbering ---------------------------------------------------
    @property
    def n(self) -> int:
        """The real links of all the chains together."""
        return sum(chain.n for chain in self.chains)

    @property
    def nq(self) -> int:
        """The full layout's length: every chain's n + 5."""
        return sum(chain.nq for chain in self.chains)

    @property
    def npoint(self) -> int:
        return sum(chain.n + 1 for chain in self.chains)

    def point_offset(self, k: int) -> int:
        """Chain k's (1-based) O_j is global point point_offset(k) + j."""
        return sum(chain.n + 1 for chain in self.chains[:k - 1])

    def state_offset(self, k: int) -> int:
        """Where chain k's full layout starts in the combined full layout."""
        return sum(chain.nq for chain in self.chains[:k - 1])

    def chain_of_link(self, i: int) -> tuple[int, int]:
        """(chain k, its link j) of global link i (named by its first point); SceneError if i is no link."""
        for k, chain in enumerate(self.chains, start=1):
            j = i - self.point_offset(k)
            if 1 <= j <= chain.n:
                return k, j
        raise SceneError(f"link {i}: no link starts at global point O_{i} (links are numbered by their first point: "
                         f"{', '.join(f'chain {k}: {self.point_offset(k) + 1}..{self.point_offset(k) + c.n}' for k, c in enumerate(self.chains, 1))})")

    def capsule_radius(self, i: int) -> float:
        """The capsule radius (m) of global link i."""
        k, j = self.chain_of_link(i)
        return self.chains[k - 1].links[j - 1].radius

    def point_radius(self, p: int) -> float:
        """The radius global point O_p touches a wall with (Scene.point_radius of its chain)."""
        for k, chain in enumerate(self.chains, start=1):
            j = p - self.point_offset(k)
            if 1 <= j <= chain.n + 1:
                return chain.point_radius(j)
        raise SceneError(f"point {p}: no such point (1..{self.npoint})")

    def full_coordinate_names(self) -> list[str]:
        """The combined full layout's names: each chain's, with its prefix."""
        return [chain_prefix(k) + name for k, chain in enumerate(self.chains, start=1)
                for name in coordinate_names(chain.n)]

    # -- what the box shares -----------------------------------------------------
    @property
    def links(self) -> tuple:
        """Every chain's links, one after the other (their order, not the global link numbers)."""
        return tuple(link for chain in self.chains for link in chain.links)

    @property
    def walls(self):
        return self.chains[0].walls

    @property
    def obstacles(self):
        return self.chains[0].obstacles

    @property
    def gravity(self) -> float:
        return self.chains[0].gravity

    @property
    def gravity_direction(self):
        return self.chains[0].gravity_direction

    @property
    def friction_velocity(self) -> float:
        return self.chains[0].friction_velocity

    @property
    def inputs(self) -> tuple:
        return ()

    def input_coordinates(self) -> list[int]:
        return []

    @property
    def nu(self) -> int:
        return 0

    @property
    def driven(self) -> bool:
        return False

    @property
    def q0(self) -> tuple:
        return tuple(x for chain in self.chains for x in chain.q0)

    @property
    def qd0(self) -> tuple:
        return tuple(x for chain in self.chains for x in chain.qd0)

    @property
    def base_twists(self):
        """The base chart of the one chain whose theta_0 may move (codegen.combine allows one at most), else
        chain 1's."""
        return self.chains[0].base_twists

    @property
    def all_twists(self) -> tuple:
        return tuple(T for chain in self.chains for T in chain.all_twists)

    @property
    def warnings(self) -> list[str]:
        return [f"chain {k}: {w}" for k, chain in enumerate(self.chains, start=1) for w in chain.warnings]

    # -- parameters ----------------------------------------------------------------
    def parameter_map(self, k: int) -> list[int]:
        """Chain k's parameter vector gathered from the combined one: p_k[i] = p[parameter_map(k)[i]]."""
        names = self.parameter_names()
        return [names.index(self.combined_name(k, name)) for name in self.chains[k - 1].parameter_names()]

    def combined_name(self, k: int, name: str) -> str:
        """Chain k's parameter ``name`` in the combined vector: a box's as it is, the chain's own with its prefix."""
        return name if is_box_parameter(name) else chain_prefix(k) + name

    def stop_parameter_index(self, kind: str, joint: int) -> int:
        """The index in p of a joint stop's parameter (kind 'e_limit', 'lower', 'upper') of the combined layout's
        joint ``joint`` (chain k's joint j is state_offset(k) + j, as the combined layout numbers its stops)."""
        for k, chain in reversed(list(enumerate(self.chains, start=1))):
            if joint > self.state_offset(k):
                return self.parameter_names().index(chain_prefix(k) + parameter_name(kind, joint - self.state_offset(k)))
        raise SceneError(f"joint {joint}: no such joint")

    def parameter_names(self) -> list[str]:
        box = [name for name in self.chains[0].parameter_names() if is_box_parameter(name)]
        own = [chain_prefix(k) + name for k, chain in enumerate(self.chains, start=1)
               for name in chain.parameter_names() if not is_box_parameter(name)]
        return box + own

    def parameter_vector(self) -> np.ndarray:
        values = dict(zip(self.chains[0].parameter_names(), self.chains[0].parameter_vector().tolist()))
        for k, chain in enumerate(self.chains, start=1):
            values.update((chain_prefix(k) + name, value)
                          for name, value in zip(chain.parameter_names(), chain.parameter_vector().tolist())
                          if not is_box_parameter(name))
        return np.array([values[name] for name in self.parameter_names()], dtype=float)

    def parameter_index(self, kind: str, owner: int | str | None = None) -> int:
        """The index in p of parameter ``kind`` of ``owner``: a box's by its name ('g', 'wall' of 'x1_min'), a
        link's or joint's by its place among all the chains' links (1..n, chain 1's first)."""
        name = parameter_name(kind, owner)
        if isinstance(owner, int) and not isinstance(owner, bool):
            for k, chain in enumerate(self.chains, start=1):
                if owner <= chain.n:
                    name = chain_prefix(k) + parameter_name(kind, owner)
                    break
                owner -= chain.n
        names = self.parameter_names()
        if name not in names:
            raise SceneError(f"{name}: this scene has no such parameter (it has {', '.join(names)})")
        return names.index(name)

    # -- contacts after the kernels' ---------------------------------------------------
    def cross_link_pairs(self) -> list[LinkPair]:
        """Every pair of links of different chains that can strike each other as capsules (radii adding up to more
        than 0), in global link numbers."""
        pairs = []
        for k, a in enumerate(self.chains, start=1):
            for l in range(k + 1, len(self.chains) + 1):
                b = self.chains[l - 1]
                for i, link_i in enumerate(a.links, start=1):
                    for j, link_j in enumerate(b.links, start=1):
                        r = link_i.radius + link_j.radius
                        if r > 0.0:
                            pairs.append(LinkPair(self.point_offset(k) + i, self.point_offset(l) + j, r,
                                                  self.link_restitution))
        return pairs

    def rowless_contacts(self) -> list:
        """Each chain's link pairs, then the pairs across chains, then each chain's links on the obstacles (global
        link numbers): the model's table after the kernels' walls and stops."""
        pairs, obstacles = [], []
        for k, chain in enumerate(self.chains, start=1):
            shift = self.point_offset(k)
            pairs += [LinkPair(c.i + shift, c.j + shift, c.radius, c.restitution) for c in chain.link_contacts()]
            obstacles += [ObstacleContact(c.i + shift, c.obstacle, c.index, c.radius)
                          for c in chain.obstacle_contacts()]
        return pairs + self.cross_link_pairs() + obstacles


def chains_layout(scene: Chains, specialise: bool = True):
    """The combined model's layout: each chain's (codegen.specialise.layout_for) shifted into the stacked full
    layout; its contacts' points (walls) and joints (stops) in global numbers."""
    from .specialise import Layout, layout_for
    free, fixed, contacts, rows, zeros, notes, held = [], [], [], [], [], [], []
    normals = set()
    for k, chain in enumerate(scene.chains, start=1):
        layout = layout_for(chain, specialise)
        off, poff = scene.state_offset(k), scene.point_offset(k)
        free += [off + i for i in layout.free]
        fixed += [(off + i, v) for i, v in layout.fixed]
        held += [off + i for i in layout.held]
        contacts += [(_shift_contact(point, wall, off, poff)) for point, wall in layout.contacts]
        rows += [(off + point, axis) if axis == "theta" else (poff + point, axis) for point, axis in layout.contact_rows]
        zeros += [scene.combined_name(k, name) for name in layout.zero_params]
        notes += [f"chain {k}: {note}" for note in layout.notes]
        normals.add(layout.planar_normal)
    normal = normals.pop() if len(normals) == 1 else None
    return Layout(tuple(free), tuple(fixed), tuple(contacts), tuple(rows), tuple(dict.fromkeys(zeros)), tuple(notes),
                  normal, tuple(held))


def _shift_contact(point, wall, off: int, poff: int):
    """A chain's (point, Wall) contact in global point numbers; a stop's (joint k, JointStop) with k shifted by the
    chain's full-layout offset (theta_k sits at full index k + 1)."""
    from .scene import JointStop
    return (off + point, wall) if isinstance(wall, JointStop) else (poff + point, wall)


def chains_from_dict(data: dict, default_name: str, folder, box_keys: tuple[str, ...]) -> Chains:
    """A scene file's [[chains]] (docs/scenes.md, "Several chains"): each entry with the keys of a one-chain scene's
    chain (CHAIN_KEYS), the rest of the file (``box_keys``) the box's, given to every chain."""
    from .scene import TOP_KEYS, scene_from_dict
    items = data["chains"]
    if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
        raise SceneError("chains: expected an array of tables [[chains]], one per chain")
    extra = sorted(set(data) - set(box_keys) - {"chains", "name", "description"})
    if extra:
        raise SceneError(f"{extra[0]}: a scene with [[chains]] gives it per chain ([[chains]] {extra[0]}), or not at "
                         f"all (top-level keys allowed with chains: {', '.join(('name', 'description', 'chains') + box_keys)})")
    name = data.get("name", default_name)
    box = {key: data[key] for key in box_keys if key in data}
    scenes = []
    for k, item in enumerate(items, start=1):
        unknown = sorted(set(item) - set(CHAIN_KEYS))
        if unknown:
            raise SceneError(f"chains[{k}].{unknown[0]}: unknown key (a chain has {', '.join(CHAIN_KEYS)}; the box's "
                             "keys go at the top of the file)")
        if "links" not in item:
            raise SceneError(f"chains[{k}].links: each chain needs its [[chains.links]]")
        merged = dict(box, **item, name=f"{name}_c{k}" if isinstance(name, str) else name)
        assert set(merged) <= set(TOP_KEYS)
        try:
            scenes.append(scene_from_dict(merged, default_name=f"{default_name}_c{k}", folder=folder))
        except SceneError as exc:
            if str(exc).startswith(tuple(box_keys)):        # the box's own field: named as it is
                raise
            raise SceneError(f"chains[{k}].{exc}") from None
    restitution = data.get("restitution", 1.0)
    e = restitution.get("links", restitution.get("default", 1.0)) if isinstance(restitution, dict) else restitution
    return Chains(name=name, chains=tuple(scenes), description=str(data.get("description", "")), link_restitution=e)


CHAIN_KEYS = ("links", "initial", "base", "contacts")
